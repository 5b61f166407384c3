//! The loader's checks across elements, once every element is read: each
//! barcode id used once, the mission's floors and barcodes in the map, the
//! cars' barcodes numbered from `car_barcode_first`, route steps naming
//! barcodes that exist, one office on the goal floor, the start pose clear.

use std::collections::BTreeMap;

use situate_robotfile::diagnostic::Diagnostic;
use situate_robotfile::yaml::Pos;

use super::read::Reader;
use super::{Floor, Map};
use crate::geom::P2;

impl Map {
    /// Checks across elements (ids, references, geometry).
    pub(super) fn check(&self, r: &Reader<'_>) -> Result<(), Diagnostic> {
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
}
