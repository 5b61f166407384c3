//! Skills that turn sensor readings into the signals the sequencer waits on:
//! `door`, `junction`, `target`, `car`, `opened`.

use situate::prelude::*;
use situate_robot::{sonar_bearing, Barcodes, Door, Junction, Odom, Opened, Target, SONARS};

use crate::util::{centre_range, side_wall, Hysteresis, LEFT, RIGHT, ROBOT_RADIUS};

/// The upper quartile of the last [`Window::N`] values: a wall's distance
/// that a bin or a box standing against it (always nearer than the wall,
/// for a minority of the scans) does not move, while noise averages out.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Window {
    values: [f64; Window::N],
    len: usize,
    next: usize,
}

impl Default for Window {
    fn default() -> Self {
        Window { values: [0.0; Window::N], len: 0, next: 0 }
    }
}

impl Window {
    /// Scans kept: over two metres of corridor at the usual speeds (0.4 m/s
    /// at 10 Hz), while clutter against a wall is at most half a metre long.
    pub const N: usize = 61;

    /// Adds `v` and returns the upper quartile of the window.
    pub fn push(&mut self, v: f64) -> f64 {
        self.values[self.next] = v;
        self.next = (self.next + 1) % Self::N;
        self.len = (self.len + 1).min(Self::N);
        self.quantile().unwrap_or(v)
    }

    /// The upper quartile of the window, once it holds a few values.
    pub fn quantile(&self) -> Option<f64> {
        if self.len < 5 {
            return None;
        }
        let mut sorted = self.values;
        let part = &mut sorted[..self.len];
        let q = part.len() * 3 / 4;
        Some(*part.select_nth_unstable_by(q, f64::total_cmp).1)
    }
}

/// An opening in a side wall beside the robot, as seen by one scan.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Opening {
    /// Width along the wall, m, between the jambs seen by the sonars either
    /// side of the ones seeing through.
    pub width: f64,
    /// Sonars seeing through.
    pub rays: usize,
    /// Bearing of the opening's centre, rad.
    pub bearing: f64,
    /// The opening's centre along the heading (negative: behind), m.
    pub centre: f64,
}

/// Tracks the distance to one side wall and finds openings in it.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct SideOpenings {
    /// Perpendicular distance from the centre to the wall, m, once seen.
    wall: Option<f64>,
    /// The recent wall distances `wall` is the median of.
    walls: Window,
    /// The widths of the opening beside in the last scans (newest first),
    /// since the side sonar first saw through it.
    recent: [Option<f64>; 3],
    /// Which sonars (k = 0..=10 from ahead, on this side) saw through in the last scan.
    was_open: [bool; 11],
    /// The far and near jambs of the last scan's opening, m along the heading.
    jambs: Option<(f64, f64)>,
    /// The wall's distance measured in the last scan, if it was seen.
    seen: Option<f64>,
}

/// Both sides of a corridor: while both walls are seen, their distances
/// sum to the corridor's width; while one is not (an opening), its distance
/// follows from the width and the other wall, so the robot drifting
/// sideways past an opening does not skew the jambs.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Corridor {
    sides: [SideOpenings; 2],
    width: Option<f64>,
    /// The recent widths `width` is the median of.
    widths: Window,
}

impl Corridor {
    /// The distance of side `k`'s wall (0 left, 1 right), once seen.
    pub fn wall(&self, k: usize) -> Option<f64> {
        self.sides[k].wall
    }

    /// Scans both sides ([`LEFT`], [`RIGHT`]).
    pub fn scan(&mut self, range: &[f32; SONARS], max_wall: f64, depth: f64) -> [Option<Opening>; 2] {
        let out = [self.sides[0].scan(range, LEFT, max_wall, depth), self.sides[1].scan(range, RIGHT, max_wall, depth)];
        match (self.sides[0].seen, self.sides[1].seen) {
            (Some(l), Some(r)) => self.width = Some(self.widths.push(l + r)),
            (Some(l), None) => {
                if let Some(w) = self.width {
                    self.sides[1].wall = Some(w - l);
                }
            }
            (None, Some(r)) => {
                if let Some(w) = self.width {
                    self.sides[0].wall = Some(w - r);
                }
            }
            (None, None) => {}
        }
        out
    }
}

