//! The ROS 2 messages the bridge publishes, as serde types that the `cdr` crate encodes in the
//! byte layout ROS 2 uses on the wire (XCDR1, little endian, behind the 4-byte encapsulation
//! header `00 01 00 00`), and the names and type hashes rmw_zenoh puts in key expressions.
//! Payloads are read back by [`crate::decode`], which bounds every declared length by the bytes
//! present (the `cdr` crate's reader allocates what a length declares: decision 0011).
//!
//! Field order and types follow the `.msg` definitions of ROS 2 Jazzy (and later: the hashes
//! below are the same in Kilted and Rolling); the Python tests decode every message with the
//! `rosbags` package's own definitions, and its `hash_rihs01` gives the same hashes.

use serde::de::{SeqAccess, Visitor};
use serde::ser::SerializeTuple;
use serde::{Deserialize, Deserializer, Serialize, Serializer};

pub use crate::decode::DecodeError;

/// A message type the bridge can publish or subscribe to. Which signal each is made from (a
/// topic out) or fills (a topic in, [`crate::inputs`]) is [`MsgType::expects`] and
/// [`MsgType::signal_type`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Deserialize, Serialize)]
pub enum MsgType {
    /// `geometry_msgs/msg/Twist` ⇄ a record `{v: f64, w: f64}` (linear.x m/s, angular.z rad/s).
    #[serde(rename = "geometry_msgs/msg/Twist")]
    Twist,
    /// `geometry_msgs/msg/TwistStamped` ⇄ a record `{v, w}`, as [`MsgType::Twist`] with a header
    /// (what many controllers of ROS 2 Jazzy take on `cmd_vel`).
    #[serde(rename = "geometry_msgs/msg/TwistStamped")]
    TwistStamped,
    /// `nav_msgs/msg/Odometry` ⇄ a record `{x, y, theta}` (and `v`, `w`: out when it has them,
    /// in always).
    #[serde(rename = "nav_msgs/msg/Odometry")]
    Odometry,
    /// `tf2_msgs/msg/TFMessage` (out only, on `/tf`): the transform `frame_id → child_frame_id`
    /// (default `odom → base_link`) from an odometry record `{x, y, theta}`, as a base driver
    /// broadcasts it.
    #[serde(rename = "tf2_msgs/msg/TFMessage")]
    TfMessage,
    /// `sensor_msgs/msg/LaserScan` ⇄ a ring of ranges (`f32[]`; out also from `f64[]`).
    #[serde(rename = "sensor_msgs/msg/LaserScan")]
    LaserScan,
    /// `sensor_msgs/msg/Range` ⇄ an `f64` (the range, m).
    #[serde(rename = "sensor_msgs/msg/Range")]
    Range,
    /// `sensor_msgs/msg/Imu` (in only) → a record of orientation (`roll`, `pitch`, `yaw`), angular
    /// velocity (`wx`, `wy`, `wz`) and linear acceleration (`ax`, `ay`, `az`).
    #[serde(rename = "sensor_msgs/msg/Imu")]
    Imu,
    /// `sensor_msgs/msg/JointState` (in only) → a record of three `f64[]`: `position`,
    /// `velocity`, `effort`, in the message's joint order.
    #[serde(rename = "sensor_msgs/msg/JointState")]
    JointState,
    /// `sensor_msgs/msg/BatteryState` (in only) → a record `{voltage, current, charge,
    /// percentage, temperature}` (f64; NaN where the battery does not say, as in ROS 2).
    #[serde(rename = "sensor_msgs/msg/BatteryState")]
    BatteryState,
    /// `situate_msgs/msg/Barcodes` (in only; the package is `ros2/situate_msgs`) → the robot's
    /// `barcodes` record `{ids: i64[], bearing: f64[], distance: f64[]}`: a barcode reader's.
    #[serde(rename = "situate_msgs/msg/Barcodes")]
    Barcodes,
    /// `situate_msgs/msg/People` (in only) → a simulator's `truth.people` record `{x: f64[],
    /// y: f64[], floor: i64[]}`: the people walking in the building (ground truth, for displays).
    #[serde(rename = "situate_msgs/msg/People")]
    People,
    /// `situate_msgs/msg/Cars` (in only) → a simulator's `truth.cars` record `{floor: f64[],
    /// door: f64[]}`: each elevator car's position in floors and its door's opening 0..1.
    #[serde(rename = "situate_msgs/msg/Cars")]
    Cars,
    /// `std_msgs/msg/Float64` ⇄ an `f64`.
    #[serde(rename = "std_msgs/msg/Float64")]
    Float64,
    /// `std_msgs/msg/Int64` ⇄ an `i64`.
    #[serde(rename = "std_msgs/msg/Int64")]
    Int64,
    /// `std_msgs/msg/Bool` ⇄ a `bool`.
    #[serde(rename = "std_msgs/msg/Bool")]
    Bool,
    /// `std_msgs/msg/String` ⇄ a `string`.
    #[serde(rename = "std_msgs/msg/String")]
    String,
}

