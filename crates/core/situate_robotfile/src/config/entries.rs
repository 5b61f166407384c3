//! The `devices:` and `skills:` sections: their entries (name, type or
//! remote manifest, activation, priority, periods and deadlines), each
//! entry's `params:` and its `remap:`.

use situate_core::value::Value;

use super::check::Checker;
use super::{Node, Pos, Spanned};
use crate::limits::MAX_ENTRIES;
use crate::names::{is_identifier, is_signal_name};

const ENTRY_KEYS: &[&str] = &[
    "name",
    "type",
    "remote",
    "timeout_ms",
    "active",
    "priority",
    "period_ms",
    "budget_ms",
    "liveness_ms",
    "params",
    "remap",
];

/// The list a skill entry came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Section {
    /// `devices:` — dskills.
    Devices,
    /// `skills:` — cskills.
    Skills,
}

impl Section {
    /// The section's key: `devices` or `skills`.
    pub fn key(self) -> &'static str {
        match self {
            Section::Devices => "devices",
            Section::Skills => "skills",
        }
    }

    /// What one entry is called in messages: `device` or `skill`.
    pub fn noun(self) -> &'static str {
        match self {
            Section::Devices => "device",
            Section::Skills => "skill",
        }
    }
}

/// One parameter value of an entry's `params:`.
#[derive(Debug, Clone, PartialEq)]
pub struct Param {
    /// The parameter's name, where its key is.
    pub name: Spanned<String>,
    /// Its value, where the value is.
    pub value: Spanned<Value>,
    /// The value as the file writes it, for messages (`1e300`, not its
    /// digits); `None` for a list.
    pub written: Option<String>,
}

/// One entry of `devices:` or `skills:`.
#[derive(Debug, Clone, PartialEq)]
pub struct SkillEntry {
    pub section: Section,
    /// Where the list item starts (its first key).
    pub pos: Pos,
    pub name: Spanned<String>,
    pub type_name: Spanned<String>,
    pub active: bool,
    pub priority: Option<Spanned<i32>>,
    /// A device's thread period, or an async skill's worker period.
    pub period_ms: Option<Spanned<f64>>,
    /// Execution budget of one in-cycle run, ms (overrides `cycle.budget_ms`).
    pub budget_ms: Option<Spanned<f64>>,
    /// Liveness deadline of one run of a threaded body, ms (overrides
    /// `cycle.liveness_ms`).
    pub liveness_ms: Option<Spanned<f64>>,
    /// Parameter values in file order.
    pub params: Vec<Param>,
    /// Port name → signal name, in file order.
    pub remap: Vec<(Spanned<String>, Spanned<String>)>,
    /// A remote skill's manifest (`remote:` instead of `type:`); its type
    /// name is then `remote.<name>`.
    pub remote: Option<Spanned<Node>>,
    /// A remote skill's deadline: once its process has answered, an answer
    /// awaited longer than this (wall-clock ms) faults the skill.
    pub timeout_ms: Option<Spanned<f64>>,
}

impl SkillEntry {
    /// `skill `runaway`` or `device `sonar``, for messages.
    pub fn label(&self) -> String {
        format!("{} `{}`", self.section.noun(), self.name.value)
    }

    /// The value given for parameter `name`.
    pub fn param(&self, name: &str) -> Option<&Spanned<Value>> {
        self.params.iter().find(|p| p.name.value == name).map(|p| &p.value)
    }
}

