//! What real buildings have: people walking, doors closed for a while, dead
//! sonars.

use std::f64::consts::PI;

use situate_sim::geom::{in_polygon, Seg, P2};
use situate_sim::people::PERSON_RADIUS;
use situate_sim::world::Closure;
use situate_sim::{load_map, BaseLimits, Map, SonarSettings, World, WorldConfig};

fn map(name: &str) -> Map {
    match load_map(format!("{}/../../../maps/{name}", env!("CARGO_MANIFEST_DIR"))) {
        Ok(m) => m,
        Err(e) => panic!("{e}"),
    }
}

fn with(people: usize, door_closures: bool, dead_sonars: Vec<usize>) -> WorldConfig {
    WorldConfig { people, door_closures, dead_sonars, ..WorldConfig::default() }
}

/// Noise-free sonars.
fn exact() -> SonarSettings {
    SonarSettings { noise: 0.0, dropout: 0.0, ..SonarSettings::default() }
}

/// Every person's position and floor, as bits.
fn trajectory(seed: u64, seconds: u64) -> Vec<u64> {
    let mut w = World::with_config(map("default.yaml"), seed, with(5, true, vec![]));
    let mut out = Vec::new();
    for i in 1..=seconds * 10 {
        w.advance_to(i as f64 * 0.1);
        w.set_drive(0.4, (i as f64 * 0.05).sin(), BaseLimits::default());
        for p in w.people() {
            out.extend([p.pos.x.to_bits(), p.pos.y.to_bits(), p.floor as u64]);
        }
    }
    out
}

#[test]
fn people_walk_the_same_way_for_the_same_seed() {
    let a = trajectory(11, 120);
    assert!(!a.is_empty());
    assert!(a == trajectory(11, 120), "two runs with seed 11 differ");
    assert!(a != trajectory(12, 120), "seeds 11 and 12 gave the same people");
    // Asked every 10 ms or every 70 ms: the same people at the common times.
    let mut fine = World::with_config(map("default.yaml"), 4, with(4, true, vec![]));
    let mut coarse = fine.clone();
    for i in 1..=1000u64 {
        fine.advance_to(i as f64 * 0.01);
        if i % 7 == 0 {
            coarse.advance_to(i as f64 * 0.01);
            assert_eq!(fine.people(), coarse.people());
        }
    }
}

#[test]
fn people_start_in_free_space_on_every_floor_away_from_the_robot() {
    let m = map("default.yaml");
    let w = World::with_config(m.clone(), 3, with(3, false, vec![]));
    let start = P2::new(m.mission.start.0, m.mission.start.1);
    for f in &m.floors {
        let here: Vec<_> = w.people().iter().filter(|p| p.floor == f.level).collect();
        assert_eq!(here.len(), 3, "floor {}", f.level);
        for p in here {
            let clear = w.segments(f.level).iter().map(|s| s.dist_to(p.pos)).fold(f64::INFINITY, f64::min);
            assert!(clear >= 0.5 - 1e-9, "a person starts {clear} m from a wall on floor {}", f.level);
            if f.level == m.mission.start_floor {
                assert!(p.pos.dist(start) >= 3.0, "a person starts {} m from the robot", p.pos.dist(start));
            }
        }
    }
    // Without people there are none, and no free space is worked out.
    let w = World::new(m, 3);
    assert!(w.people().is_empty() && w.walkable().is_empty());
}

/// Panics if a person overlaps a wall, an obstacle, a shaft (or a car door:
/// people never enter the cars), the closed door, or the robot.
fn check_people(w: &World) {
    let m = w.map();
    let r = w.robot();
    for (k, p) in w.people().iter().enumerate() {
        let fi = m.floors.iter().position(|f| f.level == p.floor).expect("a person on a floor of the map");
        let mut segs: Vec<Seg> = w.walkable()[fi].segs.clone();
        if let Some((level, seg, _)) = w.closed_door() {
            if level == p.floor {
                segs.push(seg);
            }
        }
        let t = w.time_s();
        for s in &segs {
            let d = s.dist_to(p.pos);
            assert!(d >= PERSON_RADIUS, "t {t}: person {k} overlaps {s:?} ({d} m) at {:?}", p.pos);
        }
        assert!(!m.elevator.cars.iter().any(|c| c.contains(p.pos)), "t {t}: person {k} in a shaft");
        assert!(!m.floors[fi].obstacles.iter().any(|o| in_polygon(p.pos, o)), "t {t}: person {k} in an obstacle");
        if p.floor == r.floor {
            let gap = p.pos.dist(P2::new(r.x, r.y)) - PERSON_RADIUS - m.robot_radius;
            assert!(gap >= -1e-9, "t {t}: person {k} overlaps the robot by {}", -gap);
        }
    }
}

