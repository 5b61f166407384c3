//! What the server has seen of the skills' activation: the cycle each last changed at, and the
//! faults counted (telemetry's `activity`, `/metrics`).

use std::collections::HashMap;

use serde_json::{json, Value as Json};

/// When each skill's activation last changed, as far as this server has seen.
#[derive(Default)]
pub(crate) struct Activity {
    /// The manager's cycle when the server started watching its events.
    pub(crate) observed_from: u64,
    /// Per skill, the cycle of its last activation change (activation_applied, skill_faulted).
    pub(crate) changed: HashMap<String, u64>,
    /// Per skill, the `skill_faulted` events seen (for `/metrics`).
    pub(crate) faults: HashMap<String, u64>,
}

impl Activity {
    /// An activation change seen by the history's tap (which may see it after, or, from before
    /// the server started, instead of the events thread): the latest cycle wins, and faults are
    /// counted by the events thread only.
    pub(crate) fn note_change(&mut self, event: &situate_manager::Event) {
        use situate_manager::Event;
        let mut at = |skill: &String, cycle: u64| {
            let c = self.changed.entry(skill.clone()).or_insert(cycle);
            *c = (*c).max(cycle);
        };
        match event {
            Event::ActivationApplied { activated, deactivated, cycle } => {
                for s in activated.iter().chain(deactivated) {
                    at(s, *cycle);
                }
            }
            Event::SkillFaulted { skill, cycle, .. } => at(skill, *cycle),
            _ => {}
        }
    }

    pub(crate) fn note(&mut self, event: &situate_manager::Event) {
        use situate_manager::Event;
        match event {
            Event::ActivationApplied { activated, deactivated, cycle } => {
                for s in activated.iter().chain(deactivated) {
                    self.changed.insert(s.clone(), *cycle);
                }
            }
            Event::SkillFaulted { skill, cycle, .. } => {
                self.changed.insert(skill.clone(), *cycle);
                *self.faults.entry(skill.clone()).or_default() += 1;
            }
            _ => {}
        }
    }

    pub(crate) fn to_json(&self) -> Json {
        json!({"observed_from": self.observed_from, "changed": self.changed})
    }
}
