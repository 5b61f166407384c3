//! Map files: the shipped maps load; broken ones are refused with the file,
//! line and element named.

use situate_sim::{load_map, Map};

fn path(name: &str) -> String {
    format!("{}/../../../maps/{name}", env!("CARGO_MANIFEST_DIR"))
}

fn small_text() -> String {
    match std::fs::read_to_string(path("small.yaml")) {
        Ok(t) => t,
        Err(e) => panic!("{e}"),
    }
}

/// The 1-based line of the first line containing `needle`.
fn line_of(text: &str, needle: &str) -> usize {
    text.lines().position(|l| l.contains(needle)).map(|i| i + 1).unwrap_or(0)
}

/// Parses small.yaml with `from` replaced by `to`; returns the error text and line.
fn broken(from: &str, to: &str) -> (String, usize) {
    let text = small_text();
    assert!(text.contains(from), "small.yaml has no `{from}`");
    let text = text.replacen(from, to, 1);
    match Map::parse("maps/x.yaml", &text) {
        Ok(_) => panic!("accepted a map with `{to}`"),
        Err(e) => (e.to_string(), e.line()),
    }
}

#[test]
fn the_default_map_loads_and_its_mission_barcodes_exist() {
    let m = match load_map(path("default.yaml")) {
        Ok(m) => m,
        Err(e) => panic!("{e}"),
    };
    assert_eq!(m.elevator.cars.len(), 4);
    assert_eq!(m.mission.start_floor, -1);
    assert_eq!(m.mission.goal_floor, 4);
    let ids: Vec<i64> = m.all_barcodes().into_iter().map(|(_, b)| b.id).collect();
    for id in [m.mission.lab_door_barcode, m.mission.call_button_barcode, m.mission.office_barcode] {
        assert!(ids.contains(&id), "barcode {id} missing");
    }
    for k in 0..4 {
        assert!(ids.contains(&(m.mission.car_barcode_first + k)));
    }
    // The lab door's barcode is on the start floor, next to a door.
    let start =
        m.floor(m.mission.start_floor).map(|f| f.doors.iter().any(|d| d.barcode.as_ref().map(|b| b.id) == Some(10)));
    assert_eq!(start, Some(true));
    // Every door lets the robot through with room to spare.
    for f in &m.floors {
        for d in &f.doors {
            assert!(d.seg.len() >= 1.0, "floor {}: door {:?} narrower than 1 m", f.level, d.seg);
        }
    }
    let legs: Vec<&str> = m.mission.route.iter().map(|(n, _)| n.as_str()).collect();
    assert_eq!(legs, ["lab_to_lobby", "car_to_office"]);
}

#[test]
fn world_json_has_the_gui_shape() {
    let m = match load_map(path("small.yaml")) {
        Ok(m) => m,
        Err(e) => panic!("{e}"),
    };
    let j = m.world_json();
    assert_eq!(j["robot_radius"], 0.25);
    assert_eq!(j["floors"].as_array().map(Vec::len), Some(2));
    let f0 = &j["floors"][0];
    assert_eq!(f0["level"], 0);
    assert_eq!(f0["walls"][0].as_array().map(Vec::len), Some(4));
    assert_eq!(f0["obstacles"][0][0].as_array().map(Vec::len), Some(2));
    assert_eq!(f0["doors"][0], serde_json::json!([4.4, 0.0, 5.6, 0.0]));
    assert!(f0["barcodes"].as_array().is_some_and(|b| b.iter().any(|b| b["id"] == 10 && b["x"] == 4.25)));
    assert!(f0["buttons"].as_array().is_some_and(|b| b.iter().any(|b| b["label"] == "call")));
    assert!(f0["office"].is_null());
    assert_eq!(j["floors"][1]["office"].as_array().map(Vec::len), Some(4));
    assert_eq!(j["cars"][1]["id"], 2);
    let door: Vec<f64> =
        j["cars"][0]["door"].as_array().map(|a| a.iter().filter_map(|x| x.as_f64()).collect()).unwrap_or_default();
    let want = [1.2, 4.0, 2.4, 4.0];
    assert!(door.len() == 4 && door.iter().zip(want).all(|(a, b)| (a - b).abs() < 1e-9), "{door:?}");
    assert_eq!(m.mission_json()["route"]["car_to_office"][0]["home"], 40);
}

