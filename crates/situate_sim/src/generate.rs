//! A building generator (`situate map generate`): a family of delivery
//! buildings, deterministic from a seed (same seed + options, byte-identical
//! YAML), in the format of `docs/maps.md`. The family and the options are
//! described there ("Generated buildings").
//!
//! The building is laid out in whole centimetres in a canonical frame (the lab
//! south of an east-west corridor, the lobby north of it), then mirrored
//! and/or rotated by a multiple of 90° and shifted to positive coordinates:
//! every coordinate stays exact. The route hints are worked out in the
//! canonical frame (left and right swap with the mirror). Each candidate is
//! loaded and linted ([`crate::check::lint`]); one with a finding is redrawn.

use rand_chacha::ChaCha8Rng;
use rand_core::{RngCore, SeedableRng};
use thiserror::Error;

use crate::check::lint;
use crate::map::Map;

mod family1;
mod features;
mod lobby;

pub use features::{Features, NEAR_BARCODE_M};

/// [`NEAR_BARCODE_M`] in cm.
const NEAR_BARCODE: i64 = 60;

/// The generator's options: each a range the seed draws from.
#[derive(Debug, Clone, PartialEq)]
pub struct Options {
    /// Floors in all (start, lobbies in between, goal): 2..=6.
    pub floors: (i64, i64),
    /// Elevator cars: 1..=4.
    pub cars: (i64, i64),
    /// Corridor width, m: within 1.8..=3.0.
    pub corridor_width: (f64, f64),
    /// Door width (lab, rooms, office, cars), m: within 0.8..=1.6.
    pub door_width: (f64, f64),
    /// Junctions on the start floor's way to the lobby (the last one turns
    /// towards the lobby): 1..=3.
    pub junctions: (i64, i64),
    /// Clutter boxes per metre of corridor wall (0..=1); `None`: drawn in 0..=0.3.
    pub clutter: Option<f64>,
    /// The elevator's `open_s`; `None`: drawn from [8, 12] … [15, 25].
    pub open_s: Option<(f64, f64)>,
    /// A door barcode's distance from the nearer jamb, m: within 0.05..=1.0.
    pub barcode_offset: (f64, f64),
    /// Write the route hints.
    pub route: bool,
    /// The family of buildings: 2 (the default) draws from the whole space the
    /// docs allow; 1 is the family before issue 37, frozen (the same seed, the
    /// same building as then).
    pub family: u32,
}

impl Default for Options {
    fn default() -> Options {
        Options {
            floors: (2, 6),
            cars: (1, 4),
            corridor_width: (1.8, 2.6),
            door_width: (1.0, 1.4),
            junctions: (1, 3),
            clutter: None,
            open_s: None,
            barcode_offset: (0.1, 0.6),
            route: true,
            family: 2,
        }
    }
}

/// Options out of range, or no building found.
#[derive(Debug, Error)]
pub enum GenError {
    #[error("--{option}: {message}")]
    Option { option: &'static str, message: String },
    #[error("seed {seed}: no building passed `map check` in {attempts} attempts (the last: {last})")]
    NoLayout { seed: u64, attempts: usize, last: String },
}

/// Parses `A..B` (or `A`, meaning `A..A`) as a range of numbers.
pub fn parse_range(text: &str) -> Result<(f64, f64), String> {
    let num = |s: &str| -> Result<f64, String> {
        s.trim().parse::<f64>().ok().filter(|x| x.is_finite()).ok_or_else(|| format!("`{s}` is not a number"))
    };
    let (lo, hi) = match text.split_once("..") {
        Some((a, b)) => (num(a)?, num(b.trim_start_matches('='))?),
        None => {
            let x = num(text)?;
            (x, x)
        }
    };
    if lo > hi {
        return Err(format!("`{text}`: the minimum is above the maximum"));
    }
    Ok((lo, hi))
}

/// [`parse_range`] of whole numbers.
pub fn parse_int_range(text: &str) -> Result<(i64, i64), String> {
    let (lo, hi) = parse_range(text)?;
    if lo.fract() != 0.0 || hi.fract() != 0.0 {
        return Err(format!("`{text}`: expected whole numbers"));
    }
    Ok((lo as i64, hi as i64))
}

impl Options {
    /// Checks every option against its bounds.
    pub fn validate(&self) -> Result<(), GenError> {
        fn within<T: PartialOrd + std::fmt::Display + Copy>(
            option: &'static str,
            (lo, hi): (T, T),
            min: T,
            max: T,
        ) -> Result<(), GenError> {
            if lo > hi || lo < min || hi > max {
                return Err(GenError::Option { option, message: format!("{lo}..{hi} is not within {min}..{max}") });
            }
            Ok(())
        }
        within("family", (self.family, self.family), 1, 2)?;
        within("floors", self.floors, 2, 6)?;
        within("cars", self.cars, 1, 4)?;
        within("corridor-width", self.corridor_width, 1.8, 3.0)?;
        // `situate map check`'s rules (docs/maps.md): a building outside them is never drawn, so
        // options outside them are refused here, with the range, not after 50 failed attempts.
        within("door-width", self.door_width, crate::check::DOOR_MIN, crate::check::DOOR_MAX)?;
        within("junctions", self.junctions, 1, 3)?;
        // The rule `situate map check` holds maps to (docs/maps.md, "Lab door").
        within("barcode-offset", self.barcode_offset, 0.1, 0.6)?;
        if let Some(c) = self.clutter {
            within("clutter", (c, c), 0.0, 1.0)?;
        }
        if let Some(o) = self.open_s {
            within("open-s", o, crate::check::OPEN_S_MIN, 600.0)?;
        }
        Ok(())
    }
}

/// A generated building.
#[derive(Debug, Clone)]
pub struct Generated {
    /// The map file's text.
    pub yaml: String,
    /// Every corridor's width, m.
    pub corridor_widths: Vec<f64>,
    /// Junctions on the start floor.
    pub junctions: usize,
    /// Clutter density drawn (boxes per metre of corridor wall).
    pub clutter: f64,
    /// Candidates drawn until one passed the lint (1: the first).
    pub attempts: usize,
    /// What it drew of the cases the docs allow (also the file's comment block).
    pub features: Features,
}

/// The most candidates drawn for one seed.
pub const MAX_ATTEMPTS: usize = 50;

/// Generates the building of `seed` with `opts`.
pub fn generate(seed: u64, opts: &Options) -> Result<Generated, GenError> {
    opts.validate()?;
    let mut rng = Rng(ChaCha8Rng::seed_from_u64(seed));
    let mut last = String::new();
    for attempt in 1..=MAX_ATTEMPTS {
        let b = if opts.family == 1 { family1::build(&mut rng, seed, opts) } else { build(&mut rng, seed, opts) };
        let yaml = b.building.emit(seed, opts.route, &b.features);
        match Map::parse(&format!("seed-{seed}.yaml"), &yaml) {
            Err(e) => last = e.to_string(),
            Ok(map) => match lint(&map).first() {
                Some(f) => last = f.render(&format!("seed-{seed}.yaml")),
                None => {
                    return Ok(Generated {
                        yaml,
                        corridor_widths: b.corridor_widths.iter().map(|&w| w as f64 / 100.0).collect(),
                        junctions: b.junctions,
                        clutter: b.clutter,
                        attempts: attempt,
                        features: b.features,
                    })
                }
            },
        }
    }
    Err(GenError::NoLayout { seed, attempts: MAX_ATTEMPTS, last })
}

struct Rng(ChaCha8Rng);

impl Rng {
    fn int(&mut self, lo: i64, hi: i64) -> i64 {
        if hi <= lo {
            return lo;
        }
        lo + (self.0.next_u64() % ((hi - lo + 1) as u64)) as i64
    }
    fn cm(&mut self, (lo, hi): (f64, f64)) -> i64 {
        self.int(cm(lo), cm(hi))
    }
    fn coin(&mut self) -> bool {
        self.0.next_u64() & 1 == 1
    }
    fn unit(&mut self) -> f64 {
        (self.0.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }
    fn shuffle<T>(&mut self, v: &mut [T]) {
        for i in (1..v.len()).rev() {
            let j = self.int(0, i as i64) as usize;
            v.swap(i, j);
        }
    }
}

fn cm(m: f64) -> i64 {
    (m * 100.0).round() as i64
}

/// A point in centimetres.
type Pt = (i64, i64);

#[derive(Debug, Clone, Copy)]
struct Bar {
    id: i64,
    at: Pt,
    facing: i64,
}

#[derive(Debug, Clone)]
struct DoorB {
    name: String,
    a: Pt,
    b: Pt,
    barcode: Option<Bar>,
}

#[derive(Debug, Clone, Default)]
struct FloorB {
    level: i64,
    name: String,
    walls: Vec<(Pt, Pt)>,
    obstacles: Vec<(String, Pt, Pt)>,
    doors: Vec<DoorB>,
    lobby: Option<Bar>,
    office: Option<(Pt, Pt, Bar)>,
}

impl FloorB {
    fn wall(&mut self, a: Pt, b: Pt) {
        if a != b {
            self.walls.push((a, b));
        }
    }

