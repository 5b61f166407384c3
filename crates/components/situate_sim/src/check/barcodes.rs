//! The rules on doors and barcodes: every floor door wide enough and 1.0 to
//! 1.4 m wide; barcodes stuck 1-2 cm off their wall, facing away from it
//! (the call button too); the lab door's and the office's barcodes beside
//! their doors, the office's facing out; and the lookups the other rules share
//! (a floor's barcode by id, the door nearest a point, a door's name).

use super::{
    finding, Diagnostic, BARCODE_JAMB_MAX, BARCODE_LINE_MAX, CORRIDOR_MIN, DOOR_MAX, DOOR_MIN, DOOR_SPARE, SLACK,
    STICK_MAX, STICK_SLACK,
};
use crate::geom::{cast, in_polygon, Seg, P2};
use crate::map::{Barcode, Floor, Map};

/// The door nearest a barcode: its index, how far the barcode is off the
/// door's line and from its nearer jamb along it.
pub(super) fn nearest_door(f: &Floor, at: P2) -> Option<(usize, f64, f64)> {
    f.doors
        .iter()
        .enumerate()
        .map(|(i, d)| {
            let len = d.seg.len();
            let along_dir = d.seg.b.minus(d.seg.a).scale(1.0 / len.max(1e-9));
            let rel = at.minus(d.seg.a);
            let along = rel.dot(along_dir);
            let off = rel.cross(along_dir).abs();
            let jamb = if along < 0.0 {
                -along
            } else if along > len {
                along - len
            } else {
                0.0
            };
            (i, off, jamb)
        })
        .min_by(|x, y| x.1.hypot(x.2).total_cmp(&y.1.hypot(y.2)))
}

/// The door a barcode marks is beside it: on a door's line (within
/// [`BARCODE_LINE_MAX`]), 0.1 to [`BARCODE_JAMB_MAX`] m from its nearer jamb
/// (`docs/maps.md`, "Lab door" and "Goal floor"). The robot, lined up with
/// the barcode, looks for its door there.
pub(super) fn door_beside(map: &Map, f: &Floor, id: i64, out: &mut Vec<Diagnostic>) {
    let Some((el, b)) = floor_barcode(f, id) else { return };
    let Some((i, off, jamb)) = nearest_door(f, b.at) else {
        out.push(finding(b.line, el, format!("barcode {id} marks a door, but there is no door on floor {}", f.level)));
        return;
    };
    let mut wrong = Vec::new();
    // Off its wall: stand_offs says how far (once is enough).
    let on_wall = matches!(stuck(&b, &map.static_segments(f)), Stuck::Ok);
    if off > BARCODE_LINE_MAX + SLACK && on_wall {
        wrong.push(format!("{off:.2} m off the door's line (its wall): at most {BARCODE_LINE_MAX:.2} m"));
    }
    if !(0.1 - SLACK..=BARCODE_JAMB_MAX + SLACK).contains(&jamb) {
        wrong.push(format!("{jamb:.2} m from the door's nearer jamb along its wall: 0.10 to {BARCODE_JAMB_MAX:.2} m"));
    }
    if !wrong.is_empty() {
        let d = &f.doors[i];
        out.push(finding(
            b.line,
            el,
            format!(
                "barcode {id} marks door {} (the nearest), but is {}",
                match d.name.as_str() {
                    "" => format!("{}", i + 1),
                    name => format!("{} ({name})", i + 1),
                },
                wrong.join(", and ")
            ),
        ));
    }
}

/// The office's barcode faces the corridor: out of the office.
pub(super) fn office_barcode_faces_out(f: &Floor, id: i64, out: &mut Vec<Diagnostic>) {
    let (Some(o), Some((el, b))) = (&f.office, floor_barcode(f, id)) else { return };
    let Some(facing) = b.facing else { return };
    if in_polygon(b.at.plus(P2::dir(facing).scale(0.3)), &o.polygon) {
        out.push(finding(
            b.line,
            el,
            format!("barcode {id} faces into the office: the office's barcode faces the corridor, out of the office"),
        ));
    }
}

/// Where a barcode with a facing is, against the walls around it.
pub(super) enum Stuck {
    /// 1–2 cm in front of a wall.
    Ok,
    /// It faces the wall it is on: the wall is this far ahead of it.
    FacesWall(f64),
    /// The wall behind it is this far.
    Far(f64),
    /// No wall behind it within 1 m.
    NoWall,
}

pub(super) fn stuck(b: &Barcode, segs: &[Seg]) -> Stuck {
    let Some(facing) = b.facing else { return Stuck::Ok };
    let behind = cast(b.at, P2::dir(facing + std::f64::consts::PI), segs);
    let ahead = cast(b.at, P2::dir(facing), segs);
    match (behind, ahead) {
        (Some(d), _) if d <= STICK_MAX + STICK_SLACK => Stuck::Ok,
        (_, Some(a)) if a <= 0.1 => Stuck::FacesWall(a),
        (Some(d), _) if d <= 1.0 => Stuck::Far(d),
        _ => Stuck::NoWall,
    }
}

/// `facing_deg` turned round, for a message.
fn turned_round(facing: f64) -> f64 {
    let d = (facing.to_degrees() + 180.0).rem_euclid(360.0);
    let d = if d > 180.0 { d - 360.0 } else { d };
    (d * 10.0).round() / 10.0 + 0.0
}