#[test]
fn a_zero_length_wall_names_file_line_floor_and_wall() {
    let (e, line) = broken("[2.8, 4, 3.2, 4]", "[2.8, 4, 2.8, 4]");
    let want = line_of(&small_text(), "[2.8, 4, 3.2, 4]");
    assert_eq!(e, format!("maps/x.yaml:{want}: error: floor 0, wall 2: segment has zero length"));
    assert_eq!(line, want);
}

#[test]
fn an_unknown_key_is_named_with_its_line() {
    let (e, line) = broken("lobby: {button: [3.0, 3.98]", "lobby: {buton: [3.0, 3.98]");
    assert!(e.contains("floor 0, lobby: unknown key `buton`"), "{e}");
    assert_eq!(line, line_of(&small_text(), "buton: [3.0, 3.98]").max(line_of(&small_text(), "button: [3.0, 3.98]")));
}

#[test]
fn a_mission_barcode_that_does_not_exist_is_refused() {
    let (e, line) = broken("office_barcode: 40", "office_barcode: 99");
    assert!(e.contains("mission: office_barcode: no barcode 99 in the map"), "{e}");
    assert_eq!(line, line_of(&small_text(), "office_barcode: 40"));
}

#[test]
fn a_wall_across_a_door_is_refused() {
    let (e, _) = broken("- [5.6, 0, 6, 0]", "- [5.6, 0, 6, 0]\n      - [5, -1, 5, 1]");
    assert!(e.contains("floor 0, door 1: wall 5 crosses the door"), "{e}");
}

#[test]
fn yaml_syntax_errors_give_line_and_column() {
    let (e, line) = broken("- [2.8, 4, 3.2, 4]", "- [2.8, 4, 3.2, 4");
    assert!(e.starts_with("maps/x.yaml:"), "{e}");
    assert!(line >= line_of(&small_text(), "[2.8, 4, 3.2, 4]"), "{e}");
}

#[test]
fn duplicate_levels_overlapping_cars_and_duplicate_barcodes_are_refused() {
    let (e, _) = broken("  - level: 1", "  - level: 0");
    assert!(e.contains("floor 0: this level is given twice"), "{e}");
    let (e, _) = broken("rect: [3.2, 4.0, 5.2, 6.0]", "rect: [2.2, 4.0, 4.2, 6.0]");
    assert!(e.contains("elevator, car 2: overlaps car 1"), "{e}");
    let (e, line) = broken("barcode: 31}", "barcode: 30}");
    let (first, second) = (line_of(&small_text(), "barcode: 30}"), line_of(&small_text(), "barcode: 31}"));
    assert_eq!(
        e,
        format!(
            "maps/x.yaml:{second}: error: floor 1, lobby: barcode 30 is used twice: by floor 0, lobby on line {first} and by \
             floor 1, lobby on line {second}"
        )
    );
    assert_eq!(line, second);
}

#[test]
fn a_barcode_used_twice_on_one_floor_names_both_places() {
    // Once "(floor 0 and floor 0)": now both elements and both lines.
    let at = line_of(&small_text(), "    lobby: {button: [3.0, 3.98], facing_deg: -90, barcode: 30}");
    let (e, line) = broken(
        "    lobby: {button: [3.0, 3.98], facing_deg: -90, barcode: 30}",
        "    lobby: {button: [3.0, 3.98], facing_deg: -90, barcode: 30}\n    barcodes:\n      - {id: 13, at: [0.02, 1], \
         facing_deg: 0}\n      - {id: 13, at: [5.98, 1], facing_deg: 180}",
    );
    assert_eq!(
        e,
        format!(
            "maps/x.yaml:{}: error: floor 0, barcode 2: barcode 13 is used twice: by floor 0, barcode 1 on line {} and by \
             floor 0, barcode 2 on line {}",
            at + 3,
            at + 2,
            at + 3
        )
    );
    assert_eq!(line, at + 3);
    // A car's barcode again on a floor.
    let (e, _) = broken("{id: 10, at: [4.25, 0.02]", "{id: 202, at: [4.25, 0.02]");
    assert!(
        e.contains(
            "barcode 202 is used twice: by elevator, car 2 on line 14 and by floor 0, door 1 (lab), barcode on line 26"
        ),
        "{e}"
    );
}

