//! Topics in: a ROS 2 topic feeding a signal, the way a device (dskill) feeds one.
//!
//! Each `direction: in` topic of the `ros2:` section becomes a device of the robot (named
//! `ros2_<topic>` unless the topic names it) with one output, `value`, connected to the topic's
//! signal. A Zenoh subscriber of the link's session receives the topic's messages on a Zenoh
//! thread, reads each with the bounded CDR reader ([`crate::decode`]) and turns it into the
//! signal's value there, off the cycle; the device's body only takes the latest value when there
//! is a new one (a mutex held for a move, never a wait on the network), so the manager reads a
//! topic like any device reading: the latest per cycle, an output only when a message came.
//!
//! Discovery is rmw_zenoh's: the subscription holds an `MS` liveliness token, so `ros2 topic
//! info` on the other side counts it. The subscriber listens on every type of the topic
//! (`<domain>/<topic>/*/*`): a message of another type or type hash, or one that cannot be read,
//! is counted and reported once per publisher and problem (in the log, and as the device's own
//! print, which the GUI and the link show), and the cycle runs on with the last good value.
//!
//! A replay and `situate check` make the same devices from the configuration alone
//! ([`devices`]): a replay plays their signals back from the recording like any device's.

use std::collections::HashSet;
use std::f64::consts::TAU;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Mutex, MutexGuard};

use situate_core::{
    ElemType, Io, PortSpec, RecordType, RecordValue, SignalType, Skill, SkillDecl, SkillError, SkillKind, SkillType,
    Value,
};
use situate_robotfile::config::Section;
use situate_robotfile::spec::SkillSpec;
use zenoh::Wait;

use crate::config::{Direction, Ros2Config, TopicConfig};
use crate::msgs::{self, MsgType};
use crate::{rmw, Ros2Error, Ros2Node};

/// A device hands the latest message to the cycle this often unless the topic says (`period_ms`).
pub const DEFAULT_PERIOD_MS: f64 = 1.0;

/// At most this many distinct problems are reported per topic (then one line saying so); each
/// is still counted.
const MAX_REPORTS: usize = 32;

/// What one topic in has seen so far.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct InputStats {
    /// The fully qualified topic.
    pub topic: String,
    /// The device writing its signal.
    pub device: String,
    /// Messages received on the topic's key expressions (every type).
    pub received: u64,
    /// Messages read and handed on.
    pub accepted: u64,
    /// Messages of another type or type hash.
    pub wrong_type: u64,
    /// Messages of the right type that could not be read.
    pub undecodable: u64,
}

/// The signal type a topic in of `ty` writes (`ring`: a LaserScan resampled into `n` sectors).
pub fn signal_type(ty: MsgType, ring: Option<usize>) -> SignalType {
    let record = |names: &[&str]| {
        SignalType::Record(Arc::new(RecordType::new(
            names.iter().map(|n| ((*n).to_string(), SignalType::F64)).collect(),
        )))
    };
    match ty {
        MsgType::Twist | MsgType::TwistStamped => record(&["v", "w"]),
        MsgType::Odometry | MsgType::TfMessage => record(&["x", "y", "theta", "v", "w"]),
        MsgType::LaserScan => SignalType::Array { elem: ElemType::F32, len: ring },
        MsgType::Range | MsgType::Float64 => SignalType::F64,
        MsgType::Imu => record(&["roll", "pitch", "yaw", "wx", "wy", "wz", "ax", "ay", "az"]),
        MsgType::JointState => SignalType::Record(Arc::new(RecordType::new(
            ["position", "velocity", "effort"]
                .iter()
                .map(|n| ((*n).to_string(), SignalType::Array { elem: ElemType::F64, len: None }))
                .collect(),
        ))),
        MsgType::BatteryState => record(&["voltage", "current", "charge", "percentage", "temperature"]),
        // The robot's `barcodes` record (docs/robot-signals.md, `situate_robot::Barcodes`).
        MsgType::Barcodes => SignalType::Record(Arc::new(RecordType::new(vec![
            ("ids".to_string(), SignalType::Array { elem: ElemType::I64, len: None }),
            ("bearing".to_string(), SignalType::Array { elem: ElemType::F64, len: None }),
            ("distance".to_string(), SignalType::Array { elem: ElemType::F64, len: None }),
        ]))),
        // A simulator's ground truth, as the 2-D simulator's `sim.truth` writes it.
        MsgType::People => SignalType::Record(Arc::new(RecordType::new(vec![
            ("x".to_string(), SignalType::Array { elem: ElemType::F64, len: None }),
            ("y".to_string(), SignalType::Array { elem: ElemType::F64, len: None }),
            ("floor".to_string(), SignalType::Array { elem: ElemType::I64, len: None }),
        ]))),
        MsgType::Cars => SignalType::Record(Arc::new(RecordType::new(vec![
            ("floor".to_string(), SignalType::Array { elem: ElemType::F64, len: None }),
            ("door".to_string(), SignalType::Array { elem: ElemType::F64, len: None }),
        ]))),
        MsgType::Int64 => SignalType::I64,
        MsgType::Bool => SignalType::Bool,
        MsgType::String => SignalType::Str,
    }
}