impl SideOpenings {
    /// Updates the wall distance from `range` and returns the opening
    /// beside the robot (one that the side sonar, at ±90°, sees through),
    /// its width the median of the last three scans (fewer at first).
    pub fn scan(&mut self, range: &[f32; SONARS], side: usize, max_wall: f64, depth: f64) -> Option<Opening> {
        let Some(mut opening) = self.opening(range, side, max_wall, depth) else {
            self.recent = [None; 3];
            return None;
        };
        if opening.width.is_nan() {
            return Some(opening);
        }
        self.recent = [Some(opening.width), self.recent[0], self.recent[1]];
        let mut w: Vec<f64> = self.recent.iter().flatten().copied().collect();
        w.sort_by(f64::total_cmp);
        // Of two, the smaller: a missed echo beside the run only ever widens it.
        opening.width = if w.len() == 2 { w[0] } else { w[w.len() / 2] };
        Some(opening)
    }

    fn opening(&mut self, range: &[f32; SONARS], side: usize, max_wall: f64, depth: f64) -> Option<Opening> {
        let was_open = std::mem::take(&mut self.was_open);
        let jambs = self.jambs.take();
        self.seen = None;
        if let Some(w) = side_wall(range, side, max_wall, 0.1) {
            // Only a wall roughly parallel to the heading gives the distance: the
            // nearest echo of the three side sonars, whose cones hold the perpendicular.
            if w.angle.abs() < 0.35 {
                let dist = [side - 1, side, side + 1]
                    .map(|i| centre_range(range, i))
                    .into_iter()
                    .fold(f64::INFINITY, f64::min);
                self.wall = Some(self.walls.push(dist));
                self.seen = self.wall;
            }
            return None;
        }
        let d = self.wall?;
        // Sonars from 30° to 150° on this side, front to back: k = 2..=10 (left) or 22..=14 (right).
        let sonar = |k: usize| if side == LEFT { k } else { SONARS - k };
        // Sonar k sees through when its echo lies `depth` beyond the wall line, along its
        // axis, in this scan and the last (a missed echo also reads far, but one scan only).
        for k in 2..=10 {
            let i = sonar(k);
            self.was_open[k] = centre_range(range, i) > d / sonar_bearing(i).sin().abs() + depth;
        }
        let now = self.was_open;
        let open = |k: usize| now[k] && was_open[k];
        if !open(6) {
            return None;
        }
        let (mut first, mut last) = (6, 6);
        while first > 2 && open(first - 1) {
            first -= 1;
        }
        while last < 10 && open(last + 1) {
            last += 1;
        }
        // The sonars either side of the run hit the wall, their cones reaching the opening
        // (cones tile the ring): their nearest echo is the jamb, sqrt(ρ² − d²) along the wall.
        // One that reads far this scan (a missed echo) leaves the last scan's jamb standing.
        let jamb = |k: usize| {
            let i = sonar(k);
            let rho = centre_range(range, i);
            let deep = rho > d / sonar_bearing(i).sin().abs() + depth;
            (!deep).then(|| (rho * rho - d * d).max(0.0).sqrt())
        };
        let last_jambs = jambs;
        let far = jamb(first - 1).or(last_jambs.map(|j| j.0));
        let near = jamb(last + 1).map(|a| -a).or(last_jambs.map(|j| j.1));
        let (Some(far), Some(near)) = (far, near) else {
            return Some(Opening { width: f64::NAN, rays: last - first + 1, bearing: f64::NAN, centre: f64::NAN });
        };
        self.jambs = Some((far, near));
        let (width, centre) = (far - near, (far + near) / 2.0);
        let y = if side == LEFT { d } else { -d };
        Some(Opening { width, rays: last - first + 1, bearing: y.atan2(centre), centre })
    }
}