    /// A wall along y = `y` from x0 to x1, leaving the gaps (x ranges) open.
    fn hwall(&mut self, y: i64, x0: i64, x1: i64, gaps: &[(i64, i64)]) {
        for (a, b) in runs(x0, x1, gaps) {
            self.wall((a, y), (b, y));
        }
    }

    /// A wall along x = `x` from y0 to y1, leaving the gaps (y ranges) open.
    fn vwall(&mut self, x: i64, y0: i64, y1: i64, gaps: &[(i64, i64)]) {
        for (a, b) in runs(y0, y1, gaps) {
            self.wall((x, a), (x, b));
        }
    }
}

/// The parts of [lo, hi] outside the gaps.
fn runs(lo: i64, hi: i64, gaps: &[(i64, i64)]) -> Vec<(i64, i64)> {
    let mut g: Vec<(i64, i64)> = gaps.to_vec();
    g.sort();
    let mut out = Vec::new();
    let mut at = lo;
    for (a, b) in g {
        if a > at {
            out.push((at, a.min(hi)));
        }
        at = at.max(b);
    }
    if at < hi {
        out.push((at, hi));
    }
    out.retain(|(a, b)| b > a);
    out
}

#[derive(Debug, Clone, Copy)]
struct CarB {
    lo: Pt,
    hi: Pt,
    /// Out of the car through its door (a unit vector).
    out: Pt,
    door: i64,
}

#[derive(Debug, Clone)]
struct Step(Vec<(&'static str, String)>);

#[derive(Debug, Clone, Default)]
struct Building {
    floors: Vec<FloorB>,
    cars: Vec<CarB>,
    start: (i64, i64, i64),
    start_level: i64,
    goal_level: i64,
    open_s: (f64, f64),
    lab_to_lobby: Vec<Step>,
    button_to_office: Vec<Step>,
}

struct Built {
    building: Building,
    corridor_widths: Vec<i64>,
    junctions: usize,
    clutter: f64,
    features: Features,
}

fn turn(s: &str) -> Step {
    Step(vec![("turn", s.to_string())])
}

/// Until the junction on `side` whose near edge is at `edge`, from `from`
/// (along the corridor, cm), it being the `count`-th there.
///
/// With room for it, the step first follows the corridor to 1.5 m before the
/// junction without looking (`distance`), then takes the first junction: the
/// ones before it are 1.5 m or more back, and the junction detector, started
/// there, sees too little of them to count them. A door or clutter taken for a
/// junction on the way cannot then be miscounted.
fn junction_step(side: &str, from: i64, edge: i64, count: usize) -> Step {
    let mut step = vec![("follow", "hallway".to_string()), ("until", "junction".into()), ("side", side.into())];
    let blind = edge - 150 - from;
    if blind >= 100 {
        step.push(("distance", metres(blind)));
        step.push(("count", "1".into()));
    } else {
        step.push(("count", count.to_string()));
    }
    step.push(("turn", side.into()));
    Step(step)
}

fn flip_word(s: &str) -> String {
    match s {
        "left" => "right".into(),
        "right" => "left".into(),
        o => o.into(),
    }
}

/// A corridor wall clutter may line: horizontal (y fixed) or vertical, the
/// side the corridor is on (+1/−1), its extent and where it must stay clear.
struct Run {
    horizontal: bool,
    fixed: i64,
    inward: i64,
    from: i64,
    to: i64,
    /// Ranges along the run with no box (doors with their margins, mouths).
    keep_clear: Vec<(i64, i64)>,
}

/// Lays clutter boxes (0.2–0.5 m) along the runs, never leaving less than
/// 1.2 m between a box and one on another wall (across the corridor, or
/// round a corner), in any direction.
fn clutter(rng: &mut Rng, f: &mut FloorB, runs_: &[Run], density: f64, boxes: &mut Vec<(Pt, Pt, (bool, i64))>) {
    for r in runs_ {
        let len = (r.to - r.from) as f64 / 100.0;
        let n = (density * len).round() as usize;
        for _ in 0..n {
            let a = rng.int(20, 50);
            let d = rng.int(20, 50);
            let s = rng.int(r.from, r.to - a);
            if s < r.from || r.keep_clear.iter().any(|&(c0, c1)| s < c1 && s + a > c0) {
                continue;
            }
            let (n0, n1) = if r.inward > 0 { (r.fixed + 1, r.fixed + 1 + d) } else { (r.fixed - 1 - d, r.fixed - 1) };
            let (lo, hi) = if r.horizontal { ((s, n0), (s + a, n1)) } else { ((n0, s), (n1, s + a)) };
            // At least 1.2 m from every box on another wall, in any direction (boxes staggered
            // on facing walls leave only the diagonal between them), and 10 cm from those on
            // this wall.
            let wall = (r.horizontal, r.fixed);
            let too_near = |&(blo, bhi, bwall): &(Pt, Pt, (bool, i64))| {
                let gap = |a0: i64, a1: i64, b0: i64, b1: i64| (b0 - a1).max(a0 - b1).max(0);
                let (gx, gy) = (gap(lo.0, hi.0, blo.0, bhi.0), gap(lo.1, hi.1, blo.1, bhi.1));
                let min = if bwall == wall { 10 } else { 120 };
                gx * gx + gy * gy < min * min
            };
            if boxes.iter().any(too_near) {
                continue;
            }
            boxes.push((lo, hi, wall));
            let name = if rng.coin() { "bin" } else { "box" };
            f.obstacles.push((name.to_string(), lo, hi));
        }
    }
}

/// A door with its barcode beside it, on a horizontal wall (y fixed) at
/// [x0, x0 + w]; the barcode faces `facing` (90 or −90) and sits on that side.
#[allow(clippy::too_many_arguments)]
fn hdoor(rng: &mut Rng, name: &str, y: i64, x0: i64, w: i64, off: (f64, f64), id: i64, facing: i64) -> DoorB {
    let o = rng.cm(off);
    let bx = if rng.coin() { x0 - o } else { x0 + w + o };
    let by = y + facing.signum() * rng.int(1, 2);
    DoorB { name: name.into(), a: (x0, y), b: (x0 + w, y), barcode: Some(Bar { id, at: (bx, by), facing }) }
}

/// The same on a vertical wall (x fixed), the barcode facing 0 or 180.
#[allow(clippy::too_many_arguments)]
fn vdoor(rng: &mut Rng, name: &str, x: i64, y0: i64, w: i64, off: (f64, f64), id: i64, facing: i64) -> DoorB {
    let o = rng.cm(off);
    let by = if rng.coin() { y0 - o } else { y0 + w + o };
    let bx = if facing == 0 { x + rng.int(1, 2) } else { x - rng.int(1, 2) };
    DoorB { name: name.into(), a: (x, y0), b: (x, y0 + w), barcode: Some(Bar { id, at: (bx, by), facing }) }
}

/// Which way to turn, facing the barcode (it faces `facing`), to face the
/// door beside it: left or right (canonical frame).
fn side_of_door(d: &DoorB) -> &'static str {
    let Some(b) = d.barcode else { return "left" };
    let f = match b.facing {
        0 => (1, 0),
        90 => (0, 1),
        180 => (-1, 0),
        _ => (0, -1),
    };
    let look = (-f.0, -f.1);
    let centre2 = (d.a.0 + d.b.0, d.a.1 + d.b.1);
    let v = (centre2.0 - 2 * b.at.0, centre2.1 - 2 * b.at.1);
    if look.0 * v.1 - look.1 * v.0 > 0 {
        "left"
    } else {
        "right"
    }
}

enum Feature {
    /// A dead-end side corridor: north, south or both (+).
    Junction { north: bool, south: bool },
    /// A room behind a door, north or south of the corridor.
    Room { north: bool },
}

/// Lays a corridor's side features along x from `c`: junction stubs and rooms
/// (their doors' barcodes numbered from `next_id`). Returns the new cursor
/// and how many junction openings lie on the south side and the north side.
#[allow(clippy::too_many_arguments)]
fn features(
    rng: &mut Rng,
    f: &mut FloorB,
    opts: &Options,
    list: &[Feature],
    mut c: i64,
    (ys, yn): (i64, i64),
    max_north: i64,
    next_id: &mut i64,
    north_gaps: &mut Vec<(i64, i64)>,
    south_gaps: &mut Vec<(i64, i64)>,
    widths: &mut Vec<i64>,
) -> (i64, usize, usize) {
    let off_hi = cm(opts.barcode_offset.1);
    let (mut south_open, mut north_open) = (0, 0);
    for feat in list {
        match *feat {
            Feature::Junction { north, south } => {
                let w = rng.cm(opts.corridor_width);
                widths.push(w);
                if north {
                    let l = rng.int(200, 350).min(max_north);
                    f.vwall(c, yn, yn + l, &[]);
                    f.vwall(c + w, yn, yn + l, &[]);
                    f.hwall(yn + l, c, c + w, &[]);
                    north_gaps.push((c, c + w));
                    north_open += 1;
                }
                if south {
                    let l = rng.int(200, 350);
                    f.vwall(c, ys - l, ys, &[]);
                    f.vwall(c + w, ys - l, ys, &[]);
                    f.hwall(ys - l, c, c + w, &[]);
                    south_gaps.push((c, c + w));
                    south_open += 1;
                }
                c += w + rng.int(150, 300);
            }
            Feature::Room { north } => {
                let dw = rng.cm(opts.door_width);
                let rw = (dw + 2 * (off_hi + 50)).max(300) + rng.int(0, 100);
                let rd = rng.int(250, 350).min(if north { max_north } else { 350 });
                let x0 = rng.int(c + off_hi + 40, c + rw - dw - off_hi - 40);
                let id = *next_id;
                *next_id += 1;
                let (y, far, facing) = if north { (yn, yn + rd, -90) } else { (ys, ys - rd, 90) };
                f.doors.push(hdoor(rng, "room", y, x0, dw, opts.barcode_offset, id, facing));
                f.vwall(c, y.min(far), y.max(far), &[]);
                f.vwall(c + rw, y.min(far), y.max(far), &[]);
                f.hwall(far, c, c + rw, &[]);
                if north {
                    north_gaps.push((x0, x0 + dw));
                } else {
                    south_gaps.push((x0, x0 + dw));
                }
                c += rw + rng.int(80, 200);
            }
        }
    }
    (c, south_open, north_open)
}

/// The kinds of the junctions in `list`: `T` (one side) or `+` (both).
fn junction_kinds(list: &[Feature]) -> Vec<&'static str> {
    list.iter()
        .filter_map(|f| match f {
            Feature::Junction { north: true, south: true } => Some("+"),
            Feature::Junction { .. } => Some("T"),
            Feature::Room { .. } => None,
        })
        .collect()
}

fn junction_list(rng: &mut Rng, n: i64) -> Vec<Feature> {
    (0..n)
        .map(|_| match rng.int(0, 2) {
            0 => Feature::Junction { north: true, south: false },
            1 => Feature::Junction { north: false, south: true },
            _ => Feature::Junction { north: true, south: true },
        })
        .collect()
}

/// Door gaps with a 0.6 m margin each side (no clutter there).
fn door_margins(gaps: &[(i64, i64)], doors: &[(i64, i64)]) -> Vec<(i64, i64)> {
    gaps.iter().map(|&(a, b)| if doors.contains(&(a, b)) { (a - 60, b + 60) } else { (a, b) }).collect()
}

fn build(rng: &mut Rng, seed: u64, opts: &Options) -> Built {
    let mut widths = Vec::new();
    let nfloors = rng.int(opts.floors.0, opts.floors.1);
    let ncars = rng.int(opts.cars.0, opts.cars.1);
    let start_level = rng.int(-1, 0);
    let goal_level = start_level + nfloors - 1;
    let density = opts.clutter.unwrap_or_else(|| (rng.unit() * 30.0).round() / 100.0);
    // The shortest open times the docs allow ([8, 12]) in one building of four, the others
    // anywhere from there to [15, 25].
    let open_s = opts.open_s.unwrap_or_else(|| {
        let t = if rng.int(0, 3) == 0 { 0.0 } else { rng.unit() };
        (((8.0 + 7.0 * t) * 10.0).round() / 10.0, ((12.0 + 13.0 * t) * 10.0).round() / 10.0)
    });
    // Corridor widths: in half the buildings each drawn over the whole range, in the others
    // all from its lower, middle or upper third (every corridor narrow, or every one wide).
    let corridor_band;
    let opts = &{
        let (lo, hi) = opts.corridor_width;
        let third = (hi - lo) / 3.0;
        let (name, band) = match rng.int(0, 5) {
            0 => ("narrow", (lo, lo + third)),
            1 => ("middle", (lo + third, hi - third)),
            2 => ("wide", (hi - third, hi)),
            _ => ("mixed", (lo, hi)),
        };
        corridor_band = name;
        Options { corridor_width: ((band.0 * 100.0).round() / 100.0, (band.1 * 100.0).round() / 100.0), ..opts.clone() }
    };
    let off = opts.barcode_offset;
    let off_hi = cm(off.1);

    // --- the lobby, in its own frame (south-west corner at 0, 0) ---
    let wb = rng.cm(opts.corridor_width); // the corridor into the lobby, and its entry
    widths.push(wb);
    let boff = rng.int(1, 2);
    let lobby = lobby::layout(rng, ncars as usize, wb, opts.door_width, boff);
    let ex = lobby.entry.0 + wb / 2; // the entry's centre (x, lobby frame), as the corridor's

    // --- the start floor (canonical: the corridor along x at y 0..w) ---
    let mut fs = FloorB { level: start_level, name: "start".into(), ..FloorB::default() };
    let w = rng.cm(opts.corridor_width);
    widths.push(w);
    let (lab_w, lab_h) = (rng.int(500, 900), rng.int(400, 700));
    let dw = rng.cm(opts.door_width);
    let lab_x0 = rng.int(off_hi + 50, lab_w - dw - off_hi - 50);
    fs.doors.push(hdoor(rng, "lab", 0, lab_x0, dw, off, 10, -90));
    fs.vwall(0, -lab_h, 0, &[]);
    fs.hwall(-lab_h, 0, lab_w, &[]);
    fs.vwall(lab_w, -lab_h, 0, &[]);
    // The start pose, clear of the door's approach.
    let start = (rng.int(100, lab_w - 100), rng.int(-lab_h + 100, -lab_h + 100 + (lab_h - 330).max(0)));
    let start_theta = 90 * rng.int(-1, 2);
    // Furniture against the lab's walls.
    let keep_out = [
        ((start.0 - 70, start.1 - 70), (start.0 + 70, start.1 + 70)),
        ((lab_x0 - off_hi - 90, -230), (lab_x0 + dw + off_hi + 90, 0)),
    ];
    let mut pieces: Vec<(Pt, Pt)> = Vec::new();
    let want = rng.int(2, 6);
    let names = ["desk", "table", "bench", "cabinet", "shelf", "robot parts"];
    for name in names.iter().take(want as usize) {
        for _ in 0..30 {
            let (a, d) = (rng.int(40, 160), rng.int(40, 90));
            let (lo, hi) = match rng.int(0, 3) {
                0 => {
                    let y = rng.int(-lab_h, -a);
                    ((0, y), (d, y + a))
                }
                1 => {
                    let y = rng.int(-lab_h, -a);
                    ((lab_w - d, y), (lab_w, y + a))
                }
                2 => {
                    let x = rng.int(0, lab_w - a);
                    ((x, -lab_h), (x + a, -lab_h + d))
                }
                _ => {
                    let x = rng.int(0, lab_w - a);
                    ((x, -d), (x + a, 0))
                }
            };
            let hits = |(p, q): &(Pt, Pt), gap: i64| {
                lo.0 < q.0 + gap && p.0 - gap < hi.0 && lo.1 < q.1 + gap && p.1 - gap < hi.1
            };
            if keep_out.iter().any(|r| hits(r, 0)) || pieces.iter().any(|r| hits(r, 75)) {
                continue;
            }
            pieces.push((lo, hi));
            fs.obstacles.push((name.to_string(), lo, hi));
            break;
        }
    }
    // The corridor: west end, the features, the junction to the lobby, the east end.
    let xw = -rng.int(0, 150);
    let nj = rng.int(opts.junctions.0, opts.junctions.1);
    let mut list = junction_list(rng, nj - 1);
    for _ in 0..rng.int(1, 3) {
        list.push(Feature::Room { north: rng.coin() });
    }
    rng.shuffle(&mut list);
    let mut passed = junction_kinds(&list);
    let (mut north_gaps, mut south_gaps) = (Vec::new(), vec![(lab_x0, lab_x0 + dw)]);
    let mut next_id = 11;
    let lb = rng.int(450, 650);
    let c0 = lab_w + rng.int(80, 200);
    let (jx, _, north_open) = features(
        rng,
        &mut fs,
        opts,
        &list,
        c0,
        (0, w),
        lb - 60,
        &mut next_id,
        &mut north_gaps,
        &mut south_gaps,
        &mut widths,
    );
    // The junction to the lobby, north: a T (the corridor goes on to a dead end), a + (and a
    // stub south) or an L (the corridor ends there).
    let junction_lobby = ["T", "+", "L"][rng.int(0, 2) as usize];
    north_gaps.push((jx, jx + wb));
    fs.vwall(jx, w, w + lb, &[]);
    fs.vwall(jx + wb, w, w + lb, &[]);
    if junction_lobby == "+" {
        let l = rng.int(200, 350);
        let ws = rng.cm(opts.corridor_width);
        widths.push(ws);
        let sx = jx + wb / 2 - ws / 2;
        fs.vwall(sx, -l, 0, &[]);
        fs.vwall(sx + ws, -l, 0, &[]);
        fs.hwall(-l, sx, sx + ws, &[]);
        south_gaps.push((sx, sx + ws));
    }
    let xe = if junction_lobby == "L" { jx + wb } else { jx + wb + rng.int(200, 400) };
    fs.vwall(xw, 0, w, &[]);
    fs.vwall(xe, 0, w, &[]);
    fs.hwall(w, xw, xe, &north_gaps);
    fs.hwall(0, xw, xe, &south_gaps);
    // The lobby above the corridor, its entry on the junction's corridor.
    let (ox, oy) = (jx + wb / 2 - ex, w + lb);
    lobby::walls(&lobby, &mut fs, (ox, oy), true);
    let button = |id: i64| Bar { id, at: (ox + lobby.button.at.0, oy + lobby.button.at.1), ..lobby.button };
    fs.lobby = Some(button(30));
    let door_gaps_s: Vec<(i64, i64)> = fs.doors.iter().map(|d| (d.a.0, d.b.0)).collect();
    let mut boxes = Vec::new();
    let runs_s = [
        Run {
            horizontal: true,
            fixed: w,
            inward: -1,
            from: xw,
            to: xe,
            keep_clear: door_margins(&north_gaps, &door_gaps_s),
        },
        Run {
            horizontal: true,
            fixed: 0,
            inward: 1,
            from: xw,
            to: xe,
            keep_clear: door_margins(&south_gaps, &door_gaps_s),
        },
        Run { horizontal: false, fixed: jx, inward: 1, from: w, to: w + lb, keep_clear: vec![] },
        Run { horizontal: false, fixed: jx + wb, inward: -1, from: w, to: w + lb, keep_clear: vec![] },
    ];
    clutter(rng, &mut fs, &runs_s, density, &mut boxes);
    // At an L the corridor's end wall says where to turn; at a T or a + the junction.
    let to_lobby = if junction_lobby == "L" {
        Step(vec![("follow", "hallway".into()), ("until", "wall".into()), ("turn", "left".into())])
    } else {
        junction_step("left", lab_x0 + dw / 2, jx, north_open + 1)
    };
    let mut lab_to_lobby = vec![
        turn("right"),
        to_lobby,
        Step(vec![
            ("follow", "hallway".into()),
            ("until", "distance".into()),
            ("distance", metres(w / 2 + lb + lobby.inside)),
        ]),
    ];
    lab_to_lobby.extend(lobby.turn_in.map(turn));
    lab_to_lobby.push(Step(vec![("home", "30".into())]));

    // --- the floors in between: the lobby, closed ---
    let mut floors = vec![fs];
    for k in 1..nfloors - 1 {
        let mut f = FloorB { level: start_level + k, ..FloorB::default() };
        lobby::walls(&lobby, &mut f, (ox, oy), false);
        f.lobby = Some(button(30 + k));
        floors.push(f);
    }

    // --- the goal floor: the lobby, a corridor south to a corridor along x ---
    let mut fg = FloorB { level: goal_level, name: "goal".into(), ..FloorB::default() };
    let goal_flip = rng.coin();
    let xc = jx + wb / 2; // the entry's centre line (mirror axis of the goal corridors)
    let w2 = rng.cm(opts.corridor_width);
    widths.push(w2);
    let lb2 = rng.int(350, 550);
    let y1 = oy - lb2;
    let y0 = y1 - w2;
    // Built in u = x - xc, mirrored at the end if goal_flip.
    let mut gf = FloorB::default();
    // u = x - xc: the entry is [-wb / 2, wb - wb / 2].
    gf.vwall(-wb / 2, y1, oy, &[]);
    gf.vwall(wb - wb / 2, y1, oy, &[]);
    let mut north_g = vec![(-wb / 2, wb - wb / 2)];
    let mut south_g: Vec<(i64, i64)> = Vec::new();
    // The lobby's corridor ends in a T (a dead end the other way) or an L.
    let junction_goal = if rng.coin() { "T" } else { "L" };
    let uw = if junction_goal == "L" { -wb / 2 } else { -wb / 2 - rng.int(200, 400) };
    let side_corridor = rng.coin();
    let njd = if side_corridor { rng.int(0, 1) } else { rng.int(1, 2) };
    let mut list = junction_list(rng, njd);
    for _ in 0..rng.int(0, 2) {
        list.push(Feature::Room { north: rng.coin() });
    }
    rng.shuffle(&mut list);
    passed.extend(junction_kinds(&list));
    let mut next_id = 41;
    let c0 = wb - wb / 2 + rng.int(150, 250);
    let (c, south_open, _) = features(
        rng,
        &mut gf,
        opts,
        &list,
        c0,
        (y0, y1),
        lb2 - 60,
        &mut next_id,
        &mut north_g,
        &mut south_g,
        &mut widths,
    );
    let mut runs_g = Vec::new();
    // The steps after the lobby's (mirrored with the goal corridors).
    let mut button_to_office =
        vec![Step(vec![("follow", "hallway".into()), ("until", "wall".into()), ("turn", "left".into())])];
    let ue;
    // Where a box may stand beside the office barcode, on its wall: along which wall (horizontal,
    // fixed, inward), the barcode's and the door's places along it and the office's stretch.
    let near_barcode: (bool, i64, i64, i64, (i64, i64), (i64, i64));
    let junction_office;
    if side_corridor {
        // The office on a corridor going south from a junction: a T (the corridor along x goes on
        // to a dead end), a + (and a stub north) or an L (it ends there).
        junction_office = ["T", "+", "L"][rng.int(0, 2) as usize];
        let wc = rng.cm(opts.corridor_width);
        widths.push(wc);
        south_g.push((c, c + wc));
        if junction_office == "+" {
            let l = rng.int(200, 350).min(lb2 - 60);
            gf.vwall(c, y1, y1 + l, &[]);
            gf.vwall(c + wc, y1, y1 + l, &[]);
            gf.hwall(y1 + l, c, c + wc, &[]);
            north_g.push((c, c + wc));
        }
        let mut rooms = vec![true];
        if rng.coin() {
            rooms.push(false);
        }
        rng.shuffle(&mut rooms);
        let mut yb = y0 - rng.int(100, 200);
        let mut east_gaps = Vec::new();
        let mut door_gaps = Vec::new();
        let mut found = None;
        let mut near = None;
        for is_office in rooms {
            let dwr = rng.cm(opts.door_width);
            let rh = (dwr + 2 * (off_hi + 50)).max(350) + rng.int(0, 100);
            let depth = rng.int(300, 450);
            let d0 = rng.int(yb - rh + off_hi + 40, yb - dwr - off_hi - 40);
            let id = if is_office { 40 } else { next_id };
            if !is_office {
                next_id += 1;
            }
            let door = vdoor(rng, if is_office { "office" } else { "room" }, c + wc, d0, dwr, off, id, 180);
            gf.hwall(yb, c + wc, c + wc + depth, &[]);
            gf.hwall(yb - rh, c + wc, c + wc + depth, &[]);
            gf.vwall(c + wc + depth, yb - rh, yb, &[]);
            east_gaps.push((d0, d0 + dwr));
            door_gaps.push((d0, d0 + dwr));
            if is_office {
                let bar = door.barcode.unwrap_or(Bar { id: 40, at: (0, 0), facing: 180 });
                near = Some((false, c + wc, -1, bar.at.1, (d0, d0 + dwr), (yb - rh, yb)));
                gf.office = Some(((c + wc, yb - rh), (c + wc + depth, yb), bar));
                found = Some(DoorB { barcode: None, ..door.clone() });
            }
            gf.doors.push(DoorB { barcode: if is_office { None } else { door.barcode }, ..door });
            yb -= rh;
        }
        let yend = yb - rng.int(100, 250);
        gf.vwall(c, yend, y0, &[]);
        gf.vwall(c + wc, yend, y0, &east_gaps);
        gf.hwall(yend, c, c + wc, &[]);
        runs_g.push(Run { horizontal: false, fixed: c, inward: 1, from: yend, to: y0, keep_clear: vec![] });
        runs_g.push(Run {
            horizontal: false,
            fixed: c + wc,
            inward: -1,
            from: yend,
            to: y0,
            keep_clear: door_margins(&east_gaps, &door_gaps),
        });
        near_barcode = near.unwrap_or((false, 0, 1, 0, (0, 0), (0, 0)));
        if junction_office == "L" {
            ue = c + wc;
            button_to_office.push(Step(vec![
                ("follow", "hallway".into()),
                ("until", "wall".into()),
                ("turn", "right".into()),
            ]));
        } else {
            ue = c + wc + rng.int(200, 350);
            // From the T's middle (x 0), where `until: wall` stopped.
            button_to_office.push(junction_step("right", 0, c, south_open + 1));
        }
        let d = found.unwrap_or_else(|| DoorB { name: String::new(), a: (0, 0), b: (0, 1), barcode: None });
        let bar = gf.office.map(|o| o.2);
        let full = DoorB { barcode: bar, ..d };
        button_to_office.extend(office_steps(&full));
    } else {
        // The office beside the corridor along x.
        let north = lb2 - 60 >= 300 && rng.coin();
        let dwr = rng.cm(opts.door_width);
        let ow = (dwr + 2 * (off_hi + 50)).max(350) + rng.int(0, 150);
        let od = rng.int(300, 420).min(if north { lb2 - 60 } else { 420 });
        let x0 = rng.int(c + off_hi + 40, c + ow - dwr - off_hi - 40);
        let (y, far, facing) = if north { (y1, y1 + od, -90) } else { (y0, y0 - od, 90) };
        let door = hdoor(rng, "office", y, x0, dwr, off, 40, facing);
        gf.vwall(c, y.min(far), y.max(far), &[]);
        gf.vwall(c + ow, y.min(far), y.max(far), &[]);
        gf.hwall(far, c, c + ow, &[]);
        if north {
            north_g.push((x0, x0 + dwr));
        } else {
            south_g.push((x0, x0 + dwr));
        }
        let bar = door.barcode.unwrap_or(Bar { id: 40, at: (0, 0), facing });
        junction_office = "none";
        near_barcode = (true, y, if north { -1 } else { 1 }, bar.at.0, (x0, x0 + dwr), (c, c + ow));
        gf.office = Some(((c, y.min(far)), (c + ow, y.max(far)), bar));
        gf.doors.push(DoorB { barcode: None, ..door.clone() });
        button_to_office.extend(office_steps(&door));
        ue = c + ow + rng.int(200, 350);
    }
    gf.vwall(uw, y0, y1, &[]);
    gf.vwall(ue, y0, y1, &[]);
    gf.hwall(y1, uw, ue, &north_g);
    gf.hwall(y0, uw, ue, &south_g);
    let all_doors: Vec<(i64, i64)> = gf.doors.iter().filter(|d| d.a.1 == d.b.1).map(|d| (d.a.0, d.b.0)).collect();
    // The wall facing the corridor from the lobby stays clear of doors and clutter.
    let mouth = (-wb / 2 - 60, wb - wb / 2 + 60);
    let mut south_keep = door_margins(&south_g, &all_doors);
    south_keep.push(mouth);
    runs_g.push(Run {
        horizontal: true,
        fixed: y1,
        inward: -1,
        from: uw,
        to: ue,
        keep_clear: door_margins(&north_g, &all_doors),
    });
    runs_g.push(Run { horizontal: true, fixed: y0, inward: 1, from: uw, to: ue, keep_clear: south_keep });
    runs_g.push(Run { horizontal: false, fixed: -wb / 2, inward: 1, from: y1, to: oy, keep_clear: vec![] });
    runs_g.push(Run { horizontal: false, fixed: wb - wb / 2, inward: -1, from: y1, to: oy, keep_clear: vec![] });
    // In half the buildings a box beside the office barcode, on its wall (the far side from the
    // door), laid first: the other clutter keeps its distances from it.
    let mut boxes = Vec::new();
    if rng.coin() {
        box_beside(rng, &mut gf, near_barcode, &mut boxes);
    }
    clutter(rng, &mut gf, &runs_g, density, &mut boxes);
    let (nh, nfixed, _, np, _, _) = near_barcode;
    let clutter_near_barcode = boxes.iter().any(|&(lo, hi, wall)| {
        let (a, b) = if nh { (lo.0, hi.0) } else { (lo.1, hi.1) };
        wall == (nh, nfixed) && (a - np).max(np - b).max(0) <= NEAR_BARCODE
    });
    // Into the building's frame: x = xc ± u.
    // Mirrored about the entry's centre: its ends swap exactly.
    let (e0, e1) = (xc - wb / 2, xc - wb / 2 + wb);
    let map_x = |u: i64| if goal_flip { e0 + e1 - xc - u } else { xc + u };
    let mp = |p: Pt| (map_x(p.0), p.1);
    let mf = |a: i64| if goal_flip { norm_deg(180 - a) } else { a };
    for (a, b) in gf.walls {
        fg.walls.push((mp(a), mp(b)));
    }
    for (n, a, b) in gf.obstacles {
        let (p, q) = (mp(a), mp(b));
        fg.obstacles.push((n, (p.0.min(q.0), p.1), (p.0.max(q.0), q.1)));
    }
    let mbar = |b: Bar| Bar { id: b.id, at: mp(b.at), facing: mf(b.facing) };
    for d in gf.doors {
        fg.doors.push(DoorB { name: d.name, a: mp(d.a), b: mp(d.b), barcode: d.barcode.map(mbar) });
    }
    if let Some((a, b, bar)) = gf.office {
        let (p, q) = (mp(a), mp(b));
        fg.office = Some(((p.0.min(q.0), p.1), (p.0.max(q.0), q.1), mbar(bar)));
    }
    lobby::walls(&lobby, &mut fg, (ox, oy), true);
    fg.lobby = Some(button(30 + nfloors - 1));
    if goal_flip {
        for st in &mut button_to_office {
            for (_, v) in &mut st.0 {
                *v = flip_word(v);
            }
        }
    }
    // From facing the button: towards the entry (the lobby is not mirrored with the corridors).
    button_to_office.insert(0, turn(lobby.turn_out));
    floors.push(fg);

    let cars: Vec<CarB> = lobby
        .cars
        .iter()
        .map(|(_, c)| CarB { lo: (c.lo.0 + ox, c.lo.1 + oy), hi: (c.hi.0 + ox, c.hi.1 + oy), ..*c })
        .collect();
    let features = Features {
        lobby: lobby.kind,
        car_walls: lobby.relations.clone(),
        open_s,
        clutter_near_barcode,
        corridor_band,
        corridor_width: (
            widths.iter().copied().min().unwrap_or(0) as f64 / 100.0,
            widths.iter().copied().max().unwrap_or(0) as f64 / 100.0,
        ),
        junction_lobby,
        junction_goal,
        junction_office,
        junctions_passed: passed,
    };
    let mut b = Building {
        floors,
        cars,
        start: (start.0, start.1, start_theta),
        start_level,
        goal_level,
        open_s,
        lab_to_lobby,
        button_to_office,
    };
    let _ = seed;
    b.transform(rng.coin(), rng.int(0, 3));
    Built { building: b, corridor_widths: widths, junctions: nj as usize, clutter: density, features }
}

/// A box beside a door's barcode on its wall, on the far side from the door,
/// 5–40 cm from it along the wall and within the room's stretch of wall:
/// `(horizontal, fixed, inward, barcode, door, stretch)` (positions along the
/// wall). Whether there was room for it.
fn box_beside(
    rng: &mut Rng,
    f: &mut FloorB,
    (horizontal, fixed, inward, p, door, stretch): (bool, i64, i64, i64, (i64, i64), (i64, i64)),
    boxes: &mut Vec<(Pt, Pt, (bool, i64))>,
) -> bool {
    let (a, d, gap) = (rng.int(20, 50), rng.int(20, 50), rng.int(5, 40));
    let (s0, s1) = if p < door.0 { (p - gap - a, p - gap) } else { (p + gap, p + gap + a) };
    if s0 < stretch.0 + 5 || s1 > stretch.1 - 5 {
        return false;
    }
    let (n0, n1) = if inward > 0 { (fixed + 1, fixed + 1 + d) } else { (fixed - 1 - d, fixed - 1) };
    let (lo, hi) = if horizontal { ((s0, n0), (s1, n1)) } else { ((n0, s0), (n1, s1)) };
    boxes.push((lo, hi, (horizontal, fixed)));
    f.obstacles.push(("box".to_string(), lo, hi));
    true
}

/// From the office's corridor to inside it.
fn office_steps(door: &DoorB) -> Vec<Step> {
    let id = door.barcode.map(|b| b.id).unwrap_or(40).to_string();
    vec![
        Step(vec![("follow", "hallway".into()), ("until", "barcode".into()), ("barcode", id.clone())]),
        Step(vec![("home", id)]),
        turn(side_of_door(door)),
        Step(vec![("pass", "door".into())]),
    ]
}

fn norm_deg(a: i64) -> i64 {
    let a = a.rem_euclid(360);
    if a > 180 {
        a - 360
    } else {
        a
    }
}

fn metres(v: i64) -> String {
    let sign = if v < 0 { "-" } else { "" };
    let a = v.abs();
    match a % 100 {
        0 => format!("{sign}{}", a / 100),
        r if r % 10 == 0 => format!("{sign}{}.{}", a / 100, r / 10),
        r => format!("{sign}{}.{r:02}", a / 100),
    }
}

impl Building {
    /// Mirrors (x → −x) if asked, rotates by `quarter` × 90°, and shifts the
    /// whole building so its coordinates start at 1 m.
    fn transform(&mut self, mirror: bool, quarter: i64) {
        let tp = |p: Pt| -> Pt {
            let mut q = if mirror { (-p.0, p.1) } else { p };
            for _ in 0..quarter {
                q = (-q.1, q.0);
            }
            q
        };
        let ta = |a: i64| norm_deg(if mirror { 180 - a } else { a } + 90 * quarter);
        self.apply(&tp, &ta);
        if mirror {
            for st in self.lab_to_lobby.iter_mut().chain(self.button_to_office.iter_mut()) {
                for (_, v) in &mut st.0 {
                    *v = flip_word(v);
                }
            }
        }
        let mut lo = (i64::MAX, i64::MAX);
        self.visit(&mut |p: Pt| lo = (lo.0.min(p.0), lo.1.min(p.1)));
        let shift = |p: Pt| (p.0 - lo.0 + 100, p.1 - lo.1 + 100);
        self.apply(&shift, &|a| a);
    }

