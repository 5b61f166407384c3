//! Position clues from one sonar scan of the wall ahead: the wall's line
//! (`std.fit_wall`) and the door opening in it (`std.locate_door`). A
//! sequencer lines the robot up with a door or a car's back wall from them;
//! they used to be computed in the sequencer from raw sonar, which is the
//! skills' job (the paper's "position clues").

use situate::prelude::*;
use situate_robot::{sonar_bearing, Opening, Wall, SONARS};

use crate::util::centre_range;

/// The sonars within `half_angle` of `bearing`, in bearing order (right to
/// left, relative to `bearing`).
fn around(bearing: f64, half_angle: f64) -> Vec<usize> {
    let off = |i: usize| crate::util::wrap(sonar_bearing(i) - bearing);
    let mut f: Vec<usize> = (0..SONARS).filter(|&i| off(i).abs() <= half_angle + 1e-9).collect();
    f.sort_by(|&a, &b| off(a).total_cmp(&off(b)));
    f
}

/// How a scan is read: which sonars, which echoes, how close to a line.
#[derive(Clone, Copy, Debug)]
pub struct ScanModel {
    /// Echoes at or beyond this are no echo, m.
    pub max_range: f64,
    /// Sonars within `half_angle` of this bearing are used (0: ahead), rad.
    pub bearing: f64,
    /// Sonars within this angle of `bearing` are used, rad.
    pub half_angle: f64,
    /// Half a sonar's cone, rad: a sonar reads the nearest echo within its
    /// cone, so a wall seen obliquely reads nearer than along the axis.
    pub half_cone: f64,
    /// An echo this near the line is on it, m.
    pub tolerance: f64,
    /// Echoes a line needs to count as a wall.
    pub min_inliers: usize,
}

impl Default for ScanModel {
    fn default() -> Self {
        ScanModel {
            max_range: 3.9,
            bearing: 0.0,
            half_angle: 80f64.to_radians(),
            half_cone: 7.5f64.to_radians(),
            tolerance: 0.1,
            min_inliers: 4,
        }
    }
}

/// The distance of a wall in direction `phi` that sonar `i`'s reading `r`
/// says: a sonar reads the nearest point of the wall within its cone, so
/// `r` times the cosine of how far the cone's nearer edge is off `phi`
/// (`r` itself when `phi` is within the cone: cos 0 = 1 exactly, so no
/// cosine on the axis). None when the sonar looks too far aside to see it.
#[inline]
fn wall_estimate(i: usize, r: f64, phi: f64, m: &ScanModel) -> Option<f64> {
    let off = crate::util::wrap(sonar_bearing(i) - phi).abs();
    (off < std::f64::consts::FRAC_PI_2 - m.half_cone).then(|| {
        let outside = off - m.half_cone;
        if outside > 0.0 {
            r * outside.cos()
        } else {
            r
        }
    })
}

