//! The skills that write `drive`, in closed loops over scenes.

use std::f64::consts::{FRAC_PI_2, PI};

use situate_robot::{Drive, Target, SONARS};
use situate_skills::{
    Avoid, EnterCar, FollowHallway, Home, HomePosition, LeaveCar, PassDoor, Runaway, TrackBarcode, Turn, Wander,
};

use crate::harness::{val, Harness};
use crate::scene::{wrap, Base, Noise, Pose, Scene, RADIUS};
use crate::{drive_of, odom, sonar, DT};

#[test]
fn runaway_backs_off_a_wall_ahead_then_falls_silent() {
    let scene = Scene::new().wall(0.55, -5.0, 0.55, 5.0);
    let mut h = Harness::new::<Runaway>();
    let mut pose = Pose::new(0.0, 0.0, 0.0);
    let first = drive_of(&mut h, &[("sonar", sonar(&scene, pose))]).expect("a wall 0.3 m ahead is too near");
    assert!(first.v < 0.0, "backs away from a wall ahead: {first:?}");
    let mut last = None;
    for _ in 0..200 {
        last = drive_of(&mut h, &[("sonar", sonar(&scene, pose))]);
        pose = pose.step(last.unwrap_or_default(), DT);
        assert!(scene.clearance(pose.x, pose.y) > RADIUS, "collided at {pose:?}");
    }
    assert_eq!(last, None, "silent once clear");
    let range = scene.clearance(pose.x, pose.y) - RADIUS;
    assert!((0.39..0.5).contains(&range), "stops just beyond safe_distance: {range}");
}

#[test]
fn runaway_is_silent_in_open_space_and_flees_sideways_from_a_side_wall() {
    let mut h = Harness::new::<Runaway>();
    for _ in 0..20 {
        assert_eq!(drive_of(&mut h, &[("sonar", sonar(&Scene::new(), Pose::new(0.0, 0.0, 0.0)))]), None);
    }
    // A wall 0.2 m from the rim on the left: turn right (away) and move off it.
    let scene = Scene::new().wall(-5.0, 0.45, 5.0, 0.45);
    let mut pose = Pose::new(0.0, 0.0, 0.0);
    let d = drive_of(&mut h, &[("sonar", sonar(&scene, pose))]).expect("runs away");
    assert!(d.w < 0.0, "turns right, away from the left wall: {d:?}");
    for _ in 0..200 {
        pose = pose.step(drive_of(&mut h, &[("sonar", sonar(&scene, pose))]).unwrap_or_default(), DT);
    }
    assert!(pose.y < -0.1, "moved away from the wall: {pose:?}");
}

#[test]
fn avoid_turns_away_before_a_wall_ahead_and_is_silent_when_clear() {
    let scene = Scene::new().wall(3.0, -5.0, 3.0, 5.0).wall(-5.0, 0.8, 5.0, 0.8);
    let mut h = Harness::new::<Avoid>();
    let mut pose = Pose::new(0.0, 0.0, 0.0);
    assert_eq!(drive_of(&mut h, &[("sonar", sonar(&scene, pose))]), None, "clear 2.75 m ahead");
    let mut avoided = 0;
    for _ in 0..400 {
        let d = drive_of(&mut h, &[("sonar", sonar(&scene, pose))]);
        avoided += usize::from(d.is_some());
        // Below avoid: straight ahead at 0.3 m/s.
        pose = pose.step(d.unwrap_or(Drive { v: 0.3, w: 0.0 }), DT);
        assert!(scene.clearance(pose.x, pose.y) > RADIUS + 0.05, "too close at {pose:?}");
    }
    assert!(avoided > 0);
    // The free side is the right (a wall runs 0.8 m to the left).
    assert!(pose.y < -0.5, "went off to the right: {pose:?}");
}

