//! The elevator logic on its own (`Bank`), as the physics robot steps it: a push of the call
//! button brings a car that opens at the robot's floor, a push on the panel from inside takes
//! it to the floor chosen, and a push out of reach or from behind the button does nothing.

use std::f64::consts::FRAC_PI_2;
use std::sync::Arc;

use situate_sim::elevator::{Bank, CarPhase, RobotAt};
use situate_sim::geom::P2;
use situate_sim::load_map;

fn bank(seed: u64) -> Bank {
    let path = format!("{}/../../../maps/default.yaml", env!("CARGO_MANIFEST_DIR"));
    match load_map(path) {
        Ok(m) => Bank::new(Arc::new(m), seed),
        Err(e) => panic!("{e}"),
    }
}

/// Steps `bank` by 10 ms with the robot at `robot` until `done` holds or `limit` s pass; the time.
fn run(bank: &mut Bank, robot: &RobotAt, t: &mut f64, limit: f64, done: impl Fn(&Bank) -> bool) -> bool {
    let end = *t + limit;
    while *t < end {
        bank.step(robot, *t, 0.01);
        *t += 0.01;
        if done(bank) {
            return true;
        }
    }
    false
}

#[test]
fn a_call_brings_a_car_and_its_panel_takes_the_robot_to_the_floor_chosen() {
    let mut b = bank(3);
    let mut t = 0.0;
    // The basement lobby's call button is at (15, 17.98), facing south.
    let lobby = RobotAt { floor: -1, pos: P2::new(15.0, 17.5), theta: FRAC_PI_2 };
    assert!(!b.press(&RobotAt { pos: P2::new(15.0, 16.5), ..lobby }, 30, 0.6, 0.44, t), "out of reach");
    assert!(!b.press(&RobotAt { theta: -FRAC_PI_2, ..lobby }, 30, 0.6, 0.44, t), "facing away");
    assert!(b.press(&lobby, 30, 0.6, 0.44, t));
    // A car comes within the map's arrive_s (5–20 s) and opens its doors at the basement.
    let open = |b: &Bank| b.states().iter().position(|c| c.floor() == -1 && matches!(c.phase, CarPhase::Open { .. }));
    assert!(run(&mut b, &lobby, &mut t, 30.0, |b| open(b).is_some()), "no car came: {:?}", b.states());
    let k = open(&b).unwrap_or_default();
    assert_eq!(b.states()[k].door, 1.0);
    // From inside, in front of its panel (2 cm off the back wall), floor 4 is chosen.
    let car = &b.map().elevator.cars[k];
    let (panel, _) = car.panel();
    let inside = RobotAt { floor: -1, pos: P2::new(panel.x, panel.y - 0.5), theta: FRAC_PI_2 };
    assert!(b.press(&inside, 4, 0.6, 0.44, t));
    let at = |b: &Bank| b.states()[k].floor() == 4 && matches!(b.states()[k].phase, CarPhase::Open { .. });
    assert!(run(&mut b, &inside, &mut t, 60.0, at), "the car did not take the robot up: {:?}", b.states()[k]);
    assert_eq!(b.states()[k].pos, 4.0);
    // A floor the building lacks is not taken.
    let upstairs = RobotAt { floor: 4, ..inside };
    assert!(!b.press(&upstairs, 9, 0.6, 0.44, t));
}

#[test]
fn the_same_seed_gives_the_same_cars() {
    let lobby = RobotAt { floor: -1, pos: P2::new(15.0, 17.5), theta: FRAC_PI_2 };
    let trace = |seed: u64| {
        let mut b = bank(seed);
        let mut t = 0.0;
        let mut out = Vec::new();
        for _ in 0..5 {
            b.press(&lobby, 30, 0.6, 0.44, t);
            run(&mut b, &lobby, &mut t, 40.0, |_| false);
            out.extend(b.states().iter().map(|c| (c.pos.to_bits(), c.door.to_bits())));
        }
        out
    };
    assert_eq!(trace(5), trace(5));
}
