//! What a generated building drew, of the cases `docs/maps.md` allows that the
//! delivery may find hard: written as a comment block at the top of the map
//! file and returned in [`super::Generated`], so a benchmark can count its
//! runs by them (`scripts/delivery.py`'s coverage table).

use std::fmt::Write as _;

use serde_json::{json, Value as Json};

/// The features of one generated building.
#[derive(Debug, Clone, PartialEq)]
pub struct Features {
    /// `facing` (the call button across from the lobby's entry) or `corner`
    /// (the button on a wall beside the entry, flush with it).
    pub lobby: &'static str,
    /// Each car's wall relative to the call button's (cars 1, 2, …): `same`,
    /// `side` or `across`.
    pub car_walls: Vec<&'static str>,
    /// The elevator's `open_s`, s.
    pub open_s: (f64, f64),
    /// A box within [`NEAR_BARCODE_M`] of the office barcode, on its wall.
    pub clutter_near_barcode: bool,
    /// A bin within [`NEAR_BARCODE_M`] of the lab door's barcode, on its wall
    /// (inside the lab, the far side from the door).
    pub clutter_near_lab_barcode: bool,
    /// How the corridors' widths were drawn: `narrow`, `middle` or `wide`
    /// (every one from that third of `--corridor-width`) or `mixed` (each
    /// from the whole range).
    pub corridor_band: &'static str,
    /// The narrowest and the widest corridor, m.
    pub corridor_width: (f64, f64),
    /// The start floor's junction into the lobby's corridor: `T`, `+` or `L`.
    pub junction_lobby: &'static str,
    /// Where the goal floor's corridor from the lobby ends: `T` or `L`.
    pub junction_goal: &'static str,
    /// The goal floor's junction into the office's corridor: `none` (the
    /// office is on the corridor the lobby's leads to), `T`, `+` or `L`.
    pub junction_office: &'static str,
    /// The side corridors the route passes by (`T`: on one side, `+`: both).
    pub junctions_passed: Vec<&'static str>,
}

/// "Near" the office barcode (and the lab door's), m.
pub const NEAR_BARCODE_M: f64 = 0.6;

impl Features {
    /// The open time's bucket, by its minimum: `short` (under 10 s),
    /// `medium` (under 13 s) or `long`.
    pub fn open_s_bucket(&self) -> &'static str {
        match self.open_s.0 {
            m if m < 10.0 => "short",
            m if m < 13.0 => "medium",
            _ => "long",
        }
    }

    /// The same as JSON: `{"lobby": …, "car_walls": […], "open_s": [lo, hi], …}`
    /// (the keys of [`Features::comment`]).
    pub fn to_json(&self) -> Json {
        json!({
            "lobby": self.lobby,
            "car_walls": self.car_walls,
            "open_s": [self.open_s.0, self.open_s.1],
            "open_s_bucket": self.open_s_bucket(),
            "clutter_near_barcode": self.clutter_near_barcode,
            "clutter_near_lab_barcode": self.clutter_near_lab_barcode,
            "corridor_width": self.corridor_band,
            "corridor_widths": [self.corridor_width.0, self.corridor_width.1],
            "junction_lobby": self.junction_lobby,
            "junction_goal": self.junction_goal,
            "junction_office": self.junction_office,
            "junctions_passed": self.junctions_passed,
        })
    }

    /// The comment block written at the top of the map file, each line
    /// `#   key: value` (a value is a word, a number or a `[list]`).
    pub fn comment(&self) -> String {
        let list = |v: &[&str]| format!("[{}]", v.join(", "));
        let mut s = String::new();
        let _ = writeln!(
            s,
            "# Features drawn (docs/maps.md, \"Generated buildings\"; scripts/delivery.py counts runs by them):"
        );
        let _ = writeln!(s, "#   lobby: {}", self.lobby);
        let _ = writeln!(s, "#   car_walls: {}", list(&self.car_walls));
        let _ = writeln!(s, "#   open_s: [{}, {}]", self.open_s.0, self.open_s.1);
        let _ = writeln!(s, "#   open_s_bucket: {}", self.open_s_bucket());
        let yes = |b: bool| if b { "yes" } else { "no" };
        let _ = writeln!(s, "#   clutter_near_barcode: {}", yes(self.clutter_near_barcode));
        let _ = writeln!(s, "#   clutter_near_lab_barcode: {}", yes(self.clutter_near_lab_barcode));
        let _ = writeln!(s, "#   corridor_width: {}", self.corridor_band);
        let _ = writeln!(s, "#   corridor_widths: [{}, {}]", self.corridor_width.0, self.corridor_width.1);
        let _ = writeln!(s, "#   junction_lobby: {}", self.junction_lobby);
        let _ = writeln!(s, "#   junction_goal: {}", self.junction_goal);
        let _ = writeln!(s, "#   junction_office: {}", self.junction_office);
        let _ = writeln!(s, "#   junctions_passed: {}", list(&self.junctions_passed));
        s
    }
}