/// The latest message of one topic, between the subscriber and the device.
#[derive(Default)]
struct Inbox {
    latest: Mutex<Option<Value>>,
    /// Whether `reports` has lines for the device to print.
    has_reports: AtomicBool,
    reports: Mutex<Vec<String>>,
    received: AtomicU64,
    accepted: AtomicU64,
    wrong_type: AtomicU64,
    undecodable: AtomicU64,
}

fn lock<T>(m: &Mutex<T>) -> MutexGuard<'_, T> {
    // Nothing a panicking holder could leave half-done: recover the value.
    m.lock().unwrap_or_else(|p| p.into_inner())
}

/// The device of a topic in: hands on the latest message, and prints the problems reported.
struct InDevice {
    inbox: Arc<Inbox>,
}

impl Skill for InDevice {
    fn step(&mut self, io: &mut Io<'_>) -> Result<(), SkillError> {
        if self.inbox.has_reports.swap(false, Ordering::AcqRel) {
            for line in lock(&self.inbox.reports).drain(..) {
                io.cx.print(line);
            }
        }
        if let Some(value) = lock(&self.inbox.latest).take() {
            io.outputs[0] = Some(value);
        }
        Ok(())
    }

    fn set_param(&mut self, _index: usize, _value: &Value) {}
}

/// One topic in, as the robot sees it: its device's instance and type.
fn device(robot_ns: &rmw::NodeName, t: &TopicConfig, inbox: Arc<Inbox>) -> (SkillSpec, SkillType) {
    let fq = robot_ns.resolve(&t.topic);
    let name = t.device_name(&fq);
    let type_name = format!("ros2.in.{name}");
    let mut decl = SkillDecl::new(&type_name, SkillKind::Device);
    decl.doc = format!("reads the ROS 2 topic `{fq}` ({}) into `{}`", t.msg_type.ros_name(), t.signal);
    let mut port = PortSpec::new("value", signal_type(t.msg_type, t.ring));
    port.signal = t.signal.clone();
    port.doc = format!("the latest message of `{fq}`");
    decl.outputs.push(port);
    let ty = SkillType::new(decl, move || Ok(Box::new(InDevice { inbox: Arc::clone(&inbox) }) as Box<dyn Skill>));
    let mut spec = SkillSpec::new(&name, &type_name).period_ms(t.period_ms.unwrap_or(DEFAULT_PERIOD_MS));
    spec.section = Some(Section::Devices);
    (spec, ty)
}