/// Detects a door: an opening in a side wall, beside the robot, seen
/// through by at least two sonars, at most `max_width` wide (the median of
/// three scans), for `confirm` cycles in a row. The width is measured
/// between the jambs, which the sonars either side of the opening see.
/// Tracks each side wall's distance while it is
/// continuous; `door.left`/`door.right` stay on until `release` cycles
/// without the opening; `door.bearing` is the last opening's centre
/// (positive: left). Writes `door` every run.
#[derive(Skill, Default)]
#[skill(name = "std.detect_door")]
pub struct DetectDoor {
    /// Sonar ranges, m.
    #[input(signal = "sonar.range")]
    sonar: [f32; SONARS],
    /// The doors beside the robot, written every run.
    #[output]
    door: Door,
    /// Largest width of a door, m (wider openings are junctions).
    #[param(default = 1.6, min = 0.1, max = 5.0, unit = "m")]
    max_width: f64,
    /// How far beyond the wall an echo must be to see through it, m.
    #[param(default = 0.5, min = 0.1, max = 3.0, unit = "m")]
    depth: f64,
    /// Side echoes farther than this from the centre are no wall, m.
    #[param(default = 2.0, min = 0.5, max = 5.0, unit = "m")]
    max_wall: f64,
    /// Cycles an opening must be seen before a door is reported.
    #[param(default = 3, min = 1, max = 100)]
    confirm: i64,
    /// Cycles without the opening before the report ends.
    #[param(default = 3, min = 1, max = 100)]
    release: i64,
    corridor: Corridor,
    flags: [Hysteresis; 2],
}

impl Body for DetectDoor {
    fn activate(&mut self, _: &mut Context) -> Result<(), SkillError> {
        self.corridor = Corridor::default();
        self.flags = Default::default();
        self.door = Door::default();
        Ok(())
    }

    fn step(&mut self, cx: &mut Context) -> Result<(), SkillError> {
        let mut out = Door { bearing: self.door.bearing, ..Door::default() };
        let openings = self.corridor.scan(&self.sonar, self.max_wall, self.depth);
        for (k, side) in [LEFT, RIGHT].into_iter().enumerate() {
            let door = openings[k].filter(|o| o.rays >= 2 && o.width <= self.max_width);
            let on = self.flags[k].update(door.is_some(), self.confirm, self.release);
            if let (true, Some(o)) = (on, door.filter(|o| o.bearing.is_finite())) {
                out.bearing = o.bearing;
            }
            if side == LEFT {
                out.left = on;
            } else {
                out.right = on;
            }
        }
        if out.left != self.door.left || out.right != self.door.right {
            sprint!(cx, "door: left {} right {} bearing {:.0}°", out.left, out.right, out.bearing.to_degrees());
        }
        self.door = out;
        Ok(())
    }
}

