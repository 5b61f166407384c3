//! The rules on corridors, from straight lines of walls: openings in a wall
//! (a door or a side corridor, nothing in between; openings apart), the widths
//! of corridors and the clutter in them.

use std::collections::{HashMap, HashSet};

use super::reach::Grid;
use super::{
    finding, Diagnostic, CLUTTER_FREE, CORRIDOR_MAX, CORRIDOR_MIN, DOOR_MAX, DOOR_MIN, GAP_MAX, GAP_MIN, MARGIN,
    OPENINGS_APART, OVERLAP_MIN, SLACK,
};
use crate::geom::{cast, Seg, P2};
use crate::map::{Car, Floor, Map};

/// Indices of boxes (a segment's, a polygon's) bucketed on a square grid, to
/// look only at those near a place: the corridor rules compare walls with
/// the walls near them, so a floor of many walls costs in proportion.
struct Buckets {
    cell: f64,
    count: usize,
    cells: HashMap<(i64, i64), Vec<usize>>,
    /// Boxes spanning more than [`Buckets::SPAN_MAX`] cells a side: near everything.
    big: Vec<usize>,
}

impl Buckets {
    const SPAN_MAX: f64 = 64.0;

    fn new(cell: f64, boxes: &[(P2, P2)]) -> Buckets {
        let mut b = Buckets { cell, count: boxes.len(), cells: HashMap::new(), big: Vec::new() };
        for (i, (lo, hi)) in boxes.iter().enumerate() {
            match b.span(*lo, *hi) {
                Some((x0, y0, x1, y1)) => {
                    for x in x0..=x1 {
                        for y in y0..=y1 {
                            b.cells.entry((x, y)).or_default().push(i);
                        }
                    }
                }
                None => b.big.push(i),
            }
        }
        b
    }

    fn of_segs(cell: f64, segs: &[Seg]) -> Buckets {
        let boxes: Vec<(P2, P2)> = segs.iter().map(|s| seg_box(s, 0.0)).collect();
        Buckets::new(cell, &boxes)
    }

    /// The cells a box covers, if not too many.
    fn span(&self, lo: P2, hi: P2) -> Option<(i64, i64, i64, i64)> {
        let c = |v: f64| (v / self.cell).floor();
        let (x0, y0, x1, y1) = (c(lo.x), c(lo.y), c(hi.x), c(hi.y));
        let ok = [x0, y0, x1, y1].iter().all(|v| v.is_finite())
            && x1 - x0 <= Buckets::SPAN_MAX
            && y1 - y0 <= Buckets::SPAN_MAX;
        ok.then_some((x0 as i64, y0 as i64, x1 as i64, y1 as i64))
    }

    /// The boxes that may meet the box `lo`..`hi`, in increasing order.
    fn near(&self, lo: P2, hi: P2) -> Vec<usize> {
        let Some((x0, y0, x1, y1)) = self.span(lo, hi) else { return (0..self.count).collect() };
        let mut out = self.big.clone();
        for x in x0..=x1 {
            for y in y0..=y1 {
                if let Some(v) = self.cells.get(&(x, y)) {
                    out.extend_from_slice(v);
                }
            }
        }
        out.sort_unstable();
        out.dedup();
        out
    }
}

/// A segment's bounding box, grown by `r`.
fn seg_box(s: &Seg, r: f64) -> (P2, P2) {
    (P2::new(s.a.x.min(s.b.x) - r, s.a.y.min(s.b.y) - r), P2::new(s.a.x.max(s.b.x) + r, s.a.y.max(s.b.y) + r))
}

/// The sides of the cars' shafts (whole: a car's door is no opening in a wall line).
fn shaft_sides(map: &Map) -> Vec<(usize, Seg)> {
    let mut out = Vec::new();
    for (k, c) in map.elevator.cars.iter().enumerate() {
        let p = [P2::new(c.x0, c.y0), P2::new(c.x1, c.y0), P2::new(c.x1, c.y1), P2::new(c.x0, c.y1)];
        for i in 0..4 {
            out.push((k, Seg::new(p[i], p[(i + 1) % 4])));
        }
    }
    out
}

/// What stands at one end of a gap in a wall line: a wall (its index in
/// `floor.walls`) or a car's shaft (the car's index).
#[derive(Clone, Copy)]
enum End {
    Wall(usize),
    Shaft(usize),
}

