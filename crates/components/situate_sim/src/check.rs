//! Mission feasibility of a loaded map (`situate map check`): can the robot
//! of the delivery do what the sequencer will ask of it in this building?
//!
//! The loader ([`crate::load_map`]) already refuses maps that make no sense;
//! [`lint`] looks further, with the robot's size and sensors (the rules are
//! listed in `docs/maps.md`, "Rules every building must meet"):
//!
//! - reachability, by a flood fill on a grid of [`CELL`] cells whose centres
//!   are at least the robot's radius + [`MARGIN`] from every wall, obstacle,
//!   shaft wall and closed car door: from the start pose to the start floor's
//!   call button, and from the goal floor's call button to the office;
//! - the lab door's and the office's barcodes readable (range, facing, line of
//!   sight) from some cell the robot reaches, and the goal floor's call button
//!   from in front of every car;
//! - every car boardable and every door wide enough;
//! - the lab door's and the office door's barcodes beside their doors (0.1 to
//!   0.6 m from the nearer jamb), and no opening but cars' doors in the call
//!   button's wall: what the robot relies on to find a door and to board;
//! - route steps naming barcodes that exist on the leg's floor, and a turn
//!   naming the door's side between a `home` and a `pass: door`;
//! - the start pose in the lab; `open_s` at least [`OPEN_S_MIN`]; shafts'
//!   sizes; barcodes 1–2 cm off the wall behind them (a call button or barcode
//!   facing its own wall is named, and what follows from it is not reported);
//! - the geometry of corridors, from straight lines of walls: floor doors
//!   [`DOOR_MIN`] to [`DOOR_MAX`] wide, no other opening from [`DOOR_MAX`] to
//!   [`CORRIDOR_MIN`], parallel walls the robot passes between at least
//!   [`CORRIDOR_MIN`] apart, clutter leaving [`CLUTTER_FREE`] free, openings
//!   on one wall [`OPENINGS_APART`] apart.
//!
//! Every finding names the element and the map line it is on, and its
//! message the value found and the rule's limit.

use crate::geom::Seg;
use crate::map::Map;

mod barcodes;
mod corridors;
mod finding;
mod lobby;
mod reach;
mod routes;
mod start;

use barcodes::{door_beside, doors, office_barcode_faces_out, stand_offs};
use corridors::{openings, widths};
use lobby::{button_wall, elevator_timing, goal_checks};
use reach::floor_reach;
use routes::{route, turns_before_pass};
use start::{start_checks, start_in_lab};

use finding::finding;
pub use reach::readable_from;
pub use situate_robotfile::diagnostic::Diagnostic;

/// Grid cell of the reachability flood fill, m.
pub const CELL: f64 = 0.05;
/// Clearance the robot keeps beyond its radius, m.
pub const MARGIN: f64 = 0.05;
/// The barcode reader's range, m (from the robot's centre).
pub const READ_RANGE: f64 = 5.0;
/// A barcode is readable from within this angle of its facing, degrees.
pub const READ_FACING_DEG: f64 = 80.0;
/// Extra width a door (or car door) needs beyond the robot's diameter, m.
pub const DOOR_SPARE: f64 = 0.3;
/// Where the robot stands to press a call button: this far in front of it, m.
pub const PRESS_STANDOFF: f64 = 0.4;
/// Where the robot stands when it has just left a car: this far in front of
/// the car's door, m.
pub const CAR_APRON: f64 = 1.0;
/// A door's barcode (the lab door's, the office's) is this far from the door's
/// nearer jamb at most, m: the robot takes an opening farther off for another way.
pub const BARCODE_JAMB_MAX: f64 = 0.6;
/// A door's barcode is this far from the door's line at most, m.
pub const BARCODE_LINE_MAX: f64 = 0.1;
/// Barcodes are stuck this far off their wall at most, m (1–2 cm).
pub const STICK_MAX: f64 = 0.02;
/// Doors (the floors', not the cars') are this wide at least, m.
pub const DOOR_MIN: f64 = 1.0;
/// … and at most, m: from here to [`CORRIDOR_MIN`] the junction detector
/// cannot tell a door from a side corridor.
pub const DOOR_MAX: f64 = 1.4;
/// Corridors and side corridors (junctions) are this wide at least, m.
pub const CORRIDOR_MIN: f64 = 1.8;
/// … and at most, m: a space between parallel walls this far apart or less
/// is a corridor (for the clutter rule).
pub const CORRIDOR_MAX: f64 = 2.6;
/// Clutter in a corridor leaves this much free across it, m.
pub const CLUTTER_FREE: f64 = 1.2;
/// Two openings on one side of a corridor are this far apart at least, m.
pub const OPENINGS_APART: f64 = 0.8;
/// Elevator shafts are this long on each side at least, m …
pub const SHAFT_MIN: f64 = 1.8;
/// … and at most, m.
pub const SHAFT_MAX: f64 = 2.4;
/// The elevator's doors stay open this long at least, s (`open_s`'s minimum).
pub const OPEN_S_MIN: f64 = 8.0;
/// Slack on the rules' distances for coordinates written to the centimetre, m.
const SLACK: f64 = 0.02;
/// Slack on a barcode's distance from its wall, m.
const STICK_SLACK: f64 = 0.005;
/// Gaps along a wall line narrower than this are openings in that wall
/// (wider ones: the wall ends there), m.
const GAP_MAX: f64 = 3.0;
/// Gaps narrower than this are not openings the robot or its sonar use, m.
const GAP_MIN: f64 = 0.6;
/// Parallel walls overlapping less than this do not make a corridor, m.
const OVERLAP_MIN: f64 = 1.0;