/// Detects an intersection: a side opening beside the robot at least
/// `min_width` wide (the median of three scans; `junction.left`,
/// `junction.right`), and whether the way ahead is open (`junction.ahead`:
/// nothing within `ahead_distance` straight ahead). With odometry (`odom`),
/// a side opening counts only once the robot has also travelled past enough
/// of it while the side sonar saw through: the width the jambs give is
/// noisy (a 1.4 m door can read 1.7 m), the distance travelled is not, so a
/// door is never taken for a side corridor. `junction.centre` is where the
/// centre of the side opening last seen lies along the heading.
/// Each flag changes after `confirm` cycles agreeing (`release` to turn a
/// side off). Writes `junction` every run.
#[derive(Skill, Default)]
#[skill(name = "std.detect_intersection")]
pub struct DetectIntersection {
    /// Sonar ranges, m.
    #[input(signal = "sonar.range")]
    sonar: [f32; SONARS],
    /// Odometry: the distance travelled past an opening.
    #[input]
    odom: Option<Odom>,
    /// The open ways, written every run.
    #[output]
    junction: Junction,
    /// Smallest width of a side corridor, m (narrower openings are doors).
    #[param(default = 1.7, min = 0.1, max = 10.0, unit = "m")]
    min_width: f64,
    /// How far beyond the wall an echo must be to see through it, m.
    #[param(default = 0.5, min = 0.1, max = 3.0, unit = "m")]
    depth: f64,
    /// Side echoes farther than this from the centre are no wall, m.
    #[param(default = 2.0, min = 0.5, max = 5.0, unit = "m")]
    max_wall: f64,
    /// Clearance straight ahead (sonar 0, rim to echo) under which the way ahead counts as closed, m.
    #[param(default = 1.5, min = 0.1, max = 10.0, unit = "m")]
    ahead_distance: f64,
    /// Cycles an observation must hold before a flag changes.
    #[param(default = 3, min = 1, max = 100)]
    confirm: i64,
    /// Cycles without a side opening before its flag turns off.
    #[param(default = 3, min = 1, max = 100)]
    release: i64,
    /// Of `min_width`, how much the travelled width may fall short, m (the
    /// side sonar stops seeing through a little before each edge: a 1.4 m
    /// door travels about 1.35 m, a 1.8 m side corridor about 1.58 m).
    #[param(default = 0.25, min = 0.0, max = 5.0, unit = "m")]
    travel_slack: f64,
    /// Switched on since the last run: start afresh, the way ahead as seen then.
    fresh: bool,
    corridor: Corridor,
    flags: [Hysteresis; 3],
    /// Path length travelled since activation (odometry), m.
    path: f64,
    last_xy: Option<(f64, f64)>,
    /// Per side: the path length at which the side sonar began to see through.
    since: [Option<f64>; 2],
    /// Per side: the path length at which it last saw through.
    seen_at: [f64; 2],
    /// Per side: the opening being travelled was seen `depth` deep.
    deep: [bool; 2],
    /// Per side: the side sonar read beyond the wall line in the last scan.
    beyond: [bool; 2],
    /// Per side: turned off the way since the side sonar last read on the wall line (which
    /// may then have moved: see `step`).
    stale: [bool; 2],
    /// The last opening's centre: along the path travelled (m) with odometry, else ahead.
    centre: f64,
    /// The corridor's way in the odometry frame (the heading at activation, tracked).
    axis: Option<f64>,
}

/// Half a sonar's cone, rad.
const HALF_CONE: f64 = 7.5 * std::f64::consts::PI / 180.0;

/// A side opening hidden for less than this much travel (someone standing
/// in it hides about 0.7 m) is still the same opening, m. So openings in a
/// corridor wall less than this apart read as one.
const GAP_M: f64 = 0.8;

/// Past an opening seen deep, an echo this far beyond the wall line still
/// sees through it (clutter inside its mouth), m: four times the sonar noise.
const SHALLOW_M: f64 = 0.12;

/// Turned farther than this off the corridor's way, the side sonars' view is ignored, rad.
const MAX_TURNED: f64 = 0.3;

/// Within this of the way, the heading slowly corrects it (odometry drift), rad.
const AXIS_TRACK: f64 = 0.15;

impl Body for DetectIntersection {
    fn activate(&mut self, _: &mut Context) -> Result<(), SkillError> {
        self.fresh = true;
        Ok(())
    }

