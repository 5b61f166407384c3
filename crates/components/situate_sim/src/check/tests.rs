//! Tests of [`super::lint`]: the shipped maps have no findings, and each
//! rule's finding, made by changing a map, is on its element's line with the
//! value found and the rule's limit.

use super::*;

fn maps_dir(name: &str) -> String {
    format!("{}/../../../maps/{name}", env!("CARGO_MANIFEST_DIR"))
}

fn small() -> String {
    std::fs::read_to_string(maps_dir("small.yaml")).unwrap_or_default()
}

fn line_of(text: &str, needle: &str) -> usize {
    text.lines().position(|l| l.contains(needle)).map(|i| i + 1).unwrap_or(0)
}

/// small.yaml with `from` replaced by `to`, loaded and linted.
fn lint_changed(from: &str, to: &str) -> (String, Vec<Diagnostic>) {
    let text = small();
    assert!(text.contains(from), "small.yaml has no `{from}`");
    let text = text.replacen(from, to, 1);
    match Map::parse("x.yaml", &text) {
        Ok(m) => (text, lint(&m)),
        Err(e) => panic!("the changed map does not load: {e}"),
    }
}

/// A finding as `situate map check` prints it for the file `file`.
fn render(f: &Diagnostic, file: &str) -> String {
    f.clone().in_file(file).to_string()
}

fn has(findings: &[Diagnostic], line: usize, needle: &str) -> bool {
    findings.iter().any(|f| f.line() == line && render(f, "x").contains(needle))
}

#[test]
fn the_shipped_maps_have_no_findings() {
    for name in ["default.yaml", "small.yaml"] {
        let m = match crate::load_map(maps_dir(name)) {
            Ok(m) => m,
            Err(e) => panic!("{e}"),
        };
        let f: Vec<String> = lint(&m).iter().map(|f| render(f, name)).collect();
        assert!(f.is_empty(), "{name}: {f:#?}");
    }
}

#[test]
fn a_door_barcode_far_from_its_door_is_found_on_its_line() {
    // 0.9 m from the lab door's nearer jamb (the rule: 0.1 to 0.6 m).
    let (text, f) = lint_changed("{id: 10, at: [4.25, 0.02]", "{id: 10, at: [3.5, 0.02]");
    let at = line_of(&text, "{id: 10, at: [3.5, 0.02]");
    // Which distance, its value and its limit.
    assert_eq!(
        rendered(&f),
        [format!(
            "x:{at}: error: floor 0, door 1 (lab), barcode: barcode 10 marks door 1 (lab) (the nearest), but is 0.90 m \
             from the door's nearer jamb along its wall: 0.10 to 0.60 m"
        )]
    );
    // 0.3 m off its wall (and so off the door's line): said once, with the distance and the limit.
    let (text, f) = lint_changed("{id: 10, at: [4.25, 0.02]", "{id: 10, at: [4.25, 0.3]");
    let at = line_of(&text, "{id: 10, at: [4.25, 0.3]");
    assert_eq!(
        rendered(&f),
        [format!(
            "x:{at}: error: floor 0, door 1 (lab), barcode: barcode 10 is 0.30 m in front of the wall behind it: barcodes \
             are stuck 0.01 to 0.02 m off their wall, on the side they face"
        )]
    );
    // On another wall, 0.3 m off the door's line: a wall across the lab at x = 4.0, the barcode on it.
    let text = small()
        .replacen("      - [5.6, 0, 6, 0]", "      - [5.6, 0, 6, 0]\n      - [4.0, 0.3, 4.0, 0.9]", 1)
        .replacen("{id: 10, at: [4.25, 0.02], facing_deg: 90}", "{id: 10, at: [4.02, 0.3], facing_deg: 0}", 1);
    let at = line_of(&text, "{id: 10, at: [4.02, 0.3]");
    assert_eq!(
        rendered(&lint_text(&text)),
        [format!(
            "x:{at}: error: floor 0, door 1 (lab), barcode: barcode 10 marks door 1 (lab) (the nearest), but is 0.30 m \
             off the door's line (its wall): at most 0.10 m"
        )]
    );
    // 0.5 m is within it.
    let (_, f) = lint_changed("{id: 10, at: [4.25, 0.02]", "{id: 10, at: [3.9, 0.02]");
    assert!(f.is_empty(), "{f:#?}");
}