#[test]
fn wander_is_seeded_smooth_and_bounded() {
    let run = |seed: i64| {
        let mut h = Harness::new::<Wander>().param("seed", val(seed)).param("max_turn", val(0.5));
        (0..400).map(|_| drive_of(&mut h, &[]).expect("always writes")).collect::<Vec<_>>()
    };
    let (a, b, c) = (run(7), run(7), run(8));
    assert_eq!(a, b, "same seed, same walk");
    assert_ne!(a, c, "another seed, another walk");
    assert!(a.iter().all(|d| d.v == 0.3 && d.w.abs() <= 0.5));
    // Each run closes a tenth of the gap to a goal in ±max_turn: steps of at most 0.1 rad/s.
    assert!(a.windows(2).all(|p| (p[1].w - p[0].w).abs() <= 0.1 + 1e-9), "smooth");
    let (lo, hi) = a.iter().fold((f64::MAX, f64::MIN), |(l, h), d| (l.min(d.w), h.max(d.w)));
    assert!(hi - lo > 0.3, "the turn rate varies: {lo}..{hi}");
}

/// A corridor 2 m wide along x (walls y = ±1) from x = −1 to 22, with a
/// door on each side and a side corridor on the left, ending in a wall.
fn corridor() -> Scene {
    Scene::new()
        .wall(-1.0, 1.0, 5.0, 1.0)
        .wall(6.0, 1.0, 14.0, 1.0)
        .wall(15.9, 1.0, 22.0, 1.0)
        .wall(-1.0, -1.0, 10.0, -1.0)
        .wall(11.0, -1.0, 22.0, -1.0)
        .wall(22.0, -1.0, 22.0, 1.0)
        .wall(-1.0, -1.0, -1.0, 1.0)
}

#[test]
fn follow_hallway_keeps_near_the_centre_over_20_m_with_gaps_and_stops_at_the_end() {
    let scene = corridor();
    for seed in 1..=3 {
        let mut h = Harness::new::<FollowHallway>();
        let mut noise = Noise::new(seed, 0.03, 0.02);
        let mut base = Base::new(Pose::new(0.0, 0.2, 0.15));
        let mut worst: f64 = 0.0;
        for _ in 0..3000 {
            let r = noise.apply(scene.sonar(base.pose));
            let d = drive_of(&mut h, &[("sonar", val::<[f32; SONARS]>(r))]).expect("always writes");
            base.step(Some(d), DT);
            let pose = base.pose;
            if pose.x < 20.0 {
                worst = worst.max(pose.y.abs());
            }
            assert!(scene.clearance(pose.x, pose.y) > RADIUS + 0.1, "too close at {pose:?}");
        }
        assert!(worst < 0.3, "seed {seed}: strayed {worst:.2} m off the centre line");
        let pose = base.pose;
        assert!(pose.x > 20.0 && pose.x < 22.0 - RADIUS - 0.3, "stopped before the end wall: {pose:?}");
    }
}

/// A corridor 2.6 m wide (walls y = ±1.3) with the left wall missing for 3 m.
#[test]
fn follow_hallway_keeps_the_width_it_saw_past_a_long_gap() {
    let scene = Scene::new().wall(-1.0, 1.3, 5.0, 1.3).wall(8.0, 1.3, 14.0, 1.3).wall(-1.0, -1.3, 14.0, -1.3);
    let mut h = Harness::new::<FollowHallway>();
    let mut base = Base::new(Pose::new(0.0, 0.0, 0.0));
    let mut worst: f64 = 0.0;
    while base.pose.x < 10.0 {
        let d = drive_of(&mut h, &[("sonar", sonar(&scene, base.pose))]).expect("always writes");
        base.step(Some(d), DT);
        worst = worst.max(base.pose.y.abs());
    }
    // Kept 1.3 m from the right wall: the half-width it saw, not where it was when the gap began.
    assert!(worst < 0.15, "strayed {worst:.2} m off the centre line");
}