#[test]
fn over_ten_minutes_no_person_overlaps_a_wall_a_shaft_or_the_robot() {
    let mut w = World::with_config(map("default.yaml"), 21, with(6, true, vec![]));
    let start: Vec<P2> = w.people().iter().map(|p| p.pos).collect();
    let mut nearest_gap = f64::INFINITY;
    let mut closures = 0;
    let mut was_closed = false;
    for i in 1..=60_000u64 {
        let t = i as f64 * 0.01;
        if i == 30_000 {
            // The second half: the robot stands in the ground floor's lobby
            // (where no one is: placing it is no walk).
            let x = (0..40)
                .map(|k| 11.0 + k as f64 * 0.2)
                .find(|&x| w.people().iter().all(|p| p.floor != 0 || p.pos.dist(P2::new(x, 16.8)) > 1.0))
                .expect("room in the lobby");
            w.place_robot(0, x, 16.8, -PI / 2.0);
        }
        if i < 30_000 {
            // Wander: ahead, turning now and then.
            w.set_drive(0.6, 1.5 * (t * 0.3).sin() * (t * 0.11).cos(), BaseLimits::default());
        } else {
            w.set_drive(0.0, 0.0, BaseLimits::default());
        }
        w.advance_to(t);
        if i % 5 == 0 {
            check_people(&w);
        }
        let r = w.robot();
        for p in w.people().iter().filter(|p| p.floor == r.floor) {
            nearest_gap = nearest_gap.min(p.pos.dist(P2::new(r.x, r.y)) - PERSON_RADIUS - w.map().robot_radius);
        }
        let closed = w.closed_door().is_some();
        if closed && !was_closed {
            closures += 1;
        }
        was_closed = closed;
    }
    let walked: f64 = w.people().iter().zip(&start).map(|(p, s)| p.pos.dist(*s)).sum();
    assert!(walked > 10.0, "people hardly moved: {walked} m");
    assert!(nearest_gap < 0.8, "no person came near the robot (nearest gap {nearest_gap} m): the test tests nothing");
    assert!(closures >= 2, "{closures} door closures in 10 minutes");
}

#[test]
fn a_person_ahead_is_seen_by_the_sonar_hides_barcodes_and_stops_the_robot() {
    let mut w = World::with_config(map("default.yaml"), 2, with(1, false, vec![]));
    // The basement corridor (y 6..8), facing east towards barcode 13 at x 18.98.
    w.place_robot(-1, 14.5, 7.0, 0.0);
    assert!(w.barcodes(5.0, 1.0).iter().any(|b| b.0 == 13), "barcode 13 not seen without the person");
    let before = w.sonar(&exact())[0];
    assert!(before > 3.0, "sonar 0 reads {before} without the person");
    assert!(w.place_person(0, -1, 16.5, 7.0, 1e9));
    let ahead = w.sonar(&exact())[0];
    assert!((ahead - 1.75).abs() < 0.01, "sonar 0 reads {ahead}, the person's rim is 1.75 m ahead");
    assert!(!w.barcodes(5.0, 1.0).iter().any(|b| b.0 == 13), "barcode 13 seen through the person");
    // Full speed ahead: the robot stops at the person, never in it.
    for i in 1..=600 {
        w.set_drive(0.8, 0.0, BaseLimits::default());
        w.advance_to(i as f64 * 0.01);
        let gap = 16.5 - w.robot().x;
        assert!(gap >= 0.5 - 1e-9, "the robot drove into the person: centres {gap} m apart");
    }
    assert!(16.5 - w.robot().x < 0.52, "the robot stopped short: x {}", w.robot().x);
    // It may back away.
    for i in 601..=700 {
        w.set_drive(-0.3, 0.0, BaseLimits::default());
        w.advance_to(i as f64 * 0.01);
    }
    assert!(16.5 - w.robot().x > 0.6, "the robot could not back away from the person");
}

#[test]
fn a_walking_person_waits_for_the_robot_in_its_way() {
    let mut w = World::with_config(map("default.yaml"), 2, with(1, false, vec![]));
    w.place_robot(-1, 12.0, 7.0, 0.0);
    // A person east of the robot: wherever it walks, it never touches the robot.
    assert!(w.place_person(0, -1, 13.5, 7.0, 0.0));
    for i in 1..=6000 {
        w.advance_to(i as f64 * 0.01);
        check_people(&w);
    }
}

