//! `situate schema robot|manifest|map`: JSON Schemas (draft 2020-12) of the
//! file formats, for editors (a `# yaml-language-server: $schema=…` line at
//! the top of a file makes the YAML language server complete and check it)
//! and for other tools. They describe the shape — keys, value kinds, ranges
//! the reader enforces — while `situate check` and `situate map check`
//! remain the judges (types of signals, skill types, the wiring).
//!
//! Written by hand, next to the readers: the robot file's keys are
//! `situate_robotfile`'s (`TOP_KEYS` in config/robot_file.rs, `CYCLE_KEYS`
//! in config/cycle.rs, `ENTRY_KEYS` in config/entries.rs), and a test checks
//! every key of the example files is in the schema.

use std::path::Path;

use serde_json::{json, Value as Json};

use crate::output::{problem, Exit, Out};

/// The formats, by name.
pub(crate) const FORMATS: [&str; 3] = ["robot", "manifest", "map"];

const DIALECT: &str = "https://json-schema.org/draft/2020-12/schema";

/// A name: a letter or `_`, then letters, digits and `_` (dots between for types and signals).
const IDENT: &str = "^[A-Za-z_][A-Za-z0-9_]*$";
const DOTTED: &str = "^[A-Za-z_][A-Za-z0-9_]*(\\.[A-Za-z_][A-Za-z0-9_]*)*$";

/// A parameter value as a robot file writes it: a scalar or a list of numbers.
fn param_value() -> Json {
    json!({
        "description": "A parameter's value: a number, true/false, text, or a list of numbers.",
        "anyOf": [
            {"type": ["number", "boolean", "string"]},
            {"type": "array", "items": {"type": "number"}}
        ]
    })
}

/// A signal type as written: `f64`, `bool`, `f32[24]`, `{x: f64, y: f64}` (a trailing `?` in
/// a manifest's inputs makes the port optional).
fn signal_type() -> Json {
    json!({
        "type": "string",
        "description": "A signal type: bool, i64, f64, string, bytes, f32[], f64[N], or a record {x: f64, y: f64}.",
        "minLength": 1,
        "maxLength": 1024
    })
}

/// A manifest's port: its type, or `{type, signal, doc}` (and `optional` for an input).
fn port(input: bool) -> Json {
    let mut properties = json!({
        "type": signal_type(),
        "signal": {"type": "string", "pattern": DOTTED, "maxLength": 256,
                   "description": "The signal the port connects to unless a robot file remaps it (default: the port's name)."},
        "doc": {"type": "string", "description": "What the port carries."}
    });
    if input {
        properties["optional"] =
            json!({"type": "boolean", "description": "Optional: the skill runs without it (default false)."});
    }
    json!({
        "anyOf": [
            signal_type(),
            {"type": "object", "additionalProperties": false, "required": ["type"], "properties": properties}
        ]
    })
}

fn manifest_body() -> Json {
    let scalar =
        json!({"type": ["number", "boolean", "string"], "description": "A default: a number, true/false or text."});
    json!({
        "doc": {"type": "string", "description": "What the skill does."},
        "priority": {"type": "integer", "minimum": i32::MIN, "maximum": i32::MAX,
                     "description": "Priority over a resource (a signal several skills write): higher wins."},
        "inputs": {
            "type": "object",
            "description": "Input ports, `port: type` (a trailing `?` makes one optional) or \
                            `port: {type, signal, optional, doc}`.",
            "propertyNames": {"pattern": IDENT},
            "additionalProperties": port(true),
            "maxProperties": 256
        },
        "outputs": {
            "type": "object",
            "description": "Output ports, `port: type` or `port: {type, signal, doc}`.",
            "propertyNames": {"pattern": IDENT},
            "additionalProperties": port(false),
            "maxProperties": 256
        },
        "params": {
            "type": "object",
            "description": "Parameters: a default alone, or {type, default, min, max, unit, doc}.",
            "propertyNames": {"pattern": IDENT},
            "maxProperties": 256,
            "additionalProperties": {
                "anyOf": [
                    scalar,
                    {
                        "type": "object",
                        "additionalProperties": false,
                        "required": ["default"],
                        "properties": {
                            "type": {"type": "string", "enum": ["bool", "i64", "int", "f64", "float", "string", "str"]},
                            "default": scalar,
                            "min": {"type": "number"},
                            "max": {"type": "number"},
                            "unit": {"type": "string"},
                            "doc": {"type": "string"}
                        }
                    }
                ]
            }
        }
    })
}

