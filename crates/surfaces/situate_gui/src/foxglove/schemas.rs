//! The channels in Foxglove's own schemas (`foxglove.FrameTransforms`, `foxglove.PoseInFrame`,
//! `foxglove.LaserScan`): which a robot's signals give, the JSON Schemas Foxglove publishes for
//! them, and their messages.

use serde_json::{json, Value as Json};
use situate_core::Value;

use crate::History;

/// The frame the robot's pose places `base_link` in: `world` for the ground truth (`truth.pose`),
/// `odom` for odometry (the frame of the start pose).
pub const BASE_FRAME: &str = "base_link";

/// What a channel in one of Foxglove's own schemas carries (its values: the leaves of
/// [`KnownChannel::leaves`], in order).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Known {
    /// `foxglove.FrameTransforms`: `parent` → `base_link` from `x`, `y`, `theta`.
    Transform { parent: &'static str },
    /// `foxglove.PoseInFrame`: the pose `x`, `y`, `theta` in `frame`.
    Pose { frame: &'static str },
    /// `foxglove.LaserScan`: the sonar ring in `base_link`, sonar i at i·360°/n counter-clockwise
    /// from ahead.
    Scan,
}

/// A channel in one of Foxglove's schemas, from the leaves of the signals it shows.
#[derive(Debug, Clone, PartialEq)]
pub struct KnownChannel {
    pub topic: &'static str,
    pub kind: Known,
    pub leaves: Vec<usize>,
}

/// The channels in Foxglove's own schemas a robot's signals give (each only when its signals are
/// there): the robot's frame `base_link` (`foxglove/tf`), its pose (`foxglove/truth.pose`,
/// `foxglove/odom`) and the sonar ring as a laser scan (`foxglove/sonar`).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Schemas {
    pub channels: Vec<KnownChannel>,
}

impl Schemas {
    /// From the signal leaves' paths (their index is the leaf's).
    pub fn of<'a>(paths: impl Iterator<Item = &'a str>) -> Schemas {
        let paths: Vec<&str> = paths.collect();
        let leaf = |p: &str| paths.iter().position(|q| *q == p);
        let pose = |record: &str| -> Option<Vec<usize>> {
            ["x", "y", "theta"].iter().map(|f| leaf(&format!("{record}.{f}"))).collect()
        };
        let (truth, odom) = (pose("truth.pose"), pose("odom"));
        let mut channels = Vec::new();
        let base = truth.clone().map(|l| (l, "world")).or_else(|| odom.clone().map(|l| (l, "odom")));
        if let Some((leaves, parent)) = base {
            channels.push(KnownChannel { topic: "foxglove/tf", kind: Known::Transform { parent }, leaves });
        }
        if let Some(leaves) = truth {
            channels.push(KnownChannel { topic: "foxglove/truth.pose", kind: Known::Pose { frame: "world" }, leaves });
        }
        if let Some(leaves) = odom {
            channels.push(KnownChannel { topic: "foxglove/odom", kind: Known::Pose { frame: "odom" }, leaves });
        }
        if let Some(l) = leaf("sonar.range") {
            channels.push(KnownChannel { topic: "foxglove/sonar", kind: Known::Scan, leaves: vec![l] });
        }
        Schemas { channels }
    }
}

pub(super) fn history_schemas(history: &History) -> Schemas {
    Schemas::of(history.layout().leaves.iter().map(|l| l.path.as_str()))
}

/// Foxglove's `time` (`foxglove.Timestamp` in JSON): `{sec, nsec}`.
fn time_schema(description: &str) -> Json {
    json!({"type": "object", "title": "time", "description": description, "properties": {
        "sec": {"type": "integer", "minimum": 0},
        "nsec": {"type": "integer", "minimum": 0, "maximum": 999_999_999}}})
}

fn vector3_schema(description: &str) -> Json {
    let n = |d: &str| json!({"type": "number", "description": d});
    json!({"title": "foxglove.Vector3", "description": description, "type": "object", "properties": {
        "x": n("x coordinate length"), "y": n("y coordinate length"), "z": n("z coordinate length")}})
}

fn quaternion_schema(description: &str) -> Json {
    let n = |d: &str| json!({"type": "number", "description": d});
    json!({"title": "foxglove.Quaternion", "description": description, "type": "object", "properties": {
        "x": n("x value"), "y": n("y value"), "z": n("z value"), "w": n("w value")}})
}

fn pose_schema(description: &str) -> Json {
    json!({"title": "foxglove.Pose", "description": description, "type": "object", "properties": {
        "position": vector3_schema("Point denoting position in 3D space"),
        "orientation": quaternion_schema("Quaternion denoting orientation in 3D space")}})
}