/// The devices of the configuration's topics in, with no subscription behind them (they never
/// write): for a replay, which plays their signals back, and for checking a robot file.
pub fn devices(robot: &str, config: &Ros2Config) -> Vec<(SkillSpec, SkillType)> {
    let node = rmw::NodeName {
        domain_id: config.domain_id,
        namespace: config.namespace.clone(),
        name: config.node_name(robot),
    };
    config
        .topics
        .iter()
        .filter(|t| t.direction == Direction::In)
        .map(|t| device(&node, t, Arc::new(Inbox::default())))
        .collect()
}

struct Topic {
    fq_name: String,
    device: String,
    inbox: Arc<Inbox>,
    _subscriber: zenoh::pubsub::Subscriber<()>,
    _token: zenoh::liveliness::LivelinessToken,
}

/// The subscriptions of a robot's topics in. Dropping it (or [`Inputs::close`]) undeclares them
/// and withdraws their liveliness tokens; the devices then write nothing more.
pub struct Inputs {
    topics: Vec<Topic>,
}

impl Inputs {
    /// Subscribes to each topic in of `config` on `node`'s session, holding its `MS` token, and
    /// returns the devices to add to the robot before it is built.
    pub fn declare(node: &Ros2Node, config: &Ros2Config) -> Result<(Inputs, Vec<(SkillSpec, SkillType)>), Ros2Error> {
        let mut topics = Vec::new();
        let mut devices = Vec::new();
        for (i, t) in config.topics.iter().enumerate() {
            if t.direction != Direction::In {
                continue;
            }
            let fq_name = node.name.resolve(&t.topic);
            let inbox = Arc::new(Inbox::default());
            let (spec, ty) = device(&node.name, t, Arc::clone(&inbox));
            let data_key = node.name.topic_key(&fq_name, t.msg_type);
            let prefix = format!("{}/{}", node.name.domain_id, fq_name.trim_start_matches('/'));
            let listen = format!("{prefix}/*/*");
            let reader = Reader::new(t, &fq_name, &spec.name, data_key.clone(), Arc::clone(&inbox));
            let subscriber = node
                .session
                .declare_subscriber(listen.clone())
                .callback(move |sample| reader.receive(&sample))
                .wait()
                .map_err(|e| Ros2Error::Zenoh {
                    what: format!("a subscriber on `{listen}`"),
                    message: e.to_string(),
                })?;
            let token_key = node.name.subscription_token(&node.zid, node.node_id, i as u64 + 1, &fq_name, t.msg_type);
            let token = node.declare_token(&token_key)?;
            tracing::info!(topic = %fq_name, signal = %t.signal, device = %spec.name, key = %data_key, "ROS 2 topic read");
            topics.push(Topic { fq_name, device: spec.name.clone(), inbox, _subscriber: subscriber, _token: token });
            devices.push((spec, ty));
        }
        Ok((Inputs { topics }, devices))
    }

    /// Each topic in's counts so far.
    pub fn stats(&self) -> Vec<InputStats> {
        self.topics
            .iter()
            .map(|t| InputStats {
                topic: t.fq_name.clone(),
                device: t.device.clone(),
                received: t.inbox.received.load(Ordering::Relaxed),
                accepted: t.inbox.accepted.load(Ordering::Relaxed),
                wrong_type: t.inbox.wrong_type.load(Ordering::Relaxed),
                undecodable: t.inbox.undecodable.load(Ordering::Relaxed),
            })
            .collect()
    }

    /// Whether there are no topics in.
    pub fn is_empty(&self) -> bool {
        self.topics.is_empty()
    }

    /// Undeclares the subscriptions and withdraws their tokens.
    pub fn close(self) {}
}

/// What a subscriber's callback knows: how to read its topic's messages.
struct Reader {
    fq_name: String,
    device: String,
    ty: MsgType,
    ring: Option<usize>,
    /// The key expression the expected type's messages come on.
    data_key: String,
    inbox: Arc<Inbox>,
    /// The record's field names, made once.
    fields: Vec<Arc<str>>,
    /// (publisher GID, problem kind) already reported.
    reported: Mutex<HashSet<(Option<[u8; 16]>, String)>>,
}