/// A skill manifest (C/C++ skill types, `remote:` skills, `situate gen`).
pub(crate) fn manifest() -> Json {
    let mut properties = manifest_body();
    let map = properties.as_object_mut().expect("an object");
    map.insert(
        "name".into(),
        json!({"type": "string", "pattern": DOTTED, "description": "The skill type's name (`c.runaway`)."}),
    );
    map.insert(
        "kind".into(),
        json!({"type": "string", "enum": ["sync", "async", "device"], "description": "sync (default) or async cskill, or a device (dskill)."}),
    );
    json!({
        "$schema": DIALECT,
        "$id": "situate:manifest",
        "title": "situate skill manifest",
        "description": "A skill type's declaration as data: its ports and parameters (docs/manifests.md).",
        "type": "object",
        "additionalProperties": false,
        "properties": properties
    })
}

/// A robot file.
pub(crate) fn robot() -> Json {
    let ms = |what: &str| json!({"type": "number", "exclusiveMinimum": 0, "description": what});
    let entry = json!({
        "type": "object",
        "additionalProperties": false,
        "required": ["name"],
        "properties": {
            "name": {"type": "string", "pattern": IDENT, "description": "The instance's name (unique in the robot)."},
            "type": {"type": "string", "pattern": DOTTED, "description": "The skill type (`situate types` lists them)."},
            "remote": {
                "description": "A remote skill: its manifest inline, or the path of a manifest file.",
                "anyOf": [{"type": "string"}, {"type": "object", "properties": manifest_body(), "additionalProperties": false}]
            },
            "timeout_ms": ms("A remote skill: an answer awaited longer than this faults it."),
            "active": {"type": "boolean", "description": "Active from the start (default true)."},
            "priority": {"type": "integer", "minimum": i32::MIN, "maximum": i32::MAX, "description": "Overrides the type's priority."},
            "period_ms": ms("A device's thread period, or an async skill's worker period."),
            "budget_ms": ms("How long one in-cycle run may take (overrides cycle.budget_ms)."),
            "liveness_ms": ms("How long a threaded body may stay in one run (overrides cycle.liveness_ms)."),
            "params": {
                "type": "object",
                "description": "Parameter values, `name: value` (`situate types` gives each type's).",
                "propertyNames": {"pattern": IDENT},
                "additionalProperties": param_value()
            },
            "remap": {
                "type": "object",
                "description": "Port → signal: `range: sonar.raw` connects port `range` to signal `sonar.raw`.",
                "propertyNames": {"pattern": IDENT},
                "additionalProperties": {"type": "string", "pattern": DOTTED}
            }
        },
        // Either, not both; an entry that overrides an included one of its name may give neither
        // (see the top level's `if`).
        "not": {"required": ["type", "remote"]}
    });
    let typed = json!({"type": "array", "items": {"anyOf": [{"required": ["type"]}, {"required": ["remote"]}]}});
    let endpoints = json!({"type": "array", "items": {"type": "string", "pattern": "^[a-z0-9]+/"},
                           "description": "Zenoh endpoints, e.g. tcp/127.0.0.1:7447."});
    json!({
        "$schema": DIALECT,
        "$id": "situate:robot",
        "title": "situate robot file",
        "description": "A robot: its cycle, devices (dskills), skills (cskills) and link (docs/robot-files.md).",
        "type": "object",
        "additionalProperties": false,
        // A file that includes others may take its name from them, and override their entries by
        // name alone; one that includes nothing is a whole robot.
        "if": {"required": ["include"]},
        "else": {"required": ["robot"], "properties": {"devices": typed.clone(), "skills": typed}},
        "properties": {
            "robot": {"type": "string", "pattern": IDENT, "description": "The robot's name (its link keys are situate/<robot>/…)."},
            "include": {
                "description": "Robot files merged before this one, relative to this file: their devices and skills first (an entry of the same name here overrides theirs key by key), their other sections replaced by this file's.",
                "anyOf": [{"type": "string"}, {"type": "array", "items": {"type": "string"}}]
            },
            "cycle": {
                "type": "object",
                "additionalProperties": false,
                "properties": {
                    "rate_hz": {"type": "number", "exclusiveMinimum": 0, "description": "Cycles per second (or give period_ms)."},
                    "period_ms": ms("The cycle's period (or give rate_hz)."),
                    "clock": {"enum": ["wall", "simulated"]},
                    "executor": {"enum": ["serial", "parallel"]},
                    "threads": {"type": "integer", "minimum": 1, "description": "Worker threads of the parallel executor."},
                    "budget_ms": ms("Default budget of one in-cycle run."),
                    "liveness_ms": ms("Default liveness deadline of a threaded body.")
                },
                "not": {"required": ["rate_hz", "period_ms"]}
            },
            "libraries": {"type": "array", "items": {"type": "string"}, "description": "Shared libraries of C/C++ skill types, relative to this file."},
            "python": {"type": "array", "items": {"type": "string"}, "description": "Python files of @situate.skill types, relative to this file."},
            "simulator": {
                "type": "object",
                "additionalProperties": false,
                "required": ["map"],
                "properties": {
                    "map": {"type": "string", "description": "The building's map file, relative to this file."},
                    "seed": {"type": "integer", "minimum": 0},
                    "people": {"type": "integer", "minimum": 0, "maximum": 100},
                    "door_closures": {"type": "boolean"},
                    "dead_sonars": {"type": "array", "items": {"type": "integer", "minimum": 0, "maximum": 23}}
                }
            },
            "devices": {"type": "array", "items": entry.clone(), "description": "Device skills (dskills): sensors and actuators."},
            "skills": {"type": "array", "items": entry, "description": "Computing skills (cskills)."},
            "link": {
                "type": "object",
                "additionalProperties": false,
                "properties": {
                    "listen": endpoints.clone(),
                    "connect": endpoints,
                    "telemetry_hz": {"type": "number", "exclusiveMinimum": 0},
                    "zenoh": {"type": "object", "description": "Merged into Zenoh's configuration (credentials, TLS)."}
                }
            },
            "gui": {
                "type": "object",
                "additionalProperties": false,
                "properties": {
                    "listen": {"type": "string", "description": "The GUI's address, e.g. 127.0.0.1:8080."},
                    "port": {"type": "integer", "minimum": 0, "maximum": 65535, "description": "A port on 127.0.0.1."}
                }
            },
            "ros2": ros2()
        }
    })
}