#[test]
fn home_turns_to_a_barcode_then_drives_to_it_and_stops_at_stop_distance() {
    let scene = Scene::new().wall(3.1, -3.0, 3.1, 3.0).barcode(42, 3.05, -1.0);
    let mut track = Harness::new::<TrackBarcode>().param("id", val(42i64));
    let mut home = Harness::new::<Home>().param("stop_distance", val(0.5));
    let mut base = Base::new(Pose::new(0.0, 0.0, 0.25));
    let mut first = None;
    let mut d = Drive::default();
    for k in 0..800 {
        // The reader misses the barcode one cycle in five: the tracker holds it.
        let seen = if k % 5 == 4 { Scene::new().barcodes(base.pose) } else { scene.barcodes(base.pose) };
        let target = track.run(&[("barcodes", val(seen))]).get::<Target>("target").unwrap();
        let out = drive_of(&mut home, &[("target", val(target))]);
        first = first.or(out);
        d = out.expect("the barcode stays in view");
        base.step(Some(d), DT);
    }
    let pose = base.pose;
    let first = first.unwrap();
    assert!(first.v == 0.0 && first.w < 0.0, "turns right in place first: {first:?}");
    let dist = (3.05 - pose.x).hypot(-1.0 - pose.y);
    assert!((dist - 0.5).abs() < 0.03, "stopped {dist:.3} m from the barcode");
    assert_eq!(d.v, 0.0);
    assert!(scene.clearance(pose.x, pose.y) > RADIUS);
}

#[test]
fn home_is_silent_when_the_target_is_not_seen() {
    let mut home = Harness::new::<Home>();
    let t = Target { seen: false, id: 3, bearing: 0.1, distance: 2.0 };
    assert_eq!(drive_of(&mut home, &[("target", val(t))]), None);
    let t = Target { seen: true, ..t };
    assert!(drive_of(&mut home, &[("target", val(t))]).is_some());
}

#[test]
fn home_position_reaches_an_odometry_goal() {
    let mut h = Harness::new::<HomePosition>().param("x", val(2.0)).param("y", val(-1.5));
    let mut pose = Pose::new(0.0, 0.0, 0.0);
    for _ in 0..600 {
        pose = pose.step(drive_of(&mut h, &[("odom", odom(pose))]).expect("always writes"), DT);
    }
    assert!((pose.x - 2.0).hypot(pose.y + 1.5) <= 0.1, "{pose:?}");
    assert_eq!(drive_of(&mut h, &[("odom", odom(pose))]), Some(Drive::default()), "stopped");
    // A new goal 0.17 m behind (within twice the stop distance of the old one): it goes there.
    let (gx, gy) = (pose.x - 0.17 * pose.theta.cos(), pose.y - 0.17 * pose.theta.sin());
    h.set("x", val(gx));
    h.set("y", val(gy));
    for _ in 0..600 {
        pose = pose.step(drive_of(&mut h, &[("odom", odom(pose))]).expect("always writes"), DT);
    }
    assert!((pose.x - gx).hypot(pose.y - gy) <= 0.1, "the goal just behind: {pose:?}");
}

#[test]
fn home_position_backs_up_to_a_goal_just_behind_when_allowed() {
    // 0.8 m behind and a little to the left: backed up to, facing the same way.
    let (gx, gy) = (-0.8, 0.1);
    let mut h =
        Harness::new::<HomePosition>().param("x", val(gx)).param("y", val(gy)).param("reverse_within", val(1.0));
    let mut pose = Pose::new(0.0, 0.0, 0.0);
    let mut backwards = false;
    for _ in 0..600 {
        let d = drive_of(&mut h, &[("odom", odom(pose))]).expect("always writes");
        backwards |= d.v < 0.0;
        pose = pose.step(d, DT);
    }
    assert!(backwards, "drove backwards");
    assert!((pose.x - gx).hypot(pose.y - gy) <= 0.1, "{pose:?}");
    assert!(pose.theta.abs() < 20f64.to_radians(), "did not turn round: {:.0}°", pose.theta.to_degrees());
    // Farther than `reverse_within`: turns round and drives forwards, as by default.
    let mut h =
        Harness::new::<HomePosition>().param("x", val(-1.5)).param("y", val(0.0)).param("reverse_within", val(1.0));
    let mut pose = Pose::new(0.0, 0.0, 0.0);
    for _ in 0..600 {
        let d = drive_of(&mut h, &[("odom", odom(pose))]).expect("always writes");
        assert!(d.v >= 0.0, "forwards only");
        pose = pose.step(d, DT);
    }
    assert!((pose.x + 1.5).hypot(pose.y) <= 0.1, "{pose:?}");
}