    fn step(&mut self, cx: &mut Context) -> Result<(), SkillError> {
        // Sonar 0 alone: the ones at ±15° see the side walls of a narrow corridor.
        let ahead_now = centre_range(&self.sonar, 0) - ROBOT_RADIUS >= self.ahead_distance;
        if std::mem::take(&mut self.fresh) {
            self.corridor = Corridor::default();
            self.flags = Default::default();
            // The way ahead starts as seen, not as "closed".
            let mut h = Hysteresis::default();
            if ahead_now {
                h.update(true, 1, 1);
            }
            self.flags[2] = h;
            self.path = 0.0;
            self.last_xy = None;
            self.since = [None; 2];
            self.seen_at = [0.0; 2];
            self.deep = [false; 2];
            self.beyond = [false; 2];
            self.stale = [false; 2];
            self.centre = 0.0;
            self.axis = None;
        }
        if let Some(o) = self.odom {
            if let Some((x, y)) = self.last_xy {
                self.path += (o.x - x) * o.theta.cos() + (o.y - y) * o.theta.sin();
            }
            self.last_xy = Some((o.x, o.y));
        }
        // Turned off the corridor's way (avoiding clutter or someone), the side sonars look
        // along the walls, not across them, and read far: nothing seen then counts. The way is
        // the heading at activation, following the robot's slow drift along the corridor.
        let mut turned = false;
        if let Some(o) = self.odom {
            let axis = *self.axis.get_or_insert(o.theta);
            let off = crate::util::wrap(o.theta - axis);
            if off.abs() < AXIS_TRACK {
                self.axis = Some(crate::util::wrap(axis + 0.05 * off));
            }
            turned = off.abs() > MAX_TURNED;
        }
        let mut open = [false; 2];
        let mut openings = self.corridor.scan(&self.sonar, self.max_wall, self.depth);
        if turned {
            openings = [None, None];
        }
        for k in 0..2 {
            // The side sonar has seen through since `since`: the opening's width is at least
            // the way travelled plus the span of its cone on the wall line.
            // Someone walking across the opening hides it for a moment: the way travelled
            // counts on across gaps up to `GAP_M`.
            // The side sonar sees through an opening while it reads just beyond the wall line,
            // once the opening was seen deep (`depth` beyond the line) somewhere along it: a
            // bin standing inside a side corridor's mouth (deeper than the wall, nearer than
            // `depth`) does not cut its width short. A door's jambs are on the line, so this
            // widens no door.
            let side = [LEFT, RIGHT][k];
            // In this scan and the last: a missed echo also reads far, but one scan only.
            let beyond = self.corridor.wall(k).is_some_and(|d| centre_range(&self.sonar, side) > d + SHALLOW_M);
            // Turned off the way, the robot also moves across it (round someone): the wall line
            // seen before may be nearer or farther now, so a reading just beyond it sees through
            // nothing until the side sonar reads on the line again, or sees an opening deep (a
            // door passed before the swerve, plus the wall after it read beyond a stale line,
            // made a side corridor). An opening seen deep counts as ever, its way travelled
            // carried across the turn.
            if turned {
                self.stale[k] = true;
            } else if !beyond || openings[k].is_some() {
                self.stale[k] = false;
            }
            let shallow = std::mem::replace(&mut self.beyond[k], beyond)
                && beyond
                && self.odom.is_some()
                && !turned
                && !self.stale[k];
            let travelled = if self.odom.is_some() && (openings[k].is_some() || shallow) {
                let start = *self.since[k].get_or_insert(self.path);
                self.seen_at[k] = self.path;
                self.deep[k] |= openings[k].is_some();
                let d = self.corridor.wall(k).unwrap_or(1.0);
                Some(self.path - start + 2.0 * d * HALF_CONE.tan())
            } else {
                if self.path - self.seen_at[k] > GAP_M || self.odom.is_none() {
                    self.since[k] = None;
                    self.deep[k] = false;
                }
                None
            };
            // With odometry the way travelled decides (the jambs' width only has to be
            // roughly right); without it, the jambs' width.
            let wide = match travelled {
                Some(t) => {
                    self.deep[k]
                        && t >= self.min_width - self.travel_slack
                        && openings[k]
                            .is_none_or(|o| o.width.is_nan() || o.width >= self.min_width - 2.0 * self.travel_slack)
                }
                None => self.odom.is_none() && openings[k].is_some_and(|o| o.width >= self.min_width),
            };
            if let Some(o) = openings[k].filter(|o| o.centre.is_finite()) {
                // Kept along the path: passing on (someone standing in the mouth hides the
                // opening for a while), the centre stays where it was seen.
                self.centre = o.centre + if self.odom.is_some() { self.path } else { 0.0 };
            }
            // The way travelled is itself the confirmation: one cycle is enough then.
            let confirm = if travelled.is_some() { 1 } else { self.confirm };
            open[k] = self.flags[k].update(wide, confirm, self.release);
        }
        let ahead = self.flags[2].update(ahead_now, self.confirm, self.confirm);
        let centre = self.centre - if self.odom.is_some() { self.path } else { 0.0 };
        let out = Junction { left: open[0], right: open[1], ahead, centre };
        if (out.left, out.right, out.ahead) != (self.junction.left, self.junction.right, self.junction.ahead) {
            sprint!(cx, "junction: left {} right {} ahead {}", out.left, out.right, out.ahead);
        }
        self.junction = out;
        Ok(())
    }
}