/// The robot file's `ros2:` section (`situate_ros2::Ros2Config`; docs/ros2.md).
fn ros2() -> Json {
    json!({
        "type": "object",
        "description": "Publish signals as ROS 2 topics, feed signals from ROS 2 topics, and offer activation and parameters as ROS 2 services, over the link's Zenoh session (docs/ros2.md).",
        "additionalProperties": false,
        "properties": {
            "services": {"type": "boolean", "description": "Activation (<node>/<skill>/set_active) and the skills' parameters as ROS 2 services (default false)."},
            "domain_id": {"type": "integer", "minimum": 0, "maximum": 232},
            "namespace": {"type": "string", "description": "Empty (the root) or absolute, e.g. /robot1."},
            "node": {"type": "string", "description": "The node's name (default: the robot's)."},
            "rate_hz": {"type": "number", "exclusiveMinimum": 0, "maximum": 100},
            "use_sim_time": {"type": "boolean", "description": "ROS time: the cycle follows /clock, one cycle per period of ROS time (default false)."},
            "lockstep": {"type": "boolean", "description": "With use_sim_time: the topics out go as each cycle ends, then ~/cycle says up to which ROS time the cycles ran, for a simulator to wait on (default false)."},
            "topics": {
                "type": "array",
                "items": {
                    "type": "object",
                    "additionalProperties": false,
                    "required": ["signal", "topic", "type"],
                    "properties": {
                        "signal": {"type": "string"},
                        "topic": {"type": "string"},
                        "type": {"enum": situate_ros2::MsgType::ALL.iter().map(|t| t.ros_name()).collect::<Vec<_>>()},
                        "direction": {"enum": ["out", "in"], "description": "out (default): the signal is published; in: the topic's messages feed the signal, through a device."},
                        "name": {"type": "string", "description": "A topic in: its device's name (default ros2_<topic>)."},
                        "ring": {"type": "integer", "minimum": 1, "maximum": situate_ros2::config::MAX_RING, "description": "A topic in, LaserScan: resample into this many sectors from ahead, counter-clockwise."},
                        "period_ms": {"type": "number", "minimum": 0.1, "maximum": 1000, "description": "A topic in: how often its device hands the latest message on (default 1)."},
                        "frame_id": {"type": "string"},
                        "child_frame_id": {"type": "string"},
                        "range_min": {"type": "number"},
                        "range_max": {"type": "number"}
                    }
                }
            }
        }
    })
}

