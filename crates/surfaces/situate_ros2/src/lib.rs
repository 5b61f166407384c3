//! ROS 2 can see the robot: an optional bridge that publishes chosen signals of a running skill
//! manager as ROS 2 topics over Zenoh, the way `rmw_zenoh` (ROS 2's Zenoh middleware) does, so
//! `ros2 topic list` shows them and `ros2 topic echo` prints them with no DDS and no extra process.
//!
//! The bridge samples the signals through the manager's [`Handle`] between cycles, like the
//! GUI's sampler (never on the cycle's thread), at [`Ros2Config::rate_hz`]; a signal is published
//! when it was written since the last sample (so `drive` goes quiet when no skill commands the
//! base, as ROS 2 subscribers expect of `cmd_vel`). Each is converted to its ROS 2 message
//! ([`msgs`]), encoded as CDR by the `cdr` crate and put on the key expression rmw_zenoh uses,
//! with rmw_zenoh's attachment; the node and each publisher hold rmw_zenoh's liveliness tokens
//! ([`rmw`]). The bridge shares the link's Zenoh session, so a ROS 2 node that reaches the
//! link's endpoint (or the Zenoh router the link connects to) sees the topics.
//!
//! ```no_run
//! # fn demo(handle: situate_manager::Handle, session: zenoh::Session, section: &situate_robotfile::yaml::Spanned<situate_robotfile::yaml::Node>) -> Result<(), Box<dyn std::error::Error>> {
//! let config = situate_ros2::Ros2Config::from_node(section)?;
//! let bridge = situate_ros2::Bridge::start("toybot", handle, session, &config)?;
//! // ... the robot runs ...
//! bridge.stop();
//! # Ok(()) }
//! ```
//!
//! With `services: true`, activation and the skills' parameters are ROS 2 services too
//! ([`services`]): `ros2 service call …/set_active std_srvs/srv/SetBool`, `ros2 param set`.
//!
//! Topics in (`direction: in`) feed signals through devices of the robot ([`inputs`]): they are
//! declared on the node before the manager is built ([`Ros2Node::declare`], [`Inputs::declare`],
//! then [`Bridge::start_on`]).

pub mod clock;
pub mod config;
pub mod decode;
pub mod inputs;
pub mod msgs;
pub mod rmw;
pub mod services;

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use situate_core::{ElemType, SignalType, Value};
use situate_manager::{ControlError, Handle, Reply, Request};
use situate_robotfile::diagnostic::Diagnostic;
use zenoh::Wait;

pub use config::{Direction, Ros2Config, TopicConfig};
pub use inputs::{InputStats, Inputs};
pub use msgs::MsgType;

/// How long one sample may wait for the manager.
const REQUEST_TIMEOUT: Duration = Duration::from_secs(5);