impl Known {
    /// The schema's name, as Foxglove knows it.
    pub fn schema_name(self) -> &'static str {
        match self {
            Known::Transform { .. } => "foxglove.FrameTransforms",
            Known::Pose { .. } => "foxglove.PoseInFrame",
            Known::Scan => "foxglove.LaserScan",
        }
    }

    /// The JSON Schema Foxglove publishes for it (its fields, types and titles).
    pub fn schema(self) -> Json {
        let string = |d: &str| json!({"type": "string", "description": d});
        let number = |d: &str| json!({"type": "number", "description": d});
        let numbers = |d: &str| json!({"type": "array", "items": {"type": "number"}, "description": d});
        let (description, properties) = match self {
            Known::Transform { .. } => (
                "An array of FrameTransform messages",
                json!({"transforms": {"type": "array", "description": "Array of transforms", "items": {
                    "title": "foxglove.FrameTransform",
                    "description": "A transform between two reference frames in 3D space",
                    "type": "object",
                    "properties": {
                        "timestamp": time_schema("Timestamp of transform"),
                        "parent_frame_id": string("Name of the parent frame"),
                        "child_frame_id": string("Name of the child frame"),
                        "translation": vector3_schema("Translation component of the transform"),
                        "rotation": quaternion_schema("Rotation component of the transform")}}}}),
            ),
            Known::Pose { .. } => (
                "A timestamped pose for an object or reference frame in 3D space",
                json!({
                    "timestamp": time_schema("Timestamp of pose"),
                    "frame_id": string("Frame of reference for pose position and orientation"),
                    "pose": pose_schema("Pose in 3D space")}),
            ),
            Known::Scan => (
                "A single scan from a planar laser range-finder",
                json!({
                    "timestamp": time_schema("Timestamp of scan"),
                    "frame_id": string("Frame of reference"),
                    "pose": pose_schema("Origin of scan relative to frame of reference"),
                    "start_angle": number("Bearing of first point, in radians"),
                    "end_angle": number("Bearing of last point, in radians"),
                    "ranges": numbers("Distance of detections from origin; assumed to be at equally-spaced angles between `start_angle` and `end_angle`"),
                    "intensities": numbers("Intensity of detections")}),
            ),
        };
        json!({"title": self.schema_name(), "description": description, "type": "object", "properties": properties})
    }

    /// The message of `values` (its leaves' values, in order) at `stamp_ns` (Unix nanoseconds).
    pub fn message(self, stamp_ns: u64, values: &[Value]) -> Json {
        let timestamp = json!({"sec": stamp_ns / 1_000_000_000, "nsec": stamp_ns % 1_000_000_000});
        let num = |i: usize| match values.get(i) {
            Some(Value::F64(x)) if x.is_finite() => *x,
            Some(Value::I64(x)) => *x as f64,
            _ => 0.0,
        };
        let (x, y, theta) = (num(0), num(1), num(2));
        // A turn of theta about z.
        let rotation = json!({"x": 0.0, "y": 0.0, "z": (theta / 2.0).sin(), "w": (theta / 2.0).cos()});
        let position = json!({"x": x, "y": y, "z": 0.0});
        match self {
            Known::Transform { parent } => json!({"transforms": [{"timestamp": timestamp,
                "parent_frame_id": parent, "child_frame_id": BASE_FRAME, "translation": position, "rotation": rotation}]}),
            Known::Pose { frame } => {
                json!({"timestamp": timestamp, "frame_id": frame, "pose": {"position": position, "orientation": rotation}})
            }
            Known::Scan => {
                let ranges: Vec<Json> = match values.first() {
                    Some(Value::F32s(r)) => r.iter().map(|v| finite(f64::from(*v))).collect(),
                    Some(Value::F64s(r)) => r.iter().map(|v| finite(*v)).collect(),
                    _ => vec![],
                };
                let step = if ranges.is_empty() { 0.0 } else { std::f64::consts::TAU / ranges.len() as f64 };
                let end = step * ranges.len().saturating_sub(1) as f64;
                json!({"timestamp": timestamp, "frame_id": BASE_FRAME,
                    "pose": {"position": {"x": 0.0, "y": 0.0, "z": 0.0}, "orientation": {"x": 0.0, "y": 0.0, "z": 0.0, "w": 1.0}},
                    "start_angle": 0.0, "end_angle": end, "ranges": ranges, "intensities": []})
            }
        }
    }
}

/// A number, or null for one JSON cannot hold (NaN, an infinity).
fn finite(v: f64) -> Json {
    if v.is_finite() {
        json!(v)
    } else {
        Json::Null
    }
}