impl MsgType {
    /// Every type, for messages that list them.
    pub const ALL: [MsgType; 16] = [
        MsgType::Twist,
        MsgType::TwistStamped,
        MsgType::Odometry,
        MsgType::TfMessage,
        MsgType::LaserScan,
        MsgType::Range,
        MsgType::Imu,
        MsgType::JointState,
        MsgType::BatteryState,
        MsgType::Barcodes,
        MsgType::People,
        MsgType::Cars,
        MsgType::Float64,
        MsgType::Int64,
        MsgType::Bool,
        MsgType::String,
    ];

    /// The ROS 2 name: `geometry_msgs/msg/Twist`.
    pub fn ros_name(self) -> &'static str {
        match self {
            MsgType::Twist => "geometry_msgs/msg/Twist",
            MsgType::TwistStamped => "geometry_msgs/msg/TwistStamped",
            MsgType::Odometry => "nav_msgs/msg/Odometry",
            MsgType::TfMessage => "tf2_msgs/msg/TFMessage",
            MsgType::LaserScan => "sensor_msgs/msg/LaserScan",
            MsgType::Range => "sensor_msgs/msg/Range",
            MsgType::Imu => "sensor_msgs/msg/Imu",
            MsgType::JointState => "sensor_msgs/msg/JointState",
            MsgType::BatteryState => "sensor_msgs/msg/BatteryState",
            MsgType::Barcodes => "situate_msgs/msg/Barcodes",
            MsgType::People => "situate_msgs/msg/People",
            MsgType::Cars => "situate_msgs/msg/Cars",
            MsgType::Float64 => "std_msgs/msg/Float64",
            MsgType::Int64 => "std_msgs/msg/Int64",
            MsgType::Bool => "std_msgs/msg/Bool",
            MsgType::String => "std_msgs/msg/String",
        }
    }

    /// The name as rmw_zenoh writes it in key expressions (the DDS-mangled name):
    /// `geometry_msgs::msg::dds_::Twist_`.
    pub fn dds_name(self) -> String {
        let name = self.ros_name();
        let mut parts = name.split('/');
        let (package, _, ty) = (parts.next().unwrap_or(""), parts.next(), parts.next().unwrap_or(""));
        format!("{package}::msg::dds_::{ty}_")
    }

    /// The type's RIHS01 hash (REP 2011), as ROS 2 Jazzy and later compute it (the Python tests
    /// check each against `rosbags`' `hash_rihs01`, and `std_msgs/msg/String`'s against the key
    /// rmw_zenoh's design document shows).
    pub fn type_hash(self) -> &'static str {
        match self {
            MsgType::Twist => "RIHS01_9c45bf16fe0983d80e3cfe750d6835843d265a9a6c46bd2e609fcddde6fb8d2a",
            MsgType::TwistStamped => "RIHS01_5f0fcd4f81d5d06ad9b4c4c63e3ea51b82d6ae4d0558f1d475229b1121db6f64",
            MsgType::Odometry => "RIHS01_3cc97dc7fb7502f8714462c526d369e35b603cfc34d946e3f2eda2766dfec6e0",
            MsgType::TfMessage => "RIHS01_e369d0f05a23ae52508854b66f6aa0437f3449d652e8cbf22d5abe85d020f087",
            MsgType::LaserScan => "RIHS01_64c191398013af96509d518dac71d5164f9382553fce5c1f8cca5be7924bd828",
            MsgType::Range => "RIHS01_b42b62562e93cbfe9d42b82fe5994dfa3d63d7d5c90a317981703f7388adff3a",
            MsgType::Imu => "RIHS01_7d9a00ff131080897a5ec7e26e315954b8eae3353c3f995c55faf71574000b5b",
            MsgType::JointState => "RIHS01_a13ee3a330e346c9d87b5aa18d24e11690752bd33a0350f11c5882bc9179260e",
            MsgType::BatteryState => "RIHS01_4bee5dfce981c98faa6828b868307a0a73f992ed0789f374ee96c8f840e69741",
            // From ros2/situate_msgs/msg/*.msg (checked against rosbags in test_physics_ros2.py).
            MsgType::Barcodes => "RIHS01_8158355b2018e7e7259d57dacba88095bc75e52a4f153b5debb188d3c13913ea",
            MsgType::People => "RIHS01_55fe99158076d9d56ed5b425072f64b8ba1bddb0da49b6c0366a458f90ef1a96",
            MsgType::Cars => "RIHS01_0931a9117bfc02083261a98d8ae7c041bd578fea6e966e86ae5abedd41a2726c",
            MsgType::Float64 => "RIHS01_705ba9c3d1a09df43737eb67095534de36fd426c0587779bda2bc51fe790182a",
            MsgType::Int64 => "RIHS01_8cd1048c2f186b6bd9a92472dc1ce51723c0833a221e2b7aecfff111774f4b49",
            MsgType::Bool => "RIHS01_feb91e995ff9ebd09c0cb3d2aed18b11077585839fb5db80193b62d74528f6c9",
            MsgType::String => "RIHS01_df668c740482bbd48fb39d76a70dfd4bd59db1288021743503259e948f6b1a18",
        }
    }

    /// Whether a signal can be published as this type (a topic out).
    pub fn can_publish(self) -> bool {
        !matches!(
            self,
            MsgType::Imu
                | MsgType::JointState
                | MsgType::BatteryState
                | MsgType::Barcodes
                | MsgType::People
                | MsgType::Cars
        )
    }

    /// Whether this type can feed a signal (a topic in).
    pub fn can_subscribe(self) -> bool {
        !matches!(self, MsgType::TfMessage)
    }

    /// What signal type it is made from (a topic out), for error messages.
    pub fn expects(self) -> &'static str {
        match self {
            MsgType::Twist | MsgType::TwistStamped => "a record with f64 fields `v` and `w`",
            MsgType::Odometry => "a record with f64 fields `x`, `y`, `theta` (and optionally `v`, `w`)",
            MsgType::TfMessage => "a record with f64 fields `x`, `y`, `theta` (an odometry)",
            MsgType::LaserScan => "an array of f32 or f64 (a ring of ranges)",
            MsgType::Range | MsgType::Float64 => "an f64",
            MsgType::Int64 => "an i64",
            MsgType::Bool => "a bool",
            MsgType::String => "a string",
            MsgType::Imu
            | MsgType::JointState
            | MsgType::BatteryState
            | MsgType::Barcodes
            | MsgType::People
            | MsgType::Cars => "nothing: it is read, never published",
        }
    }
}