#[test]
fn a_bracket_left_open_is_named_at_its_line_and_column() {
    let at = line_of(&small_text(), "- [2.8, 4, 3.2, 4]");
    let (e, line) = broken("- [2.8, 4, 3.2, 4]", "- [2.8, 4, 3.2, 4");
    assert_eq!(line, at);
    assert!(
        e.starts_with(&format!(
            "maps/x.yaml:{at}:9: error: missing `]` to close the `[` at line {at}, column 9 (the YAML parser stopped at line {}",
            at + 2
        )),
        "{e}"
    );
}

#[test]
fn bad_values_name_the_element() {
    let (e, _) = broken("rect: [1.0, 1.0, 1.6, 1.6]", "rect: [1.6, 1.0, 1.0, 1.6]");
    assert!(e.contains("floor 0, obstacle 1: rect [x0, y0, x1, y1] needs x0 < x1"), "{e}");
    let (e, _) = broken("door: south, barcode: 201", "door: up, barcode: 201");
    assert!(e.contains("elevator, car 1: door `up`"), "{e}");
    let (e, _) = broken("{home: 40}", "{home: 41}");
    assert!(e.contains("mission, route car_to_office, step 1: no barcode 41"), "{e}");
    let (e, _) = broken("{home: 40}", "{follow: hallway}");
    assert!(e.contains("`follow` needs `until`"), "{e}");
    let (e, _) = broken("x: 3.0, y: 2.5", "x: 0.1, y: 2.5");
    assert!(e.contains("mission: the start pose is 0.10 m from a wall"), "{e}");
}

#[test]
fn a_missing_file_is_named() {
    match load_map("maps/no-such-map.yaml") {
        Err(e) => {
            assert!(e.to_string().starts_with("maps/no-such-map.yaml: error: cannot read map file: "), "{e}");
            assert_eq!((e.line(), e.element.as_deref()), (0, None), "the file as a whole: {e:?}");
        }
        Ok(_) => panic!("a missing map file loaded"),
    }
}

#[test]
fn route_steps_count_and_distance_are_checked() {
    let (e, _) = broken("      - {home: 40}", "      - {follow: hallway, until: junction, count: 0}");
    assert!(e.contains("count must be at least 1"), "{e}");
    let (e, _) = broken("      - {home: 40}", "      - {follow: hallway, until: wall, count: 2}");
    assert!(e.contains("`count` goes with `until: junction` or `until: door`"), "{e}");
    let (e, _) = broken("      - {home: 40}", "      - {follow: hallway, until: distance}");
    assert!(e.contains("`until: distance` needs `distance: M`"), "{e}");
    let (e, _) = broken("      - {home: 40}", "      - {follow: hallway, until: distance, distance: -1}");
    assert!(e.contains("distance must be positive"), "{e}");
    let (e, _) = broken("      - {home: 40}", "      - {turn: left, distance: 2}");
    assert!(e.contains("`distance` goes with `follow: hallway`"), "{e}");
    // Accepted, and in the mission's JSON.
    let text = small_text().replacen(
        "    car_to_office:\n      - {home: 40}",
        "    button_to_office:\n      - {follow: hallway, until: junction, side: left, count: 2, turn: left}\n      - {follow: hallway, until: junction, distance: 4, turn: left}\n      - {follow: hallway, until: distance, distance: 3.5}\n      - {home: 40}",
        1,
    );
    let m = match Map::parse("maps/x.yaml", &text) {
        Ok(m) => m,
        Err(e) => panic!("{e}"),
    };
    let j = m.mission_json();
    assert_eq!(j["route"]["button_to_office"][0]["count"], 2);
    assert_eq!(j["route"]["button_to_office"][1]["distance"], 4.0);
    assert_eq!(j["route"]["button_to_office"][2]["distance"], 3.5);
    assert_eq!(j["goal_button_barcode"], 31);
    assert_eq!(j["cars"], 2);
}
