//! The `ros2:` section of a robot file.
//!
//! ```yaml
//! ros2:
//!   domain_id: 0          # ROS_DOMAIN_ID (default 0)
//!   services: true        # activation and parameters as ROS 2 services (default false)
//!   namespace: /robot1    # the node's namespace (default: none)
//!   node: situate         # the node's name (default: the robot's name)
//!   rate_hz: 20           # how often signals are sampled (default 20, at most 100)
//!   use_sim_time: false   # the cycle follows /clock (default false)
//!   lockstep: false       # with use_sim_time: outputs per cycle, then ~/cycle (default false)
//!   topics:
//!     - {signal: drive, topic: cmd_vel, type: geometry_msgs/msg/Twist}
//!     - {signal: odom, topic: odom, type: nav_msgs/msg/Odometry, frame_id: odom, child_frame_id: base_link}
//!     - {signal: odom, topic: /tf, type: tf2_msgs/msg/TFMessage}
//!     - {signal: sonar.range, topic: sonar, type: sensor_msgs/msg/LaserScan, frame_id: base_link, range_max: 4.0}
//!     # topics in: each is a device writing its signal (see `crate::inputs`)
//!     - {topic: /scan, type: sensor_msgs/msg/LaserScan, signal: sonar.range, direction: in, ring: 24}
//!     - {topic: /battery, type: sensor_msgs/msg/BatteryState, signal: battery, direction: in}
//! ```

use serde::Deserialize;
use serde_json::{json, Value as Json};
use situate_robotfile::diagnostic::Diagnostic;
use situate_robotfile::yaml::{Node, Spanned};

use crate::msgs::MsgType;
use crate::rmw::valid_ros_name;

/// The bridge's configuration (the robot file's `ros2:`).
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Ros2Config {
    /// The ROS 2 domain (`ROS_DOMAIN_ID`), 0 to 232.
    #[serde(default)]
    pub domain_id: u32,
    /// The node's namespace: empty (the root) or absolute (`/robot1`).
    #[serde(default)]
    pub namespace: String,
    /// The node's name; `None`: the robot's name (dots and dashes as underscores).
    #[serde(default)]
    pub node: Option<String>,
    /// How often the signals are sampled, per second; a signal is published only when it was
    /// written since the last sample.
    #[serde(default = "default_rate_hz")]
    pub rate_hz: f64,
    /// The signals to publish.
    #[serde(default)]
    pub topics: Vec<TopicConfig>,
    /// Offer activation (`<node>/<skill>/set_active`, `std_srvs/srv/SetBool`) and the skills'
    /// parameters (the node's parameter services) as ROS 2 services (default: no).
    #[serde(default)]
    pub services: bool,
    /// ROS time (ROS 2's `use_sim_time`): the cycle follows `/clock`, one cycle per period of
    /// ROS time, and the messages are stamped with it ([`crate::clock`]). Default: no.
    #[serde(default)]
    pub use_sim_time: bool,
    /// Lock-step with a simulator (needs `use_sim_time`): the topics out are published as each
    /// cycle ends, and the node's `~/cycle` topic (`rosgraph_msgs/msg/Clock`) says, after them,
    /// up to which ROS time the robot has run its cycles; a simulator that waits for it before
    /// its next step makes a run the same every time ([`crate::clock`]). Default: no.
    #[serde(default)]
    pub lockstep: bool,
}

fn default_rate_hz() -> f64 {
    20.0
}

/// Which way a topic goes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Direction {
    /// The signal is published as the topic (the default).
    #[default]
    Out,
    /// The topic's messages feed the signal: a device of the robot writes it.
    In,
}