#[test]
fn an_opening_in_the_call_buttons_wall_is_found_on_the_lobby_line() {
    // A narrower shaft leaves 0.4 m of the button's wall open beside it.
    let (text, f) = lint_changed("{rect: [3.2, 4.0, 5.2, 6.0]", "{rect: [3.2, 4.0, 4.8, 6.0]");
    let at = line_of(&text, "lobby: {button: [3.0, 3.98], facing_deg: -90, barcode: 30}");
    assert!(has(&f, at, "an opening 0.40 m wide at (5.00, 3.98) in the call button's wall"), "{f:#?}");
}

#[test]
fn an_unreachable_office_is_found_on_its_line() {
    // The office shrunk to floor 1's south metre, behind a new wall.
    let text = small()
        .replacen(
            "office: {rect: [0, 0, 6, 4], barcode: {id: 40, at: [0.02, 2.0], facing_deg: 0}}",
            "office: {rect: [0, 0, 6, 1], barcode: {id: 40, at: [0.02, 0.5], facing_deg: 0}}",
            1,
        )
        .replacen("      - [2.8, 4, 3.2, 4]\n    lobby: {button: [3.0, 3.98], facing_deg: -90, barcode: 31}",
            "      - [2.8, 4, 3.2, 4]\n      - [0, 1.2, 6, 1.2]\n    lobby: {button: [3.0, 3.98], facing_deg: -90, barcode: 31}",
            1,
        );
    let m = Map::parse("x.yaml", &text).unwrap_or_else(|e| panic!("{e}"));
    let f = lint(&m);
    let at = line_of(&text, "office: {rect");
    assert!(has(&f, at, "floor 1, office: the office cannot be reached"), "{f:#?}");
    // Its barcode, behind the wall, cannot be read either.
    assert!(f.iter().any(|f| f.message.contains("barcode 40 cannot be read")), "{f:#?}");
}

#[test]
fn a_barcode_facing_a_wall_is_found_on_its_line() {
    // The lab door's barcode turned to face the wall (south, away from the room).
    let (text, f) = lint_changed("at: [4.25, 0.02], facing_deg: 90}", "at: [4.25, 0.02], facing_deg: -90}");
    let at = line_of(&text, "name: lab");
    // The cause, alone (it cannot be read, and the lab would be on the other side).
    assert_eq!(
        rendered(&f),
        [format!(
            "x:{at}: error: floor 0, door 1 (lab), barcode: barcode 10 faces the wall it is on (0.02 m ahead of it): it \
             cannot be read; turn it round (facing_deg: 90)"
        )]
    );
}

fn rendered(f: &[Diagnostic]) -> Vec<String> {
    f.iter().map(|f| render(f, "x")).collect()
}

fn default_text() -> String {
    std::fs::read_to_string(maps_dir("default.yaml")).unwrap_or_default()
}

fn lint_text(text: &str) -> Vec<Diagnostic> {
    match Map::parse("x.yaml", text) {
        Ok(m) => lint(&m),
        Err(e) => panic!("the changed map does not load: {e}"),
    }
}

