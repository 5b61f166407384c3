//! Position clues from one sonar scan of the wall ahead: the wall's line
//! (`std.fit_wall`) and the door opening in it (`std.locate_door`). A
//! sequencer lines the robot up with a door or a car's back wall from them;
//! they used to be computed in the sequencer from raw sonar, which is the
//! skills' job (the paper's "position clues").

use situate::prelude::*;
use situate_robot::{sonar_bearing, Opening, Wall, SONARS};

use crate::util::{centre_range, echo_point};

/// The front sonars: those within `half_angle` of ahead, in bearing order
/// (right to left).
fn front(half_angle: f64) -> Vec<usize> {
    let mut f: Vec<usize> = (0..SONARS).filter(|&i| sonar_bearing(i).abs() <= half_angle + 1e-9).collect();
    f.sort_by(|&a, &b| sonar_bearing(a).total_cmp(&sonar_bearing(b)));
    f
}

/// How a scan is read: which sonars, which echoes, how close to a line.
#[derive(Clone, Copy, Debug)]
pub struct ScanModel {
    /// Echoes at or beyond this are no echo, m.
    pub max_range: f64,
    /// Sonars within this angle of ahead are used, rad.
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
            half_angle: 80f64.to_radians(),
            half_cone: 7.5f64.to_radians(),
            tolerance: 0.1,
            min_inliers: 4,
        }
    }
}

/// What sonar `i` reads of a wall in direction `normal` at `d`, with the
/// cone taken into account: the nearest point of the wall within the cone.
fn cone_factor(i: usize, normal: f64, half_cone: f64) -> f64 {
    let off = crate::util::wrap(sonar_bearing(i) - normal).abs();
    (off - half_cone).max(0.0).cos()
}

/// The wall ahead as `(normal, distance, inliers)` in the robot frame.
///
/// First the line through most echo points of the front sonars (a RANSAC
/// over every pair of echoes: 24 sonars make it exhaustive; the nearest of
/// equally supported lines), then refined with the sonar's cone: each
/// sonar reads the nearest point of the wall within its cone, so the
/// direction is the one in which the inliers' readings agree best on one
/// distance. Lines nearer than 0.3 m or farther than 3 m, or on fewer than
/// `min_inliers` echoes, are none.
pub fn fit_wall(range: &[f32; SONARS], m: &ScanModel) -> Option<(f64, f64, usize)> {
    let sonars: Vec<usize> =
        front(m.half_angle).into_iter().filter(|&i| centre_range(range, i) < m.max_range).collect();
    let pts: Vec<(f64, f64)> = sonars.iter().map(|&i| echo_point(range, i)).collect();
    let loose = m.tolerance * 1.5;
    let mut best: Option<(usize, f64, f64, f64)> = None; // inliers, distance, nx, ny
    for (a, &(x1, y1)) in pts.iter().enumerate() {
        for &(x2, y2) in &pts[a + 1..] {
            let (dx, dy) = (x2 - x1, y2 - y1);
            let n = dx.hypot(dy);
            if n < 0.3 {
                continue;
            }
            let (mut nx, mut ny) = (dy / n, -dx / n);
            let mut d = x1 * nx + y1 * ny;
            if d < 0.0 {
                (nx, ny, d) = (-nx, -ny, -d);
            }
            if !(0.3..3.0).contains(&d) {
                continue;
            }
            let inliers = pts.iter().filter(|p| (p.0 * nx + p.1 * ny - d).abs() < loose).count();
            let better = match best {
                None => true,
                Some((bi, bd, ..)) => inliers > bi || (inliers == bi && d < bd),
            };
            if better {
                best = Some((inliers, d, nx, ny));
            }
        }
    }
    let (_, d0, nx, ny) = best?;
    let phi0 = ny.atan2(nx);
    let on: Vec<usize> =
        sonars.iter().zip(&pts).filter(|(_, p)| (p.0 * nx + p.1 * ny - d0).abs() < loose).map(|(&i, _)| i).collect();
    // Refine: the direction (±8° in 0.2° steps) in which the cone-corrected
    // readings of the inliers spread least about their mean.
    let mut refined = (f64::INFINITY, phi0, d0);
    for step in -40..=40 {
        let phi = phi0 + f64::from(step) * 0.2f64.to_radians();
        let est: Vec<f64> = on.iter().map(|&i| centre_range(range, i) * cone_factor(i, phi, m.half_cone)).collect();
        let d = est.iter().sum::<f64>() / est.len().max(1) as f64;
        let cost: f64 = est.iter().map(|e| (e - d) * (e - d)).sum();
        if cost < refined.0 {
            refined = (cost, phi, d);
        }
    }
    let (_, phi, d) = refined;
    let inliers = sonars
        .iter()
        .filter(|&&i| (centre_range(range, i) * cone_factor(i, phi, m.half_cone) - d).abs() < m.tolerance)
        .count();
    (inliers >= m.min_inliers && (0.3..3.0).contains(&d)).then(|| (crate::util::wrap(phi), d, inliers))
}