/// The entry of barcode `id` (or the nearest one when `id` < 0), as
/// `(id, bearing, distance)`; arrays of unequal length are read up to the
/// shortest.
fn pick(b: &Barcodes, id: i64) -> Option<(i64, f64, f64)> {
    let n = b.ids.len().min(b.bearing.len()).min(b.distance.len());
    (0..n)
        .filter(|&k| (id < 0 || b.ids[k] == id) && b.bearing[k].is_finite() && b.distance[k].is_finite())
        .min_by(|&a, &c| b.distance[a].total_cmp(&b.distance[c]))
        .map(|k| (b.ids[k], b.bearing[k], b.distance[k]))
}

/// Tracks one barcode: `target` is barcode `id` (the nearest when `id` is
/// −1) while in view. When it drops out for up to `hold` cycles (a flicker),
/// the last bearing and distance are kept with `seen` true; after that
/// `seen` is false (the last values stay). Writes `target` every run.
#[derive(Skill, Default)]
#[skill(name = "std.track_barcode")]
pub struct TrackBarcode {
    /// The barcodes in view.
    #[input]
    barcodes: Barcodes,
    /// The tracked barcode, written every run.
    #[output]
    target: Target,
    /// The barcode to track (−1: the nearest in view).
    #[param(default = -1, min = -1)]
    id: i64,
    /// Cycles a lost barcode is still reported as seen.
    #[param(default = 5, min = 0, max = 1000)]
    hold: i64,
    /// The barcode tracked since the last switch on or change of `id` (`None`: start afresh).
    tracking: Option<i64>,
    missed: i64,
}

impl Body for TrackBarcode {
    fn activate(&mut self, _: &mut Context) -> Result<(), SkillError> {
        self.tracking = None;
        Ok(())
    }

    fn step(&mut self, cx: &mut Context) -> Result<(), SkillError> {
        if self.tracking != Some(self.id) {
            self.tracking = Some(self.id);
            self.target = Target { seen: false, id: self.id, bearing: 0.0, distance: 0.0 };
            self.missed = i64::MAX / 2;
        }
        // The nearest barcode, once tracked, stays the one followed while held.
        let wanted = if self.id < 0 && self.target.seen { self.target.id } else { self.id };
        let found = pick(&self.barcodes, wanted).or_else(|| if self.id < 0 { pick(&self.barcodes, -1) } else { None });
        match found {
            Some((id, bearing, distance)) => {
                if !self.target.seen {
                    sprint!(cx, "barcode {id} in view at {distance:.2} m");
                }
                self.target = Target { seen: true, id, bearing, distance };
                self.missed = 0;
            }
            None => {
                self.missed = self.missed.saturating_add(1);
                if self.missed > self.hold && self.target.seen {
                    self.target.seen = false;
                    sprint!(cx, "barcode {} lost", self.target.id);
                }
            }
        }
        Ok(())
    }
}

