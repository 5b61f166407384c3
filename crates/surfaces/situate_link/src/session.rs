//! Zenoh sessions with situate's defaults, and the `link:` section of a
//! robot file.
//!
//! Out of the box a manager is a peer listening on `tcp/127.0.0.1:7447`
//! only, with multicast and gossip scouting off: nothing leaves the machine
//! and nothing is discovered. Clients (the CLI, sequencers, remote skills)
//! are Zenoh *clients* that connect to that endpoint and listen on nothing.

use serde_json::{json, Value as Json};
use situate_robotfile::diagnostic::Diagnostic;
use situate_robotfile::yaml::{Node, Spanned};

use crate::LinkError;

/// The default endpoint of a manager.
pub const DEFAULT_ENDPOINT: &str = "tcp/127.0.0.1:7447";

/// How a manager's link is set up (robot file: `link:`).
#[derive(Debug, Clone, PartialEq)]
pub struct LinkConfig {
    /// Endpoints the manager listens on.
    pub listen: Vec<String>,
    /// Endpoints the manager connects to (another peer or a router).
    pub connect: Vec<String>,
    /// Extra Zenoh configuration merged last, as JSON: TLS (`transport.link.tls`),
    /// authentication (`transport.auth`) and access control (`access_control`).
    pub zenoh: Option<Json>,
    /// Telemetry publications per second.
    pub telemetry_hz: f64,
}

impl Default for LinkConfig {
    fn default() -> Self {
        LinkConfig { listen: vec![DEFAULT_ENDPOINT.into()], connect: Vec::new(), zenoh: None, telemetry_hz: 10.0 }
    }
}

fn node_to_json(node: &Node) -> Json {
    match node {
        Node::Null => Json::Null,
        Node::Scalar { .. } => match node.to_value() {
            Some(situate_core::Value::Bool(b)) => json!(b),
            Some(situate_core::Value::I64(i)) => json!(i),
            Some(situate_core::Value::F64(f)) => json!(f),
            _ => json!(node.as_text().unwrap_or_default()),
        },
        Node::Seq(items) => Json::Array(items.iter().map(|i| node_to_json(&i.value)).collect()),
        Node::Map(entries) => {
            Json::Object(entries.iter().map(|(k, v)| (k.value.clone(), node_to_json(&v.value))).collect())
        }
    }
}

impl LinkConfig {
    /// Reads the robot file's `link:` mapping.
    pub fn from_node(node: &Spanned<Node>) -> Result<LinkConfig, Vec<Diagnostic>> {
        let mut cfg = LinkConfig::default();
        let mut errors = Vec::new();
        let Some(entries) = node.value.as_map() else {
            return Err(vec![Diagnostic::at(node.pos, "`link` must be a mapping")]);
        };
        for (key, value) in entries {
            let endpoints = |errors: &mut Vec<Diagnostic>| -> Vec<String> {
                let items: Vec<&Spanned<Node>> = match &value.value {
                    Node::Seq(items) => items.iter().collect(),
                    Node::Scalar { .. } => vec![value],
                    _ => Vec::new(),
                };
                let mut out = Vec::new();
                for item in items {
                    match item.value.as_text() {
                        Some(t) if t.contains('/') => out.push(t.to_string()),
                        _ => errors.push(Diagnostic::at(
                            item.pos,
                            format!(
                                "`link.{}` expects endpoints like \"tcp/127.0.0.1:7447\", got {}",
                                key.value,
                                item.value.describe()
                            ),
                        )),
                    }
                }
                out
            };
            match key.value.as_str() {
                "listen" => cfg.listen = endpoints(&mut errors),
                "connect" => cfg.connect = endpoints(&mut errors),
                "telemetry_hz" => match value.value.as_f64() {
                    Some(r) if (crate::json::MIN_TELEMETRY_HZ..=crate::json::MAX_TELEMETRY_HZ).contains(&r) => {
                        cfg.telemetry_hz = r
                    }
                    _ => errors.push(Diagnostic::at(
                        value.pos,
                        format!(
                            "`link.telemetry_hz` expects a number from 0.01 to 100, got {}",
                            value.value.describe()
                        ),
                    )),
                },
                "zenoh" => match &value.value {
                    Node::Map(_) => cfg.zenoh = Some(node_to_json(&value.value)),
                    other => errors.push(Diagnostic::at(
                        value.pos,
                        format!("`link.zenoh` expects a mapping of Zenoh configuration, got {}", other.describe()),
                    )),
                },
                other => errors.push(Diagnostic::at(
                    key.pos,
                    format!(
                        "unknown key `{other}` in `link`{}",
                        situate_core::suggestion(other, ["listen", "connect", "telemetry_hz", "zenoh"])
                    ),
                )),
            }
        }
        if errors.is_empty() {
            Ok(cfg)
        } else {
            Err(errors)
        }
    }

