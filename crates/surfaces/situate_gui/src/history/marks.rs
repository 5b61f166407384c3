//! The timeline's marks: the manager's events, live or as a recording holds them, described
//! in a line each, in cycle order and bounded.

use serde_json::Value as Json;

use super::{History, MARK_TEXT, MAX_MARKS};

/// A phase's mark: its text, and who said it when the client gave a name (`deliver: leaving the
/// lab`).
fn phase_text(text: &str, client: Option<&str>) -> String {
    match client {
        Some(c) if !c.is_empty() => format!("{c}: {text}"),
        _ => text.to_string(),
    }
}

/// An event on the timeline.
#[derive(Debug, Clone, PartialEq)]
pub struct Mark {
    pub cycle: u64,
    /// `activation`, `param`, `priority`, `fault`, `monitor`, `manager`, `worker` or `phase`.
    pub kind: &'static str,
    pub text: String,
}

impl History {
    /// Whether the events given to [`History::push_event`] are marked on the timeline (default
    /// yes). A replay's timeline marks what the recording holds instead
    /// ([`History::push_recorded_event`]): the replayed manager's own events (only its live
    /// skills' changes) would show a part of the run twice and the rest not at all.
    pub fn set_events_mark(&mut self, on: bool) {
        self.events_mark = on;
    }

    /// A mark for an event as a recording holds it: the link's JSON of the event
    /// (`docs/protocol.md`, "Events"), `kind` among its members. The skills' state is not
    /// changed (a replay's comes from the replayed cycles). Prints and events without a cycle
    /// (but `worker_failed`, marked at the newest cycle held) are not marks.
    pub fn push_recorded_event(&mut self, event: &Json) {
        self.mark_event(event);
    }

    /// Marks an event given as the link's JSON of it (see [`History::push_recorded_event`]).
    pub(super) fn mark_event(&mut self, event: &Json) {
        let s = |key: &str| event.get(key).and_then(Json::as_str).unwrap_or("?").to_string();
        let names = |key: &str| -> String {
            let list = event.get(key).and_then(Json::as_array).map(Vec::as_slice).unwrap_or_default();
            list.iter().filter_map(Json::as_str).collect::<Vec<_>>().join(", ")
        };
        let kind_name = event.get("kind").and_then(Json::as_str).unwrap_or("");
        let last_cycle = self.frames.back().map(|f| f.cycle).unwrap_or(self.observed_from);
        let cycle = match (event.get("cycle").and_then(Json::as_u64), kind_name) {
            (Some(c), _) => c,
            (None, "worker_failed") => last_cycle,
            (None, _) => return,
        };
        let (kind, text) = match kind_name {
            "activation_applied" => {
                let (on, off) = (names("activated"), names("deactivated"));
                let mut parts = Vec::new();
                if !on.is_empty() {
                    parts.push(format!("activated {on}"));
                }
                if !off.is_empty() {
                    parts.push(format!("deactivated {off}"));
                }
                ("activation", parts.join("; "))
            }
            "param_changed" => {
                let value = event.get("value").map(Json::to_string).unwrap_or_default();
                ("param", format!("{}.{} = {value}", s("skill"), s("param")))
            }
            "priority_changed" => {
                let p = event.get("priority").map(Json::to_string).unwrap_or_default();
                ("priority", format!("{} priority = {p}", s("skill")))
            }
            "skill_faulted" => ("fault", format!("{} faulted: {}", s("skill"), s("cause"))),
            "monitor_fired" => ("monitor", format!("monitor {} fired: {}", event["monitor"], s("condition"))),
            "monitor_cancelled" => {
                let why = match event.get("reason").and_then(Json::as_str) {
                    Some("forced") => "cancelled by another session",
                    Some("session_ended") => "gone with its session",
                    _ => "cancelled",
                };
                ("monitor", format!("monitor {} {why}: {}", event["monitor"], s("condition")))
            }
            "manager_started" => ("manager", "the cycle started".to_string()),
            "manager_stopped" => ("manager", "the cycle stopped".to_string()),
            "worker_failed" => ("worker", format!("worker {} failed ({}): {}", s("thread"), s("cause"), s("action"))),
            "phase" => ("phase", phase_text(&s("text"), event.get("client").and_then(Json::as_str))),
            _ => return,
        };
        self.insert_mark(cycle, kind, text);
    }

    fn insert_mark(&mut self, cycle: u64, kind: &'static str, text: String) {
        let text = if text.chars().count() > MARK_TEXT {
            format!("{}…", text.chars().take(MARK_TEXT).collect::<String>())
        } else {
            text
        };
        let at = self.marks.partition_point(|m| m.cycle <= cycle);
        self.marks.insert(at, Mark { cycle, kind, text });
        while self.marks.len() > MAX_MARKS {
            self.marks.pop_front();
        }
    }
}