/// Runs `turn` on a base with acceleration limits until it falls silent
/// and the base has stopped; the heading turned.
fn turn_until_silent(h: &mut Harness, pose: &mut Pose) -> f64 {
    let start = pose.theta;
    let mut base = Base::new(*pose);
    for _ in 0..1000 {
        let d = drive_of(h, &[("odom", odom(base.pose))]);
        assert!(d.is_none_or(|d| d.v == 0.0), "turns in place");
        base.step(d, DT);
        if d.is_none() && base.w == 0.0 {
            *pose = base.pose;
            return pose.theta - start;
        }
    }
    panic!("never finished turning");
}

#[test]
fn turn_turns_by_the_angle_then_is_silent_and_again_after_reactivation() {
    let mut h = Harness::new::<Turn>();
    let mut pose = Pose::new(1.0, 2.0, 3.0);
    let turned = turn_until_silent(&mut h, &mut pose);
    assert!((turned - FRAC_PI_2).abs() < 5f64.to_radians(), "turned {:.1}°", turned.to_degrees());
    assert_eq!(drive_of(&mut h, &[("odom", odom(pose))]), None, "stays silent");
    // Deactivated, then activated again with another angle: a new turn from there.
    h.skip(10);
    h.set("angle", val(-PI));
    let turned = turn_until_silent(&mut h, &mut pose);
    assert!((turned + PI).abs() < 5f64.to_radians(), "turned {:.1}°", turned.to_degrees());
}

#[test]
fn a_turn_goes_on_across_cycles_it_did_not_run_in() {
    // Its odometry missed a few cycles (the skill stays on, it just does not run): the turn goes
    // on from where it was. It once took a gap between two runs for a switch on and began a
    // whole new turn from there, turning 90° more than asked.
    let mut h = Harness::new::<Turn>();
    let mut pose = Pose::new(0.0, 0.0, 0.0);
    let mut base = Base::new(pose);
    for _ in 0..10 {
        let d = drive_of(&mut h, &[("odom", odom(base.pose))]);
        base.step(d, DT);
    }
    h.gap(3);
    let so_far = base.pose.theta;
    assert!(so_far > 0.05, "it had begun: {so_far}");
    pose = base.pose;
    let turned = turn_until_silent(&mut h, &mut pose) + so_far;
    assert!((turned - FRAC_PI_2).abs() < 5f64.to_radians(), "turned {:.1}° in all", turned.to_degrees());
}

/// A wall along x = 2 (0.1 m thick) with a 1 m door centred on y = 0.
fn door_wall() -> Scene {
    Scene::new()
        .wall(2.0, -4.0, 2.0, -0.5)
        .wall(2.0, 0.5, 2.0, 4.0)
        .wall(2.1, -4.0, 2.1, -0.5)
        .wall(2.1, 0.5, 2.1, 4.0)
        .wall(2.0, -0.5, 2.1, -0.5)
        .wall(2.0, 0.5, 2.1, 0.5)
}