impl Reader {
    fn new(t: &TopicConfig, fq_name: &str, device: &str, data_key: String, inbox: Arc<Inbox>) -> Reader {
        let fields = match signal_type(t.msg_type, t.ring) {
            SignalType::Record(r) => r.fields.iter().map(|(n, _)| Arc::from(n.as_str())).collect(),
            _ => Vec::new(),
        };
        Reader {
            fq_name: fq_name.to_string(),
            device: device.to_string(),
            ty: t.msg_type,
            ring: t.ring,
            data_key,
            inbox,
            fields,
            reported: Mutex::new(HashSet::new()),
        }
    }

    fn receive(&self, sample: &zenoh::sample::Sample) {
        let inbox = &self.inbox;
        inbox.received.fetch_add(1, Ordering::Relaxed);
        let gid = sample.attachment().and_then(|a| publisher_gid(&a.to_bytes()));
        let key = sample.key_expr().as_str();
        if key != self.data_key {
            inbox.wrong_type.fetch_add(1, Ordering::Relaxed);
            let (ty, hash) = key
                .rsplit_once('/')
                .map_or((key, ""), |(rest, hash)| (rest.rsplit_once('/').map_or(rest, |(_, ty)| ty), hash));
            let found = ros_name_of(ty).unwrap_or_else(|| ty.to_string());
            self.report(
                gid,
                format!("type {found} {hash}"),
                format!(
                    "a message of {found} ({}) from {}: expected {} ({}); ignored, as is every such message",
                    short_hash(hash),
                    publisher(gid),
                    self.ty.ros_name(),
                    short_hash(self.ty.type_hash())
                ),
            );
            return;
        }
        let payload = sample.payload().to_bytes();
        match self.read(&payload) {
            Ok(value) => {
                inbox.accepted.fetch_add(1, Ordering::Relaxed);
                *lock(&inbox.latest) = Some(value);
            }
            Err(problem) => {
                inbox.undecodable.fetch_add(1, Ordering::Relaxed);
                self.report(
                    gid,
                    "undecodable".into(),
                    format!(
                        "a {} from {} could not be read: {problem}; ignored (and later ones like it, counted)",
                        self.ty.ros_name(),
                        publisher(gid)
                    ),
                );
            }
        }
    }

    /// Reports a problem once per publisher and kind, as the log's warning and the device's print.
    fn report(&self, gid: Option<[u8; 16]>, kind: String, line: String) {
        let mut reported = lock(&self.reported);
        if reported.len() > MAX_REPORTS || !reported.insert((gid, kind)) {
            return;
        }
        let line = if reported.len() > MAX_REPORTS {
            format!("topic `{}`: more problems than {MAX_REPORTS}: only counted from now on", self.fq_name)
        } else {
            format!("topic `{}`: {line}", self.fq_name)
        };
        drop(reported);
        tracing::warn!(topic = %self.fq_name, device = %self.device, "{line}");
        lock(&self.inbox.reports).push(line);
        self.inbox.has_reports.store(true, Ordering::Release);
    }

    fn record(&self, values: impl IntoIterator<Item = Value>) -> Value {
        Value::Record(Arc::new(RecordValue { fields: self.fields.iter().cloned().zip(values).collect() }))
    }