/// `builtin_interfaces/msg/Time`.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct Time {
    pub sec: i32,
    pub nanosec: u32,
}

impl Time {
    /// The wall clock now, as ROS 2 stamps messages.
    pub fn now() -> Time {
        let d = std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).unwrap_or_default();
        Time { sec: i32::try_from(d.as_secs()).unwrap_or(i32::MAX), nanosec: d.subsec_nanos() }
    }
}

/// `std_msgs/msg/Header`.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct Header {
    pub stamp: Time,
    pub frame_id: String,
}

/// `geometry_msgs/msg/Vector3`.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct Vector3 {
    pub x: f64,
    pub y: f64,
    pub z: f64,
}

/// `geometry_msgs/msg/Twist`.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct Twist {
    pub linear: Vector3,
    pub angular: Vector3,
}

/// `geometry_msgs/msg/Point`.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct Point {
    pub x: f64,
    pub y: f64,
    pub z: f64,
}

/// `geometry_msgs/msg/Quaternion`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Quaternion {
    pub x: f64,
    pub y: f64,
    pub z: f64,
    pub w: f64,
}

impl Quaternion {
    /// The rotation by `theta` radians about z.
    pub fn from_yaw(theta: f64) -> Quaternion {
        let half = theta / 2.0;
        Quaternion { x: 0.0, y: 0.0, z: half.sin(), w: half.cos() }
    }
}

impl Default for Quaternion {
    fn default() -> Self {
        Quaternion::from_yaw(0.0)
    }
}

/// `geometry_msgs/msg/Pose`.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct Pose {
    pub position: Point,
    pub orientation: Quaternion,
}