/// Why the bridge could not start.
#[derive(Debug, thiserror::Error)]
pub enum Ros2Error {
    /// The configuration is invalid.
    #[error(transparent)]
    Config(#[from] Diagnostic),
    /// A topic's signal does not exist.
    #[error("`ros2`: topic `{topic}`: {source}")]
    Signal {
        topic: String,
        #[source]
        source: ControlError,
    },
    /// A topic's signal has a type its message cannot be made from.
    #[error("`ros2`: topic `{topic}`: signal `{signal}` is {found}, but {msg} is made from {expects}")]
    Type { topic: String, signal: String, found: String, msg: &'static str, expects: &'static str },
    /// Zenoh refused a declaration (a publisher or a liveliness token).
    #[error("`ros2`: could not declare {what} on Zenoh: {message}")]
    Zenoh { what: String, message: String },
    /// The skill manager did not say its period, which ROS time steps by.
    #[error("`ros2`: `use_sim_time`: the skill manager did not say its cycle's period: {0}")]
    Period(String),
    /// The skill manager did not list its skills, which the services are made from.
    #[error("`ros2`: `services`: the skill manager did not list its skills: {0}")]
    Skills(String),
    /// The bridge's thread could not start.
    #[error("`ros2`: could not start the bridge's thread: {0}")]
    Thread(#[source] std::io::Error),
}

/// One signal published as a topic.
pub(crate) struct Topic {
    config: TopicConfig,
    fq_name: String,
    publisher: zenoh::pubsub::Publisher<'static>,
    /// Held while the publisher lives: what `ros2 topic list` sees.
    _token: zenoh::liveliness::LivelinessToken,
    gid: [u8; 16],
    sequence: i64,
    last_cycle: Option<u64>,
    warned: bool,
}

/// A running bridge. Dropping it stops it, like [`Bridge::stop`]; its liveliness tokens are
/// withdrawn, so ROS 2 tools see the node leave.
pub struct Bridge {
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<()>>,
    topics: Vec<(String, String)>,
    servers: Option<services::Servers>,
    node_token: String,
    inputs: Option<Inputs>,
    clock: Option<clock::ClockDriver>,
}

/// The robot's ROS 2 node on a Zenoh session: its name and its liveliness token (what `ros2
/// node list` sees), held until the node is dropped. Topics in ([`Inputs`]) and the [`Bridge`]
/// declare their entities on it.
pub struct Ros2Node {
    pub(crate) session: zenoh::Session,
    pub(crate) name: rmw::NodeName,
    pub(crate) zid: String,
    pub(crate) node_id: u64,
    _token: zenoh::liveliness::LivelinessToken,
    token_key: String,
}

impl Ros2Node {
    /// Checks the configuration and declares the node on `session`; `robot` names the node
    /// when the configuration does not.
    pub fn declare(robot: &str, session: zenoh::Session, config: &Ros2Config) -> Result<Ros2Node, Ros2Error> {
        config.check().map_err(|message| Ros2Error::Config(Diagnostic::without_place(format!("`ros2`: {message}"))))?;
        let name = rmw::NodeName {
            domain_id: config.domain_id,
            namespace: config.namespace.clone(),
            name: config.node_name(robot),
        };
        let zid = session.zid().to_string();
        let node_id = 0u64;
        let token_key = name.node_token(&zid, node_id);
        let token = declare_token(&session, &token_key)?;
        Ok(Ros2Node { session, name, zid, node_id, _token: token, token_key })
    }

    /// Declares a liveliness token of one of the node's entities.
    pub(crate) fn declare_token(&self, key: &str) -> Result<zenoh::liveliness::LivelinessToken, Ros2Error> {
        declare_token(&self.session, key)
    }

    /// The node's liveliness token.
    pub fn token(&self) -> &str {
        &self.token_key
    }
}

fn declare_token(session: &zenoh::Session, key: &str) -> Result<zenoh::liveliness::LivelinessToken, Ros2Error> {
    session
        .liveliness()
        .declare_token(key.to_string())
        .wait()
        .map_err(|e| Ros2Error::Zenoh { what: format!("the liveliness token `{key}`"), message: e.to_string() })
}

impl Bridge {
    /// Declares the node (see [`Ros2Node::declare`]) and starts the bridge on it, with no topics
    /// in (a configuration with some needs [`Inputs::declare`] before the manager is built).
    pub fn start(
        robot: &str,
        handle: Handle,
        session: zenoh::Session,
        config: &Ros2Config,
    ) -> Result<Bridge, Ros2Error> {
        let node = Ros2Node::declare(robot, session, config)?;
        Bridge::start_on(node, None, handle, config)
    }

    /// Checks every topic out's signal against its message type (through `handle`), declares the
    /// publishers and their liveliness tokens on `node`, then samples and publishes on its own
    /// thread until stopped. `inputs` (the topics in, declared before the manager was built) are
    /// kept until the bridge stops.
    pub fn start_on(
        node: Ros2Node,
        inputs: Option<Inputs>,
        handle: Handle,
        config: &Ros2Config,
    ) -> Result<Bridge, Ros2Error> {
        let mut topics = Vec::new();
        for (i, t) in config.topics.iter().enumerate() {
            if t.direction != Direction::Out {
                continue;
            }
            let fq_name = node.name.resolve(&t.topic);
            check_signal(&handle, t, &fq_name)?;
            let key = node.name.topic_key(&fq_name, t.msg_type);
            // Lock-step: a simulator waits for every message, so none is dropped.
            let congestion = if config.lockstep {
                zenoh::qos::CongestionControl::Block
            } else {
                zenoh::qos::CongestionControl::Drop
            };
            let publisher =
                node.session.declare_publisher(key.clone()).congestion_control(congestion).wait().map_err(|e| {
                    Ros2Error::Zenoh { what: format!("a publisher on `{key}`"), message: e.to_string() }
                })?;
            let token_key = node.name.publisher_token(&node.zid, node.node_id, i as u64 + 1, &fq_name, t.msg_type);
            let token = node.declare_token(&token_key)?;
            tracing::info!(topic = %fq_name, signal = %t.signal, %key, "ROS 2 topic published");
            topics.push(Topic {
                config: t.clone(),
                fq_name,
                publisher,
                _token: token,
                gid: rmw::gid(&token_key),
                sequence: 0,
                last_cycle: None,
                warned: false,
            });
        }
        let names = topics.iter().map(|t| (t.fq_name.clone(), t.publisher.key_expr().to_string())).collect();
        // Entity ids: the topics 1..=n in order, then /clock, then ~/cycle (lock-step), then the
        // services.
        let mut next_entity = config.topics.len() as u64 + 1;
        let clock = if config.use_sim_time {
            let period_s = match handle.request_timeout(Request::QueryStats, REQUEST_TIMEOUT) {
                Ok(Reply::Stats(s)) => s.period_s,
                other => return Err(Ros2Error::Period(format!("{other:?}"))),
            };
            let lockstep = if config.lockstep {
                // The driver publishes the topics out as each cycle ends: no sampling thread.
                let l = clock::Lockstep::declare(&node, next_entity + 1, std::mem::take(&mut topics))?;
                Some(l)
            } else {
                None
            };
            let driver = clock::ClockDriver::start(&node, next_entity, handle.clone(), period_s, lockstep)?;
            next_entity += if config.lockstep { 2 } else { 1 };
            Some(driver)
        } else {
            None
        };
        let stamps = clock.as_ref().map(clock::ClockDriver::time);
        let servers = if config.services {
            let first = next_entity;
            let servers = services::Servers::start(&handle, &node.session, &node.name, node.node_id, first)?;
            for (name, key) in &servers.names {
                tracing::info!(service = %name, %key, "ROS 2 service offered");
            }
            Some(servers)
        } else {
            None
        };
        let stop = Arc::new(AtomicBool::new(false));
        let period = Duration::from_secs_f64(1.0 / config.rate_hz);
        let st = Arc::clone(&stop);
        let node_token = node.token_key.clone();
        let thread = std::thread::Builder::new()
            .name("situate-ros2".into())
            .spawn(move || {
                let _node = node;
                // Lock-step: the ROS time driver publishes the topics (none are left here).
                sample_loop(&handle, &mut topics, period, &st, stamps.as_deref());
            })
            .map_err(Ros2Error::Thread)?;
        Ok(Bridge { stop, thread: Some(thread), topics: names, servers, node_token, inputs, clock })
    }

    /// What the ROS time driver counted (`None` without `use_sim_time`).
    pub fn clock_stats(&self) -> Option<clock::ClockStats> {
        self.clock.as_ref().map(clock::ClockDriver::stats)
    }

    /// What each topic in has received so far (none without topics in).
    pub fn input_stats(&self) -> Vec<InputStats> {
        self.inputs.as_ref().map_or_else(Vec::new, Inputs::stats)
    }

    /// Each topic's fully qualified name and the Zenoh key its messages are put on.
    pub fn topics(&self) -> &[(String, String)] {
        &self.topics
    }

    /// Each service's fully qualified name and its key expression (none without `services`).
    pub fn services(&self) -> &[(String, String)] {
        self.servers.as_ref().map_or(&[], |s| s.names.as_slice())
    }

    /// What the services refused so far: calls past the queue, requests that could not be read
    /// (all zero without `services`).
    pub fn service_stats(&self) -> services::ServiceStats {
        self.servers.as_ref().map_or_else(services::ServiceStats::default, services::Servers::stats)
    }

    /// The node's liveliness token.
    pub fn node_token(&self) -> &str {
        &self.node_token
    }

    /// Stops publishing and withdraws the node and its publishers.
    pub fn stop(mut self) {
        self.stop_inner();
    }

    fn stop_inner(&mut self) {
        if let Some(mut servers) = self.servers.take() {
            servers.stop();
        }
        self.stop.store(true, Ordering::SeqCst);
        self.clock.take();
        self.inputs.take();
        if let Some(t) = self.thread.take() {
            if t.join().is_err() {
                tracing::warn!("the ROS 2 bridge's thread panicked");
            }
        }
    }
}

impl Drop for Bridge {
    fn drop(&mut self) {
        self.stop_inner();
    }
}

/// Refuses a signal that is unknown or of a type its message is not made from.
fn check_signal(handle: &Handle, t: &TopicConfig, fq_name: &str) -> Result<(), Ros2Error> {
    let reply = handle
        .request_timeout(Request::QuerySignal { signal: t.signal.clone() }, REQUEST_TIMEOUT)
        .map_err(|source| Ros2Error::Signal { topic: fq_name.to_string(), source })?;
    let Reply::Signal(reading) = reply else {
        return Err(Ros2Error::Signal {
            topic: fq_name.to_string(),
            source: ControlError::Invalid(format!("unexpected reply to a signal query: {reply:?}")),
        });
    };
    let f64_field = |r: &situate_core::RecordType, name: &str| matches!(r.field(name), Some((_, SignalType::F64)));
    let fits = match (t.msg_type, &reading.ty) {
        (MsgType::Twist | MsgType::TwistStamped, SignalType::Record(r)) => f64_field(r, "v") && f64_field(r, "w"),
        (MsgType::Odometry | MsgType::TfMessage, SignalType::Record(r)) => {
            f64_field(r, "x") && f64_field(r, "y") && f64_field(r, "theta")
        }
        (MsgType::LaserScan, SignalType::Array { elem: ElemType::F32 | ElemType::F64, .. }) => true,
        (MsgType::Float64 | MsgType::Range, SignalType::F64)
        | (MsgType::Int64, SignalType::I64)
        | (MsgType::Bool, SignalType::Bool)
        | (MsgType::String, SignalType::Str) => true,
        _ => false,
    };
    if fits {
        Ok(())
    } else {
        Err(Ros2Error::Type {
            topic: fq_name.to_string(),
            signal: t.signal.clone(),
            found: reading.ty.to_string(),
            msg: t.msg_type.ros_name(),
            expects: t.msg_type.expects(),
        })
    }
}

fn sample_loop(
    handle: &Handle,
    topics: &mut [Topic],
    period: Duration,
    stop: &AtomicBool,
    stamps: Option<&clock::RosTime>,
) {
    let mut next = Instant::now();
    while !stop.load(Ordering::SeqCst) {
        publish_new(handle, topics, stamps);
        next += period;
        let now = Instant::now();
        if next < now {
            next = now + period;
        }
        // Sleep in short steps so a stop is seen promptly.
        while !stop.load(Ordering::SeqCst) {
            let now = Instant::now();
            if now >= next {
                break;
            }
            std::thread::sleep((next - now).min(Duration::from_millis(50)));
        }
    }
}

/// Publishes each topic out whose signal was written since it was last published, stamped with
/// ROS time (`stamps`) or else the wall clock's.
pub(crate) fn publish_new(handle: &Handle, topics: &mut [Topic], stamps: Option<&clock::RosTime>) {
    if topics.is_empty() {
        return;
    }
    // One request for every topic's signal: each is a round trip to the cycle's thread.
    let signals = topics.iter().map(|t| t.config.signal.clone()).collect();
    let readings = match handle.request_timeout(Request::QuerySignals { signals }, REQUEST_TIMEOUT) {
        Ok(Reply::Signals(r)) if r.len() == topics.len() => r,
        other => {
            let error = match other {
                Err(e) => e.to_string(),
                Ok(reply) => format!("unexpected reply {reply:?}"),
            };
            for topic in topics.iter_mut().filter(|t| !t.warned) {
                tracing::warn!(topic = %topic.fq_name, %error, "ROS 2 bridge: cannot read the signal");
                topic.warned = true;
            }
            return;
        }
    };
    for (topic, reading) in topics.iter_mut().zip(readings) {
        publish_reading(topic, reading, stamps);
    }
}

/// Publishes one topic's signal reading if it was written since the topic was last published.
fn publish_reading(topic: &mut Topic, reading: situate_manager::SignalReading, stamps: Option<&clock::RosTime>) {
    let Some(value) = reading.value else { return };
    if topic.last_cycle == Some(reading.cycle) {
        return;
    }
    topic.last_cycle = Some(reading.cycle);
    let stamp = stamps.and_then(clock::RosTime::now).unwrap_or_else(msgs::Time::now);
    let payload = match to_payload_stamped(&topic.config, &value, stamp) {
        Some(Ok(p)) => p,
        Some(Err(e)) => {
            tracing::warn!(topic = %topic.fq_name, error = %e, "ROS 2 bridge: cannot encode");
            return;
        }
        None => {
            if !topic.warned {
                tracing::warn!(topic = %topic.fq_name, "ROS 2 bridge: the signal's value does not fit the message");
                topic.warned = true;
            }
            return;
        }
    };
    topic.sequence += 1;
    let attachment = rmw::attachment(topic.sequence, wall_ns(), &topic.gid);
    if let Err(e) = topic.publisher.put(payload).attachment(attachment).wait() {
        tracing::warn!(topic = %topic.fq_name, error = %e, "ROS 2 bridge: put failed");
    }
    tracing::trace!(topic = %topic.fq_name, cycle = reading.cycle, "published");
}

/// The wall clock, ns since the Unix epoch (an attachment's source timestamp).
pub(crate) fn wall_ns() -> i64 {
    std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| i64::try_from(d.as_nanos()).unwrap_or(i64::MAX))
        .unwrap_or(0)
}

fn field(value: &Value, name: &str) -> Option<f64> {
    match value {
        Value::Record(r) => match r.get(name)? {
            Value::F64(f) => Some(*f),
            _ => None,
        },
        _ => None,
    }
}

/// The message for a signal's value, CDR-encoded; `None` when the value does not fit.
pub fn to_payload(t: &TopicConfig, value: &Value) -> Option<Result<Vec<u8>, cdr::Error>> {
    to_payload_stamped(t, value, msgs::Time::now())
}

/// [`to_payload`], the headers stamped `stamp` (ROS time, or the wall clock).
pub fn to_payload_stamped(t: &TopicConfig, value: &Value, stamp: msgs::Time) -> Option<Result<Vec<u8>, cdr::Error>> {
    use msgs::*;
    Some(match t.msg_type {
        MsgType::Twist => encode(&Twist {
            linear: Vector3 { x: field(value, "v")?, ..Vector3::default() },
            angular: Vector3 { z: field(value, "w")?, ..Vector3::default() },
        }),
        MsgType::Odometry => {
            let theta = field(value, "theta")?;
            encode(&Odometry {
                header: Header { stamp, frame_id: t.frame_id.clone().unwrap_or_else(|| "odom".into()) },
                child_frame_id: t.child_frame_id.clone().unwrap_or_else(|| "base_link".into()),
                pose: PoseWithCovariance {
                    pose: Pose {
                        position: Point { x: field(value, "x")?, y: field(value, "y")?, z: 0.0 },
                        orientation: Quaternion::from_yaw(theta),
                    },
                    covariance: Covariance::default(),
                },
                twist: TwistWithCovariance {
                    twist: Twist {
                        linear: Vector3 { x: field(value, "v").unwrap_or(0.0), ..Vector3::default() },
                        angular: Vector3 { z: field(value, "w").unwrap_or(0.0), ..Vector3::default() },
                    },
                    covariance: Covariance::default(),
                },
            })
        }
        MsgType::LaserScan => {
            let ranges: Vec<f32> = match value {
                Value::F32s(a) => a.to_vec(),
                Value::F64s(a) => a.iter().map(|&r| r as f32).collect(),
                _ => return None,
            };
            let n = ranges.len().max(1);
            let increment = std::f32::consts::TAU / n as f32;
            encode(&LaserScan {
                header: Header { stamp, frame_id: t.frame_id.clone().unwrap_or_else(|| "base_link".into()) },
                angle_min: 0.0,
                angle_max: increment * (n - 1) as f32,
                angle_increment: increment,
                time_increment: 0.0,
                scan_time: 0.0,
                range_min: t.range_min.unwrap_or(0.0),
                range_max: t.range_max.unwrap_or(4.0),
                ranges,
                intensities: Vec::new(),
            })
        }
        MsgType::Float64 => match value {
            Value::F64(f) => encode(&Float64 { data: *f }),
            _ => return None,
        },
        MsgType::Int64 => match value {
            Value::I64(i) => encode(&Int64 { data: *i }),
            _ => return None,
        },
        MsgType::Bool => match value {
            Value::Bool(b) => encode(&Bool { data: *b }),
            _ => return None,
        },
        MsgType::TwistStamped => encode(&TwistStamped {
            header: Header { stamp, frame_id: t.frame_id.clone().unwrap_or_else(|| "base_link".into()) },
            twist: Twist {
                linear: Vector3 { x: field(value, "v")?, ..Vector3::default() },
                angular: Vector3 { z: field(value, "w")?, ..Vector3::default() },
            },
        }),
        MsgType::TfMessage => encode(&TfMessage {
            transforms: vec![TransformStamped {
                header: Header { stamp, frame_id: t.frame_id.clone().unwrap_or_else(|| "odom".into()) },
                child_frame_id: t.child_frame_id.clone().unwrap_or_else(|| "base_link".into()),
                transform: Transform {
                    translation: Vector3 { x: field(value, "x")?, y: field(value, "y")?, z: 0.0 },
                    rotation: Quaternion::from_yaw(field(value, "theta")?),
                },
            }],
        }),
        MsgType::Range => match value {
            Value::F64(r) => encode(&Range {
                header: Header { stamp, frame_id: t.frame_id.clone().unwrap_or_else(|| "base_link".into()) },
                radiation_type: 0,
                field_of_view: 0.26,
                min_range: t.range_min.unwrap_or(0.0),
                max_range: t.range_max.unwrap_or(4.0),
                range: *r as f32,
                variance: 0.0,
            }),
            _ => return None,
        },
        MsgType::String => match value {
            Value::Str(text) => encode(&StringMsg { data: text.to_string() }),
            _ => return None,
        },
        MsgType::Imu
        | MsgType::JointState
        | MsgType::BatteryState
        | MsgType::Barcodes
        | MsgType::People
        | MsgType::Cars => return None,
    })
}
