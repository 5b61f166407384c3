//! Building maps: the YAML format (see `docs/maps.md`), its checks, and the
//! world view the GUI draws.
//!
//! Every error names the file, the line and the element, e.g.
//! `maps/x.yaml:12: floor 4, wall 3: segment has zero length`.

use std::collections::BTreeMap;
use std::path::Path;

use serde_json::{json, Value as Json};
use situate_robotfile::yaml::{self, Node, Pos, Spanned};
use thiserror::Error;

use crate::geom::{in_polygon, Seg, P2};

/// A map that could not be read or makes no sense.
#[derive(Debug, Error)]
pub enum MapError {
    /// The file could not be read.
    #[error("{file}: {source}")]
    Io {
        file: String,
        #[source]
        source: std::io::Error,
    },
    /// The file is not YAML a map may use.
    #[error("{file}:{line}:{col}: {message}")]
    Yaml { file: String, line: usize, col: usize, message: String },
    /// An element of the map is wrong.
    #[error("{file}:{line}: {element}: {message}")]
    Invalid { file: String, line: usize, element: String, message: String },
}

impl MapError {
    /// The line the error points at (0 when there is none).
    pub fn line(&self) -> usize {
        match self {
            MapError::Io { .. } => 0,
            MapError::Yaml { line, .. } | MapError::Invalid { line, .. } => *line,
        }
    }
}

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

impl Car {
    /// The door opening (a segment of the door side, centred).
    pub fn door(&self) -> Seg {
        let (cx, cy, h) = ((self.x0 + self.x1) / 2.0, (self.y0 + self.y1) / 2.0, self.door_width / 2.0);
        match self.door_side {
            Side::South => Seg::new(P2::new(cx - h, self.y0), P2::new(cx + h, self.y0)),
            Side::North => Seg::new(P2::new(cx - h, self.y1), P2::new(cx + h, self.y1)),
            Side::West => Seg::new(P2::new(self.x0, cy - h), P2::new(self.x0, cy + h)),
            Side::East => Seg::new(P2::new(self.x1, cy - h), P2::new(self.x1, cy + h)),
        }
    }

    /// The shaft's walls: the rectangle without the door opening.
    pub fn walls(&self) -> Vec<Seg> {
        let c = [
            P2::new(self.x0, self.y0),
            P2::new(self.x1, self.y0),
            P2::new(self.x1, self.y1),
            P2::new(self.x0, self.y1),
        ];
        let sides =
            [(Side::South, c[0], c[1]), (Side::East, c[1], c[2]), (Side::North, c[2], c[3]), (Side::West, c[3], c[0])];
        let door = self.door();
        let mut out = Vec::new();
        for (side, a, b) in sides {
            if side != self.door_side {
                out.push(Seg::new(a, b));
                continue;
            }
            // Split the side around the door, keeping a → b order.
            let (d0, d1) = if a.dist(door.a) < a.dist(door.b) { (door.a, door.b) } else { (door.b, door.a) };
            if a.dist(d0) > 1e-9 {
                out.push(Seg::new(a, d0));
            }
            if d1.dist(b) > 1e-9 {
                out.push(Seg::new(d1, b));
            }
        }
        out
    }

    /// The floor-button panel (also where the car's barcode is): the middle of
    /// the back wall, 2 cm inside, and the direction it faces (towards the door).
    pub fn panel(&self) -> (P2, f64) {
        use std::f64::consts::{FRAC_PI_2, PI};
        let (cx, cy) = ((self.x0 + self.x1) / 2.0, (self.y0 + self.y1) / 2.0);
        match self.door_side {
            Side::South => (P2::new(cx, self.y1 - 0.02), -FRAC_PI_2),
            Side::North => (P2::new(cx, self.y0 + 0.02), FRAC_PI_2),
            Side::West => (P2::new(self.x1 - 0.02, cy), PI),
            Side::East => (P2::new(self.x0 + 0.02, cy), 0.0),
        }
    }

    /// Whether `p` is inside the car.
    pub fn contains(&self, p: P2) -> bool {
        p.x > self.x0 && p.x < self.x1 && p.y > self.y0 && p.y < self.y1
    }
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

/// The largest map file read: 4 MiB (a larger one is refused before it is
/// read).
pub const MAX_MAP_FILE_BYTES: u64 = 4 << 20;

/// Reads and checks a map file of at most [`MAX_MAP_FILE_BYTES`].
pub fn load_map(path: impl AsRef<Path>) -> Result<Map, MapError> {
    let path = path.as_ref();
    let file = path.display().to_string();
    let text = yaml::read_source(path, "map file", MAX_MAP_FILE_BYTES).map_err(|e| match e {
        yaml::ReadError::Io { source, .. } => MapError::Io { file: file.clone(), source },
        yaml::ReadError::NotUtf8 { pos, .. } => {
            MapError::Yaml { file: file.clone(), line: pos.line, col: pos.col, message: e.to_string() }
        }
        e => MapError::Io { file: file.clone(), source: std::io::Error::new(std::io::ErrorKind::InvalidData, e) },
    })?;
    Map::parse(&file, &text)
}

impl Map {
    /// Parses and checks map text; `file` names it in errors.
    pub fn parse(file: &str, text: &str) -> Result<Map, MapError> {
        let root = yaml::parse(text).map_err(|e| MapError::Yaml {
            file: file.to_string(),
            line: e.pos.line,
            col: e.pos.col,
            message: e.message,
        })?;
        let r = Reader { file };
        let map = r.map(&root)?;
        map.check(&r)?;
        Ok(map)
    }

