//! Exact 2-D geometry: points, segments, rays, swept circles, polygons.

/// A point or vector in metres.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct P2 {
    pub x: f64,
    pub y: f64,
}

impl P2 {
    /// The point `(x, y)`.
    pub const fn new(x: f64, y: f64) -> P2 {
        P2 { x, y }
    }

    /// The unit vector at angle `a` (radians, counter-clockwise from +x).
    pub fn dir(a: f64) -> P2 {
        P2::new(a.cos(), a.sin())
    }

    /// `self + o`.
    pub fn plus(self, o: P2) -> P2 {
        P2::new(self.x + o.x, self.y + o.y)
    }

    /// `self - o`.
    pub fn minus(self, o: P2) -> P2 {
        P2::new(self.x - o.x, self.y - o.y)
    }

    /// `self · k`.
    pub fn scale(self, k: f64) -> P2 {
        P2::new(self.x * k, self.y * k)
    }

    /// The dot product.
    pub fn dot(self, o: P2) -> f64 {
        self.x * o.x + self.y * o.y
    }

    /// The z of the 3-D cross product.
    pub fn cross(self, o: P2) -> f64 {
        self.x * o.y - self.y * o.x
    }

    /// The length.
    pub fn norm(self) -> f64 {
        self.x.hypot(self.y)
    }

    /// The distance to `o`.
    pub fn dist(self, o: P2) -> f64 {
        self.minus(o).norm()
    }
}

/// A line segment from `a` to `b`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Seg {
    pub a: P2,
    pub b: P2,
}

impl Seg {
    /// The segment from `a` to `b`.
    pub const fn new(a: P2, b: P2) -> Seg {
        Seg { a, b }
    }

    /// The length.
    pub fn len(&self) -> f64 {
        self.a.dist(self.b)
    }

    /// The point at parameter `t` (0 = `a`, 1 = `b`).
    pub fn at(&self, t: f64) -> P2 {
        self.a.plus(self.b.minus(self.a).scale(t))
    }

    /// Distance from `p` to the segment.
    pub fn dist_to(&self, p: P2) -> f64 {
        let d = self.b.minus(self.a);
        let l2 = d.dot(d);
        if l2 == 0.0 {
            return p.dist(self.a);
        }
        let t = (p.minus(self.a).dot(d) / l2).clamp(0.0, 1.0);
        p.dist(self.at(t))
    }

    /// Whether the two segments touch or cross (endpoints included).
    pub fn intersects(&self, o: &Seg) -> bool {
        let d1 = orient(o.a, o.b, self.a);
        let d2 = orient(o.a, o.b, self.b);
        let d3 = orient(self.a, self.b, o.a);
        let d4 = orient(self.a, self.b, o.b);
        if ((d1 > 0.0 && d2 < 0.0) || (d1 < 0.0 && d2 > 0.0)) && ((d3 > 0.0 && d4 < 0.0) || (d3 < 0.0 && d4 > 0.0)) {
            return true;
        }
        (d1 == 0.0 && on_segment(o, self.a))
            || (d2 == 0.0 && on_segment(o, self.b))
            || (d3 == 0.0 && on_segment(self, o.a))
            || (d4 == 0.0 && on_segment(self, o.b))
    }

    /// The smallest distance between two segments.
    pub fn dist_to_seg(&self, o: &Seg) -> f64 {
        if self.intersects(o) {
            return 0.0;
        }
        self.dist_to(o.a).min(self.dist_to(o.b)).min(o.dist_to(self.a)).min(o.dist_to(self.b))
    }
}

fn orient(a: P2, b: P2, c: P2) -> f64 {
    b.minus(a).cross(c.minus(a))
}

fn on_segment(s: &Seg, p: P2) -> bool {
    p.x >= s.a.x.min(s.b.x) && p.x <= s.a.x.max(s.b.x) && p.y >= s.a.y.min(s.b.y) && p.y <= s.a.y.max(s.b.y)
}

/// Tolerance on a segment's parameter in [`ray_hit`], so a ray through a
/// segment's exact end (a corner where two walls meet) always hits.
const END_SLACK: f64 = 1e-9;

/// Distance along the ray from `origin` in unit direction `dir` to `seg`, if
/// it hits (ends included, parallel overlaps excluded).
pub fn ray_hit(origin: P2, dir: P2, seg: &Seg) -> Option<f64> {
    let e = seg.b.minus(seg.a);
    let denom = dir.cross(e);
    if denom.abs() < 1e-15 {
        return None;
    }
    let w = seg.a.minus(origin);
    let t = w.cross(e) / denom;
    let u = w.cross(dir) / denom;
    (t >= 0.0 && (-END_SLACK..=1.0 + END_SLACK).contains(&u)).then_some(t)
}

