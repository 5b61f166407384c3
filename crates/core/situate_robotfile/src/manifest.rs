//! Skill manifests: a skill's declaration written as data (YAML), for skills
//! whose code the manager does not hold — remote skills served by another
//! process, C and C++ skills (docs/manifests.md).
//!
//! ```yaml
//! doc: Doubles its input.           # optional
//! priority: 0                       # optional
//! inputs:  {x: f64, bump: "bool?"}  # port: type; a trailing `?` makes it optional
//! outputs:
//!   y: {type: f64, signal: out.y, doc: "…"}  # long form: the default signal (else `y`)
//! params:
//!   gain: 2.0                       # a default alone (its type is the default's)
//!   limit: {type: f64, default: 1.0, min: 0, max: 10, unit: m, doc: "…"}
//! ```

use situate_core::{suggestion, ParamSpec, ParamType, PortSpec, SignalType, SkillDecl, SkillKind, Value};

use crate::diagnostic::Diagnostic;
use crate::limits::MAX_NAME_CHARS;
pub use crate::limits::{MAX_PORTS, MAX_TYPE_CHARS};
use crate::names::{is_identifier, is_signal_name};
use crate::yaml::{Node, Pos, Spanned};

const MANIFEST_KEYS: &[&str] = &["doc", "priority", "inputs", "outputs", "params"];
const PARAM_KEYS: &[&str] = &["type", "default", "min", "max", "unit", "doc"];
/// A port's keys in its long form (outputs: the first three).
const PORT_KEYS: &[&str] = &["type", "signal", "doc", "optional"];

/// Reads a manifest into a declaration of `type_name` and `kind`. Its
/// problems are diagnostics at the offending key or value, without a file
/// (the caller knows it: [`Diagnostic::in_file`]).
pub fn decl_from_node(node: &Spanned<Node>, type_name: &str, kind: SkillKind) -> Result<SkillDecl, Vec<Diagnostic>> {
    decl_from_map(node, type_name, kind)
        .map_err(|problems| problems.into_iter().map(|(pos, message)| Diagnostic::at(pos, message)).collect())
}

fn decl_from_map(node: &Spanned<Node>, type_name: &str, kind: SkillKind) -> Result<SkillDecl, Vec<(Pos, String)>> {
    let mut errors = Vec::new();
    let mut decl = SkillDecl::new(type_name, kind);
    let Some(entries) = node.value.as_map() else {
        return Err(vec![(node.pos, format!("a skill manifest is a mapping, got {}", node.value.describe()))]);
    };
    for (key, value) in entries {
        match key.value.as_str() {
            "doc" => match value.value.as_text() {
                Some(t) => decl.doc = t.to_string(),
                None => errors.push((value.pos, format!("`doc` expects text, got {}", value.value.describe()))),
            },
            "priority" => match value.value.as_i64().and_then(|p| i32::try_from(p).ok()) {
                Some(p) => decl.priority = p,
                None if value.value.is_integer_literal() => errors.push((
                    value.pos,
                    format!(
                        "`priority` is out of range: expects an integer from {} to {}, got {}",
                        i32::MIN,
                        i32::MAX,
                        value.value.describe()
                    ),
                )),
                None => {
                    errors.push((value.pos, format!("`priority` expects an integer, got {}", value.value.describe())))
                }
            },
            "inputs" | "outputs" => {
                let output = key.value == "outputs";
                let Some(ports) = value.value.as_map() else {
                    errors.push((value.pos, format!("`{}` expects a mapping of port: type", key.value)));
                    continue;
                };
                if ports.len() > MAX_PORTS {
                    errors.push((value.pos, too_many(&key.value, ports.len())));
                    continue;
                }
                for (port, ty) in ports {
                    if port.value.chars().count() > MAX_NAME_CHARS {
                        errors.push((port.pos, format!("a port name may have at most {MAX_NAME_CHARS} characters")));
                        continue;
                    }
                    if !is_identifier(&port.value) {
                        errors.push((port.pos, format!("port name `{}` is not an identifier", port.value)));
                        continue;
                    }
                    match port_spec(&port.value, ty, output) {
                        Ok(spec) if output => decl.outputs.push(spec),
                        Ok(spec) => decl.inputs.push(spec),
                        Err(e) => errors.push(e),
                    }
                }
            }
            "params" => {
                let Some(params) = value.value.as_map() else {
                    errors.push((
                        value.pos,
                        "`params` expects a mapping of name: default or name: {type, default, …}".into(),
                    ));
                    continue;
                };
                if params.len() > MAX_PORTS {
                    errors.push((value.pos, too_many("params", params.len())));
                    continue;
                }
                for (name, spec) in params {
                    if name.value.chars().count() > MAX_NAME_CHARS {
                        errors
                            .push((name.pos, format!("a parameter name may have at most {MAX_NAME_CHARS} characters")));
                        continue;
                    }
                    match param_spec(&name.value, spec) {
                        Ok(p) => decl.params.push(p),
                        Err(e) => errors.push(e),
                    }
                }
            }
            other => errors.push((
                key.pos,
                format!(
                    "unknown key `{other}` in the skill manifest{}",
                    suggestion(other, MANIFEST_KEYS.iter().copied())
                ),
            )),
        }
    }
    if errors.is_empty() {
        Ok(decl)
    } else {
        Err(errors)
    }
}