#[test]
fn someone_the_robot_keeps_in_a_dead_end_walks_out_past_it() {
    // The default basement's junction stub (x 14..16, y 3..6) ends at y = 3. The robot
    // stands in it 0.3 m left of its middle, facing the dead end; someone is behind it
    // there. A person who only waited and drew waypoints through the robot stayed there
    // for good (seen in a generated building, the robot waiting for them in turn).
    let mut w = World::with_config(map("default.yaml"), 3, with(1, false, vec![]));
    w.place_robot(-1, 14.7, 4.6, -PI / 2.0);
    assert!(w.place_person(0, -1, 15.25, 3.6, 0.0));
    let mut out = None;
    for i in 1..=30_000 {
        let t = i as f64 * 0.01;
        w.advance_to(t);
        check_people(&w);
        if w.people()[0].pos.y > 5.6 {
            out = Some(t);
            break;
        }
    }
    let out = out.unwrap_or_else(|| panic!("still kept in after 300 s at {:?}", w.people()[0].pos));
    eprintln!("out past the robot after {out:.1} s");
}

#[test]
fn a_dead_sonar_reads_max_range_and_the_others_are_unchanged() {
    let m = map("default.yaml");
    let mut live = World::new(m.clone(), 5);
    let mut dead = World::with_config(m, 5, with(0, false, vec![0, 7, 23]));
    for w in [&mut live, &mut dead] {
        // Facing the lab's west wall from 0.6 m.
        w.place_robot(-1, 0.6, 3.0, PI);
    }
    assert!(live.sonar(&exact())[0] < 1.0, "the live sonar 0 reads {}", live.sonar(&exact())[0]);
    for s in [SonarSettings::default(), exact(), SonarSettings { max_range: 6.0, ..SonarSettings::default() }] {
        let (a, b) = (live.sonar(&s), dead.sonar(&s));
        for i in 0..24 {
            if [0, 7, 23].contains(&i) {
                assert_eq!(b[i], s.max_range as f32, "dead sonar {i}");
            } else {
                assert_eq!(a[i].to_bits(), b[i].to_bits(), "live sonar {i}");
            }
        }
    }
}

/// A pose 1 m in front of the opening `seg` on its side with room (facing
/// it), and the unit normal from the door to there.
fn in_front(w: &World, level: i64, seg: Seg) -> (P2, P2) {
    let mid = seg.at(0.5);
    let e = seg.b.minus(seg.a);
    let n = P2::new(-e.y, e.x).scale(1.0 / e.norm());
    for side in [n, n.scale(-1.0)] {
        let p = mid.plus(side.scale(1.0));
        let clear = w.map().static_segments(w.map().floor(level).unwrap());
        if clear.iter().all(|s| s.dist_to(p) > 0.4 && !s.intersects(&Seg::new(p, mid.plus(side.scale(0.05))))) {
            return (p, side);
        }
    }
    panic!("no room in front of the door {seg:?} on floor {level}");
}

fn heading(from: P2, to: P2) -> f64 {
    let d = to.minus(from);
    d.y.atan2(d.x)
}

#[test]
fn a_closed_door_blocks_motion_and_sonar_until_it_opens() {
    let mut w = World::with_config(map("default.yaml"), 8, with(0, true, vec![]));
    // The robot stays in the lab, away from every door.
    w.place_robot(-1, 2.0, 2.0, 0.0);
    let mut t = 0.0;
    while w.closed_door().is_none() {
        t += 0.5;
        assert!(t < 400.0, "no door closed in 400 s");
        w.advance_to(t);
    }
    let (level, seg, until) = w.closed_door().unwrap();
    assert!((20.0..=60.0 + 1.0).contains(&(until - t)), "closed for {} s", until - t);
    assert!(t >= 60.0, "the first closure came after {t} s");
    let (p, side) = in_front(&w, level, seg);
    let mid = seg.at(0.5);
    w.place_robot(level, p.x, p.y, heading(p, mid));
    let reading = w.sonar(&exact())[0];
    assert!((reading - 1.0).abs() < 0.02, "sonar 0 reads {reading} in front of the closed door 1 m away");
    // Drive at the door: stopped at it.
    let t0 = w.time_s();
    for i in 1..=400 {
        w.set_drive(0.5, 0.0, BaseLimits::default());
        w.advance_to(t0 + i as f64 * 0.01);
    }
    let r = w.robot();
    let q = P2::new(r.x, r.y);
    assert!(w.closed_door().is_some(), "the door opened too soon");
    assert!(q.minus(mid).dot(side) >= w.map().robot_radius - 1e-6, "the robot went through the closed door to {q:?}");
    assert!(seg.dist_to(q) < 0.3, "the robot did not reach the door: {q:?}");
    // After its interval it is open: the sonar sees through, the robot drives through.
    w.set_drive(0.0, 0.0, BaseLimits::default());
    w.advance_to(until + 0.05);
    assert!(w.closed_door().is_none(), "still closed after its interval");
    assert!(matches!(w.closure(), Some(Closure::Open { .. })));
    let reading = w.sonar(&exact())[0];
    assert!(reading > 0.6, "sonar 0 reads {reading} through the open door");
    let t1 = w.time_s();
    for i in 1..=300 {
        w.set_drive(0.4, 0.0, BaseLimits::default());
        w.advance_to(t1 + i as f64 * 0.01);
    }
    let r = w.robot();
    assert!(P2::new(r.x, r.y).minus(mid).dot(side) < 0.0, "the robot did not pass the open door: {r:?}");
}