/// A door in the wall ahead, from one scan: `(normal, wall, (x, y), width)`.
///
/// The wall is [`fit_wall`]'s line. Each front sonar whose axis meets that
/// line is placed along it; those reading more than `see_through` beyond the
/// line see through an opening, whose jambs lie halfway between them and
/// their neighbours that hit the wall. The opening is the run of seeing
/// sonars nearest the foot of the normal (the robot faces the door or a
/// barcode beside it). A run wider than `max_width` is no door's: its edge
/// nearer the foot is trusted, and the door taken to be `door_width` wide.
pub fn locate_door(
    range: &[f32; SONARS],
    m: &ScanModel,
    see_through: f64,
    max_width: f64,
    door_width: f64,
) -> Option<(f64, f64, (f64, f64), f64)> {
    let (normal, d, _) = fit_wall(range, m)?;
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
    for i in front(m.half_angle) {
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
/// normal from it.
#[derive(Skill, Default)]
#[skill(name = "std.fit_wall")]
pub struct FitWall {
    /// Sonar ranges, m.
    #[input(signal = "sonar.range")]
    sonar: [f32; SONARS],
    /// The wall ahead, written every run.
    #[output]
    wall: Wall,
    /// Echoes at or beyond this are no echo, m.
    #[param(default = 3.9, min = 0.5, max = 20.0, unit = "m")]
    max_range: f64,
    /// Sonars within this angle of ahead are used.
    #[param(default = 80.0, min = 20.0, max = 90.0, unit = "deg")]
    half_angle_deg: f64,
    /// An echo this near the line is on it, m.
    #[param(default = 0.1, min = 0.01, max = 1.0, unit = "m")]
    tolerance: f64,
    /// Echoes a line needs to count as a wall.
    #[param(default = 4, min = 2, max = 24)]
    min_inliers: i64,
    /// Width of each sonar's cone (as the sonar device's `cone_deg`).
    #[param(default = 15.0, min = 0.0, max = 60.0, unit = "deg")]
    cone_deg: f64,
}

impl Body for FitWall {
    fn step(&mut self, _cx: &mut Context) -> Result<(), SkillError> {
        let model = ScanModel {
            max_range: self.max_range,
            half_angle: self.half_angle_deg.to_radians(),
            half_cone: self.cone_deg.to_radians() / 2.0,
            tolerance: self.tolerance,
            min_inliers: usize::try_from(self.min_inliers).unwrap_or(4),
        };
        let fit = fit_wall(&self.sonar, &model);
        self.wall = match fit {
            Some((normal, distance, inliers)) => {
                Wall { seen: true, normal, distance, inliers: i64::try_from(inliers).unwrap_or(i64::MAX) }
            }
            None => Wall { seen: false, ..self.wall },
        };
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
}

impl Body for LocateDoor {
    fn step(&mut self, _cx: &mut Context) -> Result<(), SkillError> {
        let model = ScanModel {
            max_range: self.max_range,
            half_cone: self.cone_deg.to_radians() / 2.0,
            ..ScanModel::default()
        };
        self.opening = match locate_door(&self.sonar, &model, self.see_through, self.max_width, self.door_width) {
            Some((normal, wall, (x, y), width)) => Opening { seen: true, normal, wall, x, y, width },
            None => Opening { seen: false, ..self.opening },
        };
        Ok(())
    }
}
