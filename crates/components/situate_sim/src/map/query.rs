//! The geometry and the lookups of a loaded map: a car's door, shaft walls
//! and panel; a floor by its level, every barcode (with its floor, or named
//! as errors name its element), a floor's fixed segments, the office.

use super::{Barcode, Car, Floor, Map, Office, Side};
use crate::geom::{in_polygon, Seg, P2};

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

impl Map {
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
