//! `std.sonar_filter`: dead sonars found while the robot moves, filled in
//! from their neighbours; a live sonar seeing through a door never is.

use situate_robot::{Odom, SonarHealth, SONARS};
use situate_skills::SonarFilter;

use crate::harness::{val, Harness};
use crate::scene::{Noise, Pose, Scene, MAX_RANGE};

/// A corridor 2 m wide along x with doors on both sides every 4 m.
fn corridor() -> Scene {
    let mut s = Scene::new();
    for k in 0..10 {
        let x = f64::from(k) * 4.0;
        s = s.wall(x, 1.0, x + 3.0, 1.0).wall(x, -1.0, x + 3.0, -1.0);
    }
    s
}

/// Drives along the corridor at 5 cm per cycle, turning slowly (so every
/// sonar faces a wall now and then), with `dead` reading no echo; the
/// filter's outputs after each cycle.
fn drive(dead: Option<usize>, cycles: usize) -> Vec<([f32; SONARS], SonarHealth)> {
    let scene = corridor();
    let mut h = Harness::new::<SonarFilter>();
    let mut noise = Noise::new(3, 0.02, 0.0);
    (0..cycles)
        .map(|k| {
            let pose = Pose::new(0.5 + 0.05 * k as f64, 0.1, 0.02 * k as f64);
            let mut r = noise.apply(scene.sonar(pose));
            if let Some(i) = dead {
                r[i] = MAX_RANGE as f32;
            }
            let odom = Odom { x: pose.x, y: pose.y, theta: pose.theta, v: 0.5, w: 0.0 };
            let out = h.run(&[("raw", val(r)), ("odom", val(odom))]);
            (out.get::<[f32; SONARS]>("range").expect("range"), out.get::<SonarHealth>("health").expect("health"))
        })
        .collect()
}

#[test]
fn a_dead_side_sonar_is_found_and_filled_in_from_its_neighbours() {
    for dead in [6usize, 18, 0, 5] {
        let trace = drive(Some(dead), 400);
        let (range, health) = trace.last().unwrap();
        assert_eq!(health.mask, 1 << dead, "sonar {dead}: {health:?}");
        assert_eq!(health.dead, 1);
        let (a, b) = (range[(dead + 1) % SONARS], range[(dead + SONARS - 1) % SONARS]);
        assert_eq!(range[dead], a.min(b), "sonar {dead} filled with the nearer neighbour");
        // Before enough evidence, the reading passes through unchanged.
        assert_eq!(trace[0].1.dead, 0);
    }
}

#[test]
fn live_sonars_seeing_through_doors_are_never_taken_as_dead() {
    let trace = drive(None, 600);
    assert!(trace.iter().all(|(_, h)| h.dead == 0), "{:?}", trace.iter().find(|(_, h)| h.dead > 0));
}

#[test]
fn standing_in_front_of_an_opening_is_no_evidence() {
    // Facing a doorway: sonar 0 sees through, its neighbours hit the jambs, for a long time.
    let scene = Scene::new().wall(1.0, -3.0, 1.0, -0.3).wall(1.0, 0.3, 1.0, 3.0);
    let mut h = Harness::new::<SonarFilter>();
    let pose = Pose::new(0.0, 0.0, 0.0);
    let odom = Odom { x: 0.0, y: 0.0, theta: 0.0, v: 0.0, w: 0.0 };
    for _ in 0..2000 {
        let out = h.run(&[("raw", val(scene.sonar(pose))), ("odom", val(odom))]);
        assert_eq!(out.get::<SonarHealth>("health").unwrap().dead, 0);
    }
}

#[test]
fn a_dead_sonar_that_answers_again_is_live() {
    let mut h = Harness::new::<SonarFilter>().param("evidence", situate::Value::I64(3));
    let mut r = [1.0f32; SONARS];
    r[4] = MAX_RANGE as f32;
    for k in 0..5 {
        let odom = Odom { x: 0.1 * f64::from(k), y: 0.0, theta: 0.0, v: 0.5, w: 0.0 };
        h.run(&[("raw", val(r)), ("odom", val(odom))]);
    }
    let odom = Odom { x: 1.0, y: 0.0, theta: 0.0, v: 0.5, w: 0.0 };
    assert_eq!(h.run(&[("raw", val(r)), ("odom", val(odom))]).get::<SonarHealth>("health").unwrap().mask, 1 << 4);
    r[4] = 2.0;
    let out = h.run(&[("raw", val(r)), ("odom", val(odom))]);
    assert_eq!(out.get::<SonarHealth>("health").unwrap().dead, 0);
    assert_eq!(out.get::<[f32; SONARS]>("range").unwrap()[4], 2.0);
}