    fn visit(&self, f: &mut dyn FnMut(Pt)) {
        for fl in &self.floors {
            for &(a, b) in &fl.walls {
                f(a);
                f(b);
            }
            for (_, a, b) in &fl.obstacles {
                f(*a);
                f(*b);
            }
        }
        for c in &self.cars {
            f(c.lo);
            f(c.hi);
        }
    }

    fn apply(&mut self, tp: &dyn Fn(Pt) -> Pt, ta: &dyn Fn(i64) -> i64) {
        let rect = |a: Pt, b: Pt| {
            let (p, q) = (tp(a), tp(b));
            ((p.0.min(q.0), p.1.min(q.1)), (p.0.max(q.0), p.1.max(q.1)))
        };
        let bar = |b: Bar| Bar { id: b.id, at: tp(b.at), facing: ta(b.facing) };
        for fl in &mut self.floors {
            for wl in &mut fl.walls {
                *wl = (tp(wl.0), tp(wl.1));
            }
            for o in &mut fl.obstacles {
                (o.1, o.2) = rect(o.1, o.2);
            }
            for d in &mut fl.doors {
                d.a = tp(d.a);
                d.b = tp(d.b);
                d.barcode = d.barcode.map(bar);
            }
            fl.lobby = fl.lobby.map(bar);
            fl.office = fl.office.map(|(a, b, br)| {
                let (p, q) = rect(a, b);
                (p, q, bar(br))
            });
        }
        for c in &mut self.cars {
            (c.lo, c.hi) = rect(c.lo, c.hi);
            let o = tp(c.out);
            let z = tp((0, 0));
            c.out = (o.0 - z.0, o.1 - z.1);
        }
        let p = tp((self.start.0, self.start.1));
        self.start = (p.0, p.1, ta(self.start.2));
    }