/// A 6×6 row-major covariance (`float64[36]`): a fixed-size array, so no length on the wire.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Covariance(pub [f64; 36]);

impl Default for Covariance {
    fn default() -> Self {
        Covariance([0.0; 36])
    }
}

impl Serialize for Covariance {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        let mut t = serializer.serialize_tuple(36)?;
        for v in &self.0 {
            t.serialize_element(v)?;
        }
        t.end()
    }
}

impl<'de> Deserialize<'de> for Covariance {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = Covariance;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("36 f64")
            }
            fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Covariance, A::Error> {
                let mut out = [0.0; 36];
                for (i, slot) in out.iter_mut().enumerate() {
                    *slot = seq.next_element()?.ok_or_else(|| serde::de::Error::invalid_length(i, &self))?;
                }
                Ok(Covariance(out))
            }
        }
        deserializer.deserialize_tuple(36, V)
    }
}

/// `geometry_msgs/msg/PoseWithCovariance`.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct PoseWithCovariance {
    pub pose: Pose,
    pub covariance: Covariance,
}

/// `geometry_msgs/msg/TwistWithCovariance`.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct TwistWithCovariance {
    pub twist: Twist,
    pub covariance: Covariance,
}

/// `nav_msgs/msg/Odometry`.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct Odometry {
    pub header: Header,
    pub child_frame_id: String,
    pub pose: PoseWithCovariance,
    pub twist: TwistWithCovariance,
}

/// `sensor_msgs/msg/LaserScan`.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct LaserScan {
    pub header: Header,
    pub angle_min: f32,
    pub angle_max: f32,
    pub angle_increment: f32,
    pub time_increment: f32,
    pub scan_time: f32,
    pub range_min: f32,
    pub range_max: f32,
    pub ranges: Vec<f32>,
    pub intensities: Vec<f32>,
}

/// `std_msgs/msg/Float64`.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct Float64 {
    pub data: f64,
}

/// `std_msgs/msg/Int64`.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct Int64 {
    pub data: i64,
}

/// `std_msgs/msg/Bool`.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct Bool {
    pub data: bool,
}

/// `std_msgs/msg/String`.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct StringMsg {
    pub data: String,
}

/// `geometry_msgs/msg/TwistStamped`.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct TwistStamped {
    pub header: Header,
    pub twist: Twist,
}

/// `geometry_msgs/msg/Transform`.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct Transform {
    pub translation: Vector3,
    pub rotation: Quaternion,
}

/// `geometry_msgs/msg/TransformStamped`.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct TransformStamped {
    pub header: Header,
    pub child_frame_id: String,
    pub transform: Transform,
}

/// `tf2_msgs/msg/TFMessage`.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct TfMessage {
    pub transforms: Vec<TransformStamped>,
}

/// `sensor_msgs/msg/Range` (Jazzy's, with `variance`).
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct Range {
    pub header: Header,
    pub radiation_type: u8,
    pub field_of_view: f32,
    pub min_range: f32,
    pub max_range: f32,
    pub range: f32,
    pub variance: f32,
}

/// `sensor_msgs/msg/Imu`.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct Imu {
    pub header: Header,
    pub orientation: Quaternion,
    pub orientation_covariance: [f64; 9],
    pub angular_velocity: Vector3,
    pub angular_velocity_covariance: [f64; 9],
    pub linear_acceleration: Vector3,
    pub linear_acceleration_covariance: [f64; 9],
}

/// `sensor_msgs/msg/JointState`.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct JointState {
    pub header: Header,
    pub name: Vec<String>,
    pub position: Vec<f64>,
    pub velocity: Vec<f64>,
    pub effort: Vec<f64>,
}

/// `sensor_msgs/msg/BatteryState`.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct BatteryState {
    pub header: Header,
    pub voltage: f32,
    pub temperature: f32,
    pub current: f32,
    pub charge: f32,
    pub capacity: f32,
    pub design_capacity: f32,
    pub percentage: f32,
    pub power_supply_status: u8,
    pub power_supply_health: u8,
    pub power_supply_technology: u8,
    pub present: bool,
    pub cell_voltage: Vec<f32>,
    pub cell_temperature: Vec<f32>,
    pub location: String,
    pub serial_number: String,
}