    /// The signal's value of one payload.
    fn read(&self, payload: &[u8]) -> Result<Value, String> {
        let e = |e: msgs::DecodeError| e.to_string();
        Ok(match self.ty {
            MsgType::Twist => {
                let m: msgs::Twist = msgs::decode(payload).map_err(e)?;
                self.record([Value::F64(m.linear.x), Value::F64(m.angular.z)])
            }
            MsgType::TwistStamped => {
                let m: msgs::TwistStamped = msgs::decode(payload).map_err(e)?;
                self.record([Value::F64(m.twist.linear.x), Value::F64(m.twist.angular.z)])
            }
            MsgType::Odometry => {
                let m: msgs::Odometry = msgs::decode(payload).map_err(e)?;
                let (_, _, yaw) = m.pose.pose.orientation.to_rpy();
                let p = m.pose.pose.position;
                let t = m.twist.twist;
                self.record([p.x, p.y, yaw, t.linear.x, t.angular.z].map(Value::F64))
            }
            MsgType::LaserScan => {
                let m: msgs::LaserScan = msgs::decode(payload).map_err(e)?;
                match self.ring {
                    None => Value::F32s(m.ranges.into()),
                    Some(n) => Value::F32s(ring(&m, n)?.into()),
                }
            }
            MsgType::Range => {
                let m: msgs::Range = msgs::decode(payload).map_err(e)?;
                Value::F64(f64::from(m.range))
            }
            MsgType::Imu => {
                let m: msgs::Imu = msgs::decode(payload).map_err(e)?;
                let (roll, pitch, yaw) = m.orientation.to_rpy();
                let (w, a) = (m.angular_velocity, m.linear_acceleration);
                self.record([roll, pitch, yaw, w.x, w.y, w.z, a.x, a.y, a.z].map(Value::F64))
            }
            MsgType::JointState => {
                let m: msgs::JointState = msgs::decode(payload).map_err(e)?;
                self.record([m.position, m.velocity, m.effort].map(|v| Value::F64s(v.into())))
            }
            MsgType::BatteryState => {
                let m: msgs::BatteryState = msgs::decode(payload).map_err(e)?;
                self.record(
                    [m.voltage, m.current, m.charge, m.percentage, m.temperature].map(|v| Value::F64(f64::from(v))),
                )
            }
            MsgType::Barcodes => {
                let m: msgs::Barcodes = msgs::decode(payload).map_err(e)?;
                same_lengths(&[("ids", m.ids.len()), ("bearing", m.bearing.len()), ("distance", m.distance.len())])?;
                self.record([Value::I64s(m.ids.into()), Value::F64s(m.bearing.into()), Value::F64s(m.distance.into())])
            }
            MsgType::People => {
                let m: msgs::People = msgs::decode(payload).map_err(e)?;
                same_lengths(&[("x", m.x.len()), ("y", m.y.len()), ("floor", m.floor.len())])?;
                self.record([Value::F64s(m.x.into()), Value::F64s(m.y.into()), Value::I64s(m.floor.into())])
            }
            MsgType::Cars => {
                let m: msgs::Cars = msgs::decode(payload).map_err(e)?;
                same_lengths(&[("floor", m.floor.len()), ("door", m.door.len())])?;
                self.record([Value::F64s(m.floor.into()), Value::F64s(m.door.into())])
            }
            MsgType::Float64 => Value::F64(msgs::decode::<msgs::Float64>(payload).map_err(e)?.data),
            MsgType::Int64 => Value::I64(msgs::decode::<msgs::Int64>(payload).map_err(e)?.data),
            MsgType::Bool => Value::Bool(msgs::decode::<msgs::Bool>(payload).map_err(e)?.data),
            MsgType::String => Value::Str(msgs::decode::<msgs::StringMsg>(payload).map_err(e)?.data.into()),
            MsgType::TfMessage => return Err("tf2_msgs/msg/TFMessage is not read into a signal".into()),
        })
    }
}