/// One signal published as a topic, or one topic feeding a signal.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TopicConfig {
    /// The signal (a leaf such as `sonar.range` or a whole record such as `odom`).
    pub signal: String,
    /// `out` (default): the signal is published; `in`: the topic feeds the signal.
    #[serde(default)]
    pub direction: Direction,
    /// A topic in: the name of the device that writes the signal (default `ros2_` and the
    /// topic's name with `/` as `_`: `/scan` → `ros2_scan`).
    #[serde(default)]
    pub name: Option<String>,
    /// A topic in, LaserScan: resample the scan into this many sectors, sector k centred on
    /// bearing k·2π/n counter-clockwise from ahead and reading the nearest valid range in it
    /// (a sonar ring's layout, `f32[n]`); default: the ranges as they come (`f32[]`).
    #[serde(default)]
    pub ring: Option<usize>,
    /// A topic in: how often its device hands the latest message to the cycle, ms (default 1:
    /// a message reaches the next cycle at most 1 ms after it arrives).
    #[serde(default)]
    pub period_ms: Option<f64>,
    /// The topic: relative to the node's namespace (`odom`) or absolute (`/odom`).
    pub topic: String,
    /// The message type.
    #[serde(rename = "type")]
    pub msg_type: MsgType,
    /// The header's `frame_id` (Odometry: default `odom`; LaserScan: default `base_link`).
    #[serde(default)]
    pub frame_id: Option<String>,
    /// Odometry's `child_frame_id` (default `base_link`).
    #[serde(default)]
    pub child_frame_id: Option<String>,
    /// LaserScan's `range_min`, metres (default 0).
    #[serde(default)]
    pub range_min: Option<f32>,
    /// LaserScan's `range_max`, metres (default 4, the sonar's maximum).
    #[serde(default)]
    pub range_max: Option<f32>,
}

impl Ros2Config {
    /// The highest domain id ROS 2 allows.
    pub const MAX_DOMAIN_ID: u32 = 232;

    /// Reads and checks the robot file's `ros2:` mapping (from `situate_robotfile`'s YAML reader).
    /// A mistake is a [`Diagnostic`] at its place in the section (the file is the caller's:
    /// `RobotFile::locate`), its message beginning with `` `ros2`: ``.
    pub fn from_node(node: &Spanned<Node>) -> Result<Ros2Config, Diagnostic> {
        let mistake = |message: String| Diagnostic::at(node.pos, format!("`ros2`: {message}"));
        if node.value.as_map().is_none() {
            return Err(mistake(format!("expected a mapping, got {}", node.value.describe())));
        }
        let config: Ros2Config =
            serde_json::from_value(node_to_json(&node.value)).map_err(|e| mistake(e.to_string()))?;
        config.check().map_err(mistake)?;
        Ok(config)
    }