    /// The manager's Zenoh configuration.
    pub fn zenoh_config(&self) -> Result<zenoh::Config, LinkError> {
        let mut base = json!({
            "mode": "peer",
            "listen": {"endpoints": self.listen},
            "connect": {"endpoints": self.connect},
            "scouting": {"multicast": {"enabled": false}, "gossip": {"enabled": false}},
        });
        if let Some(extra) = &self.zenoh {
            merge(&mut base, extra);
        }
        config_from_json(&base)
    }
}

/// A client's Zenoh configuration: connect to `endpoints`, listen on nothing,
/// discover nothing.
pub fn client_config(endpoints: &[String], extra: Option<&Json>) -> Result<zenoh::Config, LinkError> {
    let mut base = json!({
        "mode": "client",
        "connect": {"endpoints": endpoints},
        "scouting": {"multicast": {"enabled": false}, "gossip": {"enabled": false}},
    });
    if let Some(extra) = extra {
        merge(&mut base, extra);
    }
    config_from_json(&base)
}

fn config_from_json(j: &Json) -> Result<zenoh::Config, LinkError> {
    zenoh::Config::from_json5(&j.to_string()).map_err(|e| LinkError::Config(e.to_string()))
}

/// Merges `extra` into `base`, objects member by member.
fn merge(base: &mut Json, extra: &Json) {
    match (base, extra) {
        (Json::Object(b), Json::Object(e)) => {
            for (k, v) in e {
                merge(b.entry(k.clone()).or_insert(Json::Null), v);
            }
        }
        (b, e) => *b = e.clone(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn robot_file_link_sections_are_read_with_positions_for_errors() {
        let src = "link:\n  listen: [tcp/127.0.0.1:9000]\n  connect: tcp/10.0.0.2:7447\n  telemetry_hz: 5\n";
        let tree = situate_robotfile::yaml::parse(src).unwrap();
        let link = tree.value.get("link").unwrap();
        let cfg = LinkConfig::from_node(link).unwrap();
        assert_eq!(cfg.listen, ["tcp/127.0.0.1:9000"]);
        assert_eq!(cfg.connect, ["tcp/10.0.0.2:7447"]);
        assert_eq!(cfg.telemetry_hz, 5.0);
        let bad = situate_robotfile::yaml::parse("link:\n  listn: []\n  listen: [7447]\n").unwrap();
        let errs = LinkConfig::from_node(bad.value.get("link").unwrap()).unwrap_err();
        assert_eq!(errs[0].message, "unknown key `listn` in `link` — did you mean `listen`?");
        assert_eq!((errs[0].line(), errs[0].col()), (2, 3));
        assert!(errs[1].message.starts_with("`link.listen` expects endpoints"), "{}", errs[1].message);
    }

    #[test]
    fn default_config_is_a_loopback_peer_without_scouting() {
        let cfg = LinkConfig::default().zenoh_config().unwrap();
        let text = format!("{cfg}");
        assert!(text.contains("127.0.0.1:7447"), "{text}");
    }
}