#[test]
fn pass_door_goes_through_a_door_ahead_without_touching_the_jambs() {
    let scene = door_wall();
    let starts = [Pose::new(0.6, -0.15, 0.12), Pose::new(0.8, 0.12, -0.1), Pose::new(0.6, 0.0, 0.0)];
    for (seed, start) in starts.into_iter().enumerate() {
        let mut h = Harness::new::<PassDoor>().param("distance", val(2.5));
        let mut noise = Noise::new(seed as u64, 0.03, 0.02);
        let mut base = Base::new(start);
        let mut pose = start;
        let mut passed = false;
        for _ in 0..1000 {
            let r = val::<[f32; SONARS]>(noise.apply(scene.sonar(pose)));
            let out = h.run(&[("sonar", r), ("odom", odom(pose))]);
            passed = out.get::<bool>("passed").unwrap();
            base.step(out.get::<Drive>("drive"), DT);
            pose = base.pose;
            assert!(scene.clearance(pose.x, pose.y) > RADIUS + 0.03, "from {start:?}: too close at {pose:?}");
        }
        assert!(passed && pose.x > 2.1 + RADIUS + 0.5, "from {start:?}: went through to {pose:?}");
    }
}

/// An elevator car 1.6 × 1.6 m (x 2.0..3.6, y −0.8..0.8) with a 1 m door in its front wall.
fn car() -> Scene {
    Scene::new()
        .wall(2.0, -3.0, 2.0, -0.5)
        .wall(2.0, 0.5, 2.0, 3.0)
        .wall(2.0, 0.8, 3.6, 0.8)
        .wall(2.0, -0.8, 3.6, -0.8)
        .wall(3.6, -0.8, 3.6, 0.8)
}

#[test]
fn enter_car_stops_inside_and_leave_car_stops_outside() {
    let scene = car();
    let mut h = Harness::new::<EnterCar>();
    let mut noise = Noise::new(11, 0.03, 0.02);
    let mut base = Base::new(Pose::new(1.1, 0.1, 0.05));
    let mut pose = base.pose;
    let mut entered = false;
    for _ in 0..600 {
        let r = val::<[f32; SONARS]>(noise.apply(scene.sonar(pose)));
        let out = h.run(&[("sonar", r), ("odom", odom(pose))]);
        entered = out.get::<bool>("entered").unwrap();
        base.step(out.get::<Drive>("drive"), DT);
        pose = base.pose;
        assert!(scene.clearance(pose.x, pose.y) > RADIUS + 0.03, "too close at {pose:?}");
    }
    assert!(entered && pose.x - RADIUS > 2.0 && pose.x + RADIUS < 3.6, "inside: {pose:?}");
    // Turned around, it leaves.
    pose.theta = wrap(pose.theta + PI);
    let mut h = Harness::new::<LeaveCar>();
    let mut base = Base::new(pose);
    let mut exited = false;
    for _ in 0..600 {
        let r = val::<[f32; SONARS]>(noise.apply(scene.sonar(pose)));
        let out = h.run(&[("sonar", r), ("odom", odom(pose))]);
        exited = out.get::<bool>("exited").unwrap();
        base.step(out.get::<Drive>("drive"), DT);
        pose = base.pose;
        assert!(scene.clearance(pose.x, pose.y) > RADIUS + 0.03, "too close at {pose:?}");
    }
    assert!(exited && pose.x + RADIUS < 2.0, "outside: {pose:?}");
    assert_eq!(
        h.run(&[("sonar", sonar(&scene, pose)), ("odom", odom(pose))]).get::<Drive>("drive"),
        Some(Drive::default())
    );
}