    /// The floor with this level.
    pub fn floor(&self, level: i64) -> Option<&Floor> {
        self.floors.iter().find(|f| f.level == level)
    }

    /// Every barcode of the map with the floor it is on (`None`: a car's, on
    /// whichever floor the car is).
    pub fn all_barcodes(&self) -> Vec<(Option<i64>, Barcode)> {
        let mut out = Vec::new();
        for f in &self.floors {
            for b in &f.barcodes {
                out.push((Some(f.level), b.clone()));
            }
            for d in &f.doors {
                if let Some(b) = &d.barcode {
                    out.push((Some(f.level), b.clone()));
                }
            }
            if let Some(l) = &f.lobby {
                out.push((
                    Some(f.level),
                    Barcode { id: l.barcode, at: l.button, facing: Some(l.facing), line: l.line },
                ));
            }
            if let Some(o) = &f.office {
                out.push((Some(f.level), o.barcode.clone()));
            }
        }
        for c in &self.elevator.cars {
            let (at, facing) = c.panel();
            out.push((None, Barcode { id: c.barcode, at, facing: Some(facing), line: c.line }));
        }
        out
    }

    /// Every barcode of the map with the element it belongs to, named as
    /// errors name it (`floor 0, door 1 (lab), barcode`, `floor 2, barcode 3`,
    /// `floor 1, lobby`, `floor 4, office, barcode`, `elevator, car 2`).
    pub fn named_barcodes(&self) -> Vec<(String, Barcode)> {
        let mut out = Vec::new();
        for f in &self.floors {
            for (i, b) in f.barcodes.iter().enumerate() {
                out.push((format!("floor {}, barcode {}", f.level, i + 1), b.clone()));
            }
            for (i, d) in f.doors.iter().enumerate() {
                if let Some(b) = &d.barcode {
                    let door = if d.name.is_empty() {
                        format!("floor {}, door {}", f.level, i + 1)
                    } else {
                        format!("floor {}, door {} ({})", f.level, i + 1, d.name)
                    };
                    out.push((format!("{door}, barcode"), b.clone()));
                }
            }
            if let Some(l) = &f.lobby {
                let b = Barcode { id: l.barcode, at: l.button, facing: Some(l.facing), line: l.line };
                out.push((format!("floor {}, lobby", f.level), b));
            }
            if let Some(o) = &f.office {
                out.push((format!("floor {}, office, barcode", f.level), o.barcode.clone()));
            }
        }
        for (k, c) in self.elevator.cars.iter().enumerate() {
            let (at, facing) = c.panel();
            out.push((
                format!("elevator, car {}", k + 1),
                Barcode { id: c.barcode, at, facing: Some(facing), line: c.line },
            ));
        }
        out
    }

    /// The world view for the GUI (shape in `docs/maps.md`).
    pub fn world_json(&self) -> Json {
        let seg = |s: &Seg| json!([s.a.x, s.a.y, s.b.x, s.b.y]);
        let car_walls: Vec<Json> = self.elevator.cars.iter().flat_map(Car::walls).map(|s| seg(&s)).collect();
        let floors: Vec<Json> = self
            .floors
            .iter()
            .map(|f| {
                let mut walls: Vec<Json> = f.walls.iter().map(seg).collect();
                walls.extend(car_walls.iter().cloned());
                let obstacles: Vec<Json> =
                    f.obstacles.iter().map(|p| Json::Array(p.iter().map(|q| json!([q.x, q.y])).collect())).collect();
                let doors: Vec<Json> = f.doors.iter().map(|d| seg(&d.seg)).collect();
                let mut barcodes = Vec::new();
                let mut buttons = Vec::new();
                for (level, b) in self.all_barcodes() {
                    if level.is_none() || level == Some(f.level) {
                        barcodes.push(json!({"id": b.id, "x": b.at.x, "y": b.at.y}));
                    }
                }
                if let Some(l) = &f.lobby {
                    buttons.push(json!({"x": l.button.x, "y": l.button.y, "label": "call"}));
                }
                for c in &self.elevator.cars {
                    let (p, _) = c.panel();
                    buttons.push(json!({"x": p.x, "y": p.y, "label": format!("car {}", c.id)}));
                }
                let office = match &f.office {
                    Some(o) => Json::Array(o.polygon.iter().map(|q| json!([q.x, q.y])).collect()),
                    None => Json::Null,
                };
                json!({"level": f.level, "walls": walls, "obstacles": obstacles, "doors": doors,
                       "barcodes": barcodes, "buttons": buttons, "office": office})
            })
            .collect();
        let cars: Vec<Json> = self
            .elevator
            .cars
            .iter()
            .map(|c| json!({"id": c.id, "x0": c.x0, "y0": c.y0, "x1": c.x1, "y1": c.y1, "door": seg(&c.door())}))
            .collect();
        json!({"floors": floors, "cars": cars, "robot_radius": self.robot_radius})
    }