    /// Checks what serde cannot: ranges, ROS 2 names, duplicate topics.
    pub fn check(&self) -> Result<(), String> {
        if self.domain_id > Self::MAX_DOMAIN_ID {
            return Err(format!("`domain_id` must be from 0 to {}, got {}", Self::MAX_DOMAIN_ID, self.domain_id));
        }
        if !(self.rate_hz.is_finite() && self.rate_hz > 0.0 && self.rate_hz <= 100.0) {
            return Err(format!("`rate_hz` must be in (0, 100], got {}", self.rate_hz));
        }
        if !self.namespace.is_empty() && self.namespace != "/" && !valid_ros_name(&self.namespace, true) {
            return Err(format!("`namespace` is no ROS 2 namespace: {:?} (write e.g. \"/robot1\")", self.namespace));
        }
        if !self.namespace.is_empty() && !self.namespace.starts_with('/') {
            return Err(format!("`namespace` must be absolute: write \"/{}\"", self.namespace));
        }
        if let Some(node) = &self.node {
            if !valid_ros_name(node, false) || node.contains('/') {
                return Err(format!("`node` is no ROS 2 node name: {node:?} (letters, digits, underscores)"));
            }
        }
        if self.lockstep && !self.use_sim_time {
            return Err("`lockstep` needs `use_sim_time: true`: the lock-step is with a simulator's /clock".into());
        }
        if self.topics.is_empty() && !self.services && !self.use_sim_time {
            return Err(
                "`topics` is empty and `services` is off: name at least one signal to publish, or set `services: true`"
                    .into(),
            );
        }
        let mut seen = std::collections::HashSet::new();
        for (i, t) in self.topics.iter().enumerate() {
            if !valid_ros_name(&t.topic, true) {
                return Err(format!(
                    "topics[{i}]: `topic` is no ROS 2 topic name: {:?} (letters, digits, underscores, `/` between parts)",
                    t.topic
                ));
            }
            let fq = crate::rmw::NodeName { domain_id: 0, namespace: self.namespace.clone(), name: String::new() }
                .resolve(&t.topic);
            let ty = t.msg_type.ros_name();
            match t.direction {
                Direction::Out => {
                    if !t.msg_type.can_publish() {
                        return Err(format!("topics[{i}]: {ty} can only be read (`direction: in`), not published"));
                    }
                    for (key, set) in
                        [("name", t.name.is_some()), ("ring", t.ring.is_some()), ("period_ms", t.period_ms.is_some())]
                    {
                        if set {
                            return Err(format!("topics[{i}]: `{key}` is for a topic in (`direction: in`)"));
                        }
                    }
                }
                Direction::In => {
                    if !t.msg_type.can_subscribe() {
                        return Err(format!("topics[{i}]: {ty} can only be published (`direction: out`)"));
                    }
                    let name = t.device_name(&fq);
                    if !valid_identifier(&name) {
                        return Err(format!(
                            "topics[{i}]: `name` {name:?} is no device name (letters, digits and `_`, not starting with a digit)"
                        ));
                    }
                    if let Some(n) = t.ring {
                        if t.msg_type != MsgType::LaserScan {
                            return Err(format!("topics[{i}]: `ring` is for sensor_msgs/msg/LaserScan, not {ty}"));
                        }
                        if !(1..=MAX_RING).contains(&n) {
                            return Err(format!("topics[{i}]: `ring` must be from 1 to {MAX_RING}, got {n}"));
                        }
                    }
                    if let Some(p) = t.period_ms {
                        if !(p.is_finite() && (0.1..=1000.0).contains(&p)) {
                            return Err(format!("topics[{i}]: `period_ms` must be from 0.1 to 1000, got {p}"));
                        }
                    }
                }
            }
            if !seen.insert((fq.clone(), t.direction)) {
                let verb = if t.direction == Direction::Out { "published" } else { "read" };
                return Err(format!("topics[{i}]: topic `{fq}` is {verb} twice"));
            }
            if let (Some(lo), Some(hi)) = (t.range_min, t.range_max) {
                if lo > hi {
                    return Err(format!("topics[{i}]: `range_min` {lo} is above `range_max` {hi}"));
                }
            }
        }
        Ok(())
    }

    /// The node's name: the configured one, or the robot's name made a valid ROS 2 name.
    pub fn node_name(&self, robot: &str) -> String {
        if let Some(n) = &self.node {
            return n.clone();
        }
        let mut name: String = robot.chars().map(|c| if c.is_ascii_alphanumeric() { c } else { '_' }).collect();
        if name.is_empty() || name.starts_with(|c: char| c.is_ascii_digit()) {
            name.insert_str(0, "situate_");
        }
        while name.contains("__") {
            name = name.replace("__", "_");
        }
        name
    }
}

/// The most sectors a LaserScan can be resampled into (`ring`).
pub const MAX_RING: usize = 4096;

impl TopicConfig {
    /// A topic in: its device's name (`name`, else `ros2_` and the fully qualified topic with
    /// `/` as `_`).
    pub fn device_name(&self, fq_topic: &str) -> String {
        match &self.name {
            Some(n) => n.clone(),
            None => format!("ros2_{}", fq_topic.trim_start_matches('/').replace('/', "_")),
        }
    }
}