/// A corridor 2.41 m wide (y −1.2..1.21) along x with a + junction (side
/// corridors 2.03 m wide, 3 m deep, at x 10..12.03), a door on the right at
/// x 5..6.14 and bins against the walls before the junction, as in a
/// generated building.
fn plus_junction() -> Scene {
    let s = Scene::new()
        .wall(-1.0, 1.21, 10.0, 1.21)
        .wall(12.03, 1.21, 24.0, 1.21)
        .wall(-1.0, -1.2, 5.0, -1.2)
        .wall(6.14, -1.2, 10.0, -1.2)
        .wall(12.03, -1.2, 24.0, -1.2)
        .wall(10.0, 1.21, 10.0, 4.2)
        .wall(12.03, 1.21, 12.03, 4.2)
        .wall(10.0, 4.2, 12.03, 4.2)
        .wall(10.0, -1.2, 10.0, -4.2)
        .wall(12.03, -1.2, 12.03, -4.2)
        .wall(10.0, -4.2, 12.03, -4.2);
    let s = s.rect(8.6, -1.2, 9.07, -0.78);
    s.rect(7.3, 0.73, 7.61, 1.21)
}

#[test]
fn follow_hallway_goes_straight_through_a_plus_junction_past_clutter() {
    let scene = plus_junction();
    for (seed, y0) in [(1u64, 0.0), (2, 0.2), (3, -0.2)] {
        let mut h = Harness::new::<FollowHallway>().param("speed", val(0.4));
        let mut noise = Noise::new(seed, 0.03, 0.02);
        let mut base = Base::new(Pose::new(0.0, y0, 0.0));
        let mut worst: f64 = 0.0;
        while base.pose.x < 16.0 {
            let r = noise.apply(scene.sonar(base.pose));
            let d = drive_of(&mut h, &[("sonar", val::<[f32; SONARS]>(r)), ("odom", odom(base.pose))])
                .expect("always writes");
            base.step(Some(d), DT);
            worst = worst.max(base.pose.theta.abs());
            assert!(base.pose.y.abs() < 1.0, "seed {seed}: into a side way at {:?}", base.pose);
        }
        eprintln!("seed {seed}: worst heading {:.1}°", worst.to_degrees());
        assert!(worst < 25f64.to_radians(), "seed {seed}: turned {:.0}° off the corridor", worst.to_degrees());
    }
}

#[test]
fn follow_hallway_with_odometry_turns_back_to_its_way_when_turned_round() {
    let scene = Scene::new().wall(-20.0, 1.1, 30.0, 1.1).wall(-20.0, -1.1, 30.0, -1.1);
    let mut h = Harness::new::<FollowHallway>().param("speed", val(0.4));
    let mut base = Base::new(Pose::new(0.0, 0.0, 0.0));
    for _ in 0..100 {
        let d = drive_of(&mut h, &[("sonar", sonar(&scene, base.pose)), ("odom", odom(base.pose))]).expect("writes");
        base.step(Some(d), DT);
    }
    let x_then = base.pose.x;
    // Something turns the robot round (as avoidance might).
    base = Base::new(Pose::new(base.pose.x, base.pose.y, std::f64::consts::PI));
    for _ in 0..600 {
        let d = drive_of(&mut h, &[("sonar", sonar(&scene, base.pose)), ("odom", odom(base.pose))]).expect("writes");
        base.step(Some(d), DT);
    }
    assert!(base.pose.x > x_then + 2.0, "went back the way it came: {:?} (from x {x_then:.2})", base.pose);
    assert!(base.pose.theta.cos() > 0.9, "faces its way again: {:?}", base.pose);
}