    /// The whole building as JSON, for another simulator built from the same file (the physics
    /// robot, `situate.physics`): every floor's walls, obstacles, doors, barcodes (with the
    /// direction each faces, `null`: readable from anywhere), lobby and office; the elevator's
    /// timing and cars (shaft, door, panel); the mission; the robot's radius. What `situate map
    /// show` prints (its shape: `docs/maps.md`, "The building as JSON").
    pub fn building_json(&self) -> Json {
        let seg = |s: &Seg| json!([s.a.x, s.a.y, s.b.x, s.b.y]);
        let barcode = |b: &Barcode| json!({"id": b.id, "x": b.at.x, "y": b.at.y, "facing": b.facing});
        let floors: Vec<Json> = self
            .floors
            .iter()
            .map(|f| {
                let doors: Vec<Json> = f
                    .doors
                    .iter()
                    .map(|d| json!({"name": d.name, "seg": seg(&d.seg), "barcode": d.barcode.as_ref().map(barcode)}))
                    .collect();
                json!({
                    "level": f.level,
                    "name": f.name,
                    "walls": f.walls.iter().map(seg).collect::<Vec<_>>(),
                    "obstacles": f.obstacles.iter().map(|p| p.iter().map(|q| json!([q.x, q.y])).collect::<Vec<_>>()).collect::<Vec<_>>(),
                    "doors": doors,
                    "barcodes": f.barcodes.iter().map(barcode).collect::<Vec<_>>(),
                    "lobby": f.lobby.as_ref().map(|l| json!({"button": [l.button.x, l.button.y], "facing": l.facing, "barcode": l.barcode})),
                    "office": f.office.as_ref().map(|o| json!({
                        "polygon": o.polygon.iter().map(|q| json!([q.x, q.y])).collect::<Vec<_>>(),
                        "barcode": barcode(&o.barcode),
                    })),
                })
            })
            .collect();
        let e = &self.elevator;
        let cars: Vec<Json> = e
            .cars
            .iter()
            .map(|c| {
                let (panel, facing) = c.panel();
                let side = match c.door_side {
                    Side::North => "north",
                    Side::South => "south",
                    Side::East => "east",
                    Side::West => "west",
                };
                json!({
                    "id": c.id, "x0": c.x0, "y0": c.y0, "x1": c.x1, "y1": c.y1,
                    "door_side": side, "door_width": c.door_width, "door": seg(&c.door()),
                    "walls": c.walls().iter().map(seg).collect::<Vec<_>>(),
                    "panel": {"x": panel.x, "y": panel.y, "facing": facing}, "barcode": c.barcode,
                })
            })
            .collect();
        json!({
            "name": self.name,
            "robot_radius": self.robot_radius,
            "floors": floors,
            "elevator": {
                "travel_s_per_floor": e.travel_s_per_floor, "door_move_s": e.door_move_s,
                "open_s": [e.open_s.0, e.open_s.1], "arrive_s": [e.arrive_s.0, e.arrive_s.1],
                "cars": cars,
            },
            "mission": self.mission_json(),
        })
    }

    /// The mission and its route hints as JSON, for a sequencer.
    pub fn mission_json(&self) -> Json {
        let m = &self.mission;
        let mut route = serde_json::Map::new();
        for (name, steps) in &m.route {
            let steps: Vec<Json> = steps
                .iter()
                .map(|s| {
                    let mut o = serde_json::Map::new();
                    let text = [("follow", &s.follow), ("until", &s.until), ("side", &s.side), ("turn", &s.turn)];
                    for (k, v) in text.into_iter().chain([("pass", &s.pass)]) {
                        if let Some(v) = v {
                            o.insert(k.into(), json!(v));
                        }
                    }
                    for (k, v) in [("count", s.count), ("barcode", s.barcode), ("home", s.home)] {
                        if let Some(v) = v {
                            o.insert(k.into(), json!(v));
                        }
                    }
                    if let Some(d) = s.distance {
                        o.insert("distance".into(), json!(d));
                    }
                    Json::Object(o)
                })
                .collect();
            route.insert(name.clone(), Json::Array(steps));
        }
        let goal_button = self.floor(m.goal_floor).and_then(|f| f.lobby.as_ref()).map(|l| l.barcode);
        json!({
            "start": {"floor": m.start_floor, "x": m.start.0, "y": m.start.1, "theta": m.start.2},
            "goal_floor": m.goal_floor, "lab_door_barcode": m.lab_door_barcode,
            "call_button_barcode": m.call_button_barcode, "office_barcode": m.office_barcode,
            "car_barcode_first": m.car_barcode_first, "cars": self.elevator.cars.len(),
            "goal_button_barcode": goal_button,
            "lobbies": self.floors.iter().filter_map(|f| f.lobby.as_ref().map(|l| json!({"floor": f.level, "barcode": l.barcode}))).collect::<Vec<_>>(),
            "message": m.message, "route": route,
        })
    }