#[test]
fn a_call_button_facing_its_own_wall_is_the_one_finding() {
    // Once 10 findings on the default map (every car's door, the button from each car,
    // the office, its barcode) and none about the facing.
    let from = "lobby: {button: [15.0, 17.98], facing_deg: -90, barcode: 35}";
    let text = default_text();
    assert!(text.contains(from));
    let text = text.replacen(from, "lobby: {button: [15.0, 17.98], facing_deg: 90, barcode: 35}", 1);
    let at = line_of(&text, "facing_deg: 90, barcode: 35}");
    assert_eq!(
        rendered(&lint_text(&text)),
        [format!(
            "x:{at}: error: floor 4, lobby: the call button (barcode 35) faces the wall it is on (0.02 m ahead of it): it \
             must face into the lobby (facing_deg: -90); what the robot does in front of it is not checked until \
             it does"
        )]
    );
    // On the start floor too.
    let (text, f) = lint_changed("facing_deg: -90, barcode: 30}", "facing_deg: 90, barcode: 30}");
    let at = line_of(&text, "facing_deg: 90, barcode: 30}");
    assert_eq!(f.len(), 1, "{f:#?}");
    assert!(has(&f, at, "floor 0, lobby: the call button (barcode 30) faces the wall it is on"), "{f:#?}");
}

#[test]
fn doors_open_too_short_a_time_are_found_on_the_open_s_line() {
    let (text, f) = lint_changed("open_s: [15, 25]", "open_s: [2, 3]");
    let at = line_of(&text, "open_s: [2, 3]");
    assert_eq!(
        rendered(&f),
        [format!(
            "x:{at}: error: elevator: open_s [2, 3]: the doors must stay open at least 8 s for the robot to board (the \
             shortest documented range is [8, 12])"
        )]
    );
    let (_, f) = lint_changed("open_s: [15, 25]", "open_s: [8, 12]");
    assert!(f.is_empty(), "{f:#?}");
}

#[test]
fn a_start_outside_the_lab_is_found_on_the_start_line() {
    // South of the lab door, in the corridor: the lab's barcode is on the north side.
    let (text, f) = lint_changed("x: 3.0, y: 2.5", "x: 3.0, y: -1.0");
    let at = line_of(&text, "x: 3.0, y: -1.0");
    assert_eq!(
        rendered(&f),
        [format!(
            "x:{at}: error: mission, start: the start pose is not in the lab: it is outside floor 0, door 1 (lab) (the lab \
             is the side its barcode 10 is on); the robot starts in the lab"
        )]
    );
}

const SOUTH: &str = "      - {polyline: [[0.8, 4], [0, 4], [0, -2], [6, -2], [6, 4], [5.2, 4]]}";

#[test]
fn a_side_corridor_of_1_6_m_is_found_once_at_its_mouth() {
    let (text, f) = lint_changed(
        SOUTH,
        "      - {polyline: [[0.8, 4], [0, 4], [0, -2], [2, -2], [2, -5], [3.6, -5], [3.6, -2], [6, -2], [6, 4], \
         [5.2, 4]]}",
    );
    let at = line_of(&text, "[2, -5], [3.6, -5]");
    assert_eq!(
        rendered(&f),
        [format!(
            "x:{at}: error: floor 0, wall 1, segment 3: an opening 1.60 m wide at (2.80, -2.00) between wall 1, segment 3 \
             and wall 1, segment 7: a side opening is a door (1.0 to 1.4 m) or a side corridor (at least 1.8 m), \
             nothing in between (the junction detector cannot tell which)"
        )]
    );
    // 1.8 m is a side corridor.
    let (_, f) = lint_changed(
        SOUTH,
        "      - {polyline: [[0.8, 4], [0, 4], [0, -2], [2, -2], [2, -5], [3.8, -5], [3.8, -2], [6, -2], [6, 4], \
         [5.2, 4]]}",
    );
    assert!(f.is_empty(), "{f:#?}");
}

#[test]
fn a_corridor_of_1_6_m_is_found() {
    let (text, f) =
        lint_changed(SOUTH, "      - {polyline: [[0.8, 4], [0, 4], [0, -1.6], [6, -1.6], [6, 4], [5.2, 4]]}");
    let at = line_of(&text, "[0, -1.6], [6, -1.6]");
    assert_eq!(
        rendered(&f),
        [format!(
            "x:{at}: error: floor 0, wall 1, segment 3: a way 1.60 m wide between wall 1, segment 3 and wall 3 (around \
             (2.20, -0.80)): corridors and side corridors are at least 1.8 m wide"
        )]
    );
}

