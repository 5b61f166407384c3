//! A loaded map as JSON: the world view the GUI draws, the whole building
//! (what `situate map show` prints) and the mission with its route hints.

use serde_json::{json, Value as Json};

use super::{Barcode, Car, Map, Side};
use crate::geom::Seg;

impl Map {
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
}
