//! The simulator's promises: determinism, walls, sensors, the elevator, the arm.

use std::f64::consts::{FRAC_PI_2, PI};

use situate_sim::world::CarPhase;
use situate_sim::{load_map, BaseLimits, Map, SonarSettings, World, WorldConfig};

fn map_path(name: &str) -> String {
    format!("{}/../../../maps/{name}", env!("CARGO_MANIFEST_DIR"))
}

fn map(name: &str) -> Map {
    match load_map(map_path(name)) {
        Ok(m) => m,
        Err(e) => panic!("{e}"),
    }
}

/// Sonar, odometry and truth of a run of `cycles` 50 ms cycles with a fixed
/// command pattern, as bits.
fn run(seed: u64, cycles: u64) -> Vec<u64> {
    let mut w = World::new(map("default.yaml"), seed);
    let mut out = Vec::new();
    for i in 1..=cycles {
        let t = i as f64 * 0.05;
        w.advance_to(t);
        let v = 0.6;
        let wr = (i as f64 * 0.037).sin() * 1.2;
        w.set_drive(v, wr, BaseLimits::default());
        out.extend(w.sonar(&SonarSettings::default()).iter().map(|r| u64::from(r.to_bits())));
        let (x, y, th, ov, ow) = w.odom();
        let r = w.robot();
        out.extend([x, y, th, ov, ow, r.x, r.y, r.theta].map(f64::to_bits));
    }
    out
}

#[test]
fn same_seed_same_run_bit_for_bit_and_other_seeds_differ() {
    // 500 cycles of 50 ms = 2,500 physics steps of 10 ms.
    let a = run(7, 500);
    let b = run(7, 500);
    assert_eq!(a.len(), b.len());
    assert!(a == b, "two runs with seed 7 differ");
    let c = run(8, 500);
    assert!(a != c, "seeds 7 and 8 gave the same run");
}

#[test]
fn the_result_does_not_depend_on_how_often_devices_ask() {
    // One world asked every 10 ms, one every 50 ms: same state at 50 ms marks.
    let mut fine = World::new(map("small.yaml"), 3);
    let mut coarse = World::new(map("small.yaml"), 3);
    for i in 1..=200u64 {
        for k in 1..=5u64 {
            fine.advance_to((i * 5 + k - 5) as f64 * 0.01);
        }
        coarse.advance_to(i as f64 * 0.05);
        assert_eq!(fine.robot(), coarse.robot());
        assert_eq!(fine.odom(), coarse.odom());
        fine.set_drive(0.3, -0.4, BaseLimits::default());
        coarse.set_drive(0.3, -0.4, BaseLimits::default());
    }
    assert!(fine.robot().x != 3.0 || fine.robot().y != 2.5, "the robot never moved");
}

fn fast() -> BaseLimits {
    BaseLimits { max_v: 3.0, max_w: 2.0, acc_v: 20.0, acc_w: 3.0 }
}

#[test]
fn the_robot_stops_at_a_wall_at_full_speed() {
    let mut w = World::new(map("small.yaml"), 1);
    w.place_robot(0, 3.0, 2.5, -FRAC_PI_2);
    for i in 1..=500 {
        w.set_drive(3.0, 0.0, fast());
        w.advance_to(i as f64 * 0.01);
        assert!(w.robot().y >= 0.25 - 1e-6, "inside the wall at y = {}", w.robot().y);
    }
    assert!(w.robot().y < 0.3, "the robot did not reach the wall: y = {}", w.robot().y);
}

#[test]
fn big_steps_never_tunnel_through_a_wall() {
    // 0.6 m per step, more than the robot's diameter.
    let cfg = WorldConfig { dt: 0.2, ..WorldConfig::default() };
    let mut w = World::with_config(map("small.yaml"), 1, cfg);
    w.place_robot(0, 3.0, 1.3, -FRAC_PI_2);
    for i in 1..=100 {
        w.set_drive(3.0, 0.0, fast());
        w.advance_to(i as f64 * 0.2);
        assert!(w.robot().y >= 0.25 - 1e-6, "passed through the wall: y = {}", w.robot().y);
    }
}