/// The wall around `m.bearing` as `(normal, distance, inliers)` in the
/// robot frame.
///
/// Each sonar reads the nearest point of a wall within its cone, so a wall
/// in direction φ at distance d makes sonar i read d / cos(max(0, |bᵢ − φ| −
/// half cone)). Every direction within 90° of `bearing` is tried (1° steps):
/// the distance most readings agree on (within `tolerance`) gives that
/// direction's inliers; the direction with most inliers wins (then the
/// least spread, then the nearer wall) and is refined to 0.1°. Walls nearer
/// than 0.3 m or farther than 3 m, or on fewer than `min_inliers` echoes,
/// are none.
pub fn fit_wall(range: &[f32; SONARS], m: &ScanModel) -> Option<(f64, f64, usize)> {
    let sonars: Vec<(usize, f64)> = around(m.bearing, m.half_angle)
        .into_iter()
        .map(|i| (i, centre_range(range, i)))
        .filter(|&(_, r)| r < m.max_range)
        .collect();
    // For direction `phi`: (inliers, spread, distance) of the best-supported distance.
    let score = |phi: f64| -> Option<(usize, f64, f64)> {
        // At most one estimate per sonar: on the stack, no allocation per direction tried.
        let mut buf = [0.0f64; SONARS];
        let mut n_est = 0;
        for &(i, r) in &sonars {
            if let Some(e) = wall_estimate(i, r, phi, m) {
                buf[n_est] = e;
                n_est += 1;
            }
        }
        let est = &buf[..n_est];
        let mut best: Option<(usize, f64, f64)> = None;
        for &seed in est {
            let on = || est.iter().copied().filter(move |e| (e - seed).abs() < m.tolerance / 2.0);
            // Count and sum in one pass (the same order of addition as two: the same `d`).
            let (count, sum) = on().fold((0usize, 0.0f64), |(n, s), e| (n + 1, s + e));
            let d = sum / count as f64;
            let spread: f64 = on().map(|e| (e - d) * (e - d)).sum();
            let cand = (count, spread, d);
            let better = match best {
                None => true,
                Some((n, sp, bd)) => {
                    cand.0 > n || (cand.0 == n && (cand.1 < sp - 1e-12 || (cand.1 <= sp + 1e-12 && d < bd)))
                }
            };
            if better && (0.3..3.0).contains(&d) {
                best = Some(cand);
            }
        }
        best
    };
    let better = |a: &(usize, f64, f64, f64), b: &(usize, f64, f64, f64)| {
        a.0 > b.0 || (a.0 == b.0 && (a.1 < b.1 - 1e-12 || (a.1 <= b.1 + 1e-12 && a.2 < b.2)))
    };
    let mut best: Option<(usize, f64, f64, f64)> = None; // inliers, spread, distance, phi
    for step in -90..=90 {
        let phi = m.bearing + f64::from(step).to_radians();
        if let Some((n, sp, d)) = score(phi) {
            let cand = (n, sp, d, phi);
            if best.as_ref().is_none_or(|b| better(&cand, b)) {
                best = Some(cand);
            }
        }
    }
    let coarse = best?;
    let mut fine = coarse;
    for step in -10..=10 {
        let phi = coarse.3 + f64::from(step) * 0.1f64.to_radians();
        if let Some((n, sp, d)) = score(phi) {
            let cand = (n, sp, d, phi);
            if better(&cand, &fine) {
                fine = cand;
            }
        }
    }
    let (inliers, _, d, phi) = fine;
    (inliers >= m.min_inliers).then(|| (crate::util::wrap(phi), d, inliers))
}

/// A barcode is this far in front of the wall it is on (docs/maps.md: 1 to 2 cm), m.
pub const BARCODE_OFF_WALL: f64 = 0.015;
/// A sonar reading this far beyond a line sees through it (no wall there), m.
const SEES_THROUGH: f64 = 0.3;
/// Openings on both sides of a barcode nearer than this are not of one wall
/// (a door's nearer jamb is 0.1 to 0.6 m from its barcode, on one side;
/// docs/maps.md), m.
const BOTH_SIDES_OPEN: f64 = 1.0;
/// A line clear of openings this far on one side of the barcode is likelier
/// its wall (the side away from the door: the wall runs on), m.
const ONE_SIDE_CLEAR: f64 = 2.0;
/// The scan's own line and the line through the barcode within this are one
/// wall (sonar noise turns either by a few degrees), rad.
const SAME_WALL: f64 = 10.0 * std::f64::consts::PI / 180.0;
/// The scan's own line this far off the line through the barcode is some
/// other wall (a side wall, a corner's), however clear, rad.
const OTHER_WALL: f64 = 45.0 * std::f64::consts::PI / 180.0;

/// The openings on the line `(phi, d)` (robot frame) beside the point `p` on
/// it: how far along the line the nearest one starts on each side of `p`
/// (left, right; infinite: none seen). An opening is where a sonar sees
/// through the line (more than `SEES_THROUGH` beyond it over its whole cone);
/// sonars whose cone comes within 12° of parallel to the line are not asked.
/// None when the sonars see through the line at `p` itself.
fn openings_beside(sonars: &[(usize, f64)], m: &ScanModel, p: (f64, f64), phi: f64, d: f64) -> Option<(f64, f64)> {
    let (nx, ny) = (phi.cos(), phi.sin());
    let at = p.0 * -ny + p.1 * nx; // the point along the line (left of the foot)
    let (mut left, mut right) = (f64::INFINITY, f64::INFINITY);
    for &(i, r) in sonars {
        let b = sonar_bearing(i);
        let (c1, c2) = ((b - m.half_cone - phi).cos(), (b + m.half_cone - phi).cos());
        if c1.min(c2) < 0.2 {
            continue;
        }
        if r >= m.max_range || r > d / c1.min(c2) + SEES_THROUGH {
            let s1 = d * crate::util::wrap(b - m.half_cone - phi).tan() - at;
            let s2 = d * crate::util::wrap(b + m.half_cone - phi).tan() - at;
            let (lo, hi) = (s1.min(s2), s1.max(s2));
            if lo < 0.0 && hi > 0.0 {
                return None;
            }
            if lo >= 0.0 {
                left = left.min(lo);
            } else {
                right = right.min(-hi);
            }
        }
    }
    Some((left, right))
}

