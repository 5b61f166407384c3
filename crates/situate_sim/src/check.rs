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
//! - route steps naming barcodes that exist on the leg's floor.
//!
//! Every finding names the element and the map line it is on.

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
/// Slack on the rules' distances for coordinates written to the centimetre, m.
const SLACK: f64 = 0.02;

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
    }
    let m = &map.mission;
    let line = |key: &str| m.lines.get(key).copied().unwrap_or(1);
    let start_floor = map.floor(m.start_floor);
    let goal_floor = map.floor(m.goal_floor);
    if let Some(f) = start_floor {
        start_checks(map, f, &mut out, line("start"));
        door_beside(f, m.lab_door_barcode, &mut out);
    }
    if let Some(f) = goal_floor {
        goal_checks(map, f, &mut out, line("goal_floor"));
        // An office with a door (one on its outline): its barcode marks it.
        let office_door = f.office.as_ref().is_some_and(|o| {
            let outline: Vec<Seg> =
                o.polygon.iter().zip(o.polygon.iter().cycle().skip(1)).map(|(a, b)| Seg::new(*a, *b)).collect();
            f.doors.iter().any(|d| outline.iter().any(|e| e.dist_to(d.seg.at(0.5)) <= 0.1))
        });
        if office_door {
            door_beside(f, m.office_barcode, &mut out);
        }
    }
    for f in &map.floors {
        button_wall(map, f, &mut out);
    }
    route(map, &mut out);
    out
}

/// The door a barcode marks is beside it: on a door's line, 0.1 to
/// [`BARCODE_JAMB_MAX`] m from its nearer jamb (`docs/maps.md`, "Lab door" and
/// "Office"). The robot, lined up with the barcode, looks for its door there.
fn door_beside(f: &Floor, id: i64, out: &mut Vec<Finding>) {
    let Some((el, b)) = floor_barcode(f, id) else { return };
    // For each door: how far the barcode is off its line, and from its nearer jamb along it.
    let nearest = f
        .doors
        .iter()
        .map(|d| {
            let len = d.seg.len();
            let along_dir = d.seg.b.minus(d.seg.a).scale(1.0 / len.max(1e-9));
            let rel = b.at.minus(d.seg.a);
            let along = rel.dot(along_dir);
            let off = rel.cross(along_dir).abs();
            let jamb = if along < 0.0 {
                -along
            } else if along > len {
                along - len
            } else {
                0.0
            };
            (off, jamb)
        })
        .min_by(|x, y| x.0.hypot(x.1).total_cmp(&y.0.hypot(y.1)));
    let ok = nearest
        .is_some_and(|(off, jamb)| off <= 0.1 + SLACK && (0.1 - SLACK..=BARCODE_JAMB_MAX + SLACK).contains(&jamb));
    if !ok {
        let what = match nearest {
            None => "there is no door on its floor".to_string(),
            Some((off, jamb)) => {
                format!("the nearest door's nearer jamb is {jamb:.2} m along its wall and {off:.2} m off it")
            }
        };
        out.push(Finding::new(
            b.line,
            el,
            format!(
                "barcode {id} marks a door, but {what}: it must be on the door's wall, 0.1 to {BARCODE_JAMB_MAX} m \
                 from the nearer jamb"
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

fn start_checks(map: &Map, f: &Floor, out: &mut Vec<Finding>, start_line: usize) {
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
            if !grid.reached_near(&reach, press, CELL * 2.0) {
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
            if !readable_somewhere(&grid, &reach, &b, &segs) {
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
        if !readable_somewhere(&grid, &reach, &b, &segs) {
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
        assert!(has(&f, at, "barcode 10 marks a door, but the nearest door's nearer jamb is 0.90 m"), "{f:#?}");
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
        assert!(has(&f, at, "floor 0, door 1 (lab), barcode: barcode 10 cannot be read"), "{f:#?}");
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