/// `situate_msgs/msg/Barcodes` (`ros2/situate_msgs/msg/Barcodes.msg`).
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct Barcodes {
    pub header: Header,
    pub ids: Vec<i64>,
    pub bearing: Vec<f64>,
    pub distance: Vec<f64>,
}

/// `situate_msgs/msg/People` (`ros2/situate_msgs/msg/People.msg`).
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct People {
    pub header: Header,
    pub x: Vec<f64>,
    pub y: Vec<f64>,
    pub floor: Vec<i64>,
}

/// `situate_msgs/msg/Cars` (`ros2/situate_msgs/msg/Cars.msg`).
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct Cars {
    pub header: Header,
    pub floor: Vec<f64>,
    pub door: Vec<f64>,
}

/// `rosgraph_msgs/msg/Clock`.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct Clock {
    pub clock: Time,
}

impl Quaternion {
    /// Roll, pitch and yaw (rad; intrinsic z-y-x, as tf2 reads them) of a unit quaternion.
    pub fn to_rpy(self) -> (f64, f64, f64) {
        let Quaternion { x, y, z, w } = self;
        let roll = (2.0 * (w * x + y * z)).atan2(1.0 - 2.0 * (x * x + y * y));
        let pitch = (2.0 * (w * y - z * x)).clamp(-1.0, 1.0).asin();
        let yaw = (2.0 * (w * z + x * y)).atan2(1.0 - 2.0 * (y * y + z * z));
        (roll, pitch, yaw)
    }
}

/// Encodes a message as a ROS 2 payload: the CDR little-endian encapsulation header, then the
/// message.
pub fn encode<T: Serialize>(msg: &T) -> Result<Vec<u8>, cdr::Error> {
    cdr::serialize::<_, _, cdr::CdrLe>(msg, cdr::Infinite)
}

/// Decodes a ROS 2 payload (plain CDR, either byte order), every declared length checked
/// against the bytes present before anything is allocated ([`crate::decode`]).
pub fn decode<'de, T: Deserialize<'de>>(payload: &'de [u8]) -> Result<T, DecodeError> {
    crate::decode::from_payload(payload)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_and_hashes_follow_rmw_zenoh() {
        assert_eq!(MsgType::Twist.dds_name(), "geometry_msgs::msg::dds_::Twist_");
        assert_eq!(MsgType::Odometry.dds_name(), "nav_msgs::msg::dds_::Odometry_");
        for t in MsgType::ALL {
            let h = t.type_hash();
            assert!(h.starts_with("RIHS01_") && h.len() == 7 + 64, "{t:?}: {h}");
            assert!(h[7..].chars().all(|c| c.is_ascii_hexdigit() && !c.is_ascii_uppercase()), "{h}");
        }
    }

    #[test]
    fn a_twist_is_the_header_then_six_doubles() {
        let t = Twist {
            linear: Vector3 { x: 0.5, ..Vector3::default() },
            angular: Vector3 { z: -1.0, ..Vector3::default() },
        };
        let bytes = encode(&t).expect("encodes");
        assert_eq!(&bytes[..4], &[0, 1, 0, 0], "CDR little endian");
        assert_eq!(bytes.len(), 4 + 6 * 8);
        assert_eq!(&bytes[4..12], &0.5f64.to_le_bytes());
        assert_eq!(&bytes[44..52], &(-1.0f64).to_le_bytes());
        assert_eq!(decode::<Twist>(&bytes).expect("decodes"), t);
    }

    #[test]
    fn strings_carry_their_terminator_and_doubles_are_aligned() {
        // Header: sec, nanosec, then "odom" as length 5 + "odom\0"; the child frame's length
        // follows at offset 20 of the body; the pose's first double is aligned to 8.
        let o = Odometry {
            header: Header { stamp: Time { sec: 1, nanosec: 2 }, frame_id: "odom".into() },
            child_frame_id: "base_link".into(),
            ..Odometry::default()
        };
        let bytes = encode(&o).expect("encodes");
        let body = &bytes[4..];
        assert_eq!(&body[8..12], &5u32.to_le_bytes());
        assert_eq!(&body[12..17], b"odom\0");
        assert_eq!(&body[20..24], &10u32.to_le_bytes());
        assert_eq!(&body[24..34], b"base_link\0");
        assert_eq!(body.len(), 40 + (7 + 36 + 6 + 36) * 8, "pose from offset 40, no gaps after");
        assert_eq!(decode::<Odometry>(&bytes).expect("decodes"), o);
    }
}