/// The sonars within `m.half_angle` of `m.bearing` and their readings.
fn readings(range: &[f32; SONARS], m: &ScanModel) -> Vec<(usize, f64)> {
    around(m.bearing, m.half_angle).into_iter().map(|i| (i, centre_range(range, i))).collect()
}

/// The wall through `p` (robot frame; a barcode on it, [`BARCODE_OFF_WALL`]
/// in front of it) as `(normal, distance, inliers)`.
///
/// Beside a door, with clutter on the wall (a bin beside the barcode), the
/// scan's best line may run through a jamb, the clutter's corner and the
/// room beyond: the wall a barcode is on is where the barcode is. Each
/// direction within 90° of `m.bearing` (1°, then 0.1°) places the line at the
/// point; its inliers are the sonars whose estimate (as in [`fit_wall`]) is
/// within half the tolerance of it, and the point itself. A line is no wall
/// where the sonars see through it at the point, or on both sides of it
/// within `BOTH_SIDES_OPEN` ([`openings_beside`]): the barcode's door is on
/// one side. Most inliers win (then the line faced most squarely from
/// `m.bearing`); a line with no opening within `ONE_SIDE_CLEAR` on one side
/// ranks one echo higher (a line through clutter beside the barcode is
/// mostly seen through on its far side too, where the wall itself runs on).
pub fn fit_wall_through(range: &[f32; SONARS], m: &ScanModel, p: (f64, f64)) -> Option<(f64, f64, usize)> {
    through_line(&readings(range, m), m, p)
}

/// [`fit_wall_through`] on the sonars' readings ([`readings`]).
fn through_line(sonars: &[(usize, f64)], m: &ScanModel, p: (f64, f64)) -> Option<(f64, f64, usize)> {
    // For direction `phi`: (rank, inliers, off square, distance).
    let score = |phi: f64| -> Option<(usize, usize, f64, f64)> {
        let d = p.0 * phi.cos() + p.1 * phi.sin() + BARCODE_OFF_WALL;
        if !(0.3..3.0).contains(&d) {
            return None;
        }
        let (left, right) = openings_beside(sonars, m, p, phi, d)?;
        let far = left.max(right);
        if far < BOTH_SIDES_OPEN {
            return None;
        }
        let echoes = sonars.iter().filter(|&&(i, r)| {
            r < m.max_range && wall_estimate(i, r, phi, m).is_some_and(|e| (e - d).abs() < m.tolerance / 2.0)
        });
        let inliers = 1 + echoes.count(); // and the point itself
        let rank = inliers + usize::from(far >= ONE_SIDE_CLEAR);
        Some((rank, inliers, crate::util::wrap(phi - m.bearing).abs(), d))
    };
    type Cand = (usize, usize, f64, f64, f64); // rank, inliers, off square, distance, phi
    let better = |a: &Cand, b: &Cand| a.0 > b.0 || (a.0 == b.0 && a.2 < b.2);
    let mut best: Option<Cand> = None;
    let consider = |phi: f64, best: &mut Option<Cand>| {
        if let Some((rank, n, off, d)) = score(phi) {
            let cand = (rank, n, off, d, phi);
            if best.as_ref().is_none_or(|b| better(&cand, b)) {
                *best = Some(cand);
            }
        }
    };
    for step in -90..=90 {
        consider(m.bearing + f64::from(step).to_radians(), &mut best);
    }
    let coarse = best?;
    for step in -10..=10 {
        consider(coarse.4 + f64::from(step) * 0.1f64.to_radians(), &mut best);
    }
    let (_, inliers, _, d, phi) = best?;
    (inliers >= m.min_inliers).then(|| (crate::util::wrap(phi), d, inliers))
}