    /// Checks across elements (ids, references, geometry).
    fn check(&self, r: &Reader<'_>) -> Result<(), MapError> {
        // Whole-map checks carry line 1: they concern several elements.
        let at = Pos::START;
        // Each id once: a second use is reported on its line, naming both elements and lines.
        let mut named = self.named_barcodes();
        named.sort_by_key(|(_, b)| b.line);
        let mut seen: BTreeMap<i64, (String, usize)> = BTreeMap::new();
        for (el, b) in named {
            if let Some((first, line)) = seen.get(&b.id) {
                let pos = Pos::new(b.line.max(1), 1);
                return Err(r.err(
                    pos,
                    &el,
                    format!(
                        "barcode {} is used twice: by {first} on line {line} and by {el} on line {}",
                        b.id,
                        b.line.max(1)
                    ),
                ));
            }
            seen.insert(b.id, (el, b.line.max(1)));
        }
        let m = &self.mission;
        let line = |key: &str| Pos::new(m.lines.get(key).copied().unwrap_or(1), 1);
        if self.floor(m.start_floor).is_none() {
            let at = line("start");
            return Err(r.err(at, "mission", format!("start floor {} is not a floor of the map", m.start_floor)));
        }
        if self.floor(m.goal_floor).is_none() {
            let at = line("goal_floor");
            return Err(r.err(at, "mission", format!("goal floor {} is not a floor of the map", m.goal_floor)));
        }
        for (what, id) in [
            ("lab_door_barcode", m.lab_door_barcode),
            ("call_button_barcode", m.call_button_barcode),
            ("office_barcode", m.office_barcode),
            ("car_barcode_first", m.car_barcode_first),
        ] {
            if !seen.contains_key(&id) {
                return Err(r.err(line(what), "mission", format!("{what}: no barcode {id} in the map")));
            }
        }
        for (k, c) in self.elevator.cars.iter().enumerate() {
            let want = m.car_barcode_first + k as i64;
            if c.barcode != want {
                return Err(r.err(
                    Pos::new(c.line.max(1), 1),
                    &format!("elevator, car {}", k + 1),
                    format!("barcode {} but car_barcode_first {} says {want}", c.barcode, m.car_barcode_first),
                ));
            }
        }
        for (leg, steps) in &m.route {
            for (i, st) in steps.iter().enumerate() {
                for id in [st.barcode, st.home].into_iter().flatten() {
                    if !seen.contains_key(&id) {
                        let el = format!("mission, route {leg}, step {}", i + 1);
                        let at = if st.line > 0 { Pos::new(st.line, 1) } else { line("route") };
                        return Err(r.err(at, &el, format!("no barcode {id} in the map")));
                    }
                }
            }
        }
        let offices: Vec<&Floor> = self.floors.iter().filter(|f| f.office.is_some()).collect();
        match offices.as_slice() {
            [f] => {
                let o = f.office.as_ref().map(|o| o.barcode.id);
                if o != Some(m.office_barcode) {
                    return Err(r.err(
                        line("office_barcode"),
                        "mission",
                        format!("office_barcode {} is not the office's", m.office_barcode),
                    ));
                }
                if f.level != m.goal_floor {
                    return Err(r.err(
                        line("goal_floor"),
                        "mission",
                        format!("the office is on floor {}, not the goal floor", f.level),
                    ));
                }
            }
            [] => return Err(r.err(at, "map", "no floor has an `office`")),
            _ => return Err(r.err(at, "map", "more than one floor has an `office`")),
        }
        let start = P2::new(m.start.0, m.start.1);
        if let Some(f) = self.floor(m.start_floor) {
            if let Some(d) = self.static_segments(f).iter().map(|s| s.dist_to(start)).min_by(f64::total_cmp) {
                if d < self.robot_radius {
                    return Err(r.err(
                        line("start"),
                        "mission",
                        format!("the start pose is {d:.2} m from a wall or obstacle"),
                    ));
                }
            }
        }
        Ok(())
    }

    /// The fixed segments of a floor: walls, obstacle edges, shaft walls.
    pub fn static_segments(&self, floor: &Floor) -> Vec<Seg> {
        let mut segs = floor.walls.clone();
        for poly in &floor.obstacles {
            for i in 0..poly.len() {
                segs.push(Seg::new(poly[i], poly[(i + 1) % poly.len()]));
            }
        }
        for c in &self.elevator.cars {
            segs.extend(c.walls());
        }
        segs
    }

    /// The office floor and polygon.
    pub fn office(&self) -> Option<(i64, &Office)> {
        self.floors.iter().find_map(|f| f.office.as_ref().map(|o| (f.level, o)))
    }

    /// Whether `p` on `floor` is inside the goal office.
    pub fn in_office(&self, floor: i64, p: P2) -> bool {
        self.office().is_some_and(|(l, o)| l == floor && in_polygon(p, &o.polygon))
    }
}

/// Reads the node tree, remembering the file for errors.
struct Reader<'a> {
    file: &'a str,
}

type N = Spanned<Node>;