#[test]
fn a_door_never_closes_on_the_robot_in_its_doorway() {
    let base = World::with_config(map("default.yaml"), 8, with(0, true, vec![]));
    // When and which door closes with the robot out of the way.
    let mut probe = base.clone();
    probe.place_robot(-1, 2.0, 2.0, 0.0);
    let mut t = 0.0;
    while probe.closed_door().is_none() {
        t += 0.01;
        probe.advance_to(t);
    }
    let (level, seg, _) = probe.closed_door().unwrap();
    // The same world with the robot standing in that doorway.
    let mut w = base.clone();
    let mid = seg.at(0.5);
    w.place_robot(level, mid.x, mid.y, 0.0);
    w.advance_to(t + 30.0);
    assert!(w.closed_door().is_none(), "the door closed on the robot");
    assert!(matches!(w.closure(), Some(Closure::Due { .. })), "{:?}", w.closure());
    // Just out of the doorway (within the margin): still open.
    let (p, side) = in_front(&w, level, seg);
    let near = mid.plus(side.scale(w.map().robot_radius + 0.2));
    w.place_robot(level, near.x, near.y, 0.0);
    w.advance_to(t + 31.0);
    assert!(w.closed_door().is_none(), "the door closed with the robot 0.2 m from it");
    // Gone: it closes.
    w.place_robot(level, p.x, p.y, 0.0);
    w.advance_to(t + 31.02);
    assert_eq!(w.closed_door().map(|d| (d.0, d.1)), Some((level, seg)));
}

#[test]
fn every_map_has_people_walking_clear_of_walls() {
    let mut names: Vec<String> = ["default.yaml", "small.yaml"].map(String::from).to_vec();
    if let Ok(dir) = std::fs::read_dir(format!("{}/../../../maps/scenarios", env!("CARGO_MANIFEST_DIR"))) {
        let mut more: Vec<String> =
            dir.filter_map(|e| e.ok()).map(|e| format!("scenarios/{}", e.file_name().to_string_lossy())).collect();
        more.sort();
        names.extend(more);
    }
    let mut maps: Vec<(String, Map)> = names.iter().map(|n| (n.clone(), map(n))).collect();
    for seed in 1..=6 {
        let g = situate_sim::generate::generate(seed, &situate_sim::generate::Options::default())
            .unwrap_or_else(|e| panic!("{e}"));
        maps.push((format!("generated {seed}"), Map::parse("generated", &g.yaml).unwrap_or_else(|e| panic!("{e}"))));
    }
    for (name, m) in maps {
        let mut w = World::with_config(m.clone(), 1, with(3, true, vec![]));
        for (f, walk) in m.floors.iter().zip(w.walkable()) {
            assert!(walk.free.len() > 20, "{name}: floor {} has {} free points", f.level, walk.free.len());
            assert_eq!(w.people().iter().filter(|p| p.floor == f.level).count(), 3, "{name}: floor {}", f.level);
        }
        for i in 1..=1200u64 {
            w.set_drive(0.5, (i as f64 * 0.02).sin(), BaseLimits::default());
            w.advance_to(i as f64 * 0.1);
            check_people(&w);
        }
    }
}

/// The physics robot steps people and door closures by `Traffic` alone (`situate._native.Traffic`):
/// with the robot's pose given each step, it is the 2-D world's, bit for bit.
#[test]
fn traffic_alone_is_the_worlds_people_and_doors() {
    use situate_sim::traffic::{RobotDisc, Traffic};
    let m = map("default.yaml");
    let mut w = World::with_config(m.clone(), 7, with(3, true, vec![]));
    let mut t = Traffic::new(&m, 7, 3, true);
    assert_eq!(w.people(), t.people());
    let mut closed = 0;
    // 400 s: long enough for closures to come and go (a gap is 60-180 s), the robot driving
    // about (people stop for it, doors wait for it).
    for i in 1..=40_000u64 {
        let r = w.robot();
        let now = w.time_s();
        w.set_drive(0.4, (i as f64 * 0.003).sin(), BaseLimits::default());
        w.advance_to(i as f64 * 0.01);
        t.step(&m, &RobotDisc { floor: r.floor, pos: P2::new(r.x, r.y), radius: m.robot_radius }, now, 0.01);
        assert_eq!(w.people(), t.people(), "step {i}");
        assert_eq!(w.closure(), t.closure(), "step {i}");
        closed += usize::from(t.closed_door(&m).is_some());
    }
    assert!(closed > 0, "no door closed in 400 s");
}
