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

use std::collections::{HashMap, HashSet};

use serde_json::{json, Value as Json};

use crate::geom::{cast, in_polygon, Seg, P2};
use crate::map::{Barcode, Car, Floor, Map, Side};

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

/// One problem found: the element, its line in the map file and what is wrong.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Finding {
    /// The map line of the element (1 when it concerns the whole map).
    pub line: usize,
    /// The element, named as the loader names it (`floor 4, door 2`).
    pub element: String,
    pub message: String,
}

impl Finding {
    fn new(line: usize, element: impl Into<String>, message: impl Into<String>) -> Finding {
        Finding { line: line.max(1), element: element.into(), message: message.into() }
    }

    /// `FILE:LINE: ELEMENT: MESSAGE`, as the loader's errors.
    pub fn render(&self, file: &str) -> String {
        format!("{file}:{}: {}: {}", self.line, self.element, self.message)
    }

    /// `{"line": …, "element": …, "message": …}`.
    pub fn to_json(&self) -> Json {
        json!({"line": self.line, "element": self.element, "message": self.message})
    }
}

/// Every feasibility problem of the map's mission, in a stable order.
pub fn lint(map: &Map) -> Vec<Finding> {
    let mut out = Vec::new();
    let r = map.robot_radius;
    elevator_timing(map, &mut out);
    doors(map, &mut out);
    for (k, c) in map.elevator.cars.iter().enumerate() {
        let el = format!("elevator, car {}", k + 1);
        if c.door_width < 2.0 * r + DOOR_SPARE - 1e-9 {
            out.push(Finding::new(
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
            out.push(Finding::new(
                c.line,
                &el,
                format!("interior {inner:.2} m across: the robot needs {:.2} m", 2.0 * (r + MARGIN)),
            ));
        }
        let (w, h) = (c.x1 - c.x0, c.y1 - c.y0);
        if [w, h].iter().any(|s| !(SHAFT_MIN - SLACK..=SHAFT_MAX + SLACK).contains(s)) {
            out.push(Finding::new(
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

/// The doors stay open long enough to board (`docs/maps.md`, "Elevator").
fn elevator_timing(map: &Map, out: &mut Vec<Finding>) {
    let (lo, hi) = map.elevator.open_s;
    if lo < OPEN_S_MIN - 1e-9 {
        out.push(Finding::new(
            map.elevator.lines.get("open_s").copied().unwrap_or(1),
            "elevator",
            format!(
                "open_s [{lo}, {hi}]: the doors must stay open at least {OPEN_S_MIN} s for the robot to board (the \
                 shortest documented range is [8, 12])"
            ),
        ));
    }
}

/// The door nearest a barcode: its index, how far the barcode is off the
/// door's line and from its nearer jamb along it.
fn nearest_door(f: &Floor, at: P2) -> Option<(usize, f64, f64)> {
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
fn door_beside(map: &Map, f: &Floor, id: i64, out: &mut Vec<Finding>) {
    let Some((el, b)) = floor_barcode(f, id) else { return };
    let Some((i, off, jamb)) = nearest_door(f, b.at) else {
        out.push(Finding::new(
            b.line,
            el,
            format!("barcode {id} marks a door, but there is no door on floor {}", f.level),
        ));
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
        out.push(Finding::new(
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
fn office_barcode_faces_out(f: &Floor, id: i64, out: &mut Vec<Finding>) {
    let (Some(o), Some((el, b))) = (&f.office, floor_barcode(f, id)) else { return };
    let Some(facing) = b.facing else { return };
    if in_polygon(b.at.plus(P2::dir(facing).scale(0.3)), &o.polygon) {
        out.push(Finding::new(
            b.line,
            el,
            format!("barcode {id} faces into the office: the office's barcode faces the corridor, out of the office"),
        ));
    }
}

/// Where a barcode with a facing is, against the walls around it.
enum Stuck {
    /// 1–2 cm in front of a wall.
    Ok,
    /// It faces the wall it is on: the wall is this far ahead of it.
    FacesWall(f64),
    /// The wall behind it is this far.
    Far(f64),
    /// No wall behind it within 1 m.
    NoWall,
}

fn stuck(b: &Barcode, segs: &[Seg]) -> Stuck {
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
fn stand_offs(map: &Map, f: &Floor, out: &mut Vec<Finding>) -> bool {
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
        out.push(Finding::new(b.line, el, message));
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
    out.push(Finding::new(l.line, el, message));
    faces
}

/// The start pose is in the lab (`docs/maps.md`, "Start"): on the side of the
/// lab door its barcode faces, with that door closed.
fn start_in_lab(map: &Map, f: &Floor, out: &mut Vec<Finding>, start_line: usize) {
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
        out.push(Finding::new(
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

/// The call button's wall has no openings but cars' doors (`docs/maps.md`,
/// "Lobby"): the robot takes a way that opens there for a car's door. Along
/// the button's wall, walls one after another with gaps between them: a gap
/// not filled by a car's shaft is an opening.
fn button_wall(map: &Map, f: &Floor, out: &mut Vec<Finding>) {
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
        out.push(Finding::new(
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

/// Indices of boxes (a segment's, a polygon's) bucketed on a square grid, to
/// look only at those near a place: the corridor rules compare walls with
/// the walls near them, so a floor of many walls costs in proportion.
struct Buckets {
    cell: f64,
    count: usize,
    cells: HashMap<(i64, i64), Vec<usize>>,
    /// Boxes spanning more than [`Buckets::SPAN_MAX`] cells a side: near everything.
    big: Vec<usize>,
}

impl Buckets {
    const SPAN_MAX: f64 = 64.0;

    fn new(cell: f64, boxes: &[(P2, P2)]) -> Buckets {
        let mut b = Buckets { cell, count: boxes.len(), cells: HashMap::new(), big: Vec::new() };
        for (i, (lo, hi)) in boxes.iter().enumerate() {
            match b.span(*lo, *hi) {
                Some((x0, y0, x1, y1)) => {
                    for x in x0..=x1 {
                        for y in y0..=y1 {
                            b.cells.entry((x, y)).or_default().push(i);
                        }
                    }
                }
                None => b.big.push(i),
            }
        }
        b
    }

    fn of_segs(cell: f64, segs: &[Seg]) -> Buckets {
        let boxes: Vec<(P2, P2)> = segs.iter().map(|s| seg_box(s, 0.0)).collect();
        Buckets::new(cell, &boxes)
    }

    /// The cells a box covers, if not too many.
    fn span(&self, lo: P2, hi: P2) -> Option<(i64, i64, i64, i64)> {
        let c = |v: f64| (v / self.cell).floor();
        let (x0, y0, x1, y1) = (c(lo.x), c(lo.y), c(hi.x), c(hi.y));
        let ok = [x0, y0, x1, y1].iter().all(|v| v.is_finite())
            && x1 - x0 <= Buckets::SPAN_MAX
            && y1 - y0 <= Buckets::SPAN_MAX;
        ok.then_some((x0 as i64, y0 as i64, x1 as i64, y1 as i64))
    }

    /// The boxes that may meet the box `lo`..`hi`, in increasing order.
    fn near(&self, lo: P2, hi: P2) -> Vec<usize> {
        let Some((x0, y0, x1, y1)) = self.span(lo, hi) else { return (0..self.count).collect() };
        let mut out = self.big.clone();
        for x in x0..=x1 {
            for y in y0..=y1 {
                if let Some(v) = self.cells.get(&(x, y)) {
                    out.extend_from_slice(v);
                }
            }
        }
        out.sort_unstable();
        out.dedup();
        out
    }
}

/// A segment's bounding box, grown by `r`.
fn seg_box(s: &Seg, r: f64) -> (P2, P2) {
    (P2::new(s.a.x.min(s.b.x) - r, s.a.y.min(s.b.y) - r), P2::new(s.a.x.max(s.b.x) + r, s.a.y.max(s.b.y) + r))
}

/// The sides of the cars' shafts (whole: a car's door is no opening in a wall line).
fn shaft_sides(map: &Map) -> Vec<(usize, Seg)> {
    let mut out = Vec::new();
    for (k, c) in map.elevator.cars.iter().enumerate() {
        let p = [P2::new(c.x0, c.y0), P2::new(c.x1, c.y0), P2::new(c.x1, c.y1), P2::new(c.x0, c.y1)];
        for i in 0..4 {
            out.push((k, Seg::new(p[i], p[(i + 1) % 4])));
        }
    }
    out
}

/// What stands at one end of a gap in a wall line: a wall (its index in
/// `floor.walls`) or a car's shaft (the car's index).
#[derive(Clone, Copy)]
enum End {
    Wall(usize),
    Shaft(usize),
}

fn end_name(f: &Floor, e: End) -> String {
    match e {
        End::Wall(j) => wall_name(f, j),
        End::Shaft(k) => format!("car {}'s shaft", k + 1),
    }
}

/// `wall K` for segment `j` of a floor's walls, `wall K, segment S` when
/// wall element K (a polyline) has more than one segment.
fn wall_name(f: &Floor, j: usize) -> String {
    let Some(&(k, _)) = f.wall_refs.get(j) else { return format!("wall {}", j + 1) };
    // Elements come in order: the element's segments are one run.
    let first = f.wall_refs.partition_point(|r| r.0 < k).min(j);
    let count = f.wall_refs.partition_point(|r| r.0 <= k).saturating_sub(first);
    if count > 1 {
        format!("wall {k}, segment {}", j - first + 1)
    } else {
        format!("wall {k}")
    }
}

/// Openings in straight walls (`docs/maps.md`, "Widths" and "Openings
/// apart"): along each line of walls (and shafts' sides), a gap under
/// [`GAP_MAX`] is an opening. One that is not a door is a side corridor: not
/// from [`DOOR_MAX`] to [`CORRIDOR_MIN`] m wide; and two openings have at
/// least [`OPENINGS_APART`] of wall between them. Returns the ends of the
/// openings found too narrow for a side corridor.
fn openings(map: &Map, f: &Floor, grid: &Grid, reach: &[bool], out: &mut Vec<Finding>) -> Vec<(P2, P2)> {
    let mut flagged = Vec::new();
    let shafts = shaft_sides(map);
    let shaft_segs: Vec<Seg> = shafts.iter().map(|(_, s)| *s).collect();
    let near_walls = Buckets::of_segs(GAP_MAX, &f.walls);
    let near_shafts = Buckets::of_segs(GAP_MAX, &shaft_segs);
    let door_segs: Vec<Seg> = f.doors.iter().map(|d| d.seg).collect();
    let near_doors = Buckets::of_segs(GAP_MAX, &door_segs);
    let mut done = vec![false; f.walls.len()];
    let wall_line = |j: usize| f.wall_refs.get(j).map_or(f.line, |r| r.1);
    for i in 0..f.walls.len() {
        if done[i] {
            continue;
        }
        let w = f.walls[i];
        let len = w.len();
        if len < 1e-9 {
            continue;
        }
        let u = w.b.minus(w.a).scale(1.0 / len);
        let n = P2::new(-u.y, u.x);
        let on = |s: &Seg| s.a.minus(w.a).dot(n).abs() <= 0.02 && s.b.minus(w.a).dot(n).abs() <= 0.02;
        let t = |p: P2| p.minus(w.a).dot(u);
        // The walls and shafts' sides on this line, each within GAP_MAX of another.
        let mut iv: Vec<(f64, f64, End)> = Vec::new();
        let mut todo = vec![w];
        let mut shafts_in: HashSet<usize> = HashSet::new();
        done[i] = true;
        iv.push((0.0, len, End::Wall(i)));
        while let Some(x) = todo.pop() {
            let (lo, hi) = seg_box(&x, GAP_MAX);
            for j in near_walls.near(lo, hi) {
                let s = f.walls[j];
                if !done[j] && on(&s) {
                    done[j] = true;
                    todo.push(s);
                    iv.push((t(s.a).min(t(s.b)), t(s.a).max(t(s.b)), End::Wall(j)));
                }
            }
            for j in near_shafts.near(lo, hi) {
                let (k, s) = shafts[j];
                if on(&s) && shafts_in.insert(j) {
                    todo.push(s);
                    iv.push((t(s.a).min(t(s.b)), t(s.a).max(t(s.b)), End::Shaft(k)));
                }
            }
        }
        iv.sort_by(|x, y| x.0.total_cmp(&y.0));
        // Runs of touching intervals: from, to, what is at each end, whether a wall is in it.
        let mut runs: Vec<(f64, f64, End, End, bool)> = Vec::new();
        for (a, b, e) in iv {
            let wall = matches!(e, End::Wall(_));
            match runs.last_mut() {
                Some(r) if a <= r.1 + SLACK => {
                    if b > r.1 {
                        r.1 = b;
                        r.3 = e;
                    }
                    r.4 |= wall;
                }
                _ => runs.push((a, b, e, e, wall)),
            }
        }
        let at = |x: f64| w.a.plus(u.scale(x));
        // Whether the robot passes by the line there (on either side).
        let by = |x: f64| {
            let k = map.robot_radius + MARGIN + 0.1;
            [1.0, -1.0].iter().any(|s| grid.reached_near(reach, at(x).plus(n.scale(s * k)), 0.1))
        };
        // Gaps between runs: openings (and whether each is a door).
        let gaps: Vec<(f64, f64, bool)> = runs
            .windows(2)
            .map(|r| {
                let (a, b) = (r[0].1, r[1].0);
                let (lo, hi) = seg_box(&Seg::new(at(a), at(b)), 0.1);
                let door = near_doors
                    .near(lo, hi)
                    .into_iter()
                    .map(|k| door_segs[k])
                    .any(|d| on(&d) && (a - 0.05..=b + 0.05).contains(&t(d.at(0.5))));
                (a, b, door)
            })
            .collect();
        for (k, &(a, b, door)) in gaps.iter().enumerate() {
            let g = b - a;
            if door || g <= DOOR_MAX + SLACK || g >= CORRIDOR_MIN - SLACK || !by((a + b) / 2.0) {
                continue;
            }
            let (left, right) = (runs[k].3, runs[k + 1].2);
            let (el_end, line) = match (left, right) {
                (End::Wall(j), _) | (_, End::Wall(j)) => (End::Wall(j), wall_line(j)),
                _ => continue, // between shafts: the lobby's business
            };
            let m = at((a + b) / 2.0);
            flagged.push((at(a), at(b)));
            out.push(Finding::new(
                line,
                format!("floor {}, {}", f.level, end_name(f, el_end)),
                format!(
                    "an opening {g:.2} m wide at ({:.2}, {:.2}) between {} and {}: a side opening is a door ({DOOR_MIN:.1} \
                     to {DOOR_MAX:.1} m) or a side corridor (at least {CORRIDOR_MIN:.1} m), nothing in between (the \
                     junction detector cannot tell which)",
                    m.x,
                    m.y,
                    end_name(f, left),
                    end_name(f, right)
                ),
            ));
        }
        for k in 1..runs.len().saturating_sub(1) {
            let (a, b, first, _, wall) = runs[k];
            let opening = |g: &(f64, f64, bool)| (GAP_MIN..GAP_MAX).contains(&(g.1 - g.0));
            if !wall
                || b - a >= OPENINGS_APART - SLACK
                || !opening(&gaps[k - 1])
                || !opening(&gaps[k])
                || !by((a + b) / 2.0)
            {
                continue;
            }
            let j = match first {
                End::Wall(j) => j,
                End::Shaft(_) => continue,
            };
            let (p, q) = (at((gaps[k - 1].0 + gaps[k - 1].1) / 2.0), at((gaps[k].0 + gaps[k].1) / 2.0));
            out.push(Finding::new(
                wall_line(j),
                format!("floor {}, {}", f.level, end_name(f, End::Wall(j))),
                format!(
                    "only {:.2} m of wall between the openings at ({:.2}, {:.2}) and ({:.2}, {:.2}): openings on one \
                     side of a corridor are at least {OPENINGS_APART} m apart (one hidden for less counts as one)",
                    b - a,
                    p.x,
                    p.y,
                    q.x,
                    q.y
                ),
            ));
        }
    }
    flagged
}

/// The cells the robot reaches on a floor: from the start on the start
/// floor, from in front of the call button on the others.
fn floor_reach(map: &Map, f: &Floor) -> Option<(Grid, Vec<bool>)> {
    let segs = blocking_segments(map, f);
    let grid = Grid::new(&segs, map.robot_radius + MARGIN);
    let from = if f.level == map.mission.start_floor {
        P2::new(map.mission.start.0, map.mission.start.1)
    } else {
        let l = f.lobby.as_ref()?;
        l.button.plus(P2::dir(l.facing).scale(PRESS_STANDOFF))
    };
    let seed = grid.free_near(from, CELL * 2.0)?;
    let reach = grid.flood(seed);
    Some((grid, reach))
}

/// Distance between two polygons (0 when they touch).
fn poly_dist(p: &[P2], q: &[P2]) -> f64 {
    let edges =
        |v: &[P2]| -> Vec<Seg> { v.iter().zip(v.iter().cycle().skip(1)).map(|(a, b)| Seg::new(*a, *b)).collect() };
    let (ep, eq) = (edges(p), edges(q));
    ep.iter().flat_map(|a| eq.iter().map(move |b| a.dist_to_seg(b))).fold(f64::INFINITY, f64::min)
}

/// Corridors' widths and their clutter (`docs/maps.md`, "Widths"): two
/// parallel walls facing each other over at least [`OVERLAP_MIN`], with
/// nothing between them and the robot reaching the space between, make a
/// corridor if they are at most [`CORRIDOR_MAX`] apart; it is at least
/// [`CORRIDOR_MIN`] wide, and obstacles in it leave [`CLUTTER_FREE`] free
/// across it. A side corridor whose mouth was found too narrow
/// (`flagged`) is not reported again.
fn widths(map: &Map, f: &Floor, grid: &Grid, reach: &[bool], flagged: &[(P2, P2)], out: &mut Vec<Finding>) {
    let mut walls: Vec<Seg> = f.walls.clone();
    walls.extend(map.elevator.cars.iter().flat_map(Car::walls));
    let reach_across = CORRIDOR_MAX + SLACK;
    let near_floor_walls = Buckets::of_segs(GAP_MAX, &f.walls);
    let near_walls = Buckets::of_segs(GAP_MAX, &walls);
    let obstacle_boxes: Vec<(P2, P2)> = f
        .obstacles
        .iter()
        .map(|o| {
            let lo = o.iter().fold(P2::new(f64::INFINITY, f64::INFINITY), |m, v| P2::new(m.x.min(v.x), m.y.min(v.y)));
            let hi = o
                .iter()
                .fold(P2::new(f64::NEG_INFINITY, f64::NEG_INFINITY), |m, v| P2::new(m.x.max(v.x), m.y.max(v.y)));
            (lo, hi)
        })
        .collect();
    let near_obstacles = Buckets::new(GAP_MAX, &obstacle_boxes);
    let flagged_segs: Vec<Seg> = flagged.iter().map(|(a, b)| Seg::new(*a, *b)).collect();
    let near_flagged = Buckets::of_segs(GAP_MAX, &flagged_segs);
    let wall_name = |j: usize| wall_name(f, j);
    let wall_line = |j: usize| f.wall_refs.get(j).map_or(f.line, |r| r.1);
    let obstacle_name = |k: usize| format!("floor {}, obstacle {}", f.level, k + 1);
    let obstacle_line = |k: usize| f.obstacle_lines.get(k).copied().unwrap_or(f.line);
    // Pairs of lines already reported (their direction and offsets, to the centimetre), obstacles
    // and pairs of obstacles reported.
    let mut narrow: HashSet<(i64, i64, i64)> = HashSet::new();
    let mut cluttered: HashSet<usize> = HashSet::new();
    let mut pairs: HashSet<(usize, usize)> = HashSet::new();
    let near = |p: P2, s: &Seg| p.dist(s.a) <= 0.05 || p.dist(s.b) <= 0.05;
    for i in 0..f.walls.len() {
        let wi = f.walls[i];
        let len = wi.len();
        if len < OVERLAP_MIN {
            continue;
        }
        let u = wi.b.minus(wi.a).scale(1.0 / len);
        let (qlo, qhi) = seg_box(&wi, reach_across);
        for j in near_floor_walls.near(qlo, qhi).into_iter().filter(|&j| j > i) {
            let wj = f.walls[j];
            let lj = wj.len();
            if lj < OVERLAP_MIN || u.cross(wj.b.minus(wj.a).scale(1.0 / lj)).abs() > 0.02 {
                continue;
            }
            let n0 = P2::new(-u.y, u.x);
            let off = wj.a.minus(wi.a).dot(n0);
            let n = n0.scale(off.signum());
            let d = off.abs();
            if d < 2.0 * (map.robot_radius + MARGIN) || d > CORRIDOR_MAX + SLACK {
                continue;
            }
            let t = |p: P2| p.minus(wi.a).dot(u);
            let (lo, hi) = (t(wj.a).min(t(wj.b)).max(0.0), t(wj.a).max(t(wj.b)).min(len));
            if hi - lo < OVERLAP_MIN {
                continue;
            }
            let p = wi.a.plus(u.scale((lo + hi) / 2.0));
            // Nothing between them: the first wall across is wj.
            let from = p.plus(n.scale(0.005));
            let (clo, chi) = seg_box(&Seg::new(from, p.plus(n.scale(d + 0.1))), 0.01);
            let across: Vec<Seg> = near_walls.near(clo, chi).into_iter().map(|k| walls[k]).collect();
            if cast(from, n, &across).is_none_or(|h| (h - (d - 0.005)).abs() > SLACK) {
                continue;
            }
            let centre = p.plus(n.scale(d / 2.0));
            if !grid.reached_near(reach, centre, d / 2.0) {
                continue;
            }
            if d < CORRIDOR_MIN - SLACK {
                let (mlo, mhi) = seg_box(&wi, 0.1);
                let mouth = near_flagged
                    .near(mlo, mhi)
                    .into_iter()
                    .map(|k| flagged[k])
                    .any(|(a, b)| (near(a, &wi) && near(b, &wj)) || (near(b, &wi) && near(a, &wj)));
                // The same two lines (walls split by doors) are reported once.
                let angle = u.y.atan2(u.x).rem_euclid(std::f64::consts::PI);
                let m = P2::new(-angle.sin(), angle.cos());
                let (ci, cj) = (m.dot(wi.a), m.dot(wj.a));
                let cm = |v: f64| (v * 100.0).round() as i64;
                let key = (cm(angle), cm(ci.min(cj)), cm(ci.max(cj)));
                if !mouth && narrow.insert(key) {
                    out.push(Finding::new(
                        wall_line(i),
                        format!("floor {}, {}", f.level, wall_name(i)),
                        format!(
                            "a way {d:.2} m wide between {} and {} (around ({:.2}, {:.2})): corridors and side \
                             corridors are at least {CORRIDOR_MIN:.1} m wide",
                            wall_name(i),
                            wall_name(j),
                            centre.x,
                            centre.y
                        ),
                    ));
                }
                continue;
            }
            // A corridor: the clutter in it (obstacles whose centre is between the walls, along the overlap).
            let strip = [wi.at(lo / len), wi.at(hi / len), wj.at(0.0), wj.at(1.0)];
            let slo =
                strip.iter().fold(P2::new(f64::INFINITY, f64::INFINITY), |m, v| P2::new(m.x.min(v.x), m.y.min(v.y)));
            let shi = strip
                .iter()
                .fold(P2::new(f64::NEG_INFINITY, f64::NEG_INFINITY), |m, v| P2::new(m.x.max(v.x), m.y.max(v.y)));
            let inside: Vec<(usize, f64)> = near_obstacles
                .near(slo, shi)
                .into_iter()
                .map(|k| (k, &f.obstacles[k]))
                .filter_map(|(k, o)| {
                    let c = o.iter().fold(P2::new(0.0, 0.0), |s, v| s.plus(*v)).scale(1.0 / o.len().max(1) as f64);
                    let across = c.minus(wi.a).dot(n);
                    ((lo..=hi).contains(&t(c)) && across > 0.0 && across < d).then_some((k, across))
                })
                .collect();
            for &(k, across) in &inside {
                let far = if across < d / 2.0 { (wj, j) } else { (wi, i) };
                let o = &f.obstacles[k];
                let edges: Vec<Seg> = o.iter().zip(o.iter().cycle().skip(1)).map(|(a, b)| Seg::new(*a, *b)).collect();
                let free = edges.iter().map(|e| e.dist_to_seg(&far.0)).fold(f64::INFINITY, f64::min);
                if free < CLUTTER_FREE - SLACK && cluttered.insert(k) {
                    out.push(Finding::new(
                        obstacle_line(k),
                        obstacle_name(k),
                        format!(
                            "it leaves {free:.2} m free across the corridor (to {}): clutter in a corridor leaves at \
                             least {CLUTTER_FREE:.1} m free",
                            wall_name(far.1)
                        ),
                    ));
                }
                for &(q, across_q) in &inside {
                    let facing_walls = (across < d / 2.0) != (across_q < d / 2.0);
                    if q <= k || !facing_walls || pairs.contains(&(k, q)) {
                        continue;
                    }
                    let between = poly_dist(o, &f.obstacles[q]);
                    if between < CLUTTER_FREE - SLACK {
                        pairs.insert((k, q));
                        out.push(Finding::new(
                            obstacle_line(q),
                            obstacle_name(q),
                            format!(
                                "it and obstacle {} (on the facing wall) leave {between:.2} m between them: clutter in \
                                 a corridor leaves at least {CLUTTER_FREE:.1} m free",
                                k + 1
                            ),
                        ));
                    }
                }
            }
        }
    }
}

/// The last turn before a `pass: door` names the side of the barcode homed
/// on that the door is on (`docs/maps.md`, "Route hints"): one is written
/// (`left` or `right`) between the `home` and the `pass`, and, where the
/// barcode marks a door, it is that door's side as the robot sees it,
/// squared up in front of the barcode.
fn turns_before_pass(map: &Map, out: &mut Vec<Finding>) {
    let m = &map.mission;
    for (leg, steps) in &m.route {
        let level = match leg.as_str() {
            "lab_to_lobby" => m.start_floor,
            "button_to_office" | "car_to_office" => m.goal_floor,
            _ => continue,
        };
        let Some(f) = map.floor(level) else { continue };
        // The last `home` so far, and the last `turn: left | right` since (the home's own included).
        let mut last_home: Option<usize> = None;
        let mut last_turn: Option<(usize, &str)> = None;
        for (p, st) in steps.iter().enumerate() {
            let side_turn = st.turn.as_deref().filter(|t| *t == "left" || *t == "right");
            let (h, turn) = (last_home, last_turn);
            if st.home.is_some() {
                (last_home, last_turn) = (Some(p), side_turn.map(|t| (p, t)));
            } else if let Some(t) = side_turn {
                last_turn = Some((p, t));
            }
            if st.pass.is_none() {
                continue;
            }
            let Some(h) = h else { continue };
            let id = steps[h].home.unwrap_or_default();
            let el = |i: usize| format!("mission, route {leg}, step {}", i + 1);
            let at =
                |i: usize| if steps[i].line > 0 { steps[i].line } else { m.lines.get("route").copied().unwrap_or(1) };
            let Some((ti, turn)) = turn else {
                out.push(Finding::new(
                    at(p),
                    el(p),
                    format!(
                        "`pass: door` after `home: {id}` (step {}) with no `turn: left` or `turn: right` between: the \
                         last turn names the side of the barcode the door is on",
                        h + 1
                    ),
                ));
                continue;
            };
            let Some((_, b)) = floor_barcode(f, id) else { continue };
            let Some(facing) = b.facing else { continue };
            let Some((i, off, jamb)) = nearest_door(f, b.at) else { continue };
            if off > BARCODE_LINE_MAX + SLACK || jamb > BARCODE_JAMB_MAX + SLACK {
                continue; // no door beside it: door_beside's finding, if it should have one
            }
            let d = &f.doors[i];
            let heading = P2::dir(facing + std::f64::consts::PI);
            let side = if heading.cross(d.seg.at(0.5).minus(b.at)) > 0.0 { "left" } else { "right" };
            if side != turn {
                out.push(Finding::new(
                    at(ti),
                    el(ti),
                    format!(
                        "`turn: {turn}` before `pass: door`, but {} is on the {side} of barcode {id} (the robot \
                         squared up in front of it): the last turn names the side the door is on",
                        door_el(f, i, &d.name)
                    ),
                ));
            }
        }
    }
}

/// Every floor door wide enough for the robot.
fn doors(map: &Map, out: &mut Vec<Finding>) {
    let need = 2.0 * map.robot_radius + DOOR_SPARE;
    for f in &map.floors {
        for (i, d) in f.doors.iter().enumerate() {
            let w = d.seg.len();
            if w < need - 1e-9 {
                out.push(Finding::new(
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
                out.push(Finding::new(
                    d.line,
                    door_el(f, i, &d.name),
                    format!("{w:.2} m wide: doors are {DOOR_MIN:.1} to {DOOR_MAX:.1} m wide{why}"),
                ));
            }
        }
    }
}

fn door_el(f: &Floor, i: usize, name: &str) -> String {
    if name.is_empty() {
        format!("floor {}, door {}", f.level, i + 1)
    } else {
        format!("floor {}, door {} ({name})", f.level, i + 1)
    }
}

fn start_checks(map: &Map, f: &Floor, out: &mut Vec<Finding>, start_line: usize, button_faces_wall: bool) {
    let m = &map.mission;
    let segs = blocking_segments(map, f);
    let grid = Grid::new(&segs, map.robot_radius + MARGIN);
    let start = P2::new(m.start.0, m.start.1);
    let reach = grid.flood(start);
    if !grid.is_free(start) {
        out.push(Finding::new(start_line, "mission, start", "the robot cannot stand at the start pose"));
        return;
    }
    match &f.lobby {
        None => out.push(Finding::new(f.line, format!("floor {}", f.level), "the start floor has no lobby")),
        Some(l) => {
            let press = l.button.plus(P2::dir(l.facing).scale(PRESS_STANDOFF));
            if !button_faces_wall && !grid.reached_near(&reach, press, CELL * 2.0) {
                out.push(Finding::new(
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
        None => out.push(Finding::new(
            m.lines.get("lab_door_barcode").copied().unwrap_or(1),
            "mission",
            format!("lab_door_barcode {id} is not on the start floor {}", f.level),
        )),
        Some((el, b)) => {
            // One facing its wall has its own finding (stand_offs).
            let faces_wall = matches!(stuck(&b, &map.static_segments(f)), Stuck::FacesWall(_));
            if !faces_wall && !readable_somewhere(&grid, &reach, &b, &segs) {
                out.push(Finding::new(
                    b.line,
                    el,
                    format!("barcode {id} cannot be read from anywhere the robot reaches (range, facing, sight)"),
                ));
            }
        }
    }
}

fn goal_checks(map: &Map, f: &Floor, out: &mut Vec<Finding>, goal_line: usize) {
    let m = &map.mission;
    let segs = blocking_segments(map, f);
    let grid = Grid::new(&segs, map.robot_radius + MARGIN);
    let Some(l) = &f.lobby else {
        out.push(Finding::new(goal_line, format!("floor {}", f.level), "the goal floor has no lobby"));
        return;
    };
    let lobby_el = format!("floor {}, lobby", f.level);
    let press = l.button.plus(P2::dir(l.facing).scale(PRESS_STANDOFF));
    let Some(from) = grid.free_near(press, CELL * 2.0) else {
        out.push(Finding::new(l.line, lobby_el, "the robot cannot stand in front of the goal floor's call button"));
        return;
    };
    let reach = grid.flood(from);
    cars_open_on(map, f, &grid, &reach, out);
    let button = Barcode { id: l.barcode, at: l.button, facing: Some(l.facing), line: l.line };
    for (k, c) in map.elevator.cars.iter().enumerate() {
        let apron = door_centre(c).plus(outward(c).scale(CAR_APRON));
        if !readable_from(&button, apron, &segs) {
            out.push(Finding::new(
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
        None => out.push(Finding::new(goal_line, "mission", format!("the goal floor {} has no office", f.level))),
        Some(o) => {
            let inside = reach.iter().enumerate().any(|(i, &r)| r && in_polygon(grid.centre(i), &o.polygon));
            if !inside {
                out.push(Finding::new(
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
            out.push(Finding::new(
                b.line,
                el,
                format!("barcode {id} cannot be read from anywhere the robot reaches (range, facing, sight)"),
            ));
        }
    }
}

/// Each car's door opens on floor the robot reaches (its apron is reached).
fn cars_open_on(map: &Map, f: &Floor, grid: &Grid, reach: &[bool], out: &mut Vec<Finding>) {
    for (k, c) in map.elevator.cars.iter().enumerate() {
        let apron = door_centre(c).plus(outward(c).scale(map.robot_radius + 0.35));
        if !grid.reached_near(reach, apron, CELL * 2.0) {
            out.push(Finding::new(
                c.line,
                format!("elevator, car {}", k + 1),
                format!("on floor {}, the car's door does not open on floor the robot reaches", f.level),
            ));
        }
    }
}

/// Route steps: the barcodes they name exist, on the leg's floor, and the
/// legs home on the barcodes their ends need.
fn route(map: &Map, out: &mut Vec<Finding>) {
    let m = &map.mission;
    let all = map.all_barcodes();
    for (leg, steps) in &m.route {
        let floor = match leg.as_str() {
            "lab_to_lobby" => Some(m.start_floor),
            "button_to_office" | "car_to_office" => Some(m.goal_floor),
            _ => None,
        };
        for (i, st) in steps.iter().enumerate() {
            let el = format!("mission, route {leg}, step {}", i + 1);
            let at = if st.line > 0 { st.line } else { m.lines.get("route").copied().unwrap_or(1) };
            for id in [st.barcode, st.home].into_iter().flatten() {
                match all.iter().find(|(_, b)| b.id == id) {
                    None => out.push(Finding::new(at, &el, format!("no barcode {id} in the map"))),
                    Some((Some(level), _)) if floor.is_some_and(|l| l != *level) => out.push(Finding::new(
                        at,
                        &el,
                        format!("barcode {id} is on floor {level}, not on this leg's floor {}", floor.unwrap_or(0)),
                    )),
                    _ => {}
                }
            }
        }
        let want = match leg.as_str() {
            "lab_to_lobby" => Some(("call_button_barcode", m.call_button_barcode)),
            "button_to_office" | "car_to_office" => Some(("office_barcode", m.office_barcode)),
            _ => None,
        };
        if let (Some((what, id)), Some((i, st))) =
            (want, steps.iter().enumerate().rev().find(|(_, s)| s.home.is_some()))
        {
            if st.home != Some(id) {
                out.push(Finding::new(
                    st.line,
                    format!("mission, route {leg}, step {}", i + 1),
                    format!("the leg's last `home` is {}, not the {what} {id}", st.home.unwrap_or(0)),
                ));
            }
        }
    }
}

/// A barcode of this floor (doors', free ones, the lobby's, the office's)
/// with the element it belongs to.
fn floor_barcode(f: &Floor, id: i64) -> Option<(String, Barcode)> {
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

/// What blocks the robot on a floor: walls, obstacles, shafts, closed car doors.
fn blocking_segments(map: &Map, f: &Floor) -> Vec<Seg> {
    let mut segs = map.static_segments(f);
    segs.extend(map.elevator.cars.iter().map(Car::door));
    segs
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

/// Whether the reader at `p` (turned towards it) reads `b`: range, facing, sight.
pub fn readable_from(b: &Barcode, p: P2, segs: &[Seg]) -> bool {
    let rel = b.at.minus(p);
    let d = rel.norm();
    if !(1e-9..=READ_RANGE).contains(&d) {
        return false;
    }
    if let Some(f) = b.facing {
        let limit = (90.0 - READ_FACING_DEG).to_radians().sin();
        if P2::dir(f).dot(rel.scale(-1.0 / d)) < limit {
            return false;
        }
    }
    !cast(p, rel.scale(1.0 / d), segs).is_some_and(|h| h < d - 0.01)
}

fn readable_somewhere(grid: &Grid, reach: &[bool], b: &Barcode, segs: &[Seg]) -> bool {
    let near: Vec<&Seg> = segs.iter().filter(|s| s.dist_to(b.at) <= READ_RANGE + 0.1).collect();
    let near: Vec<Seg> = near.into_iter().copied().collect();
    let (lo, hi) = grid.index_box(b.at, READ_RANGE);
    // Every other cell is plenty: the reader's range is 100 cells.
    for iy in (lo.1..hi.1).step_by(2) {
        for ix in (lo.0..hi.0).step_by(2) {
            let i = iy * grid.nx + ix;
            if reach[i] && readable_from(b, grid.centre(i), &near) {
                return true;
            }
        }
    }
    false
}

/// Cells whose centres the robot's centre may occupy.
struct Grid {
    x0: f64,
    y0: f64,
    nx: usize,
    ny: usize,
    free: Vec<bool>,
}

impl Grid {
    fn new(segs: &[Seg], clearance: f64) -> Grid {
        let (mut lo, mut hi) = (P2::new(f64::INFINITY, f64::INFINITY), P2::new(f64::NEG_INFINITY, f64::NEG_INFINITY));
        for s in segs {
            for p in [s.a, s.b] {
                lo = P2::new(lo.x.min(p.x), lo.y.min(p.y));
                hi = P2::new(hi.x.max(p.x), hi.y.max(p.y));
            }
        }
        if !lo.x.is_finite() {
            (lo, hi) = (P2::new(0.0, 0.0), P2::new(1.0, 1.0));
        }
        let x0 = lo.x - 1.0;
        let y0 = lo.y - 1.0;
        // Bounded: a map of a few hundred metres at most gives a few tens of millions of cells.
        let nx = (((hi.x - x0 + 1.0) / CELL).ceil() as usize).clamp(1, 8000);
        let ny = (((hi.y - y0 + 1.0) / CELL).ceil() as usize).clamp(1, 8000);
        let mut g = Grid { x0, y0, nx, ny, free: vec![true; nx * ny] };
        for s in segs {
            let a = P2::new(s.a.x.min(s.b.x) - clearance, s.a.y.min(s.b.y) - clearance);
            let b = P2::new(s.a.x.max(s.b.x) + clearance, s.a.y.max(s.b.y) + clearance);
            let (i0, j0) = g.clamp_index(a);
            let (i1, j1) = g.clamp_index(b);
            for j in j0..=j1 {
                for i in i0..=i1 {
                    let k = j * nx + i;
                    if g.free[k] && s.dist_to(g.centre(k)) < clearance {
                        g.free[k] = false;
                    }
                }
            }
        }
        g
    }

    fn clamp_index(&self, p: P2) -> (usize, usize) {
        let i = ((p.x - self.x0) / CELL).floor().clamp(0.0, (self.nx - 1) as f64) as usize;
        let j = ((p.y - self.y0) / CELL).floor().clamp(0.0, (self.ny - 1) as f64) as usize;
        (i, j)
    }

    fn index_box(&self, p: P2, r: f64) -> ((usize, usize), (usize, usize)) {
        let (i0, j0) = self.clamp_index(P2::new(p.x - r, p.y - r));
        let (i1, j1) = self.clamp_index(P2::new(p.x + r, p.y + r));
        ((i0, j0), (i1 + 1, j1 + 1))
    }

    fn index(&self, p: P2) -> Option<usize> {
        let fx = (p.x - self.x0) / CELL;
        let fy = (p.y - self.y0) / CELL;
        if !(fx >= 0.0 && fy >= 0.0) {
            return None;
        }
        let (i, j) = (fx.floor() as usize, fy.floor() as usize);
        (i < self.nx && j < self.ny).then_some(j * self.nx + i)
    }

    fn centre(&self, k: usize) -> P2 {
        let (i, j) = (k % self.nx, k / self.nx);
        P2::new(self.x0 + (i as f64 + 0.5) * CELL, self.y0 + (j as f64 + 0.5) * CELL)
    }

    fn is_free(&self, p: P2) -> bool {
        self.free_near(p, CELL * 1.5).is_some()
    }

    /// A free cell centre within `tol` of `p`.
    fn free_near(&self, p: P2, tol: f64) -> Option<P2> {
        let (lo, hi) = self.index_box(p, tol);
        (lo.1..hi.1)
            .flat_map(|j| (lo.0..hi.0).map(move |i| (i, j)))
            .map(|(i, j)| j * self.nx + i)
            .filter(|&k| self.free[k] && self.centre(k).dist(p) <= tol)
            .min_by(|&a, &b| self.centre(a).dist(p).total_cmp(&self.centre(b).dist(p)))
            .map(|k| self.centre(k))
    }

    fn reached_near(&self, reach: &[bool], p: P2, tol: f64) -> bool {
        let (lo, hi) = self.index_box(p, tol);
        (lo.1..hi.1)
            .flat_map(|j| (lo.0..hi.0).map(move |i| (i, j)))
            .map(|(i, j)| j * self.nx + i)
            .any(|k| reach[k] && self.centre(k).dist(p) <= tol)
    }

    /// The cells reached from the free cell nearest `from` (4-connected).
    fn flood(&self, from: P2) -> Vec<bool> {
        let mut reach = vec![false; self.free.len()];
        let Some(seed) = self.free_near(from, CELL * 1.5).and_then(|p| self.index(p)) else { return reach };
        let mut stack = vec![seed];
        reach[seed] = true;
        while let Some(k) = stack.pop() {
            let (i, j) = (k % self.nx, k / self.nx);
            let mut push = |n: usize| {
                if self.free[n] && !reach[n] {
                    reach[n] = true;
                    stack.push(n);
                }
            };
            if i > 0 {
                push(k - 1);
            }
            if i + 1 < self.nx {
                push(k + 1);
            }
            if j > 0 {
                push(k - self.nx);
            }
            if j + 1 < self.ny {
                push(k + self.nx);
            }
        }
        reach
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn maps_dir(name: &str) -> String {
        format!("{}/../../maps/{name}", env!("CARGO_MANIFEST_DIR"))
    }

    fn small() -> String {
        std::fs::read_to_string(maps_dir("small.yaml")).unwrap_or_default()
    }

    fn line_of(text: &str, needle: &str) -> usize {
        text.lines().position(|l| l.contains(needle)).map(|i| i + 1).unwrap_or(0)
    }

    /// small.yaml with `from` replaced by `to`, loaded and linted.
    fn lint_changed(from: &str, to: &str) -> (String, Vec<Finding>) {
        let text = small();
        assert!(text.contains(from), "small.yaml has no `{from}`");
        let text = text.replacen(from, to, 1);
        match Map::parse("x.yaml", &text) {
            Ok(m) => (text, lint(&m)),
            Err(e) => panic!("the changed map does not load: {e}"),
        }
    }

    fn has(findings: &[Finding], line: usize, needle: &str) -> bool {
        findings.iter().any(|f| f.line == line && f.render("x").contains(needle))
    }

    #[test]
    fn the_shipped_maps_have_no_findings() {
        for name in ["default.yaml", "small.yaml"] {
            let m = match crate::load_map(maps_dir(name)) {
                Ok(m) => m,
                Err(e) => panic!("{e}"),
            };
            let f: Vec<String> = lint(&m).iter().map(|f| f.render(name)).collect();
            assert!(f.is_empty(), "{name}: {f:#?}");
        }
    }

    #[test]
    fn a_door_barcode_far_from_its_door_is_found_on_its_line() {
        // 0.9 m from the lab door's nearer jamb (the rule: 0.1 to 0.6 m).
        let (text, f) = lint_changed("{id: 10, at: [4.25, 0.02]", "{id: 10, at: [3.5, 0.02]");
        let at = line_of(&text, "{id: 10, at: [3.5, 0.02]");
        // Which distance, its value and its limit.
        assert_eq!(
            rendered(&f),
            [format!(
                "x:{at}: floor 0, door 1 (lab), barcode: barcode 10 marks door 1 (lab) (the nearest), but is 0.90 m \
                 from the door's nearer jamb along its wall: 0.10 to 0.60 m"
            )]
        );
        // 0.3 m off its wall (and so off the door's line): said once, with the distance and the limit.
        let (text, f) = lint_changed("{id: 10, at: [4.25, 0.02]", "{id: 10, at: [4.25, 0.3]");
        let at = line_of(&text, "{id: 10, at: [4.25, 0.3]");
        assert_eq!(
            rendered(&f),
            [format!(
                "x:{at}: floor 0, door 1 (lab), barcode: barcode 10 is 0.30 m in front of the wall behind it: barcodes \
                 are stuck 0.01 to 0.02 m off their wall, on the side they face"
            )]
        );
        // On another wall, 0.3 m off the door's line: a wall across the lab at x = 4.0, the barcode on it.
        let text = small()
            .replacen("      - [5.6, 0, 6, 0]", "      - [5.6, 0, 6, 0]\n      - [4.0, 0.3, 4.0, 0.9]", 1)
            .replacen("{id: 10, at: [4.25, 0.02], facing_deg: 90}", "{id: 10, at: [4.02, 0.3], facing_deg: 0}", 1);
        let at = line_of(&text, "{id: 10, at: [4.02, 0.3]");
        assert_eq!(
            rendered(&lint_text(&text)),
            [format!(
                "x:{at}: floor 0, door 1 (lab), barcode: barcode 10 marks door 1 (lab) (the nearest), but is 0.30 m \
                 off the door's line (its wall): at most 0.10 m"
            )]
        );
        // 0.5 m is within it.
        let (_, f) = lint_changed("{id: 10, at: [4.25, 0.02]", "{id: 10, at: [3.9, 0.02]");
        assert!(f.is_empty(), "{f:#?}");
    }

    #[test]
    fn an_opening_in_the_call_buttons_wall_is_found_on_the_lobby_line() {
        // A narrower shaft leaves 0.4 m of the button's wall open beside it.
        let (text, f) = lint_changed("{rect: [3.2, 4.0, 5.2, 6.0]", "{rect: [3.2, 4.0, 4.8, 6.0]");
        let at = line_of(&text, "lobby: {button: [3.0, 3.98], facing_deg: -90, barcode: 30}");
        assert!(has(&f, at, "an opening 0.40 m wide at (5.00, 3.98) in the call button's wall"), "{f:#?}");
    }

    #[test]
    fn an_unreachable_office_is_found_on_its_line() {
        // The office shrunk to floor 1's south metre, behind a new wall.
        let text = small()
            .replacen(
                "office: {rect: [0, 0, 6, 4], barcode: {id: 40, at: [0.02, 2.0], facing_deg: 0}}",
                "office: {rect: [0, 0, 6, 1], barcode: {id: 40, at: [0.02, 0.5], facing_deg: 0}}",
                1,
            )
            .replacen("      - [2.8, 4, 3.2, 4]\n    lobby: {button: [3.0, 3.98], facing_deg: -90, barcode: 31}",
                "      - [2.8, 4, 3.2, 4]\n      - [0, 1.2, 6, 1.2]\n    lobby: {button: [3.0, 3.98], facing_deg: -90, barcode: 31}",
                1,
            );
        let m = Map::parse("x.yaml", &text).unwrap_or_else(|e| panic!("{e}"));
        let f = lint(&m);
        let at = line_of(&text, "office: {rect");
        assert!(has(&f, at, "floor 1, office: the office cannot be reached"), "{f:#?}");
        // Its barcode, behind the wall, cannot be read either.
        assert!(f.iter().any(|f| f.message.contains("barcode 40 cannot be read")), "{f:#?}");
    }

    #[test]
    fn a_barcode_facing_a_wall_is_found_on_its_line() {
        // The lab door's barcode turned to face the wall (south, away from the room).
        let (text, f) = lint_changed("at: [4.25, 0.02], facing_deg: 90}", "at: [4.25, 0.02], facing_deg: -90}");
        let at = line_of(&text, "name: lab");
        // The cause, alone (it cannot be read, and the lab would be on the other side).
        assert_eq!(
            rendered(&f),
            [format!(
                "x:{at}: floor 0, door 1 (lab), barcode: barcode 10 faces the wall it is on (0.02 m ahead of it): it \
                 cannot be read; turn it round (facing_deg: 90)"
            )]
        );
    }

    fn rendered(f: &[Finding]) -> Vec<String> {
        f.iter().map(|f| f.render("x")).collect()
    }

    fn default_text() -> String {
        std::fs::read_to_string(maps_dir("default.yaml")).unwrap_or_default()
    }

    fn lint_text(text: &str) -> Vec<Finding> {
        match Map::parse("x.yaml", text) {
            Ok(m) => lint(&m),
            Err(e) => panic!("the changed map does not load: {e}"),
        }
    }

    #[test]
    fn a_call_button_facing_its_own_wall_is_the_one_finding() {
        // Once 10 findings on the default map (every car's door, the button from each car,
        // the office, its barcode) and none about the facing.
        let from = "lobby: {button: [15.0, 17.98], facing_deg: -90, barcode: 35}";
        let text = default_text();
        assert!(text.contains(from));
        let text = text.replacen(from, "lobby: {button: [15.0, 17.98], facing_deg: 90, barcode: 35}", 1);
        let at = line_of(&text, "facing_deg: 90, barcode: 35}");
        assert_eq!(
            rendered(&lint_text(&text)),
            [format!(
                "x:{at}: floor 4, lobby: the call button (barcode 35) faces the wall it is on (0.02 m ahead of it): it \
                 must face into the lobby (facing_deg: -90); what the robot does in front of it is not checked until \
                 it does"
            )]
        );
        // On the start floor too.
        let (text, f) = lint_changed("facing_deg: -90, barcode: 30}", "facing_deg: 90, barcode: 30}");
        let at = line_of(&text, "facing_deg: 90, barcode: 30}");
        assert_eq!(f.len(), 1, "{f:#?}");
        assert!(has(&f, at, "floor 0, lobby: the call button (barcode 30) faces the wall it is on"), "{f:#?}");
    }

    #[test]
    fn doors_open_too_short_a_time_are_found_on_the_open_s_line() {
        let (text, f) = lint_changed("open_s: [15, 25]", "open_s: [2, 3]");
        let at = line_of(&text, "open_s: [2, 3]");
        assert_eq!(
            rendered(&f),
            [format!(
                "x:{at}: elevator: open_s [2, 3]: the doors must stay open at least 8 s for the robot to board (the \
                 shortest documented range is [8, 12])"
            )]
        );
        let (_, f) = lint_changed("open_s: [15, 25]", "open_s: [8, 12]");
        assert!(f.is_empty(), "{f:#?}");
    }

    #[test]
    fn a_start_outside_the_lab_is_found_on_the_start_line() {
        // South of the lab door, in the corridor: the lab's barcode is on the north side.
        let (text, f) = lint_changed("x: 3.0, y: 2.5", "x: 3.0, y: -1.0");
        let at = line_of(&text, "x: 3.0, y: -1.0");
        assert_eq!(
            rendered(&f),
            [format!(
                "x:{at}: mission, start: the start pose is not in the lab: it is outside floor 0, door 1 (lab) (the lab \
                 is the side its barcode 10 is on); the robot starts in the lab"
            )]
        );
    }

    const SOUTH: &str = "      - {polyline: [[0.8, 4], [0, 4], [0, -2], [6, -2], [6, 4], [5.2, 4]]}";

    #[test]
    fn a_side_corridor_of_1_6_m_is_found_once_at_its_mouth() {
        let (text, f) = lint_changed(
            SOUTH,
            "      - {polyline: [[0.8, 4], [0, 4], [0, -2], [2, -2], [2, -5], [3.6, -5], [3.6, -2], [6, -2], [6, 4], \
             [5.2, 4]]}",
        );
        let at = line_of(&text, "[2, -5], [3.6, -5]");
        assert_eq!(
            rendered(&f),
            [format!(
                "x:{at}: floor 0, wall 1, segment 3: an opening 1.60 m wide at (2.80, -2.00) between wall 1, segment 3 \
                 and wall 1, segment 7: a side opening is a door (1.0 to 1.4 m) or a side corridor (at least 1.8 m), \
                 nothing in between (the junction detector cannot tell which)"
            )]
        );
        // 1.8 m is a side corridor.
        let (_, f) = lint_changed(
            SOUTH,
            "      - {polyline: [[0.8, 4], [0, 4], [0, -2], [2, -2], [2, -5], [3.8, -5], [3.8, -2], [6, -2], [6, 4], \
             [5.2, 4]]}",
        );
        assert!(f.is_empty(), "{f:#?}");
    }

    #[test]
    fn a_corridor_of_1_6_m_is_found() {
        let (text, f) =
            lint_changed(SOUTH, "      - {polyline: [[0.8, 4], [0, 4], [0, -1.6], [6, -1.6], [6, 4], [5.2, 4]]}");
        let at = line_of(&text, "[0, -1.6], [6, -1.6]");
        assert_eq!(
            rendered(&f),
            [format!(
                "x:{at}: floor 0, wall 1, segment 3: a way 1.60 m wide between wall 1, segment 3 and wall 3 (around \
                 (2.20, -0.80)): corridors and side corridors are at least 1.8 m wide"
            )]
        );
    }

    #[test]
    fn a_door_wider_than_1_4_m_is_found_on_its_line() {
        let text = small()
            .replacen("[0, 0, 4.4, 0]", "[0, 0, 4.3, 0]", 1)
            .replacen("[5.6, 0, 6, 0]", "[5.8, 0, 6, 0]", 1)
            .replacen("at: [4.4, 0, 5.6, 0]", "at: [4.3, 0, 5.8, 0]", 1)
            .replacen("[4.25, 0.02]", "[4.1, 0.02]", 1);
        let at = line_of(&text, "name: lab");
        assert_eq!(
            rendered(&lint_text(&text)),
            [format!(
                "x:{at}: floor 0, door 1 (lab): 1.50 m wide: doors are 1.0 to 1.4 m wide (from 1.4 to 1.8 m the \
                 junction detector cannot tell a door from a side corridor)"
            )]
        );
    }

    #[test]
    fn a_shaft_out_of_size_is_found_on_its_car_line() {
        let (text, f) = lint_changed("[3.2, 4.0, 5.2, 6.0]", "[3.2, 4.0, 5.2, 6.8]");
        let at = line_of(&text, "[3.2, 4.0, 5.2, 6.8]");
        assert_eq!(
            rendered(&f),
            [format!("x:{at}: elevator, car 2: shaft 2.00 × 2.80 m: shafts are 1.8 to 2.4 m on each side")]
        );
    }

    #[test]
    fn a_barcode_off_its_wall_is_found_with_the_distance_and_the_limit() {
        let (text, f) = lint_changed("[4.25, 0.02]", "[4.25, 0.1]");
        let at = line_of(&text, "[4.25, 0.1]");
        assert_eq!(
            rendered(&f),
            [format!(
                "x:{at}: floor 0, door 1 (lab), barcode: barcode 10 is 0.10 m in front of the wall behind it: barcodes \
                 are stuck 0.01 to 0.02 m off their wall, on the side they face"
            )]
        );
    }

    #[test]
    fn openings_closer_than_0_8_m_are_found_on_the_wall_between() {
        let (text, f) = lint_changed("      - [0, 0, 4.4, 0]", "      - [0, 0, 2.9, 0]\n      - [3.9, 0, 4.4, 0]");
        // A gap without a door is an opening too (found alone); with a door, the same.
        assert_eq!(f.len(), 1, "{f:#?}");
        let text = text.replacen("    doors:\n", "    doors:\n      - {name: store, at: [2.9, 0, 3.9, 0]}\n", 1);
        let at = line_of(&text, "[3.9, 0, 4.4, 0]");
        assert_eq!(
            rendered(&lint_text(&text)),
            [format!(
                "x:{at}: floor 0, wall 4: only 0.50 m of wall between the openings at (3.40, 0.00) and (5.00, 0.00): \
                 openings on one side of a corridor are at least 0.8 m apart (one hidden for less counts as one)"
            )]
        );
    }

    #[test]
    fn clutter_leaving_less_than_1_2_m_is_found_on_its_line() {
        let (text, f) = lint_changed(
            "      - {name: box, rect: [1.0, 1.0, 1.6, 1.6]}",
            "      - {name: box, rect: [1.0, 1.0, 1.6, 1.6]}\n      - {name: crate, rect: [1.0, -2.0, 1.5, -1.1]}\n      \
             - {name: bin, rect: [3.0, -2.0, 3.5, -1.5]}\n      - {name: bin, rect: [3.2, -0.4, 3.6, 0]}",
        );
        let crate_at = line_of(&text, "name: crate");
        let bin_at = line_of(&text, "[3.2, -0.4, 3.6, 0]");
        assert_eq!(
            rendered(&f),
            [
                format!(
                    "x:{crate_at}: floor 0, obstacle 2: it leaves 1.10 m free across the corridor (to wall 3): clutter \
                     in a corridor leaves at least 1.2 m free"
                ),
                format!(
                    "x:{bin_at}: floor 0, obstacle 4: it and obstacle 3 (on the facing wall) leave 1.10 m between them: \
                     clutter in a corridor leaves at least 1.2 m free"
                )
            ]
        );
    }

    #[test]
    fn the_turn_before_a_pass_must_be_written_and_name_the_doors_side() {
        let (text, f) = lint_changed("      - {home: 40}", "      - {home: 40}\n      - {pass: door}");
        let at = line_of(&text, "{pass: door}");
        assert_eq!(
            rendered(&f),
            [format!(
                "x:{at}: mission, route car_to_office, step 2: `pass: door` after `home: 40` (step 1) with no `turn: \
                 left` or `turn: right` between: the last turn names the side of the barcode the door is on"
            )]
        );
        // The default map's office door is on the right of barcode 40, seen from in front of it.
        let from = "      - {home: 40}\n      - {turn: right}\n      - {pass: door}";
        let text = default_text();
        assert!(text.contains(from));
        let text = text.replacen(from, "      - {home: 40}\n      - {turn: left}\n      - {pass: door}", 1);
        let at = line_of(&text, "{home: 40}") + 1;
        assert_eq!(
            rendered(&lint_text(&text)),
            [format!(
                "x:{at}: mission, route car_to_office, step 4: `turn: left` before `pass: door`, but floor 4, door 1 \
                 (office) is on the right of barcode 40 (the robot squared up in front of it): the last turn names the \
                 side the door is on"
            )]
        );
    }

    #[test]
    fn a_narrow_car_door_is_found_on_its_line() {
        let (text, f) = lint_changed(
            "{rect: [3.2, 4.0, 5.2, 6.0], door: south, barcode: 202}",
            "{rect: [3.2, 4.0, 5.2, 6.0], door: south, door_width: 0.6, barcode: 202}",
        );
        let at = line_of(&text, "door_width: 0.6");
        assert!(has(&f, at, "elevator, car 2: door 0.60 m wide"), "{f:#?}");
    }

    #[test]
    fn a_route_naming_a_barcode_elsewhere_or_missing_is_found_on_its_step_line() {
        let (text, f) = lint_changed("      - {home: 40}", "      - {home: 10}");
        let at = line_of(&text, "{home: 10}");
        assert!(has(&f, at, "mission, route car_to_office, step 1: barcode 10 is on floor 0"), "{f:#?}");
        assert!(has(&f, at, "last `home` is 10, not the office_barcode 40"), "{f:#?}");
        // A missing barcode: the loader refuses it; a map built in code is linted.
        let mut m = Map::parse("x.yaml", &small()).unwrap_or_else(|e| panic!("{e}"));
        if let Some(step) = m.mission.route.get_mut(0).and_then(|(_, s)| s.get_mut(0)) {
            step.home = Some(99);
        }
        let f = lint(&m);
        let at = line_of(&small(), "{home: 40}");
        assert!(has(&f, at, "no barcode 99 in the map"), "{f:#?}");
    }

    #[test]
    fn a_narrow_door_and_a_fenced_in_start_are_found() {
        let (text, f) = lint_changed("at: [4.4, 0, 5.6, 0]", "at: [4.4, 0, 5.1, 0]");
        let at = line_of(&text, "name: lab");
        assert!(has(&f, at, "floor 0, door 1 (lab): 0.70 m wide"), "{f:#?}");
        // A crate around the start pose.
        let (text, f) = lint_changed(
            "      - {name: box, rect: [1.0, 1.0, 1.6, 1.6]}",
            "      - {name: box, rect: [1.0, 1.0, 1.6, 1.6]}\n      - {name: crate, rect: [2.2, 1.9, 3.8, 3.1]}",
        );
        let at = line_of(&text, "lobby: {button: [3.0, 3.98], facing_deg: -90, barcode: 30}");
        assert!(has(&f, at, "floor 0, lobby: the call button cannot be reached"), "{f:#?}");
    }
}
