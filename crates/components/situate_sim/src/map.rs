//! Building maps: the YAML format (see `docs/maps.md`), its checks, and the
//! world view the GUI draws.
//!
//! Every error is a [`Diagnostic`](situate_robotfile::diagnostic::Diagnostic) naming the file, the line and the
//! element, e.g. `maps/x.yaml:12: error: floor 4, wall 3: segment has zero
//! length`.

use std::collections::BTreeMap;

use crate::geom::{Seg, P2};

mod json;
mod query;
mod read;
mod validate;

pub use read::{load_map, MAX_MAP_FILE_BYTES};

/// A side of an elevator car's rectangle.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Side {
    North,
    South,
    East,
    West,
}

/// A barcode: an id at a point, readable from the side it faces.
#[derive(Debug, Clone, PartialEq)]
pub struct Barcode {
    pub id: i64,
    pub at: P2,
    /// Direction the barcode faces (radians); `None`: readable from anywhere.
    pub facing: Option<f64>,
    /// The line of the map file it is given on (0: not from a file).
    pub line: usize,
}

/// A door: a gap in the walls, optionally marked by a barcode beside it.
#[derive(Debug, Clone, PartialEq)]
pub struct Door {
    pub seg: Seg,
    pub barcode: Option<Barcode>,
    /// The door's name (may be empty).
    pub name: String,
    /// The line of the map file it is given on (0: not from a file).
    pub line: usize,
}

/// A floor's elevator lobby: the call button and its barcode.
#[derive(Debug, Clone, PartialEq)]
pub struct Lobby {
    pub line: usize,
    pub button: P2,
    /// Direction the button faces (radians).
    pub facing: f64,
    pub barcode: i64,
}

/// The goal office: a region marked by a barcode.
#[derive(Debug, Clone, PartialEq)]
pub struct Office {
    pub polygon: Vec<P2>,
    pub barcode: Barcode,
    /// The line of the map file it is given on (0: not from a file).
    pub line: usize,
}

/// One floor of the building.
#[derive(Debug, Clone, PartialEq)]
pub struct Floor {
    /// The line of the map file the floor starts on (0: not from a file).
    pub line: usize,
    pub level: i64,
    pub name: String,
    pub walls: Vec<Seg>,
    /// For each of `walls`, the wall element it comes from (1-based, as
    /// written: a polyline is one element) and that element's line (0: not
    /// from a file).
    pub wall_refs: Vec<(usize, usize)>,
    /// Furniture and other obstacles, as closed polygons.
    pub obstacles: Vec<Vec<P2>>,
    /// The line of each of `obstacles` (0: not from a file).
    pub obstacle_lines: Vec<usize>,
    pub doors: Vec<Door>,
    pub barcodes: Vec<Barcode>,
    pub lobby: Option<Lobby>,
    pub office: Option<Office>,
}

/// An elevator car: its shaft rectangle (the same on every floor), door and
/// identifying barcode on the back wall, under the floor-button panel.
#[derive(Debug, Clone, PartialEq)]
pub struct Car {
    pub line: usize,
    pub id: i64,
    pub x0: f64,
    pub y0: f64,
    pub x1: f64,
    pub y1: f64,
    pub door_side: Side,
    pub door_width: f64,
    pub barcode: i64,
}

/// The elevator bank.
#[derive(Debug, Clone, PartialEq)]
pub struct Elevator {
    /// Travel time per floor, s.
    pub travel_s_per_floor: f64,
    /// Time for the doors to open or close, s.
    pub door_move_s: f64,
    /// How long doors stay open, s: uniform in this range.
    pub open_s: (f64, f64),
    /// Delay from a call to a car's arrival, s: uniform in this range.
    pub arrive_s: (f64, f64),
    pub cars: Vec<Car>,
    /// Lines of the elevator's keys (for findings; empty: not from a file).
    pub lines: BTreeMap<String, usize>,
}

/// One step of a route hint: what a sequencer should do next.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct RouteStep {
    /// `hallway` (follow the corridor).
    pub follow: Option<String>,
    /// When to stop following: `junction`, `door`, `barcode`, `wall` or
    /// `distance`.
    pub until: Option<String>,
    /// With `until: junction` or `door`: stop at the N-th such opening on
    /// `side` (or either side) since the step started (default 1).
    pub count: Option<i64>,
    /// With `until: distance`: how far to follow the corridor, m (> 0).
    pub distance: Option<f64>,
    /// Which side the door or junction must be on: `left` or `right`.
    pub side: Option<String>,
    /// Turn to make (after `until`, or alone): `left`, `right` or `back`.
    pub turn: Option<String>,
    /// The barcode that ends the step (`until: barcode`).
    pub barcode: Option<i64>,
    /// Home on this barcode.
    pub home: Option<i64>,
    /// Pass the door ahead (`door`).
    pub pass: Option<String>,
    /// The line of the map file the step is on (0: not from a file).
    pub line: usize,
}

/// What the robot's operator would tell the sequencer.
#[derive(Debug, Clone, PartialEq)]
pub struct Mission {
    pub start_floor: i64,
    pub start: (f64, f64, f64),
    pub goal_floor: i64,
    pub lab_door_barcode: i64,
    pub call_button_barcode: i64,
    pub office_barcode: i64,
    /// Barcode id of car 1; car k has `car_barcode_first + k - 1`.
    pub car_barcode_first: i64,
    pub message: String,
    /// Named legs of the route, in file order.
    pub route: Vec<(String, Vec<RouteStep>)>,
    /// Lines of the mission's keys (for errors).
    pub lines: BTreeMap<String, usize>,
}

/// A building: floors, elevator, mission.
#[derive(Debug, Clone, PartialEq)]
pub struct Map {
    /// The file it was read from (as given).
    pub file: String,
    pub name: String,
    pub robot_radius: f64,
    pub floors: Vec<Floor>,
    pub elevator: Elevator,
    pub mission: Mission,
}
