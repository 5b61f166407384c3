//! The default map can be done: a controller that cheats (it reads the true
//! pose) drives the whole delivery through doors, corridors and the elevator.

use std::f64::consts::FRAC_PI_2;

use situate_sim::geom::wrap;
use situate_sim::{load_map, BaseLimits, World};

const DT: f64 = 0.05;

fn tick(w: &mut World) {
    let t = w.time_s() + DT;
    w.advance_to(t);
}

/// Turns in place to `heading`, then holds still.
fn face(w: &mut World, heading: f64) -> bool {
    for _ in 0..400 {
        let err = wrap(heading - w.robot().theta);
        if err.abs() < 0.02 {
            w.set_drive(0.0, 0.0, BaseLimits::default());
            tick(w);
            return true;
        }
        w.set_drive(0.0, (2.0 * err).clamp(-1.0, 1.0), BaseLimits::default());
        tick(w);
    }
    false
}

/// Drives to `(x, y)` by turning towards it and going straight.
fn goto(w: &mut World, x: f64, y: f64) -> bool {
    for _ in 0..2000 {
        let r = w.robot();
        let (dx, dy) = (x - r.x, y - r.y);
        let d = dx.hypot(dy);
        if d < 0.05 {
            w.set_drive(0.0, 0.0, BaseLimits::default());
            tick(w);
            return true;
        }
        let err = wrap(dy.atan2(dx) - r.theta);
        let v = if err.abs() < 0.2 { (0.8 * d).min(0.6) } else { 0.0 };
        w.set_drive(v, (2.5 * err).clamp(-1.5, 1.5), BaseLimits::default());
        tick(w);
    }
    false
}

fn wait(w: &mut World, limit_s: f64, mut done: impl FnMut(&World) -> bool) -> bool {
    let end = w.time_s() + limit_s;
    while w.time_s() < end {
        tick(w);
        if done(w) {
            return true;
        }
    }
    false
}

#[test]
fn the_whole_delivery_is_drivable_on_the_default_map() {
    let path = format!("{}/../../../maps/default.yaml", env!("CARGO_MANIFEST_DIR"));
    let map = load_map(&path).unwrap_or_else(|e| panic!("{e}"));
    let mut w = World::new(map, 21);
    // Out of the lab, along the corridor, north to the lobby.
    for (x, y) in [(5.0, 3.0), (6.5, 5.0), (6.5, 7.0), (15.0, 7.0), (15.0, 16.8)] {
        assert!(goto(&mut w, x, y), "stuck on the way to ({x}, {y}) at {:?}", w.robot());
    }
    assert!(face(&mut w, FRAC_PI_2));
    let seen: Vec<i64> = w.barcodes(5.0, 60f64.to_radians()).into_iter().map(|b| b.0).collect();
    assert!(seen.contains(&30), "the call button's barcode is not in view: {seen:?}");
    assert!(goto(&mut w, 15.0, 17.5));
    assert!(face(&mut w, FRAC_PI_2));
    assert!(w.press(0, 0.6, 25f64.to_radians()), "could not reach the call button");
    assert!(wait(&mut w, 30.0, |w| w.cars().iter().any(|c| c.floor() == -1 && c.door >= 1.0)), "no car came");
    let k = w.cars().iter().position(|c| c.floor() == -1 && c.door >= 1.0).unwrap_or(usize::MAX);
    let car = w.map().elevator.cars[k].clone();
    let cx = (car.x0 + car.x1) / 2.0;
    // Into the car, press 4.
    for (x, y) in [(15.0, 16.8), (cx, 16.8), (cx, 19.5)] {
        assert!(goto(&mut w, x, y), "stuck on the way to ({x}, {y}) at {:?}", w.robot());
    }
    assert!(face(&mut w, FRAC_PI_2));
    let seen: Vec<i64> = w.barcodes(5.0, 60f64.to_radians()).into_iter().map(|b| b.0).collect();
    assert_eq!(seen.first(), Some(&car.barcode), "the car's own barcode is the nearest in view");
    assert!(w.press(4, 0.6, 25f64.to_radians()), "could not reach the panel");
    assert!(wait(&mut w, 60.0, |w| w.cars()[k].floor() == 4 && w.cars()[k].door >= 1.0), "never got to 4");
    assert_eq!(w.robot().floor, 4);
    // Out, west along the corridor, into the office.
    for (x, y) in [(cx, 16.8), (6.0, 16.8), (6.0, 13.8)] {
        assert!(goto(&mut w, x, y), "stuck on the way to ({x}, {y}) at {:?}", w.robot());
    }
    w.say("hello");
    tick(&mut w);
    assert!(w.delivered_at().is_some(), "not delivered at {:?}", w.robot());
}