#[test]
fn a_door_wider_than_1_4_m_is_found_on_its_line() {
    let text = small()
        .replacen("[0, 0, 4.4, 0]", "[0, 0, 4.3, 0]", 1)
        .replacen("[5.6, 0, 6, 0]", "[5.8, 0, 6, 0]", 1)
        .replacen("at: [4.4, 0, 5.6, 0]", "at: [4.3, 0, 5.8, 0]", 1)
        .replacen("[4.25, 0.02]", "[4.1, 0.02]", 1);
    let at = line_of(&text, "name: lab");
    assert_eq!(
        rendered(&lint_text(&text)),
        [format!(
            "x:{at}: error: floor 0, door 1 (lab): 1.50 m wide: doors are 1.0 to 1.4 m wide (from 1.4 to 1.8 m the \
             junction detector cannot tell a door from a side corridor)"
        )]
    );
}

#[test]
fn a_shaft_out_of_size_is_found_on_its_car_line() {
    let (text, f) = lint_changed("[3.2, 4.0, 5.2, 6.0]", "[3.2, 4.0, 5.2, 6.8]");
    let at = line_of(&text, "[3.2, 4.0, 5.2, 6.8]");
    assert_eq!(
        rendered(&f),
        [format!("x:{at}: error: elevator, car 2: shaft 2.00 × 2.80 m: shafts are 1.8 to 2.4 m on each side")]
    );
}

#[test]
fn a_barcode_off_its_wall_is_found_with_the_distance_and_the_limit() {
    let (text, f) = lint_changed("[4.25, 0.02]", "[4.25, 0.1]");
    let at = line_of(&text, "[4.25, 0.1]");
    assert_eq!(
        rendered(&f),
        [format!(
            "x:{at}: error: floor 0, door 1 (lab), barcode: barcode 10 is 0.10 m in front of the wall behind it: barcodes \
             are stuck 0.01 to 0.02 m off their wall, on the side they face"
        )]
    );
}

#[test]
fn openings_closer_than_0_8_m_are_found_on_the_wall_between() {
    let (text, f) = lint_changed("      - [0, 0, 4.4, 0]", "      - [0, 0, 2.9, 0]\n      - [3.9, 0, 4.4, 0]");
    // A gap without a door is an opening too (found alone); with a door, the same.
    assert_eq!(f.len(), 1, "{f:#?}");
    let text = text.replacen("    doors:\n", "    doors:\n      - {name: store, at: [2.9, 0, 3.9, 0]}\n", 1);
    let at = line_of(&text, "[3.9, 0, 4.4, 0]");
    assert_eq!(
        rendered(&lint_text(&text)),
        [format!(
            "x:{at}: error: floor 0, wall 4: only 0.50 m of wall between the openings at (3.40, 0.00) and (5.00, 0.00): \
             openings on one side of a corridor are at least 0.8 m apart (one hidden for less counts as one)"
        )]
    );
}

#[test]
fn clutter_leaving_less_than_1_2_m_is_found_on_its_line() {
    let (text, f) = lint_changed(
        "      - {name: box, rect: [1.0, 1.0, 1.6, 1.6]}",
        "      - {name: box, rect: [1.0, 1.0, 1.6, 1.6]}\n      - {name: crate, rect: [1.0, -2.0, 1.5, -1.1]}\n      \
         - {name: bin, rect: [3.0, -2.0, 3.5, -1.5]}\n      - {name: bin, rect: [3.2, -0.4, 3.6, 0]}",
    );
    let crate_at = line_of(&text, "name: crate");
    let bin_at = line_of(&text, "[3.2, -0.4, 3.6, 0]");
    assert_eq!(
        rendered(&f),
        [
            format!(
                "x:{crate_at}: error: floor 0, obstacle 2: it leaves 1.10 m free across the corridor (to wall 3): clutter \
                 in a corridor leaves at least 1.2 m free"
            ),
            format!(
                "x:{bin_at}: error: floor 0, obstacle 4: it and obstacle 3 (on the facing wall) leave 1.10 m between them: \
                 clutter in a corridor leaves at least 1.2 m free"
            )
        ]
    );
}

