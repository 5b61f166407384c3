//! Where the robot reaches and what it reads from there: a grid of the cells
//! its centre may occupy (clear of walls, obstacles, shafts and closed car
//! doors), flooded from the start or the call button, and whether a barcode
//! is readable (range, facing, line of sight) from a cell reached.

use super::{CELL, MARGIN, PRESS_STANDOFF, READ_FACING_DEG, READ_RANGE};
use crate::geom::{cast, Seg, P2};
use crate::map::{Barcode, Car, Floor, Map};

/// The cells the robot reaches on a floor: from the start on the start
/// floor, from in front of the call button on the others.
pub(super) fn floor_reach(map: &Map, f: &Floor) -> Option<(Grid, Vec<bool>)> {
    let segs = blocking_segments(map, f);
    let grid = Grid::new(&segs, map.robot_radius + MARGIN);
    let from = if f.level == map.mission.start_floor {
        P2::new(map.mission.start.0, map.mission.start.1)
    } else {
        let l = f.lobby.as_ref()?;
        l.button.plus(P2::dir(l.facing).scale(PRESS_STANDOFF))
    };
    let seed = grid.free_near(from, CELL * 2.0)?;
    let reach = grid.flood(seed);
    Some((grid, reach))
}

/// What blocks the robot on a floor: walls, obstacles, shafts, closed car doors.
pub(super) fn blocking_segments(map: &Map, f: &Floor) -> Vec<Seg> {
    let mut segs = map.static_segments(f);
    segs.extend(map.elevator.cars.iter().map(Car::door));
    segs
}

/// Whether the reader at `p` (turned towards it) reads `b`: range, facing, sight.
pub fn readable_from(b: &Barcode, p: P2, segs: &[Seg]) -> bool {
    let rel = b.at.minus(p);
    let d = rel.norm();
    if !(1e-9..=READ_RANGE).contains(&d) {
        return false;
    }
    if let Some(f) = b.facing {
        let limit = (90.0 - READ_FACING_DEG).to_radians().sin();
        if P2::dir(f).dot(rel.scale(-1.0 / d)) < limit {
            return false;
        }
    }
    !cast(p, rel.scale(1.0 / d), segs).is_some_and(|h| h < d - 0.01)
}

pub(super) fn readable_somewhere(grid: &Grid, reach: &[bool], b: &Barcode, segs: &[Seg]) -> bool {
    let near: Vec<&Seg> = segs.iter().filter(|s| s.dist_to(b.at) <= READ_RANGE + 0.1).collect();
    let near: Vec<Seg> = near.into_iter().copied().collect();
    let (lo, hi) = grid.index_box(b.at, READ_RANGE);
    // Every other cell is plenty: the reader's range is 100 cells.
    for iy in (lo.1..hi.1).step_by(2) {
        for ix in (lo.0..hi.0).step_by(2) {
            let i = iy * grid.nx + ix;
            if reach[i] && readable_from(b, grid.centre(i), &near) {
                return true;
            }
        }
    }
    false
}

/// Cells whose centres the robot's centre may occupy.
pub(super) struct Grid {
    x0: f64,
    y0: f64,
    nx: usize,
    ny: usize,
    free: Vec<bool>,
}

impl Grid {
    pub(super) fn new(segs: &[Seg], clearance: f64) -> Grid {
        let (mut lo, mut hi) = (P2::new(f64::INFINITY, f64::INFINITY), P2::new(f64::NEG_INFINITY, f64::NEG_INFINITY));
        for s in segs {
            for p in [s.a, s.b] {
                lo = P2::new(lo.x.min(p.x), lo.y.min(p.y));
                hi = P2::new(hi.x.max(p.x), hi.y.max(p.y));
            }
        }
        if !lo.x.is_finite() {
            (lo, hi) = (P2::new(0.0, 0.0), P2::new(1.0, 1.0));
        }
        let x0 = lo.x - 1.0;
        let y0 = lo.y - 1.0;
        // Bounded: a map of a few hundred metres at most gives a few tens of millions of cells.
        let nx = (((hi.x - x0 + 1.0) / CELL).ceil() as usize).clamp(1, 8000);
        let ny = (((hi.y - y0 + 1.0) / CELL).ceil() as usize).clamp(1, 8000);
        let mut g = Grid { x0, y0, nx, ny, free: vec![true; nx * ny] };
        for s in segs {
            let a = P2::new(s.a.x.min(s.b.x) - clearance, s.a.y.min(s.b.y) - clearance);
            let b = P2::new(s.a.x.max(s.b.x) + clearance, s.a.y.max(s.b.y) + clearance);
            let (i0, j0) = g.clamp_index(a);
            let (i1, j1) = g.clamp_index(b);
            for j in j0..=j1 {
                for i in i0..=i1 {
                    let k = j * nx + i;
                    if g.free[k] && s.dist_to(g.centre(k)) < clearance {
                        g.free[k] = false;
                    }
                }
            }
        }
        g
    }