#[test]
fn follow_hallway_with_odometry_returns_to_its_line_across_a_lobby() {
    // A lobby (x 0..7, y -4..4) with its entry straight ahead (y -0.9..0.9), the corridor
    // beyond ending at x 14. Walking out of it, the robot is pushed aside and turned (going
    // round someone, as avoidance does): it comes back to the line it was on before the
    // entry, not parallel to it beside the jamb (generated building 20004, goal floor).
    let scene = Scene::new()
        .wall(0.0, -4.0, 7.0, -4.0)
        .wall(0.0, 4.0, 7.0, 4.0)
        .wall(0.0, -4.0, 0.0, 4.0)
        .wall(7.0, -4.0, 7.0, -0.9)
        .wall(7.0, 0.9, 7.0, 4.0)
        .wall(7.0, -0.9, 14.0, -0.9)
        .wall(7.0, 0.9, 14.0, 0.9)
        .wall(14.0, -0.9, 14.0, 0.9);
    for (seed, push, turn) in [(1u64, -0.45, -60f64), (2, 0.4, 50.0), (3, -0.3, 0.0)] {
        let mut h = Harness::new::<FollowHallway>().param("speed", val(0.4));
        let mut noise = Noise::new(seed, 0.03, 0.02);
        let mut base = Base::new(Pose::new(1.0, 0.0, 0.0));
        let mut at_entry = None;
        for i in 0..1200 {
            if i == 40 {
                base = Base::new(Pose::new(base.pose.x, base.pose.y + push, turn.to_radians()));
            }
            let r = noise.apply(scene.sonar(base.pose));
            let d = drive_of(&mut h, &[("sonar", val::<[f32; SONARS]>(r)), ("odom", odom(base.pose))])
                .expect("always writes");
            base.step(Some(d), DT);
            if at_entry.is_none() && base.pose.x > 6.5 {
                at_entry = Some(base.pose);
            }
        }
        let at_entry = at_entry.unwrap_or_else(|| panic!("seed {seed}: never reached the entry: {:?}", base.pose));
        assert!(at_entry.y.abs() < 0.15, "seed {seed}: at the entry {:.2} m off its line", at_entry.y);
        assert!(base.pose.x > 12.0 && base.pose.y.abs() < 0.3, "seed {seed}: stopped at {:?}", base.pose);
    }
}

/// A corridor 2.49 m wide along x (y 6.51..9) ending in a crossing corridor
/// 1.82 m wide (x 12.79..14.61) with a dead end 3.3 m to the right, an alcove
/// on its left past the corner and a bin in that corner: a T, as in
/// generated building 20027's floor 3.
fn t_end() -> Scene {
    let s = Scene::new()
        .wall(7.43, 6.51, 12.79, 6.51)
        .wall(7.43, 9.0, 12.79, 9.0)
        .wall(12.79, 3.2, 12.79, 6.51)
        .wall(12.79, 9.0, 12.79, 10.97)
        .wall(12.79, 10.97, 10.0, 10.97)
        .wall(10.0, 10.97, 10.0, 12.82)
        .wall(10.0, 12.82, 12.79, 12.82)
        .wall(12.79, 12.82, 12.79, 30.0)
        .wall(14.61, 3.2, 14.61, 30.0)
        .wall(12.79, 3.2, 14.61, 3.2);
    let s = s.rect(12.8, 9.38, 13.15, 9.64);
    s.rect(14.18, 11.9, 14.6, 12.37)
}

#[test]
fn follow_hallway_with_odometry_holds_its_way_into_a_t_instead_of_turning_into_a_branch() {
    let scene = t_end();
    for (seed, y0) in [(1u64, 0.0), (2, 0.15), (3, -0.15)] {
        let mut h = Harness::new::<FollowHallway>().param("speed", val(0.4));
        let mut noise = Noise::new(seed, 0.03, 0.02);
        let mut base = Base::new(Pose::new(8.5, 7.75 + y0, 0.0));
        let mut worst: f64 = 0.0;
        for _ in 0..800 {
            let r = noise.apply(scene.sonar(base.pose));
            let d = drive_of(&mut h, &[("sonar", val::<[f32; SONARS]>(r)), ("odom", odom(base.pose))])
                .expect("always writes");
            base.step(Some(d), DT);
            worst = worst.max(base.pose.theta.abs());
        }
        // It comes to a stop facing the crossing corridor's far wall, in the junction, as
        // a route's `until: wall` expects; it does not wander into either branch.
        assert!(worst < 20f64.to_radians(), "seed {seed}: turned {:.0}° into a branch", worst.to_degrees());
        assert!(base.pose.x > 12.9 && (base.pose.y - 7.75).abs() < 0.9, "seed {seed}: stopped at {:?}", base.pose);
    }
}