/// The nearest hit of a ray among `segs`.
pub fn cast(origin: P2, dir: P2, segs: &[Seg]) -> Option<f64> {
    segs.iter().filter_map(|s| ray_hit(origin, dir, s)).min_by(f64::total_cmp)
}

/// Distance along the ray from `origin` in unit direction `dir` to the
/// circle of centre `c` and radius `r`, if it hits (0 from inside the circle).
pub fn ray_circle(origin: P2, dir: P2, c: P2, r: f64) -> Option<f64> {
    let w = c.minus(origin);
    let b = w.dot(dir);
    let disc = b * b - (w.dot(w) - r * r);
    if disc < 0.0 {
        return None;
    }
    let root = disc.sqrt();
    if b + root < 0.0 {
        return None;
    }
    Some((b - root).max(0.0))
}

/// An axis-aligned box, to skip segments that cannot matter to a query
/// before doing any exact geometry with them.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Aabb {
    pub lo: P2,
    pub hi: P2,
}

impl Aabb {
    /// The box of the points within `r` of `p` (in each coordinate).
    pub fn around(p: P2, r: f64) -> Aabb {
        Aabb { lo: P2::new(p.x - r, p.y - r), hi: P2::new(p.x + r, p.y + r) }
    }

    /// The smallest box holding `a` and `b`.
    pub fn spanning(a: P2, b: P2) -> Aabb {
        Aabb { lo: P2::new(a.x.min(b.x), a.y.min(b.y)), hi: P2::new(a.x.max(b.x), a.y.max(b.y)) }
    }

    /// The box grown by `r` on every side.
    pub fn grown(self, r: f64) -> Aabb {
        Aabb { lo: P2::new(self.lo.x - r, self.lo.y - r), hi: P2::new(self.hi.x + r, self.hi.y + r) }
    }

    /// Whether the segment's own box meets this one. When it does not, every
    /// point of the segment is farther from every point of this box than the
    /// gap between the two boxes along x or y.
    pub fn meets(&self, s: &Seg) -> bool {
        s.a.x.max(s.b.x) >= self.lo.x
            && s.a.x.min(s.b.x) <= self.hi.x
            && s.a.y.max(s.b.y) >= self.lo.y
            && s.a.y.min(s.b.y) <= self.hi.y
    }
}

/// Many rays from one origin against the same segments: [`cast`] with the
/// parts of [`ray_hit`] that do not depend on the ray worked out once per
/// segment, and the segments no ray of a narrow cone can reach left out
/// (see [`RayFan::select`]). Every result is bit for bit that of [`cast`] on
/// all the segments.
#[derive(Debug, Clone)]
pub struct RayFan {
    parts: Vec<Part>,
    /// `cos` and `sin` of the cones' half width, with a margin.
    spread: Option<(f64, f64)>,
}

#[derive(Debug, Clone, Copy)]
struct Part {
    /// `b - a`, `a - origin` and their cross product, as in `ray_hit`.
    e: P2,
    w: P2,
    w_e: f64,
    /// The unit direction halfway between the segment's ends, seen from the
    /// origin, and the cosine and sine of half the angle between them; `None`
    /// for a segment too near the origin (or around it) to tell.
    wedge: Option<(P2, f64, f64)>,
}

/// Segments nearer the origin than this (at an end), or seen at more than
/// [`WIDE_COS`], are offered to every ray.
const NEAR: f64 = 0.01;
/// `cos` of 172°.
const WIDE_COS: f64 = -0.99;
/// Margin on the angles compared, rad: far more than their rounding and than
/// the [`END_SLACK`] seen from [`NEAR`].
const ANGLE_MARGIN: f64 = 0.01;

impl RayFan {
    /// Prepares rays from `origin` against `segs`, each ray to be cast
    /// within `spread` rad of the direction given to [`RayFan::select`].
    pub fn new(origin: P2, segs: &[Seg], spread: f64) -> RayFan {
        let parts = segs
            .iter()
            .map(|seg| {
                let e = seg.b.minus(seg.a);
                let w = seg.a.minus(origin);
                let v = seg.b.minus(origin);
                let (lw, lv) = (w.dot(w).sqrt(), v.dot(v).sqrt());
                let wedge = (lw > NEAR && lv > NEAR)
                    .then(|| {
                        let (uw, uv) = (w.scale(1.0 / lw), v.scale(1.0 / lv));
                        let c = uw.dot(uv);
                        (c > WIDE_COS).then(|| {
                            let mid = uw.plus(uv);
                            let c = c.min(1.0);
                            (mid.scale(1.0 / mid.dot(mid).sqrt()), ((1.0 + c) / 2.0).sqrt(), ((1.0 - c) / 2.0).sqrt())
                        })
                    })
                    .flatten();
                Part { e, w, w_e: w.cross(e), wedge }
            })
            .collect();
        // Cones of half a turn or more (or not a number) are not narrowed.
        let half = spread.abs() + ANGLE_MARGIN;
        let spread = (half < std::f64::consts::FRAC_PI_2).then(|| (half.cos(), half.sin()));
        RayFan { parts, spread }
    }