/// The wall the barcode at `p` (robot frame) is on, as `(normal, distance,
/// inliers)`: the scan's own line (`own`, as [`fit_wall`] fits it from the
/// same scan and model) or the line through the barcode
/// ([`fit_wall_through`]), whichever is the barcode's wall.
///
/// The scan's own line stands when the two are within 10° (one wall), when
/// there is no line through the barcode, or when it is a wall clear of
/// openings for `ONE_SIDE_CLEAR` on one side of the barcode within 45° of
/// the line through it (both walls there: the one on more echoes wins). It
/// gives way when it is open on both sides within `ONE_SIDE_CLEAR` (through
/// a jamb, clutter beside the barcode and the room beyond: a bin on a lab's
/// wall seen aslant gave lines 20 to 50° off) or more than 45° off (a side
/// wall). Measured on 550 fits of lab walls in the benchmark's dev sets and
/// hand-drawn building two: fits within 10° of the truth from 447 (the
/// scan's own) to 493; 20 to 70° off from 38 to 12.
pub fn barcode_wall(
    range: &[f32; SONARS],
    m: &ScanModel,
    p: (f64, f64),
    own: Option<(f64, f64, usize)>,
) -> Option<(f64, f64, usize)> {
    let sonars = readings(range, m);
    let Some(through) = through_line(&sonars, m, p) else {
        return own;
    };
    let Some((phi, d, n)) = own else {
        return Some(through);
    };
    let apart = crate::util::wrap(phi - through.0).abs();
    if apart <= SAME_WALL {
        return own;
    }
    let clear = openings_beside(&sonars, m, p, phi, d).map_or(0.0, |(l, r)| l.max(r));
    if clear >= ONE_SIDE_CLEAR && apart <= OTHER_WALL {
        Some((phi, d, n))
    } else {
        Some(through)
    }
}

/// A door in the wall ahead, from one scan: `(normal, wall, (x, y), width)`.
///
/// The wall is [`fit_wall`]'s line; see [`door_in_wall`] for the opening.
pub fn locate_door(
    range: &[f32; SONARS],
    m: &ScanModel,
    see_through: f64,
    max_width: f64,
    door_width: f64,
) -> Option<(f64, f64, (f64, f64), f64)> {
    let (normal, d, _) = fit_wall(range, m)?;
    door_in_wall(range, m, normal, d, see_through, max_width, door_width)
}

/// The door in a known wall (direction `normal`, `d` m away, robot frame),
/// from one scan: `(normal, wall, (x, y), width)`.
///
/// Each front sonar whose axis meets the wall line is placed along it; those
/// reading more than `see_through` beyond the line see through an opening,
/// whose jambs lie halfway between them and their neighbours that hit the
/// wall. The opening is the run of seeing sonars nearest the foot of the
/// normal (the robot faces the door or a barcode beside it). A run wider
/// than `max_width` is no door's: its edge nearer the foot is trusted, and
/// the door taken to be `door_width` wide.
///
/// A sequencer that has placed the wall already (from a barcode on it, say)
/// passes it in: beside a door the scan's own best line may be the room's
/// beyond, or someone standing in the corridor.
pub fn door_in_wall(
    range: &[f32; SONARS],
    m: &ScanModel,
    normal: f64,
    d: f64,
    see_through: f64,
    max_width: f64,
    door_width: f64,
) -> Option<(f64, f64, (f64, f64), f64)> {
    let (nx, ny) = (normal.cos(), normal.sin());
    let (tx, ty) = (-ny, nx); // along the wall, to the left of the normal
                              // Where a ray at bearing `b` meets the wall line, along it; None if it
                              // runs (nearly) parallel to it.
    let meet = |b: f64| {
        let c = b.cos() * nx + b.sin() * ny;
        (c > 0.1).then(|| d / c * (b.cos() * tx + b.sin() * ty))
    };
    // Each front sonar: the span its cone covers on the wall line, and
    // whether it sees through (its nearest echo well beyond the line).
    let mut hits: Vec<(f64, f64, bool, f64)> = Vec::new();
    for i in around(0.0, m.half_angle) {
        let b = sonar_bearing(i);
        let c = b.cos() * nx + b.sin() * ny;
        if c < 0.2 {
            continue;
        }
        let (Some(e1), Some(e2)) = (meet(b - m.half_cone), meet(b + m.half_cone)) else { continue };
        let r = centre_range(range, i);
        hits.push((e1.min(e2), e1.max(e2), r > d / c + see_through, r));
    }
    hits.sort_by(|a, b| (a.0 + a.1).total_cmp(&(b.0 + b.1)));
    // A run of sonars seeing through: the whole of each one's cone passes
    // the opening, and some of each neighbour's does not, so a jamb lies
    // between the near edges of the last cone that hits and the first that
    // sees through. The neighbour's reading is its nearest echo on the wall
    // within its cone, which is the jamb: the wall point at that range.
    let jamb = |n: (f64, f64, bool, f64), lo: f64, hi: f64| {
        let (lo, hi) = (lo.min(hi), lo.max(hi));
        if n.3 <= d || !n.3.is_finite() {
            return (lo + hi) / 2.0;
        }
        let s = (n.3 * n.3 - d * d).sqrt();
        let mid = (n.0 + n.1) / 2.0;
        let s = if (s - mid).abs() < (-s - mid).abs() { s } else { -s };
        s.clamp(lo, hi)
    };
    let mut runs: Vec<(f64, f64)> = Vec::new();
    let mut k = 0;
    while k < hits.len() {
        if !hits[k].2 {
            k += 1;
            continue;
        }
        let mut j = k;
        while j + 1 < hits.len() && hits[j + 1].2 {
            j += 1;
        }
        let lo = if k > 0 { jamb(hits[k - 1], hits[k - 1].0, hits[k].0) } else { hits[k].0 - 0.1 };
        let hi = if j + 1 < hits.len() { jamb(hits[j + 1], hits[j].1, hits[j + 1].1) } else { hits[j].1 + 0.1 };
        runs.push((lo, hi));
        k = j + 1;
    }
    let (mut lo, mut hi) =
        runs.into_iter().min_by(|a, b| ((a.0 + a.1) / 2.0).abs().total_cmp(&((b.0 + b.1) / 2.0).abs()))?;
    if hi - lo > max_width {
        (lo, hi) = if lo.abs() < hi.abs() { (lo, lo + door_width) } else { (hi - door_width, hi) };
    }
    let mid = (lo + hi) / 2.0;
    Some((normal, d, (nx * d + tx * mid, ny * d + ty * mid), hi - lo))
}