impl Reader<'_> {
    fn err(&self, pos: Pos, element: &str, message: impl Into<String>) -> MapError {
        MapError::Invalid {
            file: self.file.to_string(),
            line: pos.line,
            element: element.to_string(),
            message: message.into(),
        }
    }

    /// A mapping's entries, refusing keys not in `allowed`.
    fn fields<'n>(&self, n: &'n N, el: &str, allowed: &[&str]) -> Result<Fields<'n>, MapError> {
        let Some(entries) = n.value.as_map() else {
            return Err(self.err(n.pos, el, format!("expected a mapping, got {}", n.value.describe())));
        };
        for (k, _) in entries {
            if !allowed.contains(&k.value.as_str()) {
                return Err(self.err(
                    k.pos,
                    el,
                    format!("unknown key `{}` (expected one of: {})", k.value, allowed.join(", ")),
                ));
            }
        }
        Ok(Fields { node: n, entries })
    }

    fn req<'n>(&self, f: &Fields<'n>, key: &str, el: &str) -> Result<&'n N, MapError> {
        f.get(key).ok_or_else(|| self.err(f.node.pos, el, format!("missing `{key}`")))
    }

    fn num(&self, n: &N, el: &str, what: &str) -> Result<f64, MapError> {
        match n.value.as_f64() {
            Some(x) if x.is_finite() => Ok(x),
            _ => Err(self.err(n.pos, el, format!("{what}: expected a number, got {}", n.value.describe()))),
        }
    }

    fn int(&self, n: &N, el: &str, what: &str) -> Result<i64, MapError> {
        n.value
            .as_i64()
            .ok_or_else(|| self.err(n.pos, el, format!("{what}: expected an integer, got {}", n.value.describe())))
    }

    fn text(&self, n: &N, el: &str, what: &str) -> Result<String, MapError> {
        match &n.value {
            Node::Scalar { text, .. } => Ok(text.clone()),
            other => Err(self.err(n.pos, el, format!("{what}: expected text, got {}", other.describe()))),
        }
    }

    fn seq<'n>(&self, n: &'n N, el: &str, what: &str) -> Result<&'n [N], MapError> {
        match &n.value {
            Node::Seq(items) => Ok(items),
            Node::Null => Ok(&[]),
            other => Err(self.err(n.pos, el, format!("{what}: expected a list, got {}", other.describe()))),
        }
    }

    /// A list of exactly `k` numbers.
    fn nums(&self, n: &N, el: &str, what: &str, k: usize) -> Result<Vec<f64>, MapError> {
        let items = self.seq(n, el, what)?;
        if items.len() != k {
            return Err(self.err(n.pos, el, format!("{what}: expected {k} numbers, got {}", items.len())));
        }
        items.iter().map(|i| self.num(i, el, what)).collect()
    }

    fn point(&self, n: &N, el: &str, what: &str) -> Result<P2, MapError> {
        let v = self.nums(n, el, what, 2)?;
        Ok(P2::new(v[0], v[1]))
    }

    fn points(&self, n: &N, el: &str, what: &str) -> Result<Vec<P2>, MapError> {
        self.seq(n, el, what)?.iter().map(|p| self.point(p, el, what)).collect()
    }

    fn segment(&self, n: &N, el: &str) -> Result<Seg, MapError> {
        let v = self.nums(n, el, "segment [x1, y1, x2, y2]", 4)?;
        let s = Seg::new(P2::new(v[0], v[1]), P2::new(v[2], v[3]));
        if s.len() < 1e-6 {
            return Err(self.err(n.pos, el, "segment has zero length"));
        }
        Ok(s)
    }

    fn angle(&self, f: &Fields<'_>, key: &str, el: &str) -> Result<Option<f64>, MapError> {
        f.get(key).map(|n| self.num(n, el, key).map(f64::to_radians)).transpose()
    }

    fn barcode(&self, n: &N, el: &str) -> Result<Barcode, MapError> {
        let f = self.fields(n, el, &["id", "at", "facing_deg"])?;
        let id = self.int(self.req(&f, "id", el)?, el, "id")?;
        let at = self.point(self.req(&f, "at", el)?, el, "at")?;
        Ok(Barcode { id, at, facing: self.angle(&f, "facing_deg", el)?, line: n.pos.line })
    }

    /// A `{rect: [x0, y0, x1, y1]}` or `{polygon: [[x, y], …]}` region.
    fn region(&self, f: &Fields<'_>, el: &str) -> Result<Vec<P2>, MapError> {
        match (f.get("rect"), f.get("polygon")) {
            (Some(r), None) => {
                let v = self.nums(r, el, "rect [x0, y0, x1, y1]", 4)?;
                if v[2] <= v[0] || v[3] <= v[1] {
                    return Err(self.err(r.pos, el, "rect [x0, y0, x1, y1] needs x0 < x1 and y0 < y1"));
                }
                Ok(vec![P2::new(v[0], v[1]), P2::new(v[2], v[1]), P2::new(v[2], v[3]), P2::new(v[0], v[3])])
            }
            (None, Some(p)) => {
                let pts = self.points(p, el, "polygon")?;
                if pts.len() < 3 {
                    return Err(self.err(p.pos, el, format!("a polygon needs at least 3 points, got {}", pts.len())));
                }
                Ok(pts)
            }
            (Some(r), Some(_)) => Err(self.err(r.pos, el, "give `rect` or `polygon`, not both")),
            (None, None) => Err(self.err(f.node.pos, el, "missing `rect` or `polygon`")),
        }
    }

    fn map(&self, root: &N) -> Result<Map, MapError> {
        let f = self.fields(root, "map", &["name", "robot_radius", "elevator", "floors", "mission"])?;
        let name = f.get("name").map(|n| self.text(n, "map", "name")).transpose()?.unwrap_or_default();
        let robot_radius = match f.get("robot_radius") {
            Some(n) => {
                let r = self.num(n, "map", "robot_radius")?;
                if !(0.05..=2.0).contains(&r) {
                    return Err(self.err(n.pos, "map", format!("robot_radius {r} is outside 0.05..2 m")));
                }
                r
            }
            None => 0.25,
        };
        let floors_node = self.req(&f, "floors", "map")?;
        let mut floors: Vec<Floor> = Vec::new();
        for n in self.seq(floors_node, "map", "floors")? {
            let floor = self.floor(n, floors.len() + 1, robot_radius)?;
            if floors.iter().any(|g| g.level == floor.level) {
                return Err(self.err(n.pos, &format!("floor {}", floor.level), "this level is given twice"));
            }
            floors.push(floor);
        }
        if floors.is_empty() {
            return Err(self.err(floors_node.pos, "map", "`floors` is empty"));
        }
        let elevator = self.elevator(self.req(&f, "elevator", "map")?, robot_radius)?;
        let mission = self.mission(self.req(&f, "mission", "map")?)?;
        Ok(Map { file: self.file.to_string(), name, robot_radius, floors, elevator, mission })
    }

    fn floor(&self, n: &N, index: usize, radius: f64) -> Result<Floor, MapError> {
        let keys = ["level", "name", "walls", "obstacles", "doors", "barcodes", "lobby", "office"];
        let f = self.fields(n, &format!("floor #{index}"), &keys)?;
        let level =
            self.int(self.req(&f, "level", &format!("floor #{index}"))?, &format!("floor #{index}"), "level")?;
        let fl = format!("floor {level}");
        let name = f.get("name").map(|n| self.text(n, &fl, "name")).transpose()?.unwrap_or_default();
        let mut walls = Vec::new();
        // The wall element (1-based, as written) each segment comes from.
        let mut wall_el: Vec<usize> = Vec::new();
        let mut wall_refs: Vec<(usize, usize)> = Vec::new();
        if let Some(ws) = f.get("walls") {
            for (i, w) in self.seq(ws, &fl, "walls")?.iter().enumerate() {
                let el = format!("{fl}, wall {}", i + 1);
                match &w.value {
                    Node::Map(_) => {
                        let g = self.fields(w, &el, &["polyline", "closed"])?;
                        let pts = self.points(self.req(&g, "polyline", &el)?, &el, "polyline")?;
                        let closed = match g.get("closed") {
                            Some(c) => c
                                .value
                                .as_bool()
                                .ok_or_else(|| self.err(c.pos, &el, "closed: expected true or false"))?,
                            None => false,
                        };
                        if pts.len() < 2 {
                            return Err(self.err(w.pos, &el, "a polyline needs at least 2 points"));
                        }
                        let n = pts.len();
                        let edges = if closed { n } else { n - 1 };
                        for k in 0..edges {
                            let s = Seg::new(pts[k], pts[(k + 1) % n]);
                            if s.len() < 1e-6 {
                                return Err(self.err(w.pos, &el, format!("segment {} has zero length", k + 1)));
                            }
                            walls.push(s);
                        }
                    }
                    _ => walls.push(self.segment(w, &el)?),
                }
                wall_el.resize(walls.len(), i + 1);
                wall_refs.resize(walls.len(), (i + 1, w.pos.line));
            }
        }
        let mut obstacles = Vec::new();
        let mut obstacle_lines = Vec::new();
        if let Some(os) = f.get("obstacles") {
            for (i, o) in self.seq(os, &fl, "obstacles")?.iter().enumerate() {
                let el = format!("{fl}, obstacle {}", i + 1);
                let g = self.fields(o, &el, &["rect", "polygon", "name"])?;
                obstacles.push(self.region(&g, &el)?);
                obstacle_lines.push(o.pos.line);
            }
        }
        let mut doors = Vec::new();
        if let Some(ds) = f.get("doors") {
            for (i, d) in self.seq(ds, &fl, "doors")?.iter().enumerate() {
                let el = format!("{fl}, door {}", i + 1);
                let g = self.fields(d, &el, &["at", "barcode", "name"])?;
                let name = g.get("name").map(|n| self.text(n, &el, "name")).transpose()?.unwrap_or_default();
                let seg = self.segment(self.req(&g, "at", &el)?, &el)?;
                if seg.len() < 2.0 * radius {
                    return Err(self.err(d.pos, &el, format!("{:.2} m wide: narrower than the robot", seg.len())));
                }
                // A door is a gap: no wall may cross its middle part.
                let inner = Seg::new(seg.at(0.05), seg.at(0.95));
                if let Some(k) = walls.iter().position(|w| w.intersects(&inner)) {
                    let k = wall_el.get(k).copied().unwrap_or(k + 1);
                    return Err(self.err(d.pos, &el, format!("wall {k} crosses the door (a door is a gap)")));
                }
                let barcode = g.get("barcode").map(|b| self.barcode(b, &format!("{el}, barcode"))).transpose()?;
                doors.push(Door { seg, barcode, name, line: d.pos.line });
            }
        }
        let mut barcodes = Vec::new();
        if let Some(bs) = f.get("barcodes") {
            for (i, b) in self.seq(bs, &fl, "barcodes")?.iter().enumerate() {
                barcodes.push(self.barcode(b, &format!("{fl}, barcode {}", i + 1))?);
            }
        }
        let lobby = match f.get("lobby") {
            Some(l) => {
                let el = format!("{fl}, lobby");
                let g = self.fields(l, &el, &["button", "facing_deg", "barcode"])?;
                let button = self.point(self.req(&g, "button", &el)?, &el, "button")?;
                let facing = self.num(self.req(&g, "facing_deg", &el)?, &el, "facing_deg")?.to_radians();
                let barcode = self.int(self.req(&g, "barcode", &el)?, &el, "barcode")?;
                Some(Lobby { line: l.pos.line, button, facing, barcode })
            }
            None => None,
        };
        let office = match f.get("office") {
            Some(o) => {
                let el = format!("{fl}, office");
                let g = self.fields(o, &el, &["rect", "polygon", "barcode"])?;
                let polygon = self.region(&g, &el)?;
                let barcode = self.barcode(self.req(&g, "barcode", &el)?, &format!("{el}, barcode"))?;
                Some(Office { polygon, barcode, line: o.pos.line })
            }
            None => None,
        };
        Ok(Floor {
            line: n.pos.line,
            level,
            name,
            walls,
            wall_refs,
            obstacles,
            obstacle_lines,
            doors,
            barcodes,
            lobby,
            office,
        })
    }

    fn range(&self, f: &Fields<'_>, key: &str, el: &str, default: (f64, f64)) -> Result<(f64, f64), MapError> {
        let Some(n) = f.get(key) else { return Ok(default) };
        let v = self.nums(n, el, key, 2)?;
        if v[0] < 0.0 || v[1] < v[0] {
            return Err(self.err(n.pos, el, format!("{key}: expected [min, max] with 0 <= min <= max")));
        }
        Ok((v[0], v[1]))
    }

    fn positive(&self, f: &Fields<'_>, key: &str, el: &str, default: f64) -> Result<f64, MapError> {
        let Some(n) = f.get(key) else { return Ok(default) };
        let x = self.num(n, el, key)?;
        if x <= 0.0 {
            return Err(self.err(n.pos, el, format!("{key} must be positive, got {x}")));
        }
        Ok(x)
    }

    fn elevator(&self, n: &N, radius: f64) -> Result<Elevator, MapError> {
        let el = "elevator";
        let f = self.fields(n, el, &["travel_s_per_floor", "door_move_s", "open_s", "arrive_s", "cars"])?;
        let travel_s_per_floor = self.positive(&f, "travel_s_per_floor", el, 2.0)?;
        let door_move_s = self.positive(&f, "door_move_s", el, 1.5)?;
        let open_s = self.range(&f, "open_s", el, (15.0, 25.0))?;
        let arrive_s = self.range(&f, "arrive_s", el, (5.0, 20.0))?;
        let cars_node = self.req(&f, "cars", el)?;
        let mut cars: Vec<Car> = Vec::new();
        for (i, c) in self.seq(cars_node, el, "cars")?.iter().enumerate() {
            let cel = format!("elevator, car {}", i + 1);
            let g = self.fields(c, &cel, &["id", "rect", "door", "door_width", "barcode"])?;
            let id = match g.get("id") {
                Some(n) => self.int(n, &cel, "id")?,
                None => i as i64 + 1,
            };
            if id != i as i64 + 1 {
                return Err(self.err(c.pos, &cel, format!("cars are numbered 1, 2, … in order; this one says {id}")));
            }
            let rn = self.req(&g, "rect", &cel)?;
            let v = self.nums(rn, &cel, "rect [x0, y0, x1, y1]", 4)?;
            if v[2] <= v[0] || v[3] <= v[1] {
                return Err(self.err(rn.pos, &cel, "rect [x0, y0, x1, y1] needs x0 < x1 and y0 < y1"));
            }
            let dn = self.req(&g, "door", &cel)?;
            let door_side = match self.text(dn, &cel, "door")?.as_str() {
                "north" => Side::North,
                "south" => Side::South,
                "east" => Side::East,
                "west" => Side::West,
                other => {
                    return Err(self.err(dn.pos, &cel, format!("door `{other}`: expected north, south, east or west")))
                }
            };
            let door_width = self.positive(&g, "door_width", &cel, 1.2)?;
            let side_len = match door_side {
                Side::North | Side::South => v[2] - v[0],
                Side::East | Side::West => v[3] - v[1],
            };
            if door_width > side_len || door_width < 2.0 * radius {
                return Err(self.err(
                    c.pos,
                    &cel,
                    format!("door_width {door_width} must fit the side ({side_len}) and the robot ({})", 2.0 * radius),
                ));
            }
            if v[2] - v[0] < 2.0 * radius || v[3] - v[1] < 2.0 * radius {
                return Err(self.err(rn.pos, &cel, "the car is smaller than the robot"));
            }
            let barcode = self.int(self.req(&g, "barcode", &cel)?, &cel, "barcode")?;
            let car =
                Car { line: c.pos.line, id, x0: v[0], y0: v[1], x1: v[2], y1: v[3], door_side, door_width, barcode };
            if let Some(k) = cars.iter().position(|o| o.x0 < car.x1 && car.x0 < o.x1 && o.y0 < car.y1 && car.y0 < o.y1)
            {
                return Err(self.err(rn.pos, &cel, format!("overlaps car {}", k + 1)));
            }
            cars.push(car);
        }
        if cars.is_empty() {
            return Err(self.err(cars_node.pos, el, "`cars` is empty"));
        }
        let lines = f.entries.iter().map(|(k, v)| (k.value.clone(), v.pos.line)).collect();
        Ok(Elevator { travel_s_per_floor, door_move_s, open_s, arrive_s, cars, lines })
    }

    fn mission(&self, n: &N) -> Result<Mission, MapError> {
        let el = "mission";
        let keys = [
            "start",
            "goal_floor",
            "lab_door_barcode",
            "call_button_barcode",
            "office_barcode",
            "car_barcode_first",
            "message",
            "route",
        ];
        let f = self.fields(n, el, &keys)?;
        let sn = self.req(&f, "start", el)?;
        let s = self.fields(sn, "mission, start", &["floor", "x", "y", "theta_deg"])?;
        let sel = "mission, start";
        let start_floor = self.int(self.req(&s, "floor", sel)?, sel, "floor")?;
        let x = self.num(self.req(&s, "x", sel)?, sel, "x")?;
        let y = self.num(self.req(&s, "y", sel)?, sel, "y")?;
        let theta = self.angle(&s, "theta_deg", sel)?.unwrap_or(0.0);
        let int = |key: &str| -> Result<i64, MapError> { self.int(self.req(&f, key, el)?, el, key) };
        let message = match f.get("message") {
            Some(m) => self.text(m, el, "message")?,
            None => "Hello! I have a message for you.".to_string(),
        };
        let mut route = Vec::new();
        if let Some(r) = f.get("route") {
            let Some(entries) = r.value.as_map() else {
                return Err(self.err(r.pos, el, "route: expected a mapping of leg name → list of steps"));
            };
            for (name, steps) in entries {
                let mut out = Vec::new();
                for (i, st) in self.seq(steps, el, "route")?.iter().enumerate() {
                    out.push(self.step(st, &format!("mission, route {}, step {}", name.value, i + 1))?);
                }
                route.push((name.value.clone(), out));
            }
        }
        let lines = f.entries.iter().map(|(k, v)| (k.value.clone(), v.pos.line)).collect();
        Ok(Mission {
            lines,
            start_floor,
            start: (x, y, theta),
            goal_floor: int("goal_floor")?,
            lab_door_barcode: int("lab_door_barcode")?,
            call_button_barcode: int("call_button_barcode")?,
            office_barcode: int("office_barcode")?,
            car_barcode_first: int("car_barcode_first")?,
            message,
            route,
        })
    }

    fn step(&self, n: &N, el: &str) -> Result<RouteStep, MapError> {
        let keys = ["follow", "until", "side", "turn", "barcode", "home", "pass", "count", "distance"];
        let f = self.fields(n, el, &keys)?;
        let word = |key: &str, allowed: &[&str]| -> Result<Option<String>, MapError> {
            let Some(v) = f.get(key) else { return Ok(None) };
            let t = self.text(v, el, key)?;
            if !allowed.contains(&t.as_str()) {
                return Err(self.err(v.pos, el, format!("{key}: `{t}` is not one of {}", allowed.join(", "))));
            }
            Ok(Some(t))
        };
        let step = RouteStep {
            follow: word("follow", &["hallway"])?,
            until: word("until", &["junction", "door", "barcode", "wall", "distance"])?,
            side: word("side", &["left", "right"])?,
            turn: word("turn", &["left", "right", "back"])?,
            barcode: f.get("barcode").map(|b| self.int(b, el, "barcode")).transpose()?,
            home: f.get("home").map(|b| self.int(b, el, "home")).transpose()?,
            pass: word("pass", &["door"])?,
            count: f.get("count").map(|c| self.int(c, el, "count")).transpose()?,
            distance: f.get("distance").map(|d| self.num(d, el, "distance")).transpose()?,
            line: n.pos.line,
        };
        if let (Some(c), Some(node)) = (step.count, f.get("count")) {
            if c < 1 {
                return Err(self.err(node.pos, el, format!("count must be at least 1, got {c}")));
            }
            if !matches!(step.until.as_deref(), Some("junction" | "door")) {
                return Err(self.err(node.pos, el, "`count` goes with `until: junction` or `until: door`"));
            }
        }
        if let (Some(d), Some(node)) = (step.distance, f.get("distance")) {
            if d <= 0.0 {
                return Err(self.err(node.pos, el, format!("distance must be positive, got {d}")));
            }
            if step.follow.is_none() {
                return Err(self.err(node.pos, el, "`distance` goes with `follow: hallway`"));
            }
        }
        if step.until.as_deref() == Some("distance") && step.distance.is_none() {
            return Err(self.err(n.pos, el, "`until: distance` needs `distance: M` (metres)"));
        }
        if step.follow.is_some() && step.until.is_none() {
            return Err(self.err(n.pos, el, "`follow` needs `until`"));
        }
        if step.until.as_deref() == Some("barcode") && step.barcode.is_none() {
            return Err(self.err(n.pos, el, "`until: barcode` needs `barcode: ID`"));
        }
        if step.follow.is_none() && step.turn.is_none() && step.home.is_none() && step.pass.is_none() {
            return Err(self.err(n.pos, el, "a step needs one of `follow`, `turn`, `home` or `pass`"));
        }
        Ok(step)
    }
}

struct Fields<'n> {
    node: &'n N,
    entries: &'n [(Spanned<String>, N)],
}

impl<'n> Fields<'n> {
    fn get(&self, key: &str) -> Option<&'n N> {
        self.entries.iter().find(|(k, _)| k.value == key).map(|(_, v)| v)
    }
}