    /// The segments (indices, ascending, into `out`) that a ray within the
    /// spread of unit direction `axis` can hit: a hit lies in the wedge from
    /// the origin through the segment, so the ray is within the wedge's half
    /// angle of its middle; other segments are left out.
    pub fn select(&self, axis: P2, out: &mut Vec<usize>) {
        out.clear();
        for (i, part) in self.parts.iter().enumerate() {
            let keep = match (part.wedge, self.spread) {
                (Some((mid, ch, sh)), Some((cs, ss))) => {
                    // The angle from `axis` to `mid` is at most half + spread:
                    // its cosine at least cos(half + spread), both below 180°.
                    axis.dot(mid) >= ch * cs - sh * ss
                }
                _ => true,
            };
            if keep {
                out.push(i);
            }
        }
    }

    /// The nearest hit of the ray in unit direction `dir` on every segment, as [`cast`].
    pub fn cast(&self, dir: P2) -> Option<f64> {
        self.nearest(dir, self.parts.iter())
    }

    /// [`RayFan::cast`] on the segments `among` (from [`RayFan::select`]
    /// for a direction `dir` is within the spread of).
    pub fn cast_among(&self, dir: P2, among: &[usize]) -> Option<f64> {
        self.nearest(dir, among.iter().map(|&i| &self.parts[i]))
    }

    fn nearest<'a>(&self, dir: P2, parts: impl Iterator<Item = &'a Part>) -> Option<f64> {
        let mut best: Option<f64> = None;
        for part in parts {
            // The arithmetic of `ray_hit`, in the same order.
            let denom = dir.cross(part.e);
            if denom.abs() < 1e-15 {
                continue;
            }
            let t = part.w_e / denom;
            let u = part.w.cross(dir) / denom;
            if t >= 0.0 && (-END_SLACK..=1.0 + END_SLACK).contains(&u) && best.is_none_or(|b| t.total_cmp(&b).is_lt()) {
                best = Some(t);
            }
        }
        best
    }
}

/// Whether `p` is inside the polygon (even-odd rule).
pub fn in_polygon(p: P2, poly: &[P2]) -> bool {
    let mut inside = false;
    let n = poly.len();
    for i in 0..n {
        let (a, b) = (poly[i], poly[(i + 1) % n]);
        if (a.y > p.y) != (b.y > p.y) {
            let x = a.x + (p.y - a.y) * (b.x - a.x) / (b.y - a.y);
            if p.x < x {
                inside = !inside;
            }
        }
    }
    inside
}