    fn emit(&self, seed: u64, route: bool, features: &Features) -> String {
        use std::fmt::Write as _;
        let m = metres;
        let pt = |p: Pt| format!("[{}, {}]", m(p.0), m(p.1));
        let bar = |b: &Bar| format!("{{id: {}, at: {}, facing_deg: {}}}", b.id, pt(b.at), b.facing);
        let mut s = String::new();
        let _ = writeln!(s, "# Generated by `situate map generate --seed {seed}` (format and family: docs/maps.md).");
        s.push_str(&features.comment());
        let _ = writeln!(s, "name: generated-{seed}");
        let _ = writeln!(s, "robot_radius: 0.25\n\nelevator:\n  travel_s_per_floor: 2.0\n  door_move_s: 1.5");
        let _ = writeln!(s, "  open_s: [{}, {}]\n  arrive_s: [5, 20]\n  cars:", self.open_s.0, self.open_s.1);
        for (k, c) in self.cars.iter().enumerate() {
            // The door faces out of the car (towards the lobby).
            let side = match c.out {
                (0, -1) => "south",
                (0, 1) => "north",
                (1, 0) => "east",
                _ => "west",
            };
            let _ = writeln!(
                s,
                "    - {{id: {}, rect: [{}, {}, {}, {}], door: {side}, door_width: {}, barcode: {}}}",
                k + 1,
                m(c.lo.0),
                m(c.lo.1),
                m(c.hi.0),
                m(c.hi.1),
                m(c.door),
                201 + k
            );
        }
        let _ = writeln!(s, "\nfloors:");
        for f in &self.floors {
            let _ = writeln!(s, "  - level: {}", f.level);
            if !f.name.is_empty() {
                let _ = writeln!(s, "    name: {}", f.name);
            }
            let _ = writeln!(s, "    walls:");
            for (a, b) in &f.walls {
                let _ = writeln!(s, "      - [{}, {}, {}, {}]", m(a.0), m(a.1), m(b.0), m(b.1));
            }
            if !f.obstacles.is_empty() {
                let _ = writeln!(s, "    obstacles:");
                for (n, a, b) in &f.obstacles {
                    let _ =
                        writeln!(s, "      - {{name: {n}, rect: [{}, {}, {}, {}]}}", m(a.0), m(a.1), m(b.0), m(b.1));
                }
            }
            if !f.doors.is_empty() {
                let _ = writeln!(s, "    doors:");
                for d in &f.doors {
                    let at = format!("[{}, {}, {}, {}]", m(d.a.0), m(d.a.1), m(d.b.0), m(d.b.1));
                    match &d.barcode {
                        Some(b) => {
                            let _ = writeln!(s, "      - {{name: {}, at: {at}, barcode: {}}}", d.name, bar(b));
                        }
                        None => {
                            let _ = writeln!(s, "      - {{name: {}, at: {at}}}", d.name);
                        }
                    }
                }
            }
            if let Some(l) = &f.lobby {
                let _ = writeln!(s, "    lobby: {{button: {}, facing_deg: {}, barcode: {}}}", pt(l.at), l.facing, l.id);
            }
            if let Some((a, b, br)) = &f.office {
                let _ = writeln!(
                    s,
                    "    office: {{rect: [{}, {}, {}, {}], barcode: {}}}",
                    m(a.0),
                    m(a.1),
                    m(b.0),
                    m(b.1),
                    bar(br)
                );
            }
        }
        let _ = writeln!(s, "\nmission:");
        let _ = writeln!(
            s,
            "  start: {{floor: {}, x: {}, y: {}, theta_deg: {}}}",
            self.start_level,
            m(self.start.0),
            m(self.start.1),
            self.start.2
        );
        let _ = writeln!(s, "  goal_floor: {}\n  lab_door_barcode: 10", self.goal_level);
        let _ = writeln!(s, "  call_button_barcode: 30\n  office_barcode: 40\n  car_barcode_first: 201");
        if route {
            let _ = writeln!(s, "  route:");
            for (name, steps) in [("lab_to_lobby", &self.lab_to_lobby), ("button_to_office", &self.button_to_office)] {
                let _ = writeln!(s, "    {name}:");
                for st in steps {
                    let body: Vec<String> = st.0.iter().map(|(k, v)| format!("{k}: {v}")).collect();
                    let _ = writeln!(s, "      - {{{}}}", body.join(", "));
                }
            }
        }
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::P2;

    #[test]
    fn options_outside_map_checks_rules_are_refused_with_the_range() {
        let refused = |opts: Options| match opts.validate() {
            Err(GenError::Option { option, message }) => format!("{option}: {message}"),
            other => panic!("accepted: {other:?}"),
        };
        let doors = Options { door_width: (0.8, 1.2), ..Options::default() };
        assert_eq!(refused(doors), "door-width: 0.8..1.2 is not within 1..1.4");
        let open = Options { open_s: Some((2.0, 3.0)), ..Options::default() };
        assert_eq!(refused(open), "open-s: 2..3 is not within 8..600");
        let edges = Options { door_width: (1.0, 1.4), open_s: Some((8.0, 12.0)), ..Options::default() };
        assert!(edges.validate().is_ok());
    }

    fn gen(seed: u64, opts: &Options) -> (Generated, Map) {
        let g = match generate(seed, opts) {
            Ok(g) => g,
            Err(e) => panic!("seed {seed}: {e}"),
        };
        let m = match Map::parse("g.yaml", &g.yaml) {
            Ok(m) => m,
            Err(e) => panic!("seed {seed}: {e}\n{}", g.yaml),
        };
        (g, m)
    }

    #[test]
    fn the_same_seed_and_options_give_the_same_bytes() {
        let o = Options::default();
        for seed in [0, 1, 7, 12345] {
            let a = gen(seed, &o).0.yaml;
            let b = gen(seed, &o).0.yaml;
            assert_eq!(a, b, "seed {seed}");
        }
        assert_ne!(gen(1, &o).0.yaml, gen(2, &o).0.yaml);
        let narrow = Options { corridor_width: (1.8, 1.8), ..Options::default() };
        assert_ne!(gen(1, &o).0.yaml, gen(1, &narrow).0.yaml);
    }

    #[test]
    fn two_hundred_seeds_load_and_pass_the_lint() {
        let o = Options::default();
        let mut attempts = 0;
        for seed in 0..200 {
            let (g, m) = gen(seed, &o);
            let f = lint(&m);
            assert!(f.is_empty(), "seed {seed}: {f:?}");
            attempts += g.attempts;
        }
        // Redraws are the exception, not the rule.
        assert!(attempts < 300, "{attempts} candidates for 200 buildings");
    }

    fn door_offset(d: &crate::map::Door) -> Option<f64> {
        let b = d.barcode.as_ref()?;
        // Along the wall, from the nearer jamb.
        let dir = d.seg.b.minus(d.seg.a).scale(1.0 / d.seg.len());
        let t = b.at.minus(d.seg.a).dot(dir);
        Some(if t < 0.0 { -t } else { t - d.seg.len() })
    }

    #[test]
    fn every_option_is_respected() {
        for seed in 0..40 {
            let o = Options {
                floors: (3, 4),
                cars: (2, 3),
                corridor_width: (2.0, 2.2),
                door_width: (1.1, 1.2),
                junctions: (2, 3),
                clutter: Some(0.4),
                open_s: Some((9.0, 14.0)),
                barcode_offset: (0.2, 0.3),
                route: seed % 2 == 0,
                family: 2,
            };
            let (g, m) = gen(seed, &o);
            assert!((3..=4).contains(&m.floors.len()), "seed {seed}");
            assert_eq!(m.mission.goal_floor - m.mission.start_floor + 1, m.floors.len() as i64);
            assert!((-1..=0).contains(&m.mission.start_floor));
            assert!((2..=3).contains(&m.elevator.cars.len()), "seed {seed}");
            assert_eq!(m.elevator.open_s, (9.0, 14.0));
            assert!(g.corridor_widths.iter().all(|w| (2.0..=2.2).contains(w)), "{:?}", g.corridor_widths);
            assert!((2..=3).contains(&g.junctions));
            assert_eq!(g.clutter, 0.4);
            for c in &m.elevator.cars {
                assert!((1.1..=1.2).contains(&c.door_width), "seed {seed}: car door {}", c.door_width);
                assert!((1.8..=2.4).contains(&(c.x1 - c.x0)) && (1.8..=2.4).contains(&(c.y1 - c.y0)));
            }
            for f in &m.floors {
                for d in &f.doors {
                    assert!((1.1 - 1e-9..=1.2 + 1e-9).contains(&d.seg.len()), "seed {seed}: door {}", d.seg.len());
                    if let Some(x) = door_offset(d) {
                        assert!((0.2 - 1e-9..=0.3 + 1e-9).contains(&x), "seed {seed}: barcode offset {x}");
                    }
                }
            }
            let legs: Vec<&str> = m.mission.route.iter().map(|(n, _)| n.as_str()).collect();
            if o.route {
                assert_eq!(legs, ["lab_to_lobby", "button_to_office"]);
            } else {
                assert!(legs.is_empty());
            }
            let boxes = m.floors.iter().flat_map(|f| &f.obstacles).filter(|_| true).count();
            assert!(boxes > 0);
        }
        // Options out of range are refused.
        let bad = Options { corridor_width: (1.0, 2.0), ..Options::default() };
        assert!(matches!(generate(1, &bad), Err(GenError::Option { option: "corridor-width", .. })));
        let bad = Options { cars: (0, 2), ..Options::default() };
        assert!(generate(1, &bad).is_err());
    }

    #[test]
    fn the_default_ranges_are_drawn_over() {
        let mut floors = std::collections::BTreeSet::new();
        let mut cars = std::collections::BTreeSet::new();
        let mut headings = std::collections::BTreeSet::new();
        for seed in 0..60 {
            let (_, m) = gen(seed, &Options::default());
            floors.insert(m.floors.len());
            cars.insert(m.elevator.cars.len());
            let o = m.elevator.open_s;
            assert!((8.0..=15.0).contains(&o.0) && (12.0..=25.0).contains(&o.1), "{o:?}");
            // The lab door barcode's facing: the layout's orientation.
            let f = m.floor(m.mission.start_floor).map(|f| f.doors[0].barcode.as_ref().and_then(|b| b.facing));
            if let Some(Some(a)) = f {
                headings.insert(a.to_degrees().round() as i64);
            }
            // The lab door barcode sits inside the lab, 1–2 cm off the wall.
            let d = &m.floor(m.mission.start_floor).map(|f| f.doors[0].clone());
            if let Some(d) = d {
                let b = d.barcode.as_ref().map(|b| b.at).unwrap_or(P2::new(0.0, 0.0));
                let off = crate::geom::Seg::new(d.seg.a, d.seg.b);
                let line_dist = {
                    let dir = off.b.minus(off.a).scale(1.0 / off.len());
                    b.minus(off.a).cross(dir).abs()
                };
                assert!((0.009..=0.021).contains(&line_dist), "{line_dist}");
            }
        }
        assert_eq!(floors.len(), 5, "{floors:?}");
        assert_eq!(cars.len(), 4, "{cars:?}");
        assert_eq!(headings.len(), 4, "{headings:?}");
    }

    #[test]
    fn routes_count_the_junctions_on_their_side() {
        for seed in 0..30 {
            let (g, m) = gen(seed, &Options { junctions: (3, 3), ..Options::default() });
            let leg = &m.mission.route[0].1;
            if g.features.junction_lobby == "L" {
                // The corridor ends there: its end wall says where to turn.
                assert_eq!(leg[1].until.as_deref(), Some("wall"), "seed {seed}");
                assert!(leg[1].turn.is_some());
            } else {
                let count = leg[1].count.unwrap_or(0);
                assert!((1..=3).contains(&count), "seed {seed}: count {count}");
                assert_eq!(leg[1].side, leg[1].turn);
            }
            // Into the lobby, (in a corner lobby) a turn towards the button, then home on it.
            let corner = g.features.lobby == "corner";
            assert_eq!(leg.len(), if corner { 5 } else { 4 }, "seed {seed}");
            assert_eq!(leg[leg.len() - 1].home, Some(30));
            if corner {
                assert!(leg[3].turn.is_some() && leg[3].follow.is_none(), "seed {seed}");
            }
            assert!(leg[2].distance.is_some_and(|d| d > 4.0));
            let json = m.mission_json();
            assert_eq!(json["goal_button_barcode"], 30 + m.floors.len() as i64 - 1);
            let last = &m.mission.route[1].1;
            assert_eq!(last.last().and_then(|s| s.pass.as_deref()), Some("door"));
        }
    }

    #[test]
    fn ranges_parse() {
        assert_eq!(parse_range("1.8..2.6"), Ok((1.8, 2.6)));
        assert_eq!(parse_range("2"), Ok((2.0, 2.0)));
        assert_eq!(parse_int_range("1..=3"), Ok((1, 3)));
        assert!(parse_range("3..2").is_err());
        assert!(parse_int_range("1.5").is_err());
        assert!(parse_range("x").is_err());
    }
}
