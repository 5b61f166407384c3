//! Reading a map file: its size bounded, its YAML parsed, each element read
//! and checked on its own (unknown keys, types, ranges), every error naming
//! the file, the line and the element.

use std::path::Path;

use situate_robotfile::diagnostic::Diagnostic;
use situate_robotfile::yaml::{self, Node, Pos, Spanned};

use super::{Barcode, Car, Door, Elevator, Floor, Lobby, Map, Mission, Office, RouteStep, Side};
use crate::geom::{Seg, P2};

/// The largest map file read: 4 MiB (a larger one is refused before it is
/// read).
pub const MAX_MAP_FILE_BYTES: u64 = 4 << 20;

/// Reads and checks a map file of at most [`MAX_MAP_FILE_BYTES`].
pub fn load_map(path: impl AsRef<Path>) -> Result<Map, Diagnostic> {
    let path = path.as_ref();
    let file = path.display().to_string();
    let text = yaml::read_source(path, "map file", MAX_MAP_FILE_BYTES).map_err(|e| match e.pos() {
        Some(pos) => Diagnostic::new(&file, pos, e.to_string()),
        None => Diagnostic::whole_file(&file, e.to_string()),
    })?;
    Map::parse(&file, &text)
}

impl Map {
    /// Parses and checks map text; `file` names it in errors.
    pub fn parse(file: &str, text: &str) -> Result<Map, Diagnostic> {
        let root = yaml::parse(text).map_err(|e| Diagnostic::from(e).in_file(file))?;
        let r = Reader { file };
        let map = r.map(&root)?;
        map.check(&r)?;
        Ok(map)
    }
}

/// Reads the node tree, remembering the file for errors.
pub(super) struct Reader<'a> {
    file: &'a str,
}

type N = Spanned<Node>;

impl Reader<'_> {
    pub(super) fn err(&self, pos: Pos, element: &str, message: impl Into<String>) -> Diagnostic {
        // The element names the place; a column would point into its line, not at the problem.
        Diagnostic::new(self.file, Pos::new(pos.line, 0), message).about(element)
    }

    /// A mapping's entries, refusing keys not in `allowed`.
    fn fields<'n>(&self, n: &'n N, el: &str, allowed: &[&str]) -> Result<Fields<'n>, Diagnostic> {
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

    fn req<'n>(&self, f: &Fields<'n>, key: &str, el: &str) -> Result<&'n N, Diagnostic> {
        f.get(key).ok_or_else(|| self.err(f.node.pos, el, format!("missing `{key}`")))
    }

    fn num(&self, n: &N, el: &str, what: &str) -> Result<f64, Diagnostic> {
        match n.value.as_f64() {
            Some(x) if x.is_finite() => Ok(x),
            _ => Err(self.err(n.pos, el, format!("{what}: expected a number, got {}", n.value.describe()))),
        }
    }

    fn int(&self, n: &N, el: &str, what: &str) -> Result<i64, Diagnostic> {
        n.value
            .as_i64()
            .ok_or_else(|| self.err(n.pos, el, format!("{what}: expected an integer, got {}", n.value.describe())))
    }

    fn text(&self, n: &N, el: &str, what: &str) -> Result<String, Diagnostic> {
        match &n.value {
            Node::Scalar { text, .. } => Ok(text.clone()),
            other => Err(self.err(n.pos, el, format!("{what}: expected text, got {}", other.describe()))),
        }
    }

    fn seq<'n>(&self, n: &'n N, el: &str, what: &str) -> Result<&'n [N], Diagnostic> {
        match &n.value {
            Node::Seq(items) => Ok(items),
            Node::Null => Ok(&[]),
            other => Err(self.err(n.pos, el, format!("{what}: expected a list, got {}", other.describe()))),
        }
    }

    /// A list of exactly `k` numbers.
    fn nums(&self, n: &N, el: &str, what: &str, k: usize) -> Result<Vec<f64>, Diagnostic> {
        let items = self.seq(n, el, what)?;
        if items.len() != k {
            return Err(self.err(n.pos, el, format!("{what}: expected {k} numbers, got {}", items.len())));
        }
        items.iter().map(|i| self.num(i, el, what)).collect()
    }

    fn point(&self, n: &N, el: &str, what: &str) -> Result<P2, Diagnostic> {
        let v = self.nums(n, el, what, 2)?;
        Ok(P2::new(v[0], v[1]))
    }

    fn points(&self, n: &N, el: &str, what: &str) -> Result<Vec<P2>, Diagnostic> {
        self.seq(n, el, what)?.iter().map(|p| self.point(p, el, what)).collect()
    }

    fn segment(&self, n: &N, el: &str) -> Result<Seg, Diagnostic> {
        let v = self.nums(n, el, "segment [x1, y1, x2, y2]", 4)?;
        let s = Seg::new(P2::new(v[0], v[1]), P2::new(v[2], v[3]));
        if s.len() < 1e-6 {
            return Err(self.err(n.pos, el, "segment has zero length"));
        }
        Ok(s)
    }

    fn angle(&self, f: &Fields<'_>, key: &str, el: &str) -> Result<Option<f64>, Diagnostic> {
        f.get(key).map(|n| self.num(n, el, key).map(f64::to_radians)).transpose()
    }

    fn barcode(&self, n: &N, el: &str) -> Result<Barcode, Diagnostic> {
        let f = self.fields(n, el, &["id", "at", "facing_deg"])?;
        let id = self.int(self.req(&f, "id", el)?, el, "id")?;
        let at = self.point(self.req(&f, "at", el)?, el, "at")?;
        Ok(Barcode { id, at, facing: self.angle(&f, "facing_deg", el)?, line: n.pos.line })
    }

    /// A `{rect: [x0, y0, x1, y1]}` or `{polygon: [[x, y], …]}` region.
    fn region(&self, f: &Fields<'_>, el: &str) -> Result<Vec<P2>, Diagnostic> {
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

    fn map(&self, root: &N) -> Result<Map, Diagnostic> {
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

    fn floor(&self, n: &N, index: usize, radius: f64) -> Result<Floor, Diagnostic> {
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

    fn range(&self, f: &Fields<'_>, key: &str, el: &str, default: (f64, f64)) -> Result<(f64, f64), Diagnostic> {
        let Some(n) = f.get(key) else { return Ok(default) };
        let v = self.nums(n, el, key, 2)?;
        if v[0] < 0.0 || v[1] < v[0] {
            return Err(self.err(n.pos, el, format!("{key}: expected [min, max] with 0 <= min <= max")));
        }
        Ok((v[0], v[1]))
    }

    fn positive(&self, f: &Fields<'_>, key: &str, el: &str, default: f64) -> Result<f64, Diagnostic> {
        let Some(n) = f.get(key) else { return Ok(default) };
        let x = self.num(n, el, key)?;
        if x <= 0.0 {
            return Err(self.err(n.pos, el, format!("{key} must be positive, got {x}")));
        }
        Ok(x)
    }

    fn elevator(&self, n: &N, radius: f64) -> Result<Elevator, Diagnostic> {
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

    fn mission(&self, n: &N) -> Result<Mission, Diagnostic> {
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
        let int = |key: &str| -> Result<i64, Diagnostic> { self.int(self.req(&f, key, el)?, el, key) };
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

    fn step(&self, n: &N, el: &str) -> Result<RouteStep, Diagnostic> {
        let keys = ["follow", "until", "side", "turn", "barcode", "home", "pass", "count", "distance"];
        let f = self.fields(n, el, &keys)?;
        let word = |key: &str, allowed: &[&str]| -> Result<Option<String>, Diagnostic> {
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
