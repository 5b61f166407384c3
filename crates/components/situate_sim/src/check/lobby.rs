//! The rules on the elevator, the lobbies and the goal floor: the doors open
//! long enough, no opening but cars' doors in the call button's wall, every
//! car's door opening on floor the robot reaches, the goal floor's call button
//! readable from in front of every car, and its office reached and its barcode
//! read.

use super::barcodes::{floor_barcode, stuck, Stuck};
use super::reach::{blocking_segments, readable_from, readable_somewhere, Grid};
use super::{finding, Diagnostic, CAR_APRON, CELL, MARGIN, OPEN_S_MIN, PRESS_STANDOFF, SLACK};
use crate::geom::{in_polygon, P2};
use crate::map::{Barcode, Car, Floor, Map, Side};

/// The doors stay open long enough to board (`docs/maps.md`, "Elevator").
pub(super) fn elevator_timing(map: &Map, out: &mut Vec<Diagnostic>) {
    let (lo, hi) = map.elevator.open_s;
    if lo < OPEN_S_MIN - 1e-9 {
        out.push(finding(
            map.elevator.lines.get("open_s").copied().unwrap_or(1),
            "elevator",
            format!(
                "open_s [{lo}, {hi}]: the doors must stay open at least {OPEN_S_MIN} s for the robot to board (the \
                 shortest documented range is [8, 12])"
            ),
        ));
    }
}

/// The call button's wall has no openings but cars' doors (`docs/maps.md`,
/// "Lobby"): the robot takes a way that opens there for a car's door. Along
/// the button's wall, walls one after another with gaps between them: a gap
/// not filled by a car's shaft is an opening.
pub(super) fn button_wall(map: &Map, f: &Floor, out: &mut Vec<Diagnostic>) {
    let Some(l) = &f.lobby else { return };
    let normal = P2::dir(l.facing);
    let along_dir = P2::new(-normal.y, normal.x);
    let on_line = |p: P2| p.minus(l.button).dot(normal).abs() <= 0.05;
    let coord = |p: P2| p.minus(l.button).dot(along_dir);
    // The stretches along the line covered by walls, and by the cars' shafts (their walls).
    let mut cover: Vec<(f64, f64)> = f
        .walls
        .iter()
        .filter(|w| on_line(w.a) && on_line(w.b))
        .map(|w| (coord(w.a).min(coord(w.b)), coord(w.a).max(coord(w.b))))
        .collect();
    let walls = cover.len();
    for c in &map.elevator.cars {
        let corners = [P2::new(c.x0, c.y0), P2::new(c.x1, c.y0), P2::new(c.x1, c.y1), P2::new(c.x0, c.y1)];
        for k in 0..4 {
            let (a, b) = (corners[k], corners[(k + 1) % 4]);
            if on_line(a) && on_line(b) {
                cover.push((coord(a).min(coord(b)), coord(a).max(coord(b))));
            }
        }
    }
    if walls == 0 {
        return; // no wall drawn through the button: the loader's and the other checks' business
    }
    cover.sort_by(|x, y| x.0.total_cmp(&y.0));
    // The run of covered stretches that holds the button; a gap in it narrower than a corridor
    // is an opening in the button's wall (a wider one ends the wall: a corner, elsewhere).
    // Each run: where it starts and ends along the line, and the gaps in it.
    type Run = (f64, f64, Vec<(f64, f64)>);
    let mut runs: Vec<Run> = Vec::new();
    for (a, b) in cover {
        match runs.last_mut() {
            Some((_, end, gaps)) if a <= *end + 3.0 => {
                if a > *end + SLACK {
                    gaps.push((*end, a));
                }
                *end = end.max(b);
            }
            _ => runs.push((a, b, Vec::new())),
        }
    }
    let Some((_, _, gaps)) = runs.into_iter().find(|(a, b, _)| *a - SLACK <= 0.0 && 0.0 <= *b + SLACK) else {
        return;
    };
    for (a, b) in gaps {
        let at = l.button.plus(along_dir.scale((a + b) / 2.0));
        out.push(finding(
            l.line,
            format!("floor {}, lobby", f.level),
            format!(
                "an opening {:.2} m wide at ({:.2}, {:.2}) in the call button's wall: that wall may have no \
                 openings but cars' doors (the robot takes a way that opens there for a car's)",
                b - a,
                at.x,
                at.y
            ),
        ));
    }
}

pub(super) fn goal_checks(map: &Map, f: &Floor, out: &mut Vec<Diagnostic>, goal_line: usize) {
    let m = &map.mission;
    let segs = blocking_segments(map, f);
    let grid = Grid::new(&segs, map.robot_radius + MARGIN);
    let Some(l) = &f.lobby else {
        out.push(finding(goal_line, format!("floor {}", f.level), "the goal floor has no lobby"));
        return;
    };
    let lobby_el = format!("floor {}, lobby", f.level);
    let press = l.button.plus(P2::dir(l.facing).scale(PRESS_STANDOFF));
    let Some(from) = grid.free_near(press, CELL * 2.0) else {
        out.push(finding(l.line, lobby_el, "the robot cannot stand in front of the goal floor's call button"));
        return;
    };
    let reach = grid.flood(from);
    cars_open_on(map, f, &grid, &reach, out);
    let button = Barcode { id: l.barcode, at: l.button, facing: Some(l.facing), line: l.line };
    for (k, c) in map.elevator.cars.iter().enumerate() {
        let apron = door_centre(c).plus(outward(c).scale(CAR_APRON));
        if !readable_from(&button, apron, &segs) {
            out.push(finding(
                l.line,
                &lobby_el,
                format!(
                    "the call button (barcode {}) cannot be read from {CAR_APRON} m in front of car {}'s door",
                    l.barcode,
                    k + 1
                ),
            ));
        }
    }
    match &f.office {
        None => out.push(finding(goal_line, "mission", format!("the goal floor {} has no office", f.level))),
        Some(o) => {
            let inside = reach.iter().enumerate().any(|(i, &r)| r && in_polygon(grid.centre(i), &o.polygon));
            if !inside {
                out.push(finding(
                    o.line,
                    format!("floor {}, office", f.level),
                    "the office cannot be reached from the goal floor's lobby",
                ));
            }
        }
    }
    let id = m.office_barcode;
    if let Some((el, b)) = floor_barcode(f, id) {
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

/// Each car's door opens on floor the robot reaches (its apron is reached).
pub(super) fn cars_open_on(map: &Map, f: &Floor, grid: &Grid, reach: &[bool], out: &mut Vec<Diagnostic>) {
    for (k, c) in map.elevator.cars.iter().enumerate() {
        let apron = door_centre(c).plus(outward(c).scale(map.robot_radius + 0.35));
        if !grid.reached_near(reach, apron, CELL * 2.0) {
            out.push(finding(
                c.line,
                format!("elevator, car {}", k + 1),
                format!("on floor {}, the car's door does not open on floor the robot reaches", f.level),
            ));
        }
    }
}

fn door_centre(c: &Car) -> P2 {
    let d = c.door();
    d.at(0.5)
}

/// The unit vector out of the car through its door.
fn outward(c: &Car) -> P2 {
    match c.door_side {
        Side::North => P2::new(0.0, 1.0),
        Side::South => P2::new(0.0, -1.0),
        Side::East => P2::new(1.0, 0.0),
        Side::West => P2::new(-1.0, 0.0),
    }
}