/// Fits the wall ahead to the front half of the sonar ring every run:
/// `wall.normal` (the direction to it, perpendicular, in the robot frame),
/// `wall.distance` from the centre, and the echoes on it; `wall.seen` is
/// false when no line is supported by `min_inliers` echoes. A sequencer
/// squares up to a wall (a car's back wall) or lines up with a barcode's
/// normal from it. Told where a barcode is (`through_distance`,
/// `through_bearing_deg`), it also gives the wall that barcode is on
/// (`barcode_wall`, see [`barcode_wall`]).
#[derive(Skill, Default)]
#[skill(name = "std.fit_wall")]
pub struct FitWall {
    /// Sonar ranges, m.
    #[input(signal = "sonar.range")]
    sonar: [f32; SONARS],
    /// The wall ahead, written every run.
    #[output]
    wall: Wall,
    /// The wall the barcode at `through_distance`/`through_bearing_deg` is
    /// on ([`barcode_wall`]: `wall` or the line through the barcode), written
    /// every run; not seen without a point.
    #[output]
    barcode_wall: Wall,
    /// Echoes at or beyond this are no echo, m.
    #[param(default = 3.9, min = 0.5, max = 20.0, unit = "m")]
    max_range: f64,
    /// Sonars within this angle of `bearing_deg` are used.
    #[param(default = 80.0, min = 20.0, max = 90.0, unit = "deg")]
    half_angle_deg: f64,
    /// Where to look for the wall, in the robot frame (0: ahead; e.g. a
    /// barcode's bearing, for the wall it is on).
    #[param(default = 0.0, min = -180.0, max = 180.0, unit = "deg")]
    bearing_deg: f64,
    /// An echo this near the line is on it, m.
    #[param(default = 0.1, min = 0.01, max = 1.0, unit = "m")]
    tolerance: f64,
    /// Echoes a line needs to count as a wall.
    #[param(default = 4, min = 2, max = 24)]
    min_inliers: i64,
    /// Width of each sonar's cone (as the sonar device's `cone_deg`).
    #[param(default = 15.0, min = 0.0, max = 60.0, unit = "deg")]
    cone_deg: f64,
    /// A point the wall lies just behind (a barcode on it, as the barcode
    /// reader gives it): its distance (0: none), m. `barcode_wall` is the
    /// wall it is on; `wall` is fitted as without it.
    #[param(default = 0.0, min = 0.0, max = 3.0, unit = "m")]
    through_distance: f64,
    /// The point's bearing in the robot frame (with `through_distance`).
    #[param(default = 0.0, min = -180.0, max = 180.0, unit = "deg")]
    through_bearing_deg: f64,
}

