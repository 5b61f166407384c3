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