/// A skill or device name: letters, digits and `_`, not starting with a digit.
fn valid_identifier(name: &str) -> bool {
    !name.is_empty()
        && !name.starts_with(|c: char| c.is_ascii_digit())
        && name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_')
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

#[cfg(test)]
mod tests {
    use super::*;

    const SNIPPET: &str = "\
ros2:
  domain_id: 3
  namespace: /robot1
  rate_hz: 10
  topics:
    - {signal: drive, topic: cmd_vel, type: geometry_msgs/msg/Twist}
    - {signal: odom, topic: odom, type: nav_msgs/msg/Odometry, child_frame_id: base_footprint}
    - {signal: sonar.range, topic: /sonar, type: sensor_msgs/msg/LaserScan, range_max: 4}
";

    fn section(text: &str) -> Spanned<Node> {
        let root = situate_robotfile::yaml::parse(text).expect("YAML");
        root.value.get("ros2").expect("a ros2 section").clone()
    }

    #[test]
    fn the_documented_snippet_reads() {
        let c = Ros2Config::from_node(&section(SNIPPET)).expect("valid");
        assert_eq!(c.domain_id, 3);
        assert_eq!(c.namespace, "/robot1");
        assert_eq!(c.rate_hz, 10.0);
        assert_eq!(c.topics.len(), 3);
        assert_eq!(c.topics[0].msg_type, MsgType::Twist);
        assert_eq!(c.topics[1].child_frame_id.as_deref(), Some("base_footprint"));
        assert_eq!(c.topics[2].range_max, Some(4.0));
        assert_eq!(c.node_name("toy-bot.2"), "toy_bot_2");
        assert_eq!(c.node_name("9lives"), "situate_9lives");
    }

    #[test]
    fn mistakes_are_named_with_their_place() {
        let e = Ros2Config::from_node(&section("x: 1\nros2:\n  topcs: []\n")).expect_err("unknown key");
        assert!(e.to_string().starts_with("3:3: error: `ros2`: unknown field `topcs`"), "{e}");
        let e = Ros2Config::from_node(&section(
            "ros2:\n  topics:\n    - {signal: odom, topic: odom, type: nav_msgs/msg/Odom}\n",
        ))
        .expect_err("unknown type");
        assert!(e.message.contains("nav_msgs/msg/Odometry"), "lists the known types: {e}");
        let bad = |extra: &str| {
            let text = format!("ros2:\n{extra}  topics:\n    - {{signal: a, topic: a, type: std_msgs/msg/Bool}}\n");
            Ros2Config::from_node(&section(&text)).expect_err(extra).message
        };
        assert!(bad("  domain_id: 300\n").contains("domain_id"));
        assert!(bad("  rate_hz: 0\n").contains("rate_hz"));
        assert!(bad("  namespace: robot1\n").contains("absolute"));
        assert!(bad("  node: my-node\n").contains("node"));
        let e = Ros2Config::from_node(&section(
            "ros2:\n  topics:\n    - {signal: sonar.range, topic: sonar.range, type: std_msgs/msg/Bool}\n",
        ))
        .expect_err("a dot in a topic");
        assert!(e.message.contains("topics[0]"), "{e}");
        let e = Ros2Config::from_node(&section(
            "ros2:\n  topics:\n    - {signal: a, topic: x, type: std_msgs/msg/Bool}\n    - {signal: b, topic: /x, type: std_msgs/msg/Bool}\n",
        ))
        .expect_err("twice");
        assert!(e.message.contains("`/x` is published twice"), "{e}");
    }

    #[test]
    fn services_alone_are_enough_and_nothing_at_all_is_refused() {
        let c = Ros2Config::from_node(&section("ros2:\n  services: true\n")).expect("services alone");
        assert!(c.services && c.topics.is_empty());
        let e = Ros2Config::from_node(&section("ros2:\n  domain_id: 1\n")).expect_err("nothing to do");
        assert!(e.message.contains("`services: true`"), "{e}");
        let e = Ros2Config::from_node(&section("ros2:\n  services: yes please\n")).expect_err("not a bool");
        assert!(e.message.contains("bool"), "{e}");
        let e = Ros2Config::from_node(&section("ros2:\n  services: true\n  lockstep: true\n")).expect_err("no clock");
        assert!(e.message.contains("`lockstep` needs `use_sim_time: true`"), "{e}");
        let c = Ros2Config::from_node(&section("ros2:\n  use_sim_time: true\n  lockstep: true\n")).expect("lockstep");
        assert!(c.lockstep);
    }
}