/// Identifies the elevator car in view: `car` is k when the barcode
/// `first_id` + k − 1 (1 ≤ k ≤ `cars`) is in view (the nearest such when
/// several), kept for `hold` cycles when it drops out, else 0. Writes `car`
/// every run.
#[derive(Skill, Default)]
#[skill(name = "std.identify_car")]
pub struct IdentifyCar {
    /// The barcodes in view.
    #[input]
    barcodes: Barcodes,
    /// The car number seen (0: none), written every run.
    #[output]
    car: i64,
    /// Barcode id of car 1 (201 in the simulator's default building).
    #[param(default = 201, min = 0)]
    first_id: i64,
    /// Number of cars.
    #[param(default = 4, min = 1, max = 1000)]
    cars: i64,
    /// Cycles a car is still reported after its barcode drops out.
    #[param(default = 3, min = 0, max = 1000)]
    hold: i64,
    missed: i64,
}

impl Body for IdentifyCar {
    fn activate(&mut self, _: &mut Context) -> Result<(), SkillError> {
        self.car = 0;
        self.missed = 0;
        Ok(())
    }

    fn step(&mut self, cx: &mut Context) -> Result<(), SkillError> {
        let b = &self.barcodes;
        let n = b.ids.len().min(b.distance.len());
        let last = self.first_id.saturating_add(self.cars - 1);
        let seen = (0..n)
            .filter(|&k| (self.first_id..=last).contains(&b.ids[k]))
            .min_by(|&a, &c| b.distance[a].total_cmp(&b.distance[c]))
            .map(|k| b.ids[k] - self.first_id + 1);
        match seen {
            Some(car) => {
                if car != self.car {
                    sprint!(cx, "car {car} in view");
                }
                self.car = car;
                self.missed = 0;
            }
            None => {
                self.missed += 1;
                if self.missed > self.hold {
                    self.car = 0;
                }
            }
        }
        Ok(())
    }
}

/// Scans kept by [`WatchOpenings`]: one second at the demo's 10 Hz.
const WATCHED_SCANS: usize = 10;

/// Watches for a way opening near the robot, in any direction: a sonar whose
/// reading was near and steady (under `near`, within `steady` of itself, for
/// the whole of the last second: a wall or a closed door) jumps to
/// at least `jump` beyond the farthest it read then, and stays there for
/// `confirm` cycles. Readings are compared as of now: driving on by `d`, a
/// wall along the way reads as before, and one square to the sonar's axis
/// `d·cos(bearing)` nearer (ahead it comes nearer, behind it recedes); readings
/// steady under either count. So a door opening beside the robot, ahead of it
/// or behind it is seen while it drives. A car's door
/// opening on any lobby wall within the sonars' reach is seen at once, not
/// only when the robot passes it; someone walking out of a sonar's view is
/// not (their readings were not steady, or the wall behind them was read
/// within the second), and turning in place (faster than `max_turn`) starts the
/// watch afresh, since every reading then changes. `opened` is the sonar
/// that jumped farthest; written every run.
#[derive(Skill, Default)]
#[skill(name = "std.watch_openings")]
pub struct WatchOpenings {
    /// Sonar ranges, m.
    #[input(signal = "sonar.range")]
    sonar: [f32; SONARS],
    /// Odometry (the way travelled, the turn rate); without it the robot is taken to stand.
    #[input]
    odom: Option<Odom>,
    /// The way that opened, written every run.
    #[output]
    opened: Opened,
    /// How much farther than before a reading must be, m.
    #[param(default = 0.8, min = 0.2, max = 5.0, unit = "m")]
    jump: f64,
    /// A reading before must have been nearer than this, m.
    #[param(default = 3.2, min = 0.3, max = 10.0, unit = "m")]
    near: f64,
    /// The readings before may spread over at most this (a wall, not someone moving), m.
    #[param(default = 0.15, min = 0.0, max = 5.0, unit = "m")]
    steady: f64,
    /// Cycles the farther reading must last.
    #[param(default = 2, min = 1, max = 20)]
    confirm: i64,
    /// Turning faster than this starts the watch afresh, rad/s.
    #[param(default = 0.3, min = 0.0, max = 10.0, unit = "rad/s")]
    max_turn: f64,
    /// The last scans (oldest first once full) and the way made along the heading at each.
    scans: Vec<([f32; SONARS], f64)>,
    /// The way made along the heading (odometry), signed: backing off counts negative, m.
    path: f64,
    last_xy: Option<(f64, f64)>,
    held: [i64; SONARS],
}