#[test]
fn the_turn_before_a_pass_must_be_written_and_name_the_doors_side() {
    let (text, f) = lint_changed("      - {home: 40}", "      - {home: 40}\n      - {pass: door}");
    let at = line_of(&text, "{pass: door}");
    assert_eq!(
        rendered(&f),
        [format!(
            "x:{at}: error: mission, route car_to_office, step 2: `pass: door` after `home: 40` (step 1) with no `turn: \
             left` or `turn: right` between: the last turn names the side of the barcode the door is on"
        )]
    );
    // The default map's office door is on the right of barcode 40, seen from in front of it.
    let from = "      - {home: 40}\n      - {turn: right}\n      - {pass: door}";
    let text = default_text();
    assert!(text.contains(from));
    let text = text.replacen(from, "      - {home: 40}\n      - {turn: left}\n      - {pass: door}", 1);
    let at = line_of(&text, "{home: 40}") + 1;
    assert_eq!(
        rendered(&lint_text(&text)),
        [format!(
            "x:{at}: error: mission, route car_to_office, step 4: `turn: left` before `pass: door`, but floor 4, door 1 \
             (office) is on the right of barcode 40 (the robot squared up in front of it): the last turn names the \
             side the door is on"
        )]
    );
}

#[test]
fn a_narrow_car_door_is_found_on_its_line() {
    let (text, f) = lint_changed(
        "{rect: [3.2, 4.0, 5.2, 6.0], door: south, barcode: 202}",
        "{rect: [3.2, 4.0, 5.2, 6.0], door: south, door_width: 0.6, barcode: 202}",
    );
    let at = line_of(&text, "door_width: 0.6");
    assert!(has(&f, at, "elevator, car 2: door 0.60 m wide"), "{f:#?}");
}

#[test]
fn a_route_naming_a_barcode_elsewhere_or_missing_is_found_on_its_step_line() {
    let (text, f) = lint_changed("      - {home: 40}", "      - {home: 10}");
    let at = line_of(&text, "{home: 10}");
    assert!(has(&f, at, "mission, route car_to_office, step 1: barcode 10 is on floor 0"), "{f:#?}");
    assert!(has(&f, at, "last `home` is 10, not the office_barcode 40"), "{f:#?}");
    // A missing barcode: the loader refuses it; a map built in code is linted.
    let mut m = Map::parse("x.yaml", &small()).unwrap_or_else(|e| panic!("{e}"));
    if let Some(step) = m.mission.route.get_mut(0).and_then(|(_, s)| s.get_mut(0)) {
        step.home = Some(99);
    }
    let f = lint(&m);
    let at = line_of(&small(), "{home: 40}");
    assert!(has(&f, at, "no barcode 99 in the map"), "{f:#?}");
}

#[test]
fn a_narrow_door_and_a_fenced_in_start_are_found() {
    let (text, f) = lint_changed("at: [4.4, 0, 5.6, 0]", "at: [4.4, 0, 5.1, 0]");
    let at = line_of(&text, "name: lab");
    assert!(has(&f, at, "floor 0, door 1 (lab): 0.70 m wide"), "{f:#?}");
    // A crate around the start pose.
    let (text, f) = lint_changed(
        "      - {name: box, rect: [1.0, 1.0, 1.6, 1.6]}",
        "      - {name: box, rect: [1.0, 1.0, 1.6, 1.6]}\n      - {name: crate, rect: [2.2, 1.9, 3.8, 3.1]}",
    );
    let at = line_of(&text, "lobby: {button: [3.0, 3.98], facing_deg: -90, barcode: 30}");
    assert!(has(&f, at, "floor 0, lobby: the call button cannot be reached"), "{f:#?}");
}