impl Checker<'_> {
    pub(super) fn section(&mut self, section: Section, node: Spanned<Node>) -> Vec<SkillEntry> {
        let items = match node.value {
            Node::Seq(items) => items,
            Node::Null => Vec::new(),
            other => {
                self.push(
                    node.pos,
                    format!(
                        "`{}` expects a list of {}s (`- name: …`), got {}",
                        section.key(),
                        section.noun(),
                        other.describe()
                    ),
                );
                return Vec::new();
            }
        };
        let mut out = Vec::new();
        for (i, item) in items.into_iter().enumerate() {
            if self.entries == MAX_ENTRIES {
                self.push(
                    item.pos,
                    format!(
                        "too many entries: `devices` and `skills` may hold at most {MAX_ENTRIES} together; \
                         this is entry {} of `{}`",
                        i + 1,
                        section.key()
                    ),
                );
                self.entries += 1;
            }
            if self.entries > MAX_ENTRIES {
                break;
            }
            self.entries += 1;
            out.extend(self.entry(section, i, item));
        }
        out
    }

    pub(super) fn entry(&mut self, section: Section, index: usize, item: Spanned<Node>) -> Option<SkillEntry> {
        let Node::Map(entries) = item.value else {
            self.push(
                item.pos,
                format!(
                    "each entry of `{}` must be a mapping with `name:` and `type:`, got {}",
                    section.key(),
                    item.value.describe()
                ),
            );
            return None;
        };
        let name_node = entries.iter().find(|(k, _)| k.value == "name").map(|(_, v)| v);
        let name = name_node.and_then(|v| self.entry_name(section, v));
        let place = match &name {
            Some(n) => format!("{} `{}`", section.noun(), n.value),
            None => format!("entry {} of `{}`", index + 1, section.key()),
        };
        let mut type_name = None;
        let mut type_given = false;
        let mut active = true;
        let mut priority = None;
        let mut period_ms = None;
        let mut timeout_ms = None;
        let mut budget_ms = None;
        let mut liveness_ms = None;
        let mut params = Vec::new();
        let mut remap = Vec::new();
        let mut remote = None;
        for (key, value) in entries.iter() {
            let k = key.value.as_str();
            match k {
                "name" => {}
                "remote" => {
                    if section == Section::Devices {
                        self.push(
                            key.pos,
                            "a remote skill is an asynchronous cskill: list it under `skills:`".to_string(),
                        );
                    } else if !matches!(value.value, Node::Map(_))
                        && value.value.as_text().is_none_or(|t| t.trim().is_empty())
                    {
                        self.push(
                            value.pos,
                            format!(
                                "`remote` expects the skill's manifest (inputs, outputs, params) or the path of a \
                                 manifest file, got {}",
                                value.value.describe()
                            ),
                        );
                    } else {
                        remote = Some(value.clone());
                    }
                }
                "type" => {
                    type_given = true;
                    type_name = match value.value.as_text() {
                        Some(t) if self.too_long("the type name", t, value.pos) => None,
                        Some(t) if !t.trim().is_empty() => Some(Spanned::new(t.to_string(), value.pos)),
                        _ => {
                            self.push(
                                value.pos,
                                format!("`type` expects a skill type name, got {}", value.value.describe()),
                            );
                            None
                        }
                    };
                }
                "active" => match value.value.as_bool() {
                    Some(b) => active = b,
                    None => {
                        self.push(value.pos, format!("`active` expects true or false, got {}", value.value.describe()))
                    }
                },
                "priority" => {
                    priority = self
                        .integer(k, value, i32::MIN.into(), i32::MAX.into())
                        .and_then(|p| i32::try_from(p).ok())
                        .map(|p| Spanned::new(p, value.pos));
                }
                "period_ms" => {
                    period_ms = self.period(k, value).map(|ms| Spanned::new(ms, value.pos));
                }
                "timeout_ms" => {
                    timeout_ms = self.deadline(k, value).map(|ms| Spanned::new(ms, value.pos));
                }
                "budget_ms" => {
                    budget_ms = self.deadline(k, value).map(|ms| Spanned::new(ms, value.pos));
                }
                "liveness_ms" => {
                    liveness_ms = self.deadline(k, value).map(|ms| Spanned::new(ms, value.pos));
                }
                "params" => params = self.params(value.clone()),
                "remap" => remap = self.remap(value.clone()),
                _ => self.unknown_key(key, &format!("in {place}"), ENTRY_KEYS),
            }
        }
        if name_node.is_none() {
            self.push(item.pos, format!("missing required key `name` in {place}"));
        }
        let remote_given = entries.iter().any(|(k, _)| k.value == "remote");
        if type_given && remote_given {
            self.push(item.pos, format!("{place} has both `type` and `remote`; a remote skill has no type"));
        } else if !type_given && !remote_given {
            self.push(item.pos, format!("missing required key `type` in {place}"));
        }
        if let (Some(r), Some(n)) = (&remote, &name) {
            type_name = Some(Spanned::new(format!("remote.{}", n.value), r.pos));
        }
        if let (Some(t), false) = (&timeout_ms, remote_given) {
            self.push(t.pos, format!("`timeout_ms` in {place} is for remote skills (how long an answer may take)"));
        }
        Some(SkillEntry {
            section,
            pos: item.pos,
            name: name?,
            type_name: type_name?,
            active,
            priority,
            period_ms,
            budget_ms,
            liveness_ms,
            params,
            remap,
            remote,
            timeout_ms,
        })
    }

    pub(super) fn entry_name(&mut self, section: Section, value: &Spanned<Node>) -> Option<Spanned<String>> {
        match value.value.as_text() {
            Some(name) if self.too_long(&format!("the {} name", section.noun()), name, value.pos) => None,
            Some(name) if is_identifier(name) => Some(Spanned::new(name.to_string(), value.pos)),
            Some(name) => {
                self.push(
                    value.pos,
                    format!(
                        "{} name `{name}` is not an identifier (letters, digits and `_`, not starting with a digit)",
                        section.noun()
                    ),
                );
                None
            }
            None => {
                self.push(value.pos, format!("`name` expects a name, got {}", value.value.describe()));
                None
            }
        }
    }

    pub(super) fn params(&mut self, node: Spanned<Node>) -> Vec<Param> {
        let Some(entries) = self.mapping("params", node, "a mapping of parameter names to values") else {
            return Vec::new();
        };
        let mut out = Vec::new();
        for (key, value) in entries {
            let name = &key.value;
            if self.too_long("the parameter name", name, key.pos) {
                continue;
            }
            let v = match &value.value {
                Node::Scalar { .. } => value.value.to_value(),
                Node::Seq(items) => {
                    let mut ok = true;
                    for item in items.iter().filter(|i| i.value.as_f64().is_none()) {
                        ok = false;
                        self.push(
                            item.pos,
                            format!(
                                "parameter `{name}` expects a list of numbers, got {} in it",
                                item.value.describe()
                            ),
                        );
                    }
                    if ok {
                        value.value.to_f64s()
                    } else {
                        None
                    }
                }
                Node::Null => {
                    self.push(value.pos, format!("parameter `{name}` has no value"));
                    None
                }
                Node::Map(_) => {
                    self.push(
                        value.pos,
                        format!("parameter `{name}` expects a scalar or a list of numbers, got a mapping"),
                    );
                    None
                }
            };
            if let Some(v) = v {
                let written = matches!(value.value, Node::Scalar { .. }).then(|| value.value.describe());
                out.push(Param { name: key, value: Spanned::new(v, value.pos), written });
            }
        }
        out
    }

    pub(super) fn remap(&mut self, node: Spanned<Node>) -> Vec<(Spanned<String>, Spanned<String>)> {
        let Some(entries) = self.mapping("remap", node, "a mapping of port names to signal names") else {
            return Vec::new();
        };
        let mut out = Vec::new();
        for (port, target) in entries {
            if self.too_long("the port name", &port.value, port.pos) {
                continue;
            }
            match target.value.as_text() {
                Some(signal) if self.too_long("the signal name", signal, target.pos) => {}
                Some(signal) if is_signal_name(signal) => {
                    let signal = Spanned::new(signal.to_string(), target.pos);
                    out.push((port, signal));
                }
                Some(signal) => self.push(
                    target.pos,
                    format!(
                        "remap target `{signal}` of port `{}` is not a signal name (identifiers joined by `.`, like `sonar.range`)",
                        port.value
                    ),
                ),
                None => self.push(
                    target.pos,
                    format!(
                        "remap of port `{}` expects a signal name, got {}",
                        port.value,
                        target.value.describe()
                    ),
                ),
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use crate::config::tests::{error, errors, skill};
    use crate::limits::{MAX_ENTRIES, MAX_NAME_CHARS};

    #[test]
    fn unknown_key_in_an_unnamed_entry_names_its_index() {
        assert_eq!(
            errors("robot: r\ndevices:\n  - {name: a, type: t}\n  - type: t\n    remp: {}\n"),
            [
                "robot.yaml:4:5: error: missing required key `name` in entry 2 of `devices`",
                "robot.yaml:5:5: error: unknown key `remp` in entry 2 of `devices` — did you mean `remap`?",
            ]
        );
    }

    #[test]
    fn bad_remap_targets() {
        assert_eq!(
            error(&skill("    remap: {sonar_range: sonar..range}\n")),
            "robot.yaml:5:26: error: remap target `sonar..range` of port `sonar_range` is not a signal name (identifiers joined by `.`, like `sonar.range`)"
        );
        assert_eq!(
            error(&skill("    remap:\n      sonar_range: [a]\n")),
            "robot.yaml:6:20: error: remap of port `sonar_range` expects a signal name, got a list"
        );
        assert_eq!(
            error(&skill("    remap: [a]\n")),
            "robot.yaml:5:12: error: `remap` expects a mapping of port names to signal names, got a list"
        );
    }

    #[test]
    fn bad_param_values() {
        assert_eq!(
            errors(&skill(
                "    params:\n      gains: [1, x, 2, {a: 1}]\n      nested: {a: 1}\n      none:\n      ok: [1, 2]\n"
            )),
            [
                "robot.yaml:6:18: error: parameter `gains` expects a list of numbers, got \"x\" in it",
                "robot.yaml:6:24: error: parameter `gains` expects a list of numbers, got a mapping in it",
                "robot.yaml:7:15: error: parameter `nested` expects a scalar or a list of numbers, got a mapping",
                "robot.yaml:8:7: error: parameter `none` has no value",
            ]
        );
        assert_eq!(
            error(&skill("    params: 5\n")),
            "robot.yaml:5:13: error: `params` expects a mapping of parameter names to values, got 5"
        );
    }

    #[test]
    fn list_shapes() {
        assert_eq!(
            error("robot: r\nskills:\n  - runaway\n"),
            "robot.yaml:3:5: error: each entry of `skills` must be a mapping with `name:` and `type:`, got \"runaway\""
        );
        assert_eq!(
            error("robot: r\nskills:\n  runaway: {type: t}\n"),
            "robot.yaml:3:3: error: `skills` expects a list of skills (`- name: …`), got a mapping"
        );
        assert_eq!(
            error("robot: r\ndevices: sonar\n"),
            "robot.yaml:2:10: error: `devices` expects a list of devices (`- name: …`), got \"sonar\""
        );
    }

    #[test]
    fn entries_and_names_are_capped() {
        let mut src = String::from("robot: r\ndevices:\n  - {name: d, type: t}\nskills:\n");
        for i in 0..MAX_ENTRIES + 5 {
            src.push_str(&format!("  - {{name: s{i}, type: t}}\n"));
        }
        assert_eq!(
            error(&src),
            "robot.yaml:1028:5: error: too many entries: `devices` and `skills` may hold at most 1024 together; \
             this is entry 1024 of `skills`"
        );
        let long = "x".repeat(MAX_NAME_CHARS + 1);
        let too_long = |what: &str| format!("{what} is 257 characters long; a name may have at most 256");
        assert_eq!(
            error(&format!("robot: {long}\n")),
            format!("robot.yaml:1:8: error: {}", too_long("the robot name"))
        );
        assert_eq!(
            errors(&skill(&format!("    params: {{{long}: 1}}\n    remap: {{a: {long}}}\n"))),
            [
                format!("robot.yaml:5:14: error: {}", too_long("the parameter name")),
                format!("robot.yaml:6:16: error: {}", too_long("the signal name")),
            ]
        );
        let errors =
            errors(&format!("robot: r\nskills:\n  - {{name: {long}, type: {long}, remap: {{p: a.{long}}}}}\n"));
        assert_eq!(
            errors,
            [
                format!("robot.yaml:3:12: error: {}", too_long("the skill name")),
                format!("robot.yaml:3:277: error: {}", too_long("the type name")),
                "robot.yaml:3:547: error: the signal name is 259 characters long; a name may have at most 256"
                    .to_string(),
            ]
        );
    }
}