/// "`inputs` declares 300 entries; a skill may have at most 256".
fn too_many(key: &str, n: usize) -> String {
    format!("`{key}` declares {n} entries; a skill may have at most {MAX_PORTS}")
}

/// One port: `type` (a trailing `?` makes an input optional), or
/// `{type, signal, optional, doc}`.
fn port_spec(name: &str, node: &Spanned<Node>, output: bool) -> Result<PortSpec, (Pos, String)> {
    let expects = |got: &Node| {
        format!(
            "port `{name}` expects a type such as f64 or f32[24], or {{type, signal{}, doc}}, got {}",
            if output { "" } else { ", optional" },
            got.describe()
        )
    };
    let (ty, signal, mut optional, doc) = match node.value.as_map() {
        None => (node, None, false, String::new()),
        Some(entries) => {
            let (mut ty, mut signal, mut optional, mut doc) = (None, None, false, String::new());
            let keys = if output { &PORT_KEYS[..3] } else { PORT_KEYS };
            for (key, value) in entries {
                match key.value.as_str() {
                    "type" => ty = Some(value),
                    "signal" => match value.value.as_text().map(str::trim) {
                        Some(s) if s.chars().count() > MAX_NAME_CHARS => {
                            return Err((
                                value.pos,
                                format!("port `{name}`: a signal name may have at most {MAX_NAME_CHARS} characters"),
                            ))
                        }
                        Some(s) if is_signal_name(s) => signal = Some(s.to_string()),
                        _ => {
                            return Err((
                                value.pos,
                                format!(
                                    "port `{name}`: `signal` expects a signal name (identifiers joined by `.`, like \
                                     `sonar.range`), got {}",
                                    value.value.describe()
                                ),
                            ))
                        }
                    },
                    "optional" if !output => match value.value.as_bool() {
                        Some(b) => optional = b,
                        _ => {
                            return Err((
                                value.pos,
                                format!(
                                    "port `{name}`: `optional` expects true or false, got {}",
                                    value.value.describe()
                                ),
                            ))
                        }
                    },
                    "doc" => match value.value.as_text() {
                        Some(t) => doc = t.to_string(),
                        None => {
                            return Err((
                                value.pos,
                                format!("port `{name}`: `doc` expects text, got {}", value.value.describe()),
                            ))
                        }
                    },
                    other => {
                        return Err((
                            key.pos,
                            format!("port `{name}`: unknown key `{other}`{}", suggestion(other, keys.iter().copied())),
                        ))
                    }
                }
            }
            let ty = ty.ok_or((node.pos, format!("port `{name}` needs a `type`")))?;
            (ty, signal, optional, doc)
        }
    };
    let Some(text) = ty.value.as_text() else {
        return Err((ty.pos, expects(&ty.value)));
    };
    if text.chars().count() > MAX_TYPE_CHARS {
        return Err((ty.pos, format!("port `{name}`: a type may have at most {MAX_TYPE_CHARS} characters")));
    }
    let text = match text.trim().strip_suffix('?') {
        Some(t) if !output => {
            optional = true;
            t
        }
        _ => text.trim(),
    };
    let t = SignalType::parse(text)
        .map_err(|e| (Pos { col: ty.pos.col + e.column - 1, ..ty.pos }, format!("port `{name}`: {}", e.message)))?;
    let mut spec = PortSpec::new(name, t);
    spec.optional = optional;
    spec.doc = doc;
    if let Some(s) = signal {
        spec.signal = s;
    }
    Ok(spec)
}