/// A scan resampled into `n` sectors, sector k centred on bearing k·2π/n (counter-clockwise from
/// ahead), each the nearest valid range in it; a sector with none reads `range_max`, as a sonar
/// with no echo does.
pub fn ring(scan: &msgs::LaserScan, n: usize) -> Result<Vec<f32>, String> {
    let (min, inc) = (f64::from(scan.angle_min), f64::from(scan.angle_increment));
    if !(min.is_finite() && inc.is_finite() && inc != 0.0) {
        return Err(format!("angle_min {min} and angle_increment {inc} place no ray"));
    }
    let max = scan.range_max;
    let no_echo = if max.is_finite() && max > 0.0 { max } else { f32::INFINITY };
    let mut out = vec![no_echo; n];
    let sector = TAU / n as f64;
    for (i, &r) in scan.ranges.iter().enumerate() {
        if !(r.is_finite() && r >= scan.range_min && r <= max) {
            continue;
        }
        let bearing = (min + inc * i as f64).rem_euclid(TAU);
        let k = ((bearing / sector).round() as usize) % n;
        if r < out[k] {
            out[k] = r;
        }
    }
    Ok(out)
}

/// The publisher's GID from rmw_zenoh's attachment (sequence number, timestamp, GID: 33 bytes).
fn publisher_gid(attachment: &[u8]) -> Option<[u8; 16]> {
    if attachment.len() != 33 || attachment[16] != 16 {
        return None;
    }
    attachment[17..].try_into().ok()
}

fn publisher(gid: Option<[u8; 16]>) -> String {
    match gid {
        Some(g) => format!("publisher {}", g.iter().map(|b| format!("{b:02x}")).collect::<String>()),
        None => "a publisher with no rmw_zenoh attachment".into(),
    }
}

/// Parallel arrays of a message must be of one length: else `x, y and floor differ in length
/// (2, 1, 1)`.
fn same_lengths(arrays: &[(&str, usize)]) -> Result<(), String> {
    if arrays.windows(2).all(|w| w[0].1 == w[1].1) {
        return Ok(());
    }
    let names: Vec<&str> = arrays.iter().map(|a| a.0).collect();
    let lens: Vec<String> = arrays.iter().map(|a| a.1.to_string()).collect();
    let (last, first) = names.split_last().unwrap_or((&"", &[]));
    Err(format!("{} and {last} differ in length ({})", first.join(", "), lens.join(", ")))
}

/// `pkg::msg::dds_::Name_` → `pkg/msg/Name`.
fn ros_name_of(dds: &str) -> Option<String> {
    let (pkg, rest) = dds.split_once("::msg::dds_::")?;
    Some(format!("{pkg}/msg/{}", rest.strip_suffix('_')?))
}