    fn clamp_index(&self, p: P2) -> (usize, usize) {
        let i = ((p.x - self.x0) / CELL).floor().clamp(0.0, (self.nx - 1) as f64) as usize;
        let j = ((p.y - self.y0) / CELL).floor().clamp(0.0, (self.ny - 1) as f64) as usize;
        (i, j)
    }

    fn index_box(&self, p: P2, r: f64) -> ((usize, usize), (usize, usize)) {
        let (i0, j0) = self.clamp_index(P2::new(p.x - r, p.y - r));
        let (i1, j1) = self.clamp_index(P2::new(p.x + r, p.y + r));
        ((i0, j0), (i1 + 1, j1 + 1))
    }

    fn index(&self, p: P2) -> Option<usize> {
        let fx = (p.x - self.x0) / CELL;
        let fy = (p.y - self.y0) / CELL;
        if !(fx >= 0.0 && fy >= 0.0) {
            return None;
        }
        let (i, j) = (fx.floor() as usize, fy.floor() as usize);
        (i < self.nx && j < self.ny).then_some(j * self.nx + i)
    }

    pub(super) fn centre(&self, k: usize) -> P2 {
        let (i, j) = (k % self.nx, k / self.nx);
        P2::new(self.x0 + (i as f64 + 0.5) * CELL, self.y0 + (j as f64 + 0.5) * CELL)
    }

    pub(super) fn is_free(&self, p: P2) -> bool {
        self.free_near(p, CELL * 1.5).is_some()
    }

    /// A free cell centre within `tol` of `p`.
    pub(super) fn free_near(&self, p: P2, tol: f64) -> Option<P2> {
        let (lo, hi) = self.index_box(p, tol);
        (lo.1..hi.1)
            .flat_map(|j| (lo.0..hi.0).map(move |i| (i, j)))
            .map(|(i, j)| j * self.nx + i)
            .filter(|&k| self.free[k] && self.centre(k).dist(p) <= tol)
            .min_by(|&a, &b| self.centre(a).dist(p).total_cmp(&self.centre(b).dist(p)))
            .map(|k| self.centre(k))
    }

    pub(super) fn reached_near(&self, reach: &[bool], p: P2, tol: f64) -> bool {
        let (lo, hi) = self.index_box(p, tol);
        (lo.1..hi.1)
            .flat_map(|j| (lo.0..hi.0).map(move |i| (i, j)))
            .map(|(i, j)| j * self.nx + i)
            .any(|k| reach[k] && self.centre(k).dist(p) <= tol)
    }

    /// The cells reached from the free cell nearest `from` (4-connected).
    pub(super) fn flood(&self, from: P2) -> Vec<bool> {
        let mut reach = vec![false; self.free.len()];
        let Some(seed) = self.free_near(from, CELL * 1.5).and_then(|p| self.index(p)) else { return reach };
        let mut stack = vec![seed];
        reach[seed] = true;
        while let Some(k) = stack.pop() {
            let (i, j) = (k % self.nx, k / self.nx);
            let mut push = |n: usize| {
                if self.free[n] && !reach[n] {
                    reach[n] = true;
                    stack.push(n);
                }
            };
            if i > 0 {
                push(k - 1);
            }
            if i + 1 < self.nx {
                push(k + 1);
            }
            if j > 0 {
                push(k - self.nx);
            }
            if j + 1 < self.ny {
                push(k + self.nx);
            }
        }
        reach
    }
}