#[test]
fn sonar_reads_walls_from_the_centre_with_max_range_for_no_echo() {
    let mut w = World::new(map("small.yaml"), 1);
    w.place_robot(0, 3.0, 2.0, 0.0);
    let clean = SonarSettings { noise: 0.0, dropout: 0.0, cone: 0.0, rays: 1, ..SonarSettings::default() };
    let r = w.sonar(&clean);
    // Ahead: the east wall at x = 6; left: the call button wall at y = 4.
    assert!((r[0] - 3.0).abs() < 1e-4, "ahead {}", r[0]);
    assert!((r[6] - 2.0).abs() < 1e-4, "left {}", r[6]);
    let short = SonarSettings { max_range: 1.0, ..clean };
    assert_eq!(w.sonar(&short)[0], 1.0);
    let deaf = SonarSettings { dropout: 1.0, ..clean };
    assert!(w.sonar(&deaf).iter().all(|&x| x == 4.0));
}

fn ids(w: &World, range: f64, fov_deg: f64) -> Vec<i64> {
    w.barcodes(range, fov_deg.to_radians()).into_iter().map(|b| b.0).collect()
}

#[test]
fn barcode_reader_respects_range_field_of_view_and_walls() {
    let mut w = World::new(map("small.yaml"), 1);
    // The lab door's barcode 10 at (4.25, 0.02), facing north.
    w.place_robot(0, 4.25, 2.0, -FRAC_PI_2);
    let seen = w.barcodes(5.0, 60f64.to_radians());
    let (id, bearing, dist) = seen.iter().copied().find(|b| b.0 == 10).expect("barcode 10 in view");
    assert_eq!(id, 10);
    assert!(bearing.abs() < 1e-9 && (dist - 1.98).abs() < 1e-9, "{bearing} {dist}");
    assert!(!ids(&w, 1.5, 60.0).contains(&10), "out of range");
    w.place_robot(0, 4.25, 2.0, 0.0);
    assert!(!ids(&w, 5.0, 60.0).contains(&10), "90° off is outside ±60°");
    assert!(ids(&w, 5.0, 100.0).contains(&10));
    // The call button's barcode 30 hidden behind the box at (1..1.6, 1..1.6).
    let (bx, by) = (3.0, 3.98);
    let (rx, ry) = (1.3, 0.5);
    w.place_robot(0, rx, ry, (by - ry).atan2(bx - rx));
    assert!(!ids(&w, 5.0, 60.0).contains(&30), "seen through the box");
    w.place_robot(0, 3.0, 1.0, FRAC_PI_2);
    assert!(ids(&w, 5.0, 60.0).contains(&30));
    // Car 1's barcode behind its closed door.
    w.place_robot(0, 1.8, 3.0, FRAC_PI_2);
    assert!(!ids(&w, 5.0, 60.0).contains(&201), "seen through a closed car door");
}

/// Advances in 50 ms cycles until `done` or `limit_s`; returns whether done.
fn run_until(w: &mut World, limit_s: f64, mut done: impl FnMut(&World) -> bool) -> bool {
    let mut t = w.time_s();
    while t < limit_s {
        t += 0.05;
        w.advance_to(t);
        if done(w) {
            return true;
        }
    }
    false
}

