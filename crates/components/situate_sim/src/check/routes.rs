//! The rules on the route hints: the barcodes their steps name exist on the
//! leg's floor, the legs home on the barcodes their ends need, and the turn
//! before a `pass: door` names the door's side.

use super::barcodes::{door_el, floor_barcode, nearest_door};
use super::{finding, Diagnostic, BARCODE_JAMB_MAX, BARCODE_LINE_MAX, SLACK};
use crate::geom::P2;
use crate::map::Map;

/// The last turn before a `pass: door` names the side of the barcode homed
/// on that the door is on (`docs/maps.md`, "Route hints"): one is written
/// (`left` or `right`) between the `home` and the `pass`, and, where the
/// barcode marks a door, it is that door's side as the robot sees it,
/// squared up in front of the barcode.
pub(super) fn turns_before_pass(map: &Map, out: &mut Vec<Diagnostic>) {
    let m = &map.mission;
    for (leg, steps) in &m.route {
        let level = match leg.as_str() {
            "lab_to_lobby" => m.start_floor,
            "button_to_office" | "car_to_office" => m.goal_floor,
            _ => continue,
        };
        let Some(f) = map.floor(level) else { continue };
        // The last `home` so far, and the last `turn: left | right` since (the home's own included).
        let mut last_home: Option<usize> = None;
        let mut last_turn: Option<(usize, &str)> = None;
        for (p, st) in steps.iter().enumerate() {
            let side_turn = st.turn.as_deref().filter(|t| *t == "left" || *t == "right");
            let (h, turn) = (last_home, last_turn);
            if st.home.is_some() {
                (last_home, last_turn) = (Some(p), side_turn.map(|t| (p, t)));
            } else if let Some(t) = side_turn {
                last_turn = Some((p, t));
            }
            if st.pass.is_none() {
                continue;
            }
            let Some(h) = h else { continue };
            let id = steps[h].home.unwrap_or_default();
            let el = |i: usize| format!("mission, route {leg}, step {}", i + 1);
            let at =
                |i: usize| if steps[i].line > 0 { steps[i].line } else { m.lines.get("route").copied().unwrap_or(1) };
            let Some((ti, turn)) = turn else {
                out.push(finding(
                    at(p),
                    el(p),
                    format!(
                        "`pass: door` after `home: {id}` (step {}) with no `turn: left` or `turn: right` between: the \
                         last turn names the side of the barcode the door is on",
                        h + 1
                    ),
                ));
                continue;
            };
            let Some((_, b)) = floor_barcode(f, id) else { continue };
            let Some(facing) = b.facing else { continue };
            let Some((i, off, jamb)) = nearest_door(f, b.at) else { continue };
            if off > BARCODE_LINE_MAX + SLACK || jamb > BARCODE_JAMB_MAX + SLACK {
                continue; // no door beside it: door_beside's finding, if it should have one
            }
            let d = &f.doors[i];
            let heading = P2::dir(facing + std::f64::consts::PI);
            let side = if heading.cross(d.seg.at(0.5).minus(b.at)) > 0.0 { "left" } else { "right" };
            if side != turn {
                out.push(finding(
                    at(ti),
                    el(ti),
                    format!(
                        "`turn: {turn}` before `pass: door`, but {} is on the {side} of barcode {id} (the robot \
                         squared up in front of it): the last turn names the side the door is on",
                        door_el(f, i, &d.name)
                    ),
                ));
            }
        }
    }
}

/// Route steps: the barcodes they name exist, on the leg's floor, and the
/// legs home on the barcodes their ends need.
pub(super) fn route(map: &Map, out: &mut Vec<Diagnostic>) {
    let m = &map.mission;
    let all = map.all_barcodes();
    for (leg, steps) in &m.route {
        let floor = match leg.as_str() {
            "lab_to_lobby" => Some(m.start_floor),
            "button_to_office" | "car_to_office" => Some(m.goal_floor),
            _ => None,
        };
        for (i, st) in steps.iter().enumerate() {
            let el = format!("mission, route {leg}, step {}", i + 1);
            let at = if st.line > 0 { st.line } else { m.lines.get("route").copied().unwrap_or(1) };
            for id in [st.barcode, st.home].into_iter().flatten() {
                match all.iter().find(|(_, b)| b.id == id) {
                    None => out.push(finding(at, &el, format!("no barcode {id} in the map"))),
                    Some((Some(level), _)) if floor.is_some_and(|l| l != *level) => out.push(finding(
                        at,
                        &el,
                        format!("barcode {id} is on floor {level}, not on this leg's floor {}", floor.unwrap_or(0)),
                    )),
                    _ => {}
                }
            }
        }
        let want = match leg.as_str() {
            "lab_to_lobby" => Some(("call_button_barcode", m.call_button_barcode)),
            "button_to_office" | "car_to_office" => Some(("office_barcode", m.office_barcode)),
            _ => None,
        };
        if let (Some((what, id)), Some((i, st))) =
            (want, steps.iter().enumerate().rev().find(|(_, s)| s.home.is_some()))
        {
            if st.home != Some(id) {
                out.push(finding(
                    st.line,
                    format!("mission, route {leg}, step {}", i + 1),
                    format!("the leg's last `home` is {}, not the {what} {id}", st.home.unwrap_or(0)),
                ));
            }
        }
    }
}
