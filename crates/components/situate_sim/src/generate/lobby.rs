//! The lobby of a generated building, in its own frame (south-west corner at
//! 0, 0; the entry in the south wall), and where its cars are.
//!
//! Two kinds, which between them put cars on every wall `docs/maps.md` allows
//! (any lobby wall but the entry's), anywhere along it:
//!
//! - **facing**: the call button on the north wall, straight across from the
//!   entry, facing it; cars on the button's wall (either side of it) and on
//!   the side walls;
//! - **corner**: the entry at the east end of the south wall, flush with the
//!   east wall, which holds the call button (facing west); cars on the
//!   button's wall (north of it), on the north wall (a side wall) and on the
//!   west wall (across from the button).

use super::{Bar, CarB, Pt, Rng};

/// A wall of the lobby (its frame).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Wall {
    N,
    E,
    W,
}

pub(super) struct Lobby {
    /// `facing` or `corner`.
    pub kind: &'static str,
    pub lw: i64,
    pub lh: i64,
    /// The entry's x range in the south wall.
    pub entry: (i64, i64),
    /// The call button (its id is set per floor).
    pub button: Bar,
    /// The cars (lobby frame), in their numbering order, with their walls.
    pub cars: Vec<(Wall, CarB)>,
    /// Each car's wall relative to the button's: `same`, `side` or `across`.
    pub relations: Vec<&'static str>,
    /// How far past the entry's line the route follows into the lobby (cm),
    /// and the turn there, before homing on the button.
    pub inside: i64,
    pub turn_in: Option<&'static str>,
    /// From facing the goal floor's button, the turn towards the entry.
    pub turn_out: &'static str,
}

/// Lays `k` items of the given lengths along [lo, hi] in order, `gap` apart
/// at least and `margin` from the ends, the slack spread at random. Returns
/// each item's start.
fn spread(rng: &mut Rng, lo: i64, hi: i64, lens: &[i64], gap: i64, margin: i64) -> Vec<i64> {
    let n = lens.len() as i64;
    let used: i64 = lens.iter().sum::<i64>() + gap * (n - 1).max(0) + 2 * margin;
    let slack = (hi - lo - used).max(0);
    let mut cuts: Vec<i64> = (0..lens.len()).map(|_| rng.int(0, slack)).collect();
    cuts.sort_unstable();
    let mut out = Vec::new();
    let mut x = lo + margin;
    let mut last = 0;
    for (k, &len) in lens.iter().enumerate() {
        x += cuts[k] - last;
        last = cuts[k];
        out.push(x);
        x += len + gap;
    }
    out
}

/// A car on `wall` of a `lw` × `lh` lobby, `at` along it (x on the north
/// wall, y on the side walls), its shaft `s` on a side.
fn car(wall: Wall, at: i64, s: i64, lw: i64, lh: i64) -> CarB {
    match wall {
        Wall::N => CarB { lo: (at, lh), hi: (at + s, lh + s), out: (0, -1), door: 0 },
        Wall::E => CarB { lo: (lw, at), hi: (lw + s, at + s), out: (-1, 0), door: 0 },
        Wall::W => CarB { lo: (-s, at), hi: (0, at + s), out: (1, 0), door: 0 },
    }
}