fn short_hash(hash: &str) -> String {
    hash.chars().take(7 + 12).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::msgs::{encode, Header, LaserScan};

    #[test]
    fn a_scan_is_resampled_into_a_ring_from_ahead_counter_clockwise() {
        // Eight rays from -π at π/4: ray 4 looks ahead, ray 6 to the left.
        let mut ranges = vec![5.0f32; 8];
        ranges[4] = 1.0;
        ranges[6] = 2.0;
        ranges[0] = f32::NAN;
        let scan = LaserScan {
            header: Header::default(),
            angle_min: -std::f32::consts::PI,
            angle_increment: std::f32::consts::FRAC_PI_4,
            range_min: 0.1,
            range_max: 4.0,
            ranges,
            ..LaserScan::default()
        };
        let r = ring(&scan, 4).expect("a ring");
        assert_eq!(r, vec![1.0, 2.0, 4.0, 4.0], "5 m is past range_max: no echo reads range_max");
        let bad = LaserScan { angle_increment: 0.0, ..scan };
        assert!(ring(&bad, 4).is_err());
    }

    #[test]
    fn every_type_read_is_a_value_of_its_signal_type() {
        let t = |ty: MsgType| TopicConfig {
            signal: "s".into(),
            topic: "t".into(),
            msg_type: ty,
            direction: Direction::In,
            name: None,
            ring: None,
            period_ms: None,
            frame_id: None,
            child_frame_id: None,
            range_min: None,
            range_max: None,
        };
        let payloads: Vec<(MsgType, Vec<u8>)> = vec![
            (MsgType::Twist, encode(&msgs::Twist::default()).unwrap()),
            (MsgType::TwistStamped, encode(&msgs::TwistStamped::default()).unwrap()),
            (MsgType::Odometry, encode(&msgs::Odometry::default()).unwrap()),
            (MsgType::LaserScan, encode(&LaserScan { ranges: vec![1.0, 2.0], ..LaserScan::default() }).unwrap()),
            (MsgType::Range, encode(&msgs::Range { range: 0.5, ..msgs::Range::default() }).unwrap()),
            (MsgType::Imu, encode(&msgs::Imu::default()).unwrap()),
            (MsgType::JointState, encode(&msgs::JointState { position: vec![1.0], ..Default::default() }).unwrap()),
            (MsgType::BatteryState, encode(&msgs::BatteryState::default()).unwrap()),
            (
                MsgType::Barcodes,
                encode(&msgs::Barcodes {
                    ids: vec![10],
                    bearing: vec![0.5],
                    distance: vec![2.0],
                    ..Default::default()
                })
                .unwrap(),
            ),
            (
                MsgType::People,
                encode(&msgs::People { x: vec![1.0], y: vec![2.0], floor: vec![3], ..Default::default() }).unwrap(),
            ),
            (
                MsgType::Cars,
                encode(&msgs::Cars { floor: vec![0.5, 4.0], door: vec![0.0, 1.0], ..Default::default() }).unwrap(),
            ),
            (MsgType::Float64, encode(&msgs::Float64 { data: 2.5 }).unwrap()),
            (MsgType::Int64, encode(&msgs::Int64 { data: -3 }).unwrap()),
            (MsgType::Bool, encode(&msgs::Bool { data: true }).unwrap()),
            (MsgType::String, encode(&msgs::StringMsg { data: "hi".into() }).unwrap()),
        ];
        for (ty, payload) in payloads {
            let reader = Reader::new(&t(ty), "/t", "ros2_t", String::new(), Arc::new(Inbox::default()));
            let value = reader.read(&payload).unwrap_or_else(|e| panic!("{ty:?}: {e}"));
            assert!(value.conforms(&signal_type(ty, None)), "{ty:?}: {value:?}");
            // Every shorter payload is an error, never a panic or a wrong value.
            for cut in 0..payload.len() {
                assert!(reader.read(&payload[..cut]).is_err(), "{ty:?} cut at {cut}");
            }
        }
    }

    #[test]
    fn arrays_of_different_lengths_are_a_message_that_cannot_be_read() {
        let read = |ty: MsgType, payload: Vec<u8>| {
            let topic = TopicConfig {
                signal: "s".into(),
                topic: "t".into(),
                msg_type: ty,
                direction: Direction::In,
                name: None,
                ring: None,
                period_ms: None,
                frame_id: None,
                child_frame_id: None,
                range_min: None,
                range_max: None,
            };
            Reader::new(&topic, "/t", "ros2_t", String::new(), Arc::new(Inbox::default())).read(&payload)
        };
        let people = msgs::People { x: vec![1.0, 2.0], y: vec![2.0], floor: vec![3], ..Default::default() };
        let err = read(MsgType::People, encode(&people).unwrap()).unwrap_err();
        assert_eq!(err, "x, y and floor differ in length (2, 1, 1)");
        let cars = msgs::Cars { floor: vec![0.5], door: vec![], ..Default::default() };
        let err = read(MsgType::Cars, encode(&cars).unwrap()).unwrap_err();
        assert_eq!(err, "floor and door differ in length (1, 0)");
    }

    #[test]
    fn dds_names_read_back_as_ros_names() {
        assert_eq!(ros_name_of("sensor_msgs::msg::dds_::LaserScan_").as_deref(), Some("sensor_msgs/msg/LaserScan"));
        assert_eq!(ros_name_of("nonsense"), None);
        let mut a = vec![0u8; 33];
        a[16] = 16;
        a[17] = 0xab;
        assert_eq!(publisher_gid(&a).map(|g| g[0]), Some(0xab));
        assert_eq!(publisher_gid(&a[..32]), None);
    }
}