/// A fit as the `Wall` signal: `last` kept (not seen) without one.
fn as_wall(fit: Option<(f64, f64, usize)>, last: Wall) -> Wall {
    match fit {
        Some((normal, distance, inliers)) => {
            Wall { seen: true, normal, distance, inliers: i64::try_from(inliers).unwrap_or(i64::MAX) }
        }
        None => Wall { seen: false, ..last },
    }
}

impl Body for FitWall {
    fn step(&mut self, _cx: &mut Context) -> Result<(), SkillError> {
        let model = ScanModel {
            max_range: self.max_range,
            bearing: self.bearing_deg.to_radians(),
            half_angle: self.half_angle_deg.to_radians(),
            half_cone: self.cone_deg.to_radians() / 2.0,
            tolerance: self.tolerance,
            min_inliers: usize::try_from(self.min_inliers).unwrap_or(4),
        };
        let own = fit_wall(&self.sonar, &model);
        self.wall = as_wall(own, self.wall);
        let through = (self.through_distance > 0.0).then(|| {
            let b = self.through_bearing_deg.to_radians();
            (self.through_distance * b.cos(), self.through_distance * b.sin())
        });
        let fit = through.and_then(|p| barcode_wall(&self.sonar, &model, p, own));
        self.barcode_wall = as_wall(fit, self.barcode_wall);
        Ok(())
    }
}

/// Finds the door opening in the wall ahead every run ([`locate_door`]):
/// `opening.x`/`opening.y` its centre on the wall line in the robot frame,
/// `opening.normal` and `opening.wall` the wall's direction and distance,
/// `opening.width` between the jambs; `opening.seen` is false when there is
/// no wall ahead or no sonar sees through it.
#[derive(Skill, Default)]
#[skill(name = "std.locate_door")]
pub struct LocateDoor {
    /// Sonar ranges, m.
    #[input(signal = "sonar.range")]
    sonar: [f32; SONARS],
    /// The opening ahead, written every run.
    #[output]
    opening: Opening,
    /// Echoes at or beyond this are no echo, m.
    #[param(default = 3.9, min = 0.5, max = 20.0, unit = "m")]
    max_range: f64,
    /// A sonar reading this far beyond the wall line sees through it, m.
    #[param(default = 0.5, min = 0.1, max = 3.0, unit = "m")]
    see_through: f64,
    /// Openings wider than this are not one door, m.
    #[param(default = 1.8, min = 0.5, max = 5.0, unit = "m")]
    max_width: f64,
    /// The width taken for a door whose far jamb is not seen, m.
    #[param(default = 1.1, min = 0.5, max = 5.0, unit = "m")]
    door_width: f64,
    /// Width of each sonar's cone (as the sonar device's `cone_deg`).
    #[param(default = 15.0, min = 0.0, max = 60.0, unit = "deg")]
    cone_deg: f64,
    /// The wall's distance when the sequencer knows it (0: fit the wall
    /// from the scan), m.
    #[param(default = 0.0, min = 0.0, max = 3.0, unit = "m")]
    wall_distance: f64,
    /// The known wall's direction in the robot frame (with `wall_distance`).
    #[param(default = 0.0, min = -90.0, max = 90.0, unit = "deg")]
    wall_normal_deg: f64,
}

impl Body for LocateDoor {
    fn step(&mut self, _cx: &mut Context) -> Result<(), SkillError> {
        let model = ScanModel {
            max_range: self.max_range,
            half_cone: self.cone_deg.to_radians() / 2.0,
            ..ScanModel::default()
        };
        let found = if self.wall_distance > 0.0 {
            let normal = self.wall_normal_deg.to_radians();
            door_in_wall(
                &self.sonar,
                &model,
                normal,
                self.wall_distance,
                self.see_through,
                self.max_width,
                self.door_width,
            )
        } else {
            locate_door(&self.sonar, &model, self.see_through, self.max_width, self.door_width)
        };
        self.opening = match found {
            Some((normal, wall, (x, y), width)) => Opening { seen: true, normal, wall, x, y, width },
            None => Opening { seen: false, ..self.opening },
        };
        Ok(())
    }
}
