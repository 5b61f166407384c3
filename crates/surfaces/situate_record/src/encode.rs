//! A leaf's message written straight into a byte buffer, the writer's
//! inner loop: `{"cycle":N,"value":V}` with `V` exactly as the link writes
//! values ([`value_to_json`]), without building a `serde_json::Value` tree
//! per message (which cost the writer two thirds of its time).

use std::io::Write as _;

use situate_core::ValueRef;
use situate_link::json::value_to_json;

/// Appends `{"cycle":cycle,"value":…}` to `buf`; returns where the value's
/// JSON is in it.
pub(crate) fn leaf_message(buf: &mut Vec<u8>, cycle: u64, value: ValueRef<'_>) -> std::ops::Range<usize> {
    let _ = write!(buf, "{{\"cycle\":{cycle},\"value\":");
    let start = buf.len();
    write_value(buf, value);
    let end = buf.len();
    buf.push(b'}');
    start..end
}

/// Appends a keyframe, `{"cycle":cycle,"leaves":{path:{"cycle":c,"value":V},…}}`,
/// from each leaf's path, cycle and value JSON.
pub(crate) fn keyframe<'a>(buf: &mut Vec<u8>, cycle: u64, leaves: impl Iterator<Item = (&'a str, u64, &'a [u8])>) {
    let _ = write!(buf, "{{\"cycle\":{cycle},\"leaves\":{{");
    for (k, (path, c, value)) in leaves.enumerate() {
        if k > 0 {
            buf.push(b',');
        }
        let _ = serde_json::to_writer(&mut *buf, path);
        let _ = write!(buf, ":{{\"cycle\":{c},\"value\":");
        buf.extend_from_slice(value);
        buf.push(b'}');
    }
    buf.extend_from_slice(b"}}");
}

/// Appends `value` as JSON, as [`value_to_json`] would write it.
pub(crate) fn write_value(buf: &mut Vec<u8>, value: ValueRef<'_>) {
    match value {
        ValueRef::Bool(b) => buf.extend_from_slice(if b { b"true" } else { b"false" }),
        ValueRef::I64(x) => {
            let _ = write!(buf, "{x}");
        }
        ValueRef::F64(x) => float(buf, x),
        ValueRef::F32s(a) => list(buf, a.iter(), |buf, x| float(buf, f64::from(*x))),
        ValueRef::F64s(a) => list(buf, a.iter(), |buf, x| float(buf, *x)),
        ValueRef::I64s(a) => list(buf, a.iter(), |buf, x| {
            let _ = write!(buf, "{x}");
        }),
        // Text, bytes and records are rare as leaves: through the tree.
        other => {
            let _ = serde_json::to_writer(&mut *buf, &value_to_json(&other.to_value()));
        }
    }
}

fn list<T>(buf: &mut Vec<u8>, items: impl Iterator<Item = T>, mut each: impl FnMut(&mut Vec<u8>, T)) {
    buf.push(b'[');
    for (k, x) in items.enumerate() {
        if k > 0 {
            buf.push(b',');
        }
        each(buf, x);
    }
    buf.push(b']');
}

/// A float as `serde_json` writes a finite one (shortest round trip), and a
/// non-finite one as the link does: `"nan"`, `"inf"`, `"-inf"`.
fn float(buf: &mut Vec<u8>, x: f64) {
    if x.is_finite() {
        let _ = serde_json::to_writer(&mut *buf, &x);
    } else if x.is_nan() {
        buf.extend_from_slice(b"\"nan\"");
    } else if x > 0.0 {
        buf.extend_from_slice(b"\"inf\"");
    } else {
        buf.extend_from_slice(b"\"-inf\"");
    }
}

#[cfg(test)]
mod tests {
    use std::sync::Arc;

    use serde_json::{json, Value as Json};
    use situate_core::{RecordValue, Value};

    use super::*;

    #[test]
    fn a_message_is_the_json_the_link_writes() {
        let values = [
            Value::Bool(true),
            Value::I64(i64::MIN),
            Value::I64(i64::MAX),
            Value::F64(0.1),
            Value::F64(-0.0),
            Value::F64(1e300),
            Value::F64(f64::NAN),
            Value::F64(f64::NEG_INFINITY),
            Value::F32s(vec![0.1f32, f32::INFINITY, -0.0, 3.5].into()),
            Value::F64s(vec![].into()),
            Value::I64s(vec![1, -2].into()),
            Value::Str("a \"quoted\" line\n".into()),
            Value::Bytes(vec![0u8, 255].into()),
            Value::Record(Arc::new(RecordValue { fields: vec![("x".into(), Value::F64(2.5))] })),
        ];
        for v in values {
            let mut buf = Vec::new();
            let at = leaf_message(&mut buf, 7, (&v).into());
            buf.clear();
            assert_eq!(leaf_message(&mut buf, 7, (&v).into()), at);
            let got: Json = serde_json::from_slice(&buf).unwrap_or_else(|e| panic!("{v:?}: {e}"));
            assert_eq!(serde_json::from_slice::<Json>(&buf[at]).ok(), Some(value_to_json(&v)));
            assert_eq!(got, json!({"cycle": 7, "value": value_to_json(&v)}), "{v:?}");
            // Bit for bit, as the tree's text.
            let tree = serde_json::to_string(&value_to_json(&v)).unwrap_or_default();
            assert!(String::from_utf8_lossy(&buf).contains(&tree), "{v:?}: {}", String::from_utf8_lossy(&buf));
        }
    }

    #[test]
    fn a_keyframe_is_json_with_every_leaf() {
        let mut buf = Vec::new();
        keyframe(&mut buf, 100, [("a.x", 99, &b"1.5"[..]), ("say \"hi\"", 3, &b"\"x\""[..])].into_iter());
        let got: Json =
            serde_json::from_slice(&buf).unwrap_or_else(|e| panic!("{e}: {}", String::from_utf8_lossy(&buf)));
        assert_eq!(
            got,
            json!({"cycle": 100, "leaves": {"a.x": {"cycle": 99, "value": 1.5}, "say \"hi\"": {"cycle": 3, "value": "x"}}})
        );
        buf.clear();
        keyframe(&mut buf, 1, std::iter::empty());
        assert_eq!(serde_json::from_slice::<Json>(&buf).ok(), Some(json!({"cycle": 1, "leaves": {}})));
    }
}
