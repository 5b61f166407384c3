//! Values and parameters in their JSON forms (docs/protocol.md, "Values").

use std::sync::Arc;

use base64::Engine as _;
use serde_json::{json, Value as Json};
use situate_core::{ElemType, ParamType, SignalType, Value};

fn float_to_json(x: f64) -> Json {
    if x.is_finite() {
        json!(x)
    } else if x.is_nan() {
        json!("nan")
    } else if x > 0.0 {
        json!("inf")
    } else {
        json!("-inf")
    }
}

pub(super) fn json_to_float(j: &Json) -> Option<f64> {
    match j {
        Json::Number(n) => n.as_f64(),
        Json::String(s) => match s.as_str() {
            "nan" => Some(f64::NAN),
            "inf" => Some(f64::INFINITY),
            "-inf" => Some(f64::NEG_INFINITY),
            _ => None,
        },
        _ => None,
    }
}

/// A value's JSON form (self-describing enough for any client; the type
/// travels beside it where it matters).
pub fn value_to_json(v: &Value) -> Json {
    match v {
        Value::Bool(b) => json!(b),
        Value::I64(x) => json!(x),
        Value::F64(x) => float_to_json(*x),
        Value::Str(s) => json!(&**s),
        Value::Bytes(b) => json!({"$bytes": base64::engine::general_purpose::STANDARD.encode(b)}),
        Value::F32s(a) => Json::Array(a.iter().map(|x| float_to_json(f64::from(*x))).collect()),
        Value::F64s(a) => Json::Array(a.iter().map(|x| float_to_json(*x)).collect()),
        Value::I64s(a) => Json::Array(a.iter().map(|x| json!(x)).collect()),
        Value::Record(r) => Json::Object(r.fields.iter().map(|(n, v)| (n.to_string(), value_to_json(v))).collect()),
    }
}

pub fn opt_value_to_json(v: &Option<Value>) -> Json {
    v.as_ref().map(value_to_json).unwrap_or(Json::Null)
}

/// Reads a value of type `ty`; the error says what was expected.
pub fn value_from_json(j: &Json, ty: &SignalType) -> Result<Value, String> {
    let fail = || format!("expected {ty}, got {}", describe(j));
    match ty {
        SignalType::Bool => j.as_bool().map(Value::Bool).ok_or_else(fail),
        SignalType::I64 => j.as_i64().map(Value::I64).ok_or_else(fail),
        SignalType::F64 => json_to_float(j).map(Value::F64).ok_or_else(fail),
        SignalType::Str => j.as_str().map(|s| Value::Str(Arc::from(s))).ok_or_else(fail),
        SignalType::Bytes => j
            .get("$bytes")
            .and_then(Json::as_str)
            .and_then(|b| base64::engine::general_purpose::STANDARD.decode(b).ok())
            .map(|b| Value::Bytes(Arc::from(b)))
            .ok_or_else(fail),
        SignalType::Array { elem, len } => {
            let items = j.as_array().ok_or_else(fail)?;
            if len.is_some_and(|n| n != items.len()) {
                return Err(format!("expected {ty}, got an array of {} elements", items.len()));
            }
            let v = match elem {
                ElemType::F32 => Value::F32s(
                    items
                        .iter()
                        .map(|x| json_to_float(x).map(|f| f as f32))
                        .collect::<Option<Vec<_>>>()
                        .ok_or_else(fail)?
                        .into(),
                ),
                ElemType::F64 => {
                    Value::F64s(items.iter().map(json_to_float).collect::<Option<Vec<_>>>().ok_or_else(fail)?.into())
                }
                ElemType::I64 => {
                    Value::I64s(items.iter().map(Json::as_i64).collect::<Option<Vec<_>>>().ok_or_else(fail)?.into())
                }
            };
            Ok(v)
        }
        SignalType::Record(rt) => {
            let obj = j.as_object().ok_or_else(fail)?;
            if let Some(extra) = obj.keys().find(|k| rt.field(k).is_none()) {
                return Err(format!("expected {ty}, got an unknown field `{extra}`"));
            }
            let mut fields = Vec::with_capacity(rt.fields.len());
            for (name, fty) in &rt.fields {
                let fj = obj.get(name).ok_or_else(|| format!("expected {ty}, field `{name}` is missing"))?;
                let fv = value_from_json(fj, fty).map_err(|e| format!("field `{name}`: {e}"))?;
                fields.push((Arc::from(name.as_str()), fv));
            }
            Ok(Value::Record(Arc::new(situate_core::RecordValue { fields })))
        }
    }
}

/// A parameter value as the manager sends it to a remote skill, before the
/// declaration's check (which maps an integer to a float where one is due).
pub fn param_from_json(j: &Json) -> Result<Value, String> {
    match j {
        Json::Bool(b) => Ok(Value::Bool(*b)),
        Json::Number(n) => match n.as_i64() {
            Some(i) => Ok(Value::I64(i)),
            None => n.as_f64().map(Value::F64).ok_or_else(|| "a number out of range".to_string()),
        },
        Json::String(s) => Ok(Value::Str(Arc::from(s.as_str()))),
        other => Err(format!("a parameter value is a bool, number or string, got {}", describe(other))),
    }
}

pub(super) fn describe(j: &Json) -> String {
    match j {
        Json::Null => "null".into(),
        Json::Bool(b) => b.to_string(),
        Json::Number(n) => n.to_string(),
        Json::String(s) => {
            let short: String = s.chars().take(40).collect();
            format!("{short:?}")
        }
        Json::Array(_) => "an array".into(),
        Json::Object(_) => "an object".into(),
    }
}

pub fn param_type_name(t: ParamType) -> &'static str {
    t.name()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn values_round_trip_by_type() {
        let t = SignalType::parse("{range: f32[3], id: i64, name: string, raw: bytes, ok: bool, x: f64}").unwrap();
        let v = situate_core::record_value(vec![
            ("range", Value::F32s(vec![0.5, f32::INFINITY, 2.0].into())),
            ("id", Value::I64(3)),
            ("name", Value::Str("door".into())),
            ("raw", Value::Bytes(vec![0u8, 255, 7].into())),
            ("ok", Value::Bool(true)),
            ("x", Value::F64(-1.25)),
        ]);
        let j = value_to_json(&v);
        assert_eq!(j["range"], json!([0.5, "inf", 2.0]));
        assert_eq!(j["raw"], json!({"$bytes": "AP8H"}));
        assert_eq!(value_from_json(&j, &t).unwrap(), v);
    }

    #[test]
    fn wrongly_typed_values_name_the_expectation() {
        let t = SignalType::parse("{v: f64, w: f64}").unwrap();
        assert_eq!(
            value_from_json(&json!({"v": 1}), &t).unwrap_err(),
            "expected {v: f64, w: f64}, field `w` is missing"
        );
        assert_eq!(value_from_json(&json!({"v": 1, "w": "x"}), &t).unwrap_err(), "field `w`: expected f64, got \"x\"");
        assert_eq!(
            value_from_json(&json!([1, 2]), &SignalType::parse("f32[3]").unwrap()).unwrap_err(),
            "expected f32[3], got an array of 2 elements"
        );
        // An integer is fine where a float is expected.
        assert_eq!(value_from_json(&json!(2), &SignalType::F64).unwrap(), Value::F64(2.0));
    }
}