fn end_name(f: &Floor, e: End) -> String {
    match e {
        End::Wall(j) => wall_name(f, j),
        End::Shaft(k) => format!("car {}'s shaft", k + 1),
    }
}

/// `wall K` for segment `j` of a floor's walls, `wall K, segment S` when
/// wall element K (a polyline) has more than one segment.
fn wall_name(f: &Floor, j: usize) -> String {
    let Some(&(k, _)) = f.wall_refs.get(j) else { return format!("wall {}", j + 1) };
    // Elements come in order: the element's segments are one run.
    let first = f.wall_refs.partition_point(|r| r.0 < k).min(j);
    let count = f.wall_refs.partition_point(|r| r.0 <= k).saturating_sub(first);
    if count > 1 {
        format!("wall {k}, segment {}", j - first + 1)
    } else {
        format!("wall {k}")
    }
}

/// Openings in straight walls (`docs/maps.md`, "Widths" and "Openings
/// apart"): along each line of walls (and shafts' sides), a gap under
/// [`GAP_MAX`] is an opening. One that is not a door is a side corridor: not
/// from [`DOOR_MAX`] to [`CORRIDOR_MIN`] m wide; and two openings have at
/// least [`OPENINGS_APART`] of wall between them. Returns the ends of the
/// openings found too narrow for a side corridor.
pub(super) fn openings(map: &Map, f: &Floor, grid: &Grid, reach: &[bool], out: &mut Vec<Diagnostic>) -> Vec<(P2, P2)> {
    let mut flagged = Vec::new();
    let shafts = shaft_sides(map);
    let shaft_segs: Vec<Seg> = shafts.iter().map(|(_, s)| *s).collect();
    let near_walls = Buckets::of_segs(GAP_MAX, &f.walls);
    let near_shafts = Buckets::of_segs(GAP_MAX, &shaft_segs);
    let door_segs: Vec<Seg> = f.doors.iter().map(|d| d.seg).collect();
    let near_doors = Buckets::of_segs(GAP_MAX, &door_segs);
    let mut done = vec![false; f.walls.len()];
    let wall_line = |j: usize| f.wall_refs.get(j).map_or(f.line, |r| r.1);
    for i in 0..f.walls.len() {
        if done[i] {
            continue;
        }
        let w = f.walls[i];
        let len = w.len();
        if len < 1e-9 {
            continue;
        }
        let u = w.b.minus(w.a).scale(1.0 / len);
        let n = P2::new(-u.y, u.x);
        let on = |s: &Seg| s.a.minus(w.a).dot(n).abs() <= 0.02 && s.b.minus(w.a).dot(n).abs() <= 0.02;
        let t = |p: P2| p.minus(w.a).dot(u);
        // The walls and shafts' sides on this line, each within GAP_MAX of another.
        let mut iv: Vec<(f64, f64, End)> = Vec::new();
        let mut todo = vec![w];
        let mut shafts_in: HashSet<usize> = HashSet::new();
        done[i] = true;
        iv.push((0.0, len, End::Wall(i)));
        while let Some(x) = todo.pop() {
            let (lo, hi) = seg_box(&x, GAP_MAX);
            for j in near_walls.near(lo, hi) {
                let s = f.walls[j];
                if !done[j] && on(&s) {
                    done[j] = true;
                    todo.push(s);
                    iv.push((t(s.a).min(t(s.b)), t(s.a).max(t(s.b)), End::Wall(j)));
                }
            }
            for j in near_shafts.near(lo, hi) {
                let (k, s) = shafts[j];
                if on(&s) && shafts_in.insert(j) {
                    todo.push(s);
                    iv.push((t(s.a).min(t(s.b)), t(s.a).max(t(s.b)), End::Shaft(k)));
                }
            }
        }
        iv.sort_by(|x, y| x.0.total_cmp(&y.0));
        // Runs of touching intervals: from, to, what is at each end, whether a wall is in it.
        let mut runs: Vec<(f64, f64, End, End, bool)> = Vec::new();
        for (a, b, e) in iv {
            let wall = matches!(e, End::Wall(_));
            match runs.last_mut() {
                Some(r) if a <= r.1 + SLACK => {
                    if b > r.1 {
                        r.1 = b;
                        r.3 = e;
                    }
                    r.4 |= wall;
                }
                _ => runs.push((a, b, e, e, wall)),
            }
        }
        let at = |x: f64| w.a.plus(u.scale(x));
        // Whether the robot passes by the line there (on either side).
        let by = |x: f64| {
            let k = map.robot_radius + MARGIN + 0.1;
            [1.0, -1.0].iter().any(|s| grid.reached_near(reach, at(x).plus(n.scale(s * k)), 0.1))
        };
        // Gaps between runs: openings (and whether each is a door).
        let gaps: Vec<(f64, f64, bool)> = runs
            .windows(2)
            .map(|r| {
                let (a, b) = (r[0].1, r[1].0);
                let (lo, hi) = seg_box(&Seg::new(at(a), at(b)), 0.1);
                let door = near_doors
                    .near(lo, hi)
                    .into_iter()
                    .map(|k| door_segs[k])
                    .any(|d| on(&d) && (a - 0.05..=b + 0.05).contains(&t(d.at(0.5))));
                (a, b, door)
            })
            .collect();
        for (k, &(a, b, door)) in gaps.iter().enumerate() {
            let g = b - a;
            if door || g <= DOOR_MAX + SLACK || g >= CORRIDOR_MIN - SLACK || !by((a + b) / 2.0) {
                continue;
            }
            let (left, right) = (runs[k].3, runs[k + 1].2);
            let (el_end, line) = match (left, right) {
                (End::Wall(j), _) | (_, End::Wall(j)) => (End::Wall(j), wall_line(j)),
                _ => continue, // between shafts: the lobby's business
            };
            let m = at((a + b) / 2.0);
            flagged.push((at(a), at(b)));
            out.push(finding(
                line,
                format!("floor {}, {}", f.level, end_name(f, el_end)),
                format!(
                    "an opening {g:.2} m wide at ({:.2}, {:.2}) between {} and {}: a side opening is a door ({DOOR_MIN:.1} \
                     to {DOOR_MAX:.1} m) or a side corridor (at least {CORRIDOR_MIN:.1} m), nothing in between (the \
                     junction detector cannot tell which)",
                    m.x,
                    m.y,
                    end_name(f, left),
                    end_name(f, right)
                ),
            ));
        }
        for k in 1..runs.len().saturating_sub(1) {
            let (a, b, first, _, wall) = runs[k];
            let opening = |g: &(f64, f64, bool)| (GAP_MIN..GAP_MAX).contains(&(g.1 - g.0));
            if !wall
                || b - a >= OPENINGS_APART - SLACK
                || !opening(&gaps[k - 1])
                || !opening(&gaps[k])
                || !by((a + b) / 2.0)
            {
                continue;
            }
            let j = match first {
                End::Wall(j) => j,
                End::Shaft(_) => continue,
            };
            let (p, q) = (at((gaps[k - 1].0 + gaps[k - 1].1) / 2.0), at((gaps[k].0 + gaps[k].1) / 2.0));
            out.push(finding(
                wall_line(j),
                format!("floor {}, {}", f.level, end_name(f, End::Wall(j))),
                format!(
                    "only {:.2} m of wall between the openings at ({:.2}, {:.2}) and ({:.2}, {:.2}): openings on one \
                     side of a corridor are at least {OPENINGS_APART} m apart (one hidden for less counts as one)",
                    b - a,
                    p.x,
                    p.y,
                    q.x,
                    q.y
                ),
            ));
        }
    }
    flagged
}