/// Wraps an angle to (-π, π].
pub fn wrap(a: f64) -> f64 {
    let mut a = a % std::f64::consts::TAU;
    if a > std::f64::consts::PI {
        a -= std::f64::consts::TAU;
    } else if a <= -std::f64::consts::PI {
        a += std::f64::consts::TAU;
    }
    a
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rays_hit_the_exact_inner_corner_of_a_square() {
        let c = [P2::new(0.0, 0.0), P2::new(2.0, 0.0), P2::new(2.0, 2.0), P2::new(0.0, 2.0)];
        let segs: Vec<Seg> = (0..4).map(|i| Seg::new(c[i], c[(i + 1) % 4])).collect();
        for k in 0..4 {
            let a = std::f64::consts::FRAC_PI_4 + k as f64 * std::f64::consts::FRAC_PI_2;
            let d = cast(P2::new(1.0, 1.0), P2::dir(a), &segs).expect("a ray through a corner must hit");
            assert!((d - 2f64.sqrt()).abs() < 1e-9, "angle {a}: {d}");
        }
    }

    /// Segments in every direction and at every distance, with ends on the
    /// axes and diagonals of the origins below.
    fn clutter() -> Vec<Seg> {
        let mut segs = Vec::new();
        for k in 0..60 {
            let a = k as f64 * 0.37;
            let c = P2::new((k as f64 * 1.3).sin() * 3.0, (k as f64 * 0.7).cos() * 3.0);
            segs.push(Seg::new(c, c.plus(P2::dir(a).scale(0.05 + (k % 7) as f64 * 0.4))));
        }
        let sq = [P2::new(-2.0, -2.0), P2::new(2.0, -2.0), P2::new(2.0, 2.0), P2::new(-2.0, 2.0)];
        segs.extend((0..4).map(|i| Seg::new(sq[i], sq[(i + 1) % 4])));
        // Through the origin, ending at it, and just beside it.
        segs.push(Seg::new(P2::new(-1.0, 0.0), P2::new(1.0, 0.0)));
        segs.push(Seg::new(P2::new(0.0, 0.0), P2::new(0.0, 1.0)));
        segs.push(Seg::new(P2::new(0.005, -1.0), P2::new(0.005, 1.0)));
        segs.push(Seg::new(P2::new(0.3, -1.1), P2::new(0.3, -1.1)));
        segs
    }

    #[test]
    fn a_ray_fan_casts_exactly_as_cast() {
        let segs = clutter();
        let origins = [P2::new(0.0, 0.0), P2::new(0.3, -1.1), P2::new(5.0, 5.0), P2::new(-2.0, 0.0), P2::new(1.0, 2.0)];
        let mut among = Vec::new();
        for origin in origins {
            for spread in [0.0, 0.01, 7.5f64.to_radians(), 0.5, 1.4, 3.0, f64::NAN] {
                let fan = RayFan::new(origin, &segs, spread);
                for k in 0..360 {
                    let axis = k as f64 * std::f64::consts::TAU / 360.0 - 3.0;
                    fan.select(P2::dir(axis), &mut among);
                    for r in -2..=2 {
                        let off = if spread.is_nan() { 0.3 * r as f64 } else { spread * r as f64 / 2.0 };
                        let dir = P2::dir(axis + off);
                        let want = cast(origin, dir, &segs).map(f64::to_bits);
                        assert_eq!(fan.cast(dir).map(f64::to_bits), want, "origin {origin:?} ray {k}/{r}");
                        assert_eq!(
                            fan.cast_among(dir, &among).map(f64::to_bits),
                            want,
                            "origin {origin:?} spread {spread} ray {k}/{r}"
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn a_narrow_cone_leaves_most_segments_out() {
        let segs = clutter();
        let fan = RayFan::new(P2::new(0.0, 0.0), &segs, 7.5f64.to_radians());
        let mut among = Vec::new();
        fan.select(P2::dir(0.3), &mut among);
        assert!(among.len() < segs.len() / 2, "{} of {}", among.len(), segs.len());
    }

    #[test]
    fn a_box_meets_the_segments_that_reach_into_it() {
        let b = Aabb::spanning(P2::new(1.0, 2.0), P2::new(0.0, 0.0)).grown(0.5);
        assert!(b.meets(&Seg::new(P2::new(-3.0, 1.0), P2::new(3.0, 1.0))));
        assert!(b.meets(&Seg::new(P2::new(1.5, 2.5), P2::new(4.0, 4.0))));
        assert!(!b.meets(&Seg::new(P2::new(1.6, -5.0), P2::new(1.6, 5.0))));
        assert!(!b.meets(&Seg::new(P2::new(-5.0, 2.6), P2::new(5.0, 2.7))));
        assert_eq!(Aabb::around(P2::new(1.0, 1.0), 1.0), Aabb::spanning(P2::new(0.0, 0.0), P2::new(2.0, 2.0)));
    }

    #[test]
    fn segment_distance_is_zero_when_crossing() {
        let s = Seg::new(P2::new(0.0, 0.0), P2::new(2.0, 0.0));
        assert_eq!(s.dist_to_seg(&Seg::new(P2::new(1.0, -1.0), P2::new(1.0, 1.0))), 0.0);
        assert!((s.dist_to_seg(&Seg::new(P2::new(3.0, 1.0), P2::new(3.0, 2.0))) - 2f64.sqrt()).abs() < 1e-12);
    }

    #[test]
    fn polygon_contains_points_inside_only() {
        let sq = [P2::new(0.0, 0.0), P2::new(1.0, 0.0), P2::new(1.0, 1.0), P2::new(0.0, 1.0)];
        assert!(in_polygon(P2::new(0.5, 0.5), &sq));
        assert!(!in_polygon(P2::new(1.5, 0.5), &sq));
    }

    #[test]
    fn wrap_keeps_angles_in_range() {
        assert!((wrap(3.0 * std::f64::consts::PI) - std::f64::consts::PI).abs() < 1e-12);
        assert!((wrap(-0.5) + 0.5).abs() < 1e-12);
    }
}
