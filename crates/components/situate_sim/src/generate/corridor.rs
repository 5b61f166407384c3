//! A corridor's parts as the generator draws them: its side features
//! (junction stubs, rooms behind doors), doors with their barcodes beside
//! them, and clutter boxes along its walls (a box beside the office barcode
//! among them).

use super::{cm, Bar, DoorB, FloorB, Options, Pt, Rng};

/// A corridor wall clutter may line: horizontal (y fixed) or vertical, the
/// side the corridor is on (+1/−1), its extent and where it must stay clear.
pub(super) struct Run {
    pub(super) horizontal: bool,
    pub(super) fixed: i64,
    pub(super) inward: i64,
    pub(super) from: i64,
    pub(super) to: i64,
    /// Ranges along the run with no box (doors with their margins, mouths).
    pub(super) keep_clear: Vec<(i64, i64)>,
}

/// Lays clutter boxes (0.2–0.5 m) along the runs, never leaving less than
/// 1.2 m between a box and one on another wall (across the corridor, or
/// round a corner), in any direction.
pub(super) fn clutter(
    rng: &mut Rng,
    f: &mut FloorB,
    runs_: &[Run],
    density: f64,
    boxes: &mut Vec<(Pt, Pt, (bool, i64))>,
) {
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
pub(super) fn hdoor(
    rng: &mut Rng,
    name: &str,
    y: i64,
    x0: i64,
    w: i64,
    off: (f64, f64),
    id: i64,
    facing: i64,
) -> DoorB {
    let o = rng.cm(off);
    let bx = if rng.coin() { x0 - o } else { x0 + w + o };
    let by = y + facing.signum() * rng.int(1, 2);
    DoorB { name: name.into(), a: (x0, y), b: (x0 + w, y), barcode: Some(Bar { id, at: (bx, by), facing }) }
}

/// The same on a vertical wall (x fixed), the barcode facing 0 or 180.
#[allow(clippy::too_many_arguments)]
pub(super) fn vdoor(
    rng: &mut Rng,
    name: &str,
    x: i64,
    y0: i64,
    w: i64,
    off: (f64, f64),
    id: i64,
    facing: i64,
) -> DoorB {
    let o = rng.cm(off);
    let by = if rng.coin() { y0 - o } else { y0 + w + o };
    let bx = if facing == 0 { x + rng.int(1, 2) } else { x - rng.int(1, 2) };
    DoorB { name: name.into(), a: (x, y0), b: (x, y0 + w), barcode: Some(Bar { id, at: (bx, by), facing }) }
}

pub(super) enum Feature {
    /// A dead-end side corridor: north, south or both (+).
    Junction { north: bool, south: bool },
    /// A room behind a door, north or south of the corridor.
    Room { north: bool },
}

/// Lays a corridor's side features along x from `c`: junction stubs and rooms
/// (their doors' barcodes numbered from `next_id`). Returns the new cursor
/// and how many junction openings lie on the south side and the north side.
#[allow(clippy::too_many_arguments)]
pub(super) fn features(
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
pub(super) fn junction_kinds(list: &[Feature]) -> Vec<&'static str> {
    list.iter()
        .filter_map(|f| match f {
            Feature::Junction { north: true, south: true } => Some("+"),
            Feature::Junction { .. } => Some("T"),
            Feature::Room { .. } => None,
        })
        .collect()
}

pub(super) fn junction_list(rng: &mut Rng, n: i64) -> Vec<Feature> {
    (0..n)
        .map(|_| match rng.int(0, 2) {
            0 => Feature::Junction { north: true, south: false },
            1 => Feature::Junction { north: false, south: true },
            _ => Feature::Junction { north: true, south: true },
        })
        .collect()
}

/// Door gaps with a 0.6 m margin each side (no clutter there).
pub(super) fn door_margins(gaps: &[(i64, i64)], doors: &[(i64, i64)]) -> Vec<(i64, i64)> {
    gaps.iter().map(|&(a, b)| if doors.contains(&(a, b)) { (a - 60, b + 60) } else { (a, b) }).collect()
}

/// A box beside a door's barcode on its wall, on the far side from the door,
/// 5–40 cm from it along the wall and within the room's stretch of wall:
/// `(horizontal, fixed, inward, barcode, door, stretch)` (positions along the
/// wall). Whether there was room for it.
pub(super) fn box_beside(
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