#[test]
fn elevator_call_arrive_time_out_then_ride_to_another_floor() {
    let mut w = World::new(map("small.yaml"), 11);
    w.place_robot(0, 3.0, 3.5, FRAC_PI_2);
    assert!(w.press(0, 0.6, 25f64.to_radians()), "the call button is in reach");
    // A car arrives (after 5..10 s) and opens.
    assert!(run_until(&mut w, 15.0, |w| w.cars().iter().any(|c| c.door >= 1.0)), "no car came");
    let k = w.cars().iter().position(|c| c.door >= 1.0).unwrap_or(usize::MAX);
    assert_eq!(w.cars()[k].floor(), 0);
    // Its barcode is visible through the open door from the lobby.
    let car = w.map().elevator.cars[k].clone();
    let cx = (car.x0 + car.x1) / 2.0;
    w.place_robot(0, cx, 3.0, FRAC_PI_2);
    assert!(ids(&w, 5.0, 60.0).contains(&car.barcode));
    // Nobody gets in: the doors time out and close.
    assert!(run_until(&mut w, 60.0, |w| w.cars()[k].door == 0.0), "doors never closed");
    assert_eq!(w.cars()[k].phase, CarPhase::Idle);
    assert!(!ids(&w, 5.0, 60.0).contains(&car.barcode), "closed door hides the car's barcode");
    // Call again, get in, press 1.
    w.place_robot(0, 3.0, 3.5, FRAC_PI_2);
    assert!(w.press(0, 0.6, 25f64.to_radians()));
    assert!(run_until(&mut w, 90.0, |w| w.cars().iter().any(|c| c.door >= 1.0)), "no car came again");
    let k = w.cars().iter().position(|c| c.door >= 1.0).unwrap_or(usize::MAX);
    let car = w.map().elevator.cars[k].clone();
    let cx = (car.x0 + car.x1) / 2.0;
    w.place_robot(0, cx, car.y1 - 0.5, FRAC_PI_2);
    assert!(!w.press(7, 0.6, 25f64.to_radians()), "there is no floor 7");
    assert!(w.press(1, 0.6, 25f64.to_radians()), "the panel is in reach");
    assert!(run_until(&mut w, 150.0, |w| w.cars()[k].floor() == 1 && w.cars()[k].door >= 1.0), "never got to 1");
    assert_eq!(w.robot().floor, 1);
    assert_eq!(w.cars()[k].pos, 1.0);
    // The office on floor 1: the message counts there.
    w.say("hello");
    w.advance_to(w.time_s() + 0.05);
    assert!(w.delivered_at().is_none(), "inside the car is not the office");
}

#[test]
fn a_car_does_not_close_on_the_robot_in_its_doorway() {
    let mut w = World::new(map("small.yaml"), 5);
    w.place_robot(0, 3.0, 3.5, FRAC_PI_2);
    assert!(w.press(0, 0.6, 25f64.to_radians()));
    assert!(run_until(&mut w, 15.0, |w| w.cars().iter().any(|c| c.door >= 1.0)));
    let k = w.cars().iter().position(|c| c.door >= 1.0).unwrap_or(usize::MAX);
    let door = w.map().elevator.cars[k].door();
    w.place_robot(0, (door.a.x + door.b.x) / 2.0, door.a.y, FRAC_PI_2);
    assert!(!run_until(&mut w, 80.0, |w| w.cars()[k].door < 0.5), "the door closed on the robot");
}

#[test]
fn the_arm_only_presses_within_reach_in_front() {
    let mut w = World::new(map("small.yaml"), 1);
    let fov = 25f64.to_radians();
    w.place_robot(0, 3.0, 3.3, FRAC_PI_2); // 0.68 m away
    assert!(!w.press(0, 0.6, fov));
    w.place_robot(0, 3.0, 3.5, FRAC_PI_2 + 40f64.to_radians()); // in reach, 40° off
    assert!(!w.press(0, 0.6, fov));
    w.place_robot(0, 3.0, 3.5, PI); // facing away
    assert!(!w.press(0, 0.6, fov));
    w.place_robot(0, 3.0, 3.5, FRAC_PI_2 + 20f64.to_radians());
    assert!(w.press(0, 0.6, fov));
    assert_eq!(w.arm_counts(), (4, 1));
}