/// Every feasibility problem of the map's mission, in a stable order.
pub fn lint(map: &Map) -> Vec<Diagnostic> {
    let mut out = Vec::new();
    let r = map.robot_radius;
    elevator_timing(map, &mut out);
    doors(map, &mut out);
    for (k, c) in map.elevator.cars.iter().enumerate() {
        let el = format!("elevator, car {}", k + 1);
        if c.door_width < 2.0 * r + DOOR_SPARE - 1e-9 {
            out.push(finding(
                c.line,
                &el,
                format!(
                    "door {:.2} m wide: the robot ({:.2} m) needs {:.2} m to board",
                    c.door_width,
                    2.0 * r,
                    2.0 * r + DOOR_SPARE
                ),
            ));
        }
        let inner = (c.x1 - c.x0).min(c.y1 - c.y0);
        if inner < 2.0 * (r + MARGIN) {
            out.push(finding(
                c.line,
                &el,
                format!("interior {inner:.2} m across: the robot needs {:.2} m", 2.0 * (r + MARGIN)),
            ));
        }
        let (w, h) = (c.x1 - c.x0, c.y1 - c.y0);
        if [w, h].iter().any(|s| !(SHAFT_MIN - SLACK..=SHAFT_MAX + SLACK).contains(s)) {
            out.push(finding(
                c.line,
                &el,
                format!("shaft {w:.2} × {h:.2} m: shafts are {SHAFT_MIN} to {SHAFT_MAX} m on each side"),
            ));
        }
    }
    // Barcodes stuck on their walls; a call button facing its own wall is named first,
    // and what depends on standing in front of it is not checked on that floor.
    let mut button_faces_wall = Vec::new();
    for f in &map.floors {
        if stand_offs(map, f, &mut out) {
            button_faces_wall.push(f.level);
        }
    }
    let m = &map.mission;
    let line = |key: &str| m.lines.get(key).copied().unwrap_or(1);
    let start_floor = map.floor(m.start_floor);
    let goal_floor = map.floor(m.goal_floor);
    if let Some(f) = start_floor {
        start_checks(map, f, &mut out, line("start"), button_faces_wall.contains(&f.level));
        door_beside(map, f, m.lab_door_barcode, &mut out);
        start_in_lab(map, f, &mut out, line("start"));
    }
    if let Some(f) = goal_floor {
        if !button_faces_wall.contains(&f.level) {
            goal_checks(map, f, &mut out, line("goal_floor"));
        }
        // An office with a door (one on its outline): its barcode marks it.
        let office_door = f.office.as_ref().is_some_and(|o| {
            let outline: Vec<Seg> =
                o.polygon.iter().zip(o.polygon.iter().cycle().skip(1)).map(|(a, b)| Seg::new(*a, *b)).collect();
            f.doors.iter().any(|d| outline.iter().any(|e| e.dist_to(d.seg.at(0.5)) <= 0.1))
        });
        if office_door {
            door_beside(map, f, m.office_barcode, &mut out);
            office_barcode_faces_out(f, m.office_barcode, &mut out);
        }
    }
    for f in &map.floors {
        button_wall(map, f, &mut out);
    }
    for f in &map.floors {
        // What the robot does not reach is no corridor of its.
        let Some((grid, reach)) = floor_reach(map, f) else { continue };
        let flagged = openings(map, f, &grid, &reach, &mut out);
        widths(map, f, &grid, &reach, &flagged, &mut out);
    }
    route(map, &mut out);
    turns_before_pass(map, &mut out);
    out
}

#[cfg(test)]
mod tests;