/// Distance between two polygons (0 when they touch).
fn poly_dist(p: &[P2], q: &[P2]) -> f64 {
    let edges =
        |v: &[P2]| -> Vec<Seg> { v.iter().zip(v.iter().cycle().skip(1)).map(|(a, b)| Seg::new(*a, *b)).collect() };
    let (ep, eq) = (edges(p), edges(q));
    ep.iter().flat_map(|a| eq.iter().map(move |b| a.dist_to_seg(b))).fold(f64::INFINITY, f64::min)
}

/// Corridors' widths and their clutter (`docs/maps.md`, "Widths"): two
/// parallel walls facing each other over at least [`OVERLAP_MIN`], with
/// nothing between them and the robot reaching the space between, make a
/// corridor if they are at most [`CORRIDOR_MAX`] apart; it is at least
/// [`CORRIDOR_MIN`] wide, and obstacles in it leave [`CLUTTER_FREE`] free
/// across it. A side corridor whose mouth was found too narrow
/// (`flagged`) is not reported again.
pub(super) fn widths(
    map: &Map,
    f: &Floor,
    grid: &Grid,
    reach: &[bool],
    flagged: &[(P2, P2)],
    out: &mut Vec<Diagnostic>,
) {
    let mut walls: Vec<Seg> = f.walls.clone();
    walls.extend(map.elevator.cars.iter().flat_map(Car::walls));
    let reach_across = CORRIDOR_MAX + SLACK;
    let near_floor_walls = Buckets::of_segs(GAP_MAX, &f.walls);
    let near_walls = Buckets::of_segs(GAP_MAX, &walls);
    let obstacle_boxes: Vec<(P2, P2)> = f
        .obstacles
        .iter()
        .map(|o| {
            let lo = o.iter().fold(P2::new(f64::INFINITY, f64::INFINITY), |m, v| P2::new(m.x.min(v.x), m.y.min(v.y)));
            let hi = o
                .iter()
                .fold(P2::new(f64::NEG_INFINITY, f64::NEG_INFINITY), |m, v| P2::new(m.x.max(v.x), m.y.max(v.y)));
            (lo, hi)
        })
        .collect();
    let near_obstacles = Buckets::new(GAP_MAX, &obstacle_boxes);
    let flagged_segs: Vec<Seg> = flagged.iter().map(|(a, b)| Seg::new(*a, *b)).collect();
    let near_flagged = Buckets::of_segs(GAP_MAX, &flagged_segs);
    let wall_name = |j: usize| wall_name(f, j);
    let wall_line = |j: usize| f.wall_refs.get(j).map_or(f.line, |r| r.1);
    let obstacle_name = |k: usize| format!("floor {}, obstacle {}", f.level, k + 1);
    let obstacle_line = |k: usize| f.obstacle_lines.get(k).copied().unwrap_or(f.line);
    // Pairs of lines already reported (their direction and offsets, to the centimetre), obstacles
    // and pairs of obstacles reported.
    let mut narrow: HashSet<(i64, i64, i64)> = HashSet::new();
    let mut cluttered: HashSet<usize> = HashSet::new();
    let mut pairs: HashSet<(usize, usize)> = HashSet::new();
    let near = |p: P2, s: &Seg| p.dist(s.a) <= 0.05 || p.dist(s.b) <= 0.05;
    for i in 0..f.walls.len() {
        let wi = f.walls[i];
        let len = wi.len();
        if len < OVERLAP_MIN {
            continue;
        }
        let u = wi.b.minus(wi.a).scale(1.0 / len);
        let (qlo, qhi) = seg_box(&wi, reach_across);
        for j in near_floor_walls.near(qlo, qhi).into_iter().filter(|&j| j > i) {
            let wj = f.walls[j];
            let lj = wj.len();
            if lj < OVERLAP_MIN || u.cross(wj.b.minus(wj.a).scale(1.0 / lj)).abs() > 0.02 {
                continue;
            }
            let n0 = P2::new(-u.y, u.x);
            let off = wj.a.minus(wi.a).dot(n0);
            let n = n0.scale(off.signum());
            let d = off.abs();
            if d < 2.0 * (map.robot_radius + MARGIN) || d > CORRIDOR_MAX + SLACK {
                continue;
            }
            let t = |p: P2| p.minus(wi.a).dot(u);
            let (lo, hi) = (t(wj.a).min(t(wj.b)).max(0.0), t(wj.a).max(t(wj.b)).min(len));
            if hi - lo < OVERLAP_MIN {
                continue;
            }
            let p = wi.a.plus(u.scale((lo + hi) / 2.0));
            // Nothing between them: the first wall across is wj.
            let from = p.plus(n.scale(0.005));
            let (clo, chi) = seg_box(&Seg::new(from, p.plus(n.scale(d + 0.1))), 0.01);
            let across: Vec<Seg> = near_walls.near(clo, chi).into_iter().map(|k| walls[k]).collect();
            if cast(from, n, &across).is_none_or(|h| (h - (d - 0.005)).abs() > SLACK) {
                continue;
            }
            let centre = p.plus(n.scale(d / 2.0));
            if !grid.reached_near(reach, centre, d / 2.0) {
                continue;
            }
            if d < CORRIDOR_MIN - SLACK {
                let (mlo, mhi) = seg_box(&wi, 0.1);
                let mouth = near_flagged
                    .near(mlo, mhi)
                    .into_iter()
                    .map(|k| flagged[k])
                    .any(|(a, b)| (near(a, &wi) && near(b, &wj)) || (near(b, &wi) && near(a, &wj)));
                // The same two lines (walls split by doors) are reported once.
                let angle = u.y.atan2(u.x).rem_euclid(std::f64::consts::PI);
                let m = P2::new(-angle.sin(), angle.cos());
                let (ci, cj) = (m.dot(wi.a), m.dot(wj.a));
                let cm = |v: f64| (v * 100.0).round() as i64;
                let key = (cm(angle), cm(ci.min(cj)), cm(ci.max(cj)));
                if !mouth && narrow.insert(key) {
                    out.push(finding(
                        wall_line(i),
                        format!("floor {}, {}", f.level, wall_name(i)),
                        format!(
                            "a way {d:.2} m wide between {} and {} (around ({:.2}, {:.2})): corridors and side \
                             corridors are at least {CORRIDOR_MIN:.1} m wide",
                            wall_name(i),
                            wall_name(j),
                            centre.x,
                            centre.y
                        ),
                    ));
                }
                continue;
            }
            // A corridor: the clutter in it (obstacles whose centre is between the walls, along the overlap).
            let strip = [wi.at(lo / len), wi.at(hi / len), wj.at(0.0), wj.at(1.0)];
            let slo =
                strip.iter().fold(P2::new(f64::INFINITY, f64::INFINITY), |m, v| P2::new(m.x.min(v.x), m.y.min(v.y)));
            let shi = strip
                .iter()
                .fold(P2::new(f64::NEG_INFINITY, f64::NEG_INFINITY), |m, v| P2::new(m.x.max(v.x), m.y.max(v.y)));
            let inside: Vec<(usize, f64)> = near_obstacles
                .near(slo, shi)
                .into_iter()
                .map(|k| (k, &f.obstacles[k]))
                .filter_map(|(k, o)| {
                    let c = o.iter().fold(P2::new(0.0, 0.0), |s, v| s.plus(*v)).scale(1.0 / o.len().max(1) as f64);
                    let across = c.minus(wi.a).dot(n);
                    ((lo..=hi).contains(&t(c)) && across > 0.0 && across < d).then_some((k, across))
                })
                .collect();
            for &(k, across) in &inside {
                let far = if across < d / 2.0 { (wj, j) } else { (wi, i) };
                let o = &f.obstacles[k];
                let edges: Vec<Seg> = o.iter().zip(o.iter().cycle().skip(1)).map(|(a, b)| Seg::new(*a, *b)).collect();
                let free = edges.iter().map(|e| e.dist_to_seg(&far.0)).fold(f64::INFINITY, f64::min);
                if free < CLUTTER_FREE - SLACK && cluttered.insert(k) {
                    out.push(finding(
                        obstacle_line(k),
                        obstacle_name(k),
                        format!(
                            "it leaves {free:.2} m free across the corridor (to {}): clutter in a corridor leaves at \
                             least {CLUTTER_FREE:.1} m free",
                            wall_name(far.1)
                        ),
                    ));
                }
                for &(q, across_q) in &inside {
                    let facing_walls = (across < d / 2.0) != (across_q < d / 2.0);
                    if q <= k || !facing_walls || pairs.contains(&(k, q)) {
                        continue;
                    }
                    let between = poly_dist(o, &f.obstacles[q]);
                    if between < CLUTTER_FREE - SLACK {
                        pairs.insert((k, q));
                        out.push(finding(
                            obstacle_line(q),
                            obstacle_name(q),
                            format!(
                                "it and obstacle {} (on the facing wall) leave {between:.2} m between them: clutter in \
                                 a corridor leaves at least {CLUTTER_FREE:.1} m free",
                                k + 1
                            ),
                        ));
                    }
                }
            }
        }
    }
}