impl Body for WatchOpenings {
    fn activate(&mut self, _: &mut Context) -> Result<(), SkillError> {
        self.scans.clear();
        self.held = [0; SONARS];
        Ok(())
    }

    fn step(&mut self, cx: &mut Context) -> Result<(), SkillError> {
        let turning = self.odom.is_some_and(|o| o.w.abs() > self.max_turn);
        if turning {
            self.scans.clear();
            self.held = [0; SONARS];
        }
        if let Some(o) = self.odom {
            if let Some((x, y)) = self.last_xy {
                self.path += (o.x - x).hypot(o.y - y);
            }
            self.last_xy = Some((o.x, o.y));
        }
        let mut best: Option<(usize, f64, f64, f64)> = None; // sonar, margin, before, now
        if self.scans.len() == WATCHED_SCANS {
            for i in 0..SONARS {
                // The readings before as they would read now, for a wall along the way (they
                // stay as they were) and for one square to the sonar's axis (the way made
                // since, along the axis, brings it that much nearer): the wall (a closed
                // door) read steadily before under either, not someone walking by.
                let axis = sonar_bearing(i).cos();
                let (mut along, mut square) = ((0.0_f64, f64::INFINITY), (0.0_f64, f64::INFINITY));
                for (scan, at) in &self.scans {
                    let r = centre_range(scan, i);
                    let r_square = r - (self.path - at) * axis;
                    along = (along.0.max(r), along.1.min(r));
                    square = (square.0.max(r_square), square.1.min(r_square));
                }
                let steady = |(most, least): (f64, f64)| most - least < self.steady;
                let before = match (steady(along), steady(square)) {
                    (true, _) => Some(along.0),
                    (false, true) => Some(square.0),
                    (false, false) => None,
                };
                let now = centre_range(&self.sonar, i);
                let far = before.is_some_and(|b| b < self.near && now.is_finite() && now > b + self.jump);
                let before = before.unwrap_or(f64::INFINITY);
                self.held[i] = if far { self.held[i] + 1 } else { 0 };
                let margin = now - before;
                if self.held[i] >= self.confirm && best.is_none_or(|b| margin > b.1) {
                    best = Some((i, margin, before, now));
                }
            }
        }
        // The scan joins the history only while it shows nothing opened: the reading before
        // stays the near one for as long as the opening is reported.
        if best.is_none() && self.held.iter().all(|&h| h == 0) {
            if self.scans.len() == WATCHED_SCANS {
                self.scans.remove(0);
            }
            self.scans.push((self.sonar, self.path));
        }
        self.opened = match best {
            Some((i, _, before, now)) => Opened { seen: true, bearing: sonar_bearing(i), before, range: now },
            None => Opened { seen: false, ..self.opened },
        };
        if self.opened.seen {
            sprint!(
                cx,
                "opened: bearing {:.0}° from {:.2} to {:.2} m",
                self.opened.bearing.to_degrees(),
                self.opened.before,
                self.opened.range
            );
        }
        Ok(())
    }
}
