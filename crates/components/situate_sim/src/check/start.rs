//! The rules on the start floor: the start pose in the lab, free, with the
//! call button reached from it and the lab door's barcode readable.

use super::barcodes::{door_el, floor_barcode, nearest_door, stuck, Stuck};
use super::lobby::cars_open_on;
use super::reach::{blocking_segments, readable_somewhere, Grid};
use super::{finding, Diagnostic, CELL, MARGIN, PRESS_STANDOFF};
use crate::geom::P2;
use crate::map::{Floor, Map};

/// The start pose is in the lab (`docs/maps.md`, "Start"): on the side of the
/// lab door its barcode faces, with that door closed.
pub(super) fn start_in_lab(map: &Map, f: &Floor, out: &mut Vec<Diagnostic>, start_line: usize) {
    let m = &map.mission;
    let Some((_, b)) = floor_barcode(f, m.lab_door_barcode) else { return };
    let Some((i, _, _)) = nearest_door(f, b.at) else { return };
    let d = &f.doors[i];
    let u = d.seg.b.minus(d.seg.a).scale(1.0 / d.seg.len().max(1e-9));
    let n = P2::new(-u.y, u.x);
    // The lab's side: the one the barcode is on (or, on the door's line, the one it faces).
    let k = b.at.minus(d.seg.a).dot(n);
    let side = match b.facing {
        _ if k.abs() >= 0.005 => k.signum(),
        Some(a) if P2::dir(a).dot(n).abs() > 0.1 => P2::dir(a).dot(n).signum(),
        _ => return,
    };
    let mut segs = blocking_segments(map, f);
    segs.push(d.seg);
    let grid = Grid::new(&segs, map.robot_radius + MARGIN);
    let start = P2::new(m.start.0, m.start.1);
    if !grid.is_free(start) {
        return; // the loader's and start_checks' business
    }
    let inside = d.seg.at(0.5).plus(n.scale(side * (map.robot_radius + MARGIN + 0.3)));
    let reach = grid.flood(start);
    if !grid.reached_near(&reach, inside, 0.3) {
        out.push(finding(
            start_line,
            "mission, start",
            format!(
                "the start pose is not in the lab: it is outside {} (the lab is the side its barcode {} is on); the \
                 robot starts in the lab",
                door_el(f, i, &d.name),
                b.id
            ),
        ));
    }
}

pub(super) fn start_checks(
    map: &Map,
    f: &Floor,
    out: &mut Vec<Diagnostic>,
    start_line: usize,
    button_faces_wall: bool,
) {
    let m = &map.mission;
    let segs = blocking_segments(map, f);
    let grid = Grid::new(&segs, map.robot_radius + MARGIN);
    let start = P2::new(m.start.0, m.start.1);
    let reach = grid.flood(start);
    if !grid.is_free(start) {
        out.push(finding(start_line, "mission, start", "the robot cannot stand at the start pose"));
        return;
    }
    match &f.lobby {
        None => out.push(finding(f.line, format!("floor {}", f.level), "the start floor has no lobby")),
        Some(l) => {
            let press = l.button.plus(P2::dir(l.facing).scale(PRESS_STANDOFF));
            if !button_faces_wall && !grid.reached_near(&reach, press, CELL * 2.0) {
                out.push(finding(
                    l.line,
                    format!("floor {}, lobby", f.level),
                    "the call button cannot be reached from the start pose",
                ));
            }
            cars_open_on(map, f, &grid, &reach, out);
        }
    }
    let id = m.lab_door_barcode;
    match floor_barcode(f, id) {
        None => out.push(finding(
            m.lines.get("lab_door_barcode").copied().unwrap_or(1),
            "mission",
            format!("lab_door_barcode {id} is not on the start floor {}", f.level),
        )),
        Some((el, b)) => {
            // One facing its wall has its own finding (stand_offs).
            let faces_wall = matches!(stuck(&b, &map.static_segments(f)), Stuck::FacesWall(_));
            if !faces_wall && !readable_somewhere(&grid, &reach, &b, &segs) {
                out.push(finding(
                    b.line,
                    el,
                    format!("barcode {id} cannot be read from anywhere the robot reaches (range, facing, sight)"),
                ));
            }
        }
    }
}