/// Draws a lobby for `ncars` cars, its entry `wb` wide, the cars' doors from
/// `door` (cm), the button `boff` off its wall.
pub(super) fn layout(rng: &mut Rng, ncars: usize, wb: i64, door: (f64, f64), boff: i64) -> Lobby {
    let s = rng.int(180, 240);
    let (g, m) = (40, 30);
    let corner = rng.coin();
    let mut placed: Vec<(Wall, CarB)> = Vec::new();
    let lobby = if !corner {
        let mut walls = vec![Wall::N, Wall::N, Wall::E, Wall::W];
        rng.shuffle(&mut walls);
        walls.truncate(ncars);
        let kn = walls.iter().filter(|&&w| w == Wall::N).count();
        // The button's stretch of wall among the cars of its wall, in any place.
        let stretch = 120.max(wb + 60);
        let at = rng.int(0, kn as i64) as usize;
        let lens: Vec<i64> = (0..=kn).map(|k| if k == at { stretch } else { s }).collect();
        let need: i64 = lens.iter().sum::<i64>() + g * kn as i64 + 2 * m;
        let lw = need.max(400) + rng.int(0, 150);
        let lh = rng.int(400, 500);
        let starts = spread(rng, 0, lw, &lens, g, m);
        let bx = starts[at] + stretch / 2;
        for (k, &x) in starts.iter().enumerate() {
            if k != at {
                placed.push((Wall::N, car(Wall::N, x, s, lw, lh)));
            }
        }
        for &w in walls.iter().filter(|&&w| w != Wall::N) {
            let y = rng.int(m, lh - m - s);
            placed.push((w, car(w, y, s, lw, lh)));
        }
        Lobby {
            kind: "facing",
            lw,
            lh,
            entry: (bx - wb / 2, bx - wb / 2 + wb),
            button: Bar { id: 0, at: (bx, lh - boff), facing: -90 },
            cars: Vec::new(),
            relations: Vec::new(),
            inside: 100,
            turn_in: None,
            turn_out: "back",
        }
    } else {
        let mut walls = vec![Wall::E, Wall::N, Wall::N, Wall::W, Wall::W];
        rng.shuffle(&mut walls);
        walls.truncate(ncars);
        let count = |w: Wall| walls.iter().filter(|&&x| x == w).count();
        let (ke, kn, kw) = (count(Wall::E), count(Wall::N), count(Wall::W));
        let lw_need = (kn as i64 * s + g * (kn as i64 - 1).max(0) + 2 * m).max(wb + 200);
        let lw = lw_need.max(400) + rng.int(0, 150);
        // The button at yb on the east wall; a car there is north of it.
        let yb_e = rng.int(100, 200);
        let need_e = if ke > 0 { yb_e + 60 + s + m } else { 0 };
        let need_w = kw as i64 * s + g * (kw as i64 - 1).max(0) + 2 * m;
        let lh = need_e.max(need_w).max(400) + rng.int(0, 100);
        let yb = if ke > 0 { yb_e } else { rng.int(100, lh - 100) };
        if ke > 0 {
            let y = rng.int(yb + 60, lh - m - s);
            placed.push((Wall::E, car(Wall::E, y, s, lw, lh)));
        }
        for x in spread(rng, 0, lw, &vec![s; kn], g, m) {
            placed.push((Wall::N, car(Wall::N, x, s, lw, lh)));
        }
        for y in spread(rng, 0, lh, &vec![s; kw], g, m) {
            placed.push((Wall::W, car(Wall::W, y, s, lw, lh)));
        }
        Lobby {
            kind: "corner",
            lw,
            lh,
            entry: (lw - wb, lw),
            button: Bar { id: 0, at: (lw - boff, yb), facing: 180 },
            cars: Vec::new(),
            relations: Vec::new(),
            inside: yb,
            turn_in: Some("right"),
            turn_out: "right",
        }
    };
    // Numbered in a random order; each car's door drawn.
    rng.shuffle(&mut placed);
    let mut cars = Vec::new();
    let mut relations = Vec::new();
    for (w, mut c) in placed {
        c.door = rng.cm(door).min(s - 20);
        relations.push(match (corner, w) {
            (false, Wall::N) | (true, Wall::E) => "same",
            (true, Wall::W) => "across",
            _ => "side",
        });
        cars.push((w, c));
    }
    Lobby { cars, relations, ..lobby }
}

/// The lobby's walls on a floor, its south-west corner at `o`, the entry
/// open or walled.
pub(super) fn walls(l: &Lobby, f: &mut super::FloorB, o: Pt, open: bool) {
    let (ox, oy) = o;
    let span = |w: Wall| -> Vec<(i64, i64)> {
        l.cars
            .iter()
            .filter(|(x, _)| *x == w)
            .map(|(_, c)| if w == Wall::N { (ox + c.lo.0, ox + c.hi.0) } else { (oy + c.lo.1, oy + c.hi.1) })
            .collect()
    };
    f.hwall(oy + l.lh, ox, ox + l.lw, &span(Wall::N));
    f.vwall(ox + l.lw, oy, oy + l.lh, &span(Wall::E));
    f.vwall(ox, oy, oy + l.lh, &span(Wall::W));
    let entry = if open { vec![(ox + l.entry.0, ox + l.entry.1)] } else { vec![] };
    f.hwall(oy, ox, ox + l.lw, &entry);
}