/// A simulator map (docs/maps.md): the top level and the mission checked
/// closely; the floors' elements loosely (`situate map check` is exact).
pub(crate) fn map() -> Json {
    let range = json!({"type": "array", "items": {"type": "number", "minimum": 0}, "minItems": 2, "maxItems": 2});
    json!({
        "$schema": DIALECT,
        "$id": "situate:map",
        "title": "situate simulator map",
        "description": "A building for the simulator: floors, an elevator bank, the mission (docs/maps.md).",
        "type": "object",
        "required": ["floors", "elevator", "mission"],
        "additionalProperties": false,
        "properties": {
            "name": {"type": "string"},
            "robot_radius": {"type": "number", "exclusiveMinimum": 0},
            "elevator": {
                "type": "object",
                "properties": {
                    "travel_s_per_floor": {"type": "number", "exclusiveMinimum": 0},
                    "door_move_s": {"type": "number", "exclusiveMinimum": 0},
                    "open_s": range.clone(),
                    "arrive_s": range,
                    "cars": {"type": "array", "items": {"type": "object"}}
                }
            },
            "floors": {"type": "array", "items": {"type": "object"}, "minItems": 1},
            "mission": {
                "type": "object",
                "required": ["start", "goal_floor"],
                "properties": {
                    "start": {"type": "object", "properties": {
                        "floor": {"type": "integer"}, "x": {"type": "number"}, "y": {"type": "number"}, "theta_deg": {"type": "number"}
                    }},
                    "goal_floor": {"type": "integer"},
                    "lab_door_barcode": {"type": "integer"},
                    "call_button_barcode": {"type": "integer"},
                    "office_barcode": {"type": "integer"},
                    "car_barcode_first": {"type": "integer"},
                    "message": {"type": "string"},
                    "route": {"type": "object"}
                }
            }
        }
    })
}

pub(crate) fn schema(format: &str) -> Option<Json> {
    match format {
        "robot" => Some(robot()),
        "manifest" => Some(manifest()),
        "map" => Some(map()),
        _ => None,
    }
}

/// `situate schema FORMAT [-o FILE]`.
pub(crate) fn schema_command(format: &str, output: Option<&Path>, out: Out) -> anyhow::Result<()> {
    let schema = schema(format)
        .ok_or_else(|| problem(Exit::Usage, format!("no schema `{format}` (there are: {})", FORMATS.join(", "))))?;
    let text = serde_json::to_string_pretty(&schema)?;
    match output {
        Some(path) => {
            std::fs::write(path, text + "\n")
                .map_err(|e| problem(Exit::Failure, format!("writing {}: {e}", path.display())))?;
            out.note(format_args!("{}: the {format} schema written", path.display()));
        }
        None => stdoutln!("{text}"),
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The keys a schema allows at an object (its `properties`).
    fn keys(schema: &Json) -> Vec<&str> {
        schema["properties"].as_object().map(|m| m.keys().map(String::as_str).collect()).unwrap_or_default()
    }

    #[test]
    fn the_robot_schema_names_every_key_the_manager_reads() {
        let s = robot();
        let mut top = keys(&s);
        top.sort_unstable();
        let mut want = vec![
            "robot",
            "include",
            "cycle",
            "libraries",
            "python",
            "simulator",
            "devices",
            "skills",
            "link",
            "gui",
            "ros2",
        ];
        want.sort_unstable();
        assert_eq!(top, want);
        let mut entry = keys(&s["properties"]["skills"]["items"]);
        entry.sort_unstable();
        let mut want = vec![
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
        want.sort_unstable();
        assert_eq!(entry, want);
        let mut cycle = keys(&s["properties"]["cycle"]);
        cycle.sort_unstable();
        let mut want = vec!["rate_hz", "period_ms", "clock", "executor", "threads", "budget_ms", "liveness_ms"];
        want.sort_unstable();
        assert_eq!(cycle, want);
    }

    #[test]
    fn every_format_has_a_schema_in_the_2020_12_dialect() {
        for f in FORMATS {
            let s = schema(f).unwrap_or_else(|| panic!("no schema {f}"));
            assert_eq!(s["$schema"], DIALECT);
            assert_eq!(s["type"], "object");
        }
        assert!(schema("nope").is_none());
    }
}

#[cfg(test)]
mod committed {
    use super::*;

    /// `docs/schemas/*.schema.json` (what the examples' `yaml-language-server` lines name) are
    /// the schemas this program prints.
    #[test]
    fn the_committed_schemas_are_current() {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../docs/schemas");
        for f in FORMATS {
            let path = dir.join(format!("{f}.schema.json"));
            let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
            let want = serde_json::to_string_pretty(&schema(f).unwrap()).unwrap() + "\n";
            assert!(
                text == want,
                "{} is stale: run `situate schema {f} -o docs/schemas/{f}.schema.json`",
                path.display()
            );
        }
    }
}
