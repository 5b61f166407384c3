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

use crate::check::lint;
use crate::map::Map;

mod corridor;
mod emit;
mod family1;
mod family2;
mod features;
mod lobby;
mod options;
mod route;

use family2::build;

pub use features::{Features, NEAR_BARCODE_M};
pub use options::{parse_int_range, parse_range, GenError, Options};

/// [`NEAR_BARCODE_M`] in cm.
const NEAR_BARCODE: i64 = 60;

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
            Ok(map) => match lint(&map).into_iter().next() {
                Some(f) => last = f.in_file(&format!("seed-{seed}.yaml")).to_string(),
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::P2;

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
}