/// Barcodes with a facing are stuck 1–2 cm off their wall, on the side they
/// face (`docs/maps.md`, "Elements"); the call button is on a wall, facing
/// into the lobby. Returns whether this floor's call button faces the wall it
/// is on (what is checked from in front of it is then skipped).
pub(super) fn stand_offs(map: &Map, f: &Floor, out: &mut Vec<Diagnostic>) -> bool {
    let segs = map.static_segments(f);
    let rule = format!("barcodes are stuck 0.01 to {STICK_MAX:.2} m off their wall, on the side they face");
    let mut barcodes: Vec<(String, Barcode)> = Vec::new();
    for (i, d) in f.doors.iter().enumerate() {
        if let Some(b) = &d.barcode {
            barcodes.push((format!("{}, barcode", door_el(f, i, &d.name)), b.clone()));
        }
    }
    for (i, b) in f.barcodes.iter().enumerate() {
        barcodes.push((format!("floor {}, barcode {}", f.level, i + 1), b.clone()));
    }
    if let Some(o) = &f.office {
        barcodes.push((format!("floor {}, office, barcode", f.level), o.barcode.clone()));
    }
    for (el, b) in barcodes {
        let id = b.id;
        let message = match stuck(&b, &segs) {
            Stuck::Ok => continue,
            Stuck::FacesWall(a) => format!(
                "barcode {id} faces the wall it is on ({a:.2} m ahead of it): it cannot be read; turn it round \
                 (facing_deg: {})",
                turned_round(b.facing.unwrap_or(0.0))
            ),
            Stuck::Far(d) => format!("barcode {id} is {d:.2} m in front of the wall behind it: {rule}"),
            Stuck::NoWall => format!("barcode {id} has no wall behind it within 1 m: {rule}"),
        };
        out.push(finding(b.line, el, message));
    }
    let Some(l) = &f.lobby else { return false };
    let b = Barcode { id: l.barcode, at: l.button, facing: Some(l.facing), line: l.line };
    let el = format!("floor {}, lobby", f.level);
    let (message, faces) = match stuck(&b, &segs) {
        Stuck::Ok => return false,
        Stuck::FacesWall(a) => (
            format!(
                "the call button (barcode {}) faces the wall it is on ({a:.2} m ahead of it): it must face into the \
                 lobby (facing_deg: {}); what the robot does in front of it is not checked until it does",
                l.barcode,
                turned_round(l.facing)
            ),
            true,
        ),
        Stuck::Far(d) => (
            format!(
                "the call button (barcode {}) is {d:.2} m in front of the wall behind it: it is on a wall (at most \
                 {STICK_MAX:.2} m off it), facing into the lobby",
                l.barcode
            ),
            false,
        ),
        Stuck::NoWall => (
            format!(
                "the call button (barcode {}) has no wall behind it within 1 m: it is on a wall, facing into the lobby",
                l.barcode
            ),
            false,
        ),
    };
    out.push(finding(l.line, el, message));
    faces
}

/// Every floor door wide enough for the robot.
pub(super) fn doors(map: &Map, out: &mut Vec<Diagnostic>) {
    let need = 2.0 * map.robot_radius + DOOR_SPARE;
    for f in &map.floors {
        for (i, d) in f.doors.iter().enumerate() {
            let w = d.seg.len();
            if w < need - 1e-9 {
                out.push(finding(
                    d.line,
                    door_el(f, i, &d.name),
                    format!("{w:.2} m wide: the robot needs {need:.2} m (its diameter + {DOOR_SPARE} m)"),
                ));
            } else if !(DOOR_MIN - SLACK..=DOOR_MAX + SLACK).contains(&w) {
                let why = if w > DOOR_MAX {
                    format!(
                        " (from {DOOR_MAX} to {CORRIDOR_MIN} m the junction detector cannot tell a door from a side \
                         corridor)"
                    )
                } else {
                    String::new()
                };
                out.push(finding(
                    d.line,
                    door_el(f, i, &d.name),
                    format!("{w:.2} m wide: doors are {DOOR_MIN:.1} to {DOOR_MAX:.1} m wide{why}"),
                ));
            }
        }
    }
}

pub(super) fn door_el(f: &Floor, i: usize, name: &str) -> String {
    if name.is_empty() {
        format!("floor {}, door {}", f.level, i + 1)
    } else {
        format!("floor {}, door {} ({name})", f.level, i + 1)
    }
}

/// A barcode of this floor (doors', free ones, the lobby's, the office's)
/// with the element it belongs to.
pub(super) fn floor_barcode(f: &Floor, id: i64) -> Option<(String, Barcode)> {
    for (i, d) in f.doors.iter().enumerate() {
        if let Some(b) = d.barcode.as_ref().filter(|b| b.id == id) {
            return Some((format!("{}, barcode", door_el(f, i, &d.name)), b.clone()));
        }
    }
    if let Some((i, b)) = f.barcodes.iter().enumerate().find(|(_, b)| b.id == id) {
        return Some((format!("floor {}, barcode {}", f.level, i + 1), b.clone()));
    }
    if let Some(o) = f.office.as_ref().filter(|o| o.barcode.id == id) {
        return Some((format!("floor {}, office, barcode", f.level), o.barcode.clone()));
    }
    if let Some(l) = f.lobby.as_ref().filter(|l| l.barcode == id) {
        return Some((
            format!("floor {}, lobby", f.level),
            Barcode { id, at: l.button, facing: Some(l.facing), line: l.line },
        ));
    }
    None
}