#[test]
fn saying_the_message_in_the_office_delivers_it() {
    let mut w = World::new(map("small.yaml"), 1);
    w.say("not here");
    w.advance_to(0.05);
    assert_eq!(w.delivered_at(), None);
    w.place_robot(1, 3.0, 2.0, 0.0);
    w.advance_to(1.0);
    w.say("hello");
    w.advance_to(1.05);
    assert_eq!(w.delivered_at(), Some(1.0));
    assert_eq!(w.said().len(), 2);
    // Where each was said, for tasks with several stops (`situate_sim::task`).
    let said = w.said();
    assert_eq!((said[1].floor, said[1].text.as_str(), said[1].time_s), (1, "hello", 1.0));
    assert!((said[1].at.x - 3.0).abs() < 1e-9 && (said[1].at.y - 2.0).abs() < 1e-9);
    let m = map("small.yaml");
    use situate_sim::task::{judge, parse};
    assert_eq!(judge(&m, &parse("office").unwrap(), said), vec![Some(1.0)]);
    // The first was said at the start, 1.5 m from floor 0's call button; each utterance
    // makes one stop at most, in order.
    assert_eq!(judge(&m, &parse("lobby:0,office").unwrap(), said), vec![Some(0.0), Some(1.0)]);
    assert_eq!(judge(&m, &parse("office,office").unwrap(), said), vec![Some(1.0), None]);
    assert_eq!(judge(&m, &parse("office,lobby:0").unwrap(), said), vec![Some(1.0), None]);
}

#[test]
fn a_lobby_stop_is_made_in_front_of_that_floors_button_only() {
    use situate_sim::task::{judge, parse, LOBBY_REACH_M};
    let m = map("small.yaml");
    let button = m.floor(0).and_then(|f| f.lobby.as_ref()).map(|l| l.button).expect("floor 0 has a lobby");
    let mut w = World::new(m.clone(), 1);
    // Near enough, on floor 0; then as near on floor 1's plan but on floor 0 far away.
    w.place_robot(0, button.x, button.y - (LOBBY_REACH_M - 0.5), 0.0);
    w.say("first");
    w.advance_to(0.1);
    w.place_robot(0, button.x, button.y - (LOBBY_REACH_M + 1.0), 0.0);
    w.say("too far");
    w.advance_to(0.2);
    assert_eq!(judge(&m, &parse("lobby:0").unwrap(), w.said()), vec![Some(0.0)]);
    assert_eq!(judge(&m, &parse("lobby:0,lobby:0").unwrap(), w.said()), vec![Some(0.0), None]);
    assert_eq!(judge(&m, &parse("lobby:1").unwrap(), w.said()), vec![None]);
    assert!(situate_sim::task::check("lobby:7", &parse("lobby:7").unwrap(), &m).is_err());
    assert!(situate_sim::task::check("lobby:1,office", &parse("lobby:1,office").unwrap(), &m).is_ok());
}

#[test]
fn calling_while_the_doors_close_opens_them_again() {
    let mut w = World::new(map("small.yaml"), 2);
    w.place_robot(0, 3.0, 3.5, FRAC_PI_2);
    assert!(w.press(0, 0.6, 25f64.to_radians()));
    assert!(run_until(&mut w, 15.0, |w| w.cars().iter().any(|c| c.door >= 1.0)));
    let k = w.cars().iter().position(|c| c.door >= 1.0).unwrap_or(usize::MAX);
    assert!(run_until(&mut w, 60.0, |w| w.cars()[k].phase == CarPhase::Closing && w.cars()[k].door < 0.8));
    assert!(w.press(0, 0.6, 25f64.to_radians()));
    assert!(run_until(&mut w, 80.0, |w| w.cars()[k].door >= 1.0), "the closing car did not open again");
    assert!(w.cars().iter().enumerate().all(|(j, c)| j == k || c.door == 0.0), "another car came");
}
