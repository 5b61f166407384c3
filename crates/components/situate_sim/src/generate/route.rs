//! The route hints the generator writes, worked out in the canonical frame:
//! turns, following a corridor to the N-th junction on a side, and the steps
//! from the office's corridor into the office.

use super::{metres, DoorB, Step};

pub(super) fn turn(s: &str) -> Step {
    Step(vec![("turn", s.to_string())])
}

/// Until the junction on `side` whose near edge is at `edge`, from `from`
/// (along the corridor, cm), it being the `count`-th there.
///
/// With room for it, the step first follows the corridor to 1.5 m before the
/// junction without looking (`distance`), then takes the first junction: the
/// ones before it are 1.5 m or more back, and the junction detector, started
/// there, sees too little of them to count them. A door or clutter taken for a
/// junction on the way cannot then be miscounted.
pub(super) fn junction_step(side: &str, from: i64, edge: i64, count: usize) -> Step {
    let mut step = vec![("follow", "hallway".to_string()), ("until", "junction".into()), ("side", side.into())];
    let blind = edge - 150 - from;
    if blind >= 100 {
        step.push(("distance", metres(blind)));
        step.push(("count", "1".into()));
    } else {
        step.push(("count", count.to_string()));
    }
    step.push(("turn", side.into()));
    Step(step)
}

pub(super) fn flip_word(s: &str) -> String {
    match s {
        "left" => "right".into(),
        "right" => "left".into(),
        o => o.into(),
    }
}

/// Which way to turn, facing the barcode (it faces `facing`), to face the
/// door beside it: left or right (canonical frame).
fn side_of_door(d: &DoorB) -> &'static str {
    let Some(b) = d.barcode else { return "left" };
    let f = match b.facing {
        0 => (1, 0),
        90 => (0, 1),
        180 => (-1, 0),
        _ => (0, -1),
    };
    let look = (-f.0, -f.1);
    let centre2 = (d.a.0 + d.b.0, d.a.1 + d.b.1);
    let v = (centre2.0 - 2 * b.at.0, centre2.1 - 2 * b.at.1);
    if look.0 * v.1 - look.1 * v.0 > 0 {
        "left"
    } else {
        "right"
    }
}

/// From the office's corridor to inside it.
pub(super) fn office_steps(door: &DoorB) -> Vec<Step> {
    let id = door.barcode.map(|b| b.id).unwrap_or(40).to_string();
    vec![
        Step(vec![("follow", "hallway".into()), ("until", "barcode".into()), ("barcode", id.clone())]),
        Step(vec![("home", id)]),
        turn(side_of_door(door)),
        Step(vec![("pass", "door".into())]),
    ]
}