fn param_spec(name: &str, node: &Spanned<Node>) -> Result<ParamSpec, (Pos, String)> {
    let scalar_type = |v: &Value| match v {
        Value::Bool(_) => Some(ParamType::Bool),
        Value::I64(_) => Some(ParamType::I64),
        Value::F64(_) => Some(ParamType::F64),
        Value::Str(_) => Some(ParamType::Str),
        _ => None,
    };
    if let Some(default) = node.value.to_value() {
        let ty = scalar_type(&default).ok_or((node.pos, format!("parameter `{name}`: a default must be a scalar")))?;
        return Ok(ParamSpec::new(name, ty, default));
    }
    let Some(entries) = node.value.as_map() else {
        return Err((
            node.pos,
            format!("parameter `{name}` expects a default value or {{type, default, min, max, unit, doc}}"),
        ));
    };
    let mut ty = None;
    let mut default = None;
    let (mut min, mut max, mut unit, mut doc) = (None, None, String::new(), String::new());
    for (key, value) in entries {
        match key.value.as_str() {
            "type" => {
                ty = Some(match value.value.as_text() {
                    Some("bool") => ParamType::Bool,
                    Some("i64" | "int") => ParamType::I64,
                    Some("f64" | "float") => ParamType::F64,
                    Some("string" | "str") => ParamType::Str,
                    _ => {
                        return Err((
                            value.pos,
                            format!(
                                "parameter `{name}`: `type` is bool, i64, f64 or string, got {}",
                                value.value.describe()
                            ),
                        ))
                    }
                })
            }
            "default" => default = Some((value.value.to_value(), value.pos, value.value.describe())),
            "min" => {
                min = Some(
                    value.value.as_f64().ok_or((value.pos, format!("parameter `{name}`: `min` expects a number")))?,
                )
            }
            "max" => {
                max = Some(
                    value.value.as_f64().ok_or((value.pos, format!("parameter `{name}`: `max` expects a number")))?,
                )
            }
            "unit" => unit = value.value.as_text().unwrap_or_default().to_string(),
            "doc" => doc = value.value.as_text().unwrap_or_default().to_string(),
            other => {
                return Err((
                    key.pos,
                    format!(
                        "parameter `{name}`: unknown key `{other}`{}",
                        suggestion(other, PARAM_KEYS.iter().copied())
                    ),
                ))
            }
        }
    }
    let (default, pos, written) = match default {
        Some((Some(v), pos, written)) => (v, pos, written),
        _ => return Err((node.pos, format!("parameter `{name}` needs a `default`"))),
    };
    let ty = match ty.or_else(|| scalar_type(&default)) {
        Some(t) => t,
        None => return Err((pos, format!("parameter `{name}`: a default must be a scalar"))),
    };
    let mut spec = ParamSpec::new(name, ty, default.clone()).range(min, max);
    spec.unit = unit;
    spec.doc = doc;
    spec.default = spec.check(&default).map_err(|mut e| {
        // As written: `1e300`, not its digits.
        e.got = written;
        (pos, format!("parameter `{name}`: the default {e}"))
    })?;
    Ok(spec)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The declaration, or each problem's place and message.
    fn manifest(src: &str) -> Result<SkillDecl, Vec<(Pos, String)>> {
        let tree = crate::yaml::parse(src).unwrap();
        decl_from_node(&tree, "remote.t", SkillKind::Async)
            .map_err(|problems| problems.into_iter().map(|d| (d.pos.expect("a place"), d.message)).collect())
    }

    #[test]
    fn a_manifest_declares_ports_and_parameters() {
        let d = manifest(
            "doc: Doubles.\ninputs: {x: f64, bump: \"bool?\"}\noutputs: {y: f64}\nparams:\n  gain: 2.0\n  limit: {type: f64, default: 1, min: 0, max: 10, unit: m}\n",
        )
        .unwrap();
        assert_eq!(d.doc, "Doubles.");
        assert_eq!(d.inputs.len(), 2);
        assert!(d.inputs[1].optional && !d.inputs[0].optional);
        assert_eq!(d.outputs[0].ty, SignalType::F64);
        assert_eq!(d.params[0].default, Value::F64(2.0));
        assert_eq!(d.params[1].default, Value::F64(1.0));
        assert_eq!(d.params[1].expectation(), "a number in [0.0, 10.0]");
    }

    #[test]
    fn manifest_errors_point_at_the_problem() {
        let e = manifest("inputs: {x: f46}\n").unwrap_err();
        assert_eq!(e[0].0, Pos::new(1, 13));
        assert!(e[0].1.starts_with("port `x`: unknown type `f46`"), "{}", e[0].1);
        let e = manifest("ouputs: {}\n").unwrap_err();
        assert_eq!(e[0].1, "unknown key `ouputs` in the skill manifest — did you mean `outputs`?");
        let e = manifest("params:\n  g: {type: f64, default: 5, max: 1}\n").unwrap_err();
        assert_eq!(e[0].1, "parameter `g`: the default expects a number ≤ 1.0, got 5");
    }

    #[test]
    fn a_port_may_name_its_default_signal() {
        let d = manifest(
            "inputs:\n  range: {type: \"f32[24]\", signal: sonar.range, doc: Metres.}\n  bump: {type: bool, optional: true}\n  \
             x: \"f64?\"\noutputs:\n  y: {type: f64, signal: cmd.y}\n  z: f64\n",
        )
        .unwrap();
        assert_eq!(
            (d.inputs[0].signal.as_str(), d.inputs[0].doc.as_str(), d.inputs[0].optional),
            ("sonar.range", "Metres.", false)
        );
        assert_eq!(d.inputs[0].ty, SignalType::parse("f32[24]").unwrap());
        assert!(d.inputs[1].optional && d.inputs[1].signal == "bump");
        assert!(d.inputs[2].optional && d.inputs[2].signal == "x");
        assert_eq!((d.outputs[0].signal.as_str(), d.outputs[1].signal.as_str()), ("cmd.y", "z"));
    }

    #[test]
    fn a_bad_port_says_which_key() {
        let e = manifest("inputs:\n  r: {type: f64, signal: sonar..range}\n").unwrap_err();
        assert_eq!(
            e[0],
            (
                Pos::new(2, 26),
                "port `r`: `signal` expects a signal name (identifiers joined by `.`, like `sonar.range`), got \
                 \"sonar..range\""
                    .into()
            )
        );
        let e = manifest("inputs:\n  r: {type: f64, signl: s}\n").unwrap_err();
        assert_eq!(e[0], (Pos::new(2, 18), "port `r`: unknown key `signl` — did you mean `signal`?".into()));
        let e = manifest("outputs:\n  y: {type: f64, optional: true}\n").unwrap_err();
        assert_eq!(e[0].0, Pos::new(2, 18));
        assert!(e[0].1.starts_with("port `y`: unknown key `optional`"), "{}", e[0].1);
        let e = manifest("inputs:\n  r: {signal: s}\n").unwrap_err();
        assert_eq!(e[0], (Pos::new(2, 6), "port `r` needs a `type`".into()));
        let e = manifest("inputs:\n  r: {type: f46}\n").unwrap_err();
        assert_eq!(e[0].0, Pos::new(2, 13));
        assert!(e[0].1.starts_with("port `r`: unknown type `f46`"), "{}", e[0].1);
        let e = manifest("inputs:\n  r: [f64]\n").unwrap_err();
        assert!(e[0].1.starts_with("port `r` expects a type such as f64"), "{}", e[0].1);
        let e = manifest("inputs:\n  r: {type: f64, optional: maybe}\n").unwrap_err();
        assert_eq!(e[0].1, "port `r`: `optional` expects true or false, got \"maybe\"");
    }

    #[test]
    fn ports_params_and_types_are_capped() {
        let ports: Vec<String> = (0..=MAX_PORTS).map(|i| format!("p{i}: f64")).collect();
        let e = manifest(&format!("inputs: {{{}}}\n", ports.join(", "))).unwrap_err();
        assert_eq!(e[0], (Pos::new(1, 9), "`inputs` declares 257 entries; a skill may have at most 256".into()));
        let e = manifest(&format!("params: {{{}}}\n", ports.join(", "))).unwrap_err();
        assert_eq!(e[0].1, "`params` declares 257 entries; a skill may have at most 256");
        // Deeply nested records: refused by length before the type parser
        // recurses into them.
        let deep = format!("{}f64{}", "{a: ".repeat(300), "}".repeat(300));
        let e = manifest(&format!("outputs: {{y: \"{deep}\"}}\n")).unwrap_err();
        assert_eq!(e[0], (Pos::new(1, 14), "port `y`: a type may have at most 1024 characters".into()));
    }

    #[test]
    fn numbers_out_of_range_are_quoted_as_written() {
        let e = manifest("params:\n  g: {type: f64, default: 1e300, max: 1}\n").unwrap_err();
        assert_eq!(e[0], (Pos::new(2, 27), "parameter `g`: the default expects a number ≤ 1.0, got 1e300".into()));
        let e = manifest("priority: 0x80000000\n").unwrap_err();
        assert_eq!(
            e[0].1,
            "`priority` is out of range: expects an integer from -2147483648 to 2147483647, got 0x80000000"
        );
    }
}
