//! `#[derive(Record)]`: record types and values from Rust structs.

use std::sync::Arc;

use situate::prelude::*;
use situate::{record_value, SignalType};

#[derive(Record, Clone, Debug, PartialEq)]
struct Pose {
    x: f64,
    y: f64,
    theta: f64,
}

/// A scan with where it was taken.
#[derive(Record, Clone, Debug, PartialEq)]
struct Scan {
    pose: Pose,
    ranges: [f32; 24],
    raw: Arc<[f32]>,
    label: String,
    stamp: i64,
    ok: bool,
}

#[derive(Record, Clone, Debug, PartialEq)]
struct Empty {}

#[derive(Record, Clone, Debug, PartialEq)]
struct Stamped<T> {
    t: f64,
    value: T,
}

#[derive(Record, Clone, Debug, PartialEq)]
struct Keyword {
    r#type: i64,
}

fn scan() -> Scan {
    let mut ranges = [0.0f32; 24];
    for (i, r) in ranges.iter_mut().enumerate() {
        *r = i as f32 * 0.5;
    }
    Scan {
        pose: Pose { x: 1.0, y: -2.0, theta: 0.25 },
        ranges,
        raw: vec![1.0, 2.0].into(),
        label: "front".into(),
        stamp: 42,
        ok: true,
    }
}

#[test]
fn the_signal_type_lists_fields_in_order_with_nested_records_and_arrays() {
    assert_eq!(Pose::signal_type(), SignalType::parse("{x: f64, y: f64, theta: f64}").unwrap());
    let t = Scan::signal_type();
    assert_eq!(
        t,
        SignalType::parse(
            "{pose: {x: f64, y: f64, theta: f64}, ranges: f32[24], raw: f32[], label: string, stamp: i64, ok: bool}"
        )
        .unwrap()
    );
    let fields: Vec<&str> = t.as_record().unwrap().fields.iter().map(|(n, _)| n.as_str()).collect();
    assert_eq!(fields, ["pose", "ranges", "raw", "label", "stamp", "ok"]);
    assert_eq!(Empty::signal_type().to_string(), "{}");
    assert_eq!(Keyword::signal_type().to_string(), "{type: i64}");
}

#[test]
fn values_round_trip_and_conform_to_the_type() {
    let v = scan().into_value();
    assert!(v.conforms(&Scan::signal_type()));
    assert_eq!(v.at_path(&["pose", "y"]), Some(&Value::F64(-2.0)));
    assert_eq!(v.at_path(&["ranges"]).and_then(|r| r.index_f64(3)), Some(1.5));
    assert_eq!(Scan::from_value(&v), Some(scan()));

    let e = Empty {}.into_value();
    assert!(e.conforms(&Empty::signal_type()));
    assert_eq!(Empty::from_value(&e), Some(Empty {}));

    let k = Keyword { r#type: 3 }.into_value();
    assert_eq!(k.at_path(&["type"]), Some(&Value::I64(3)));
    assert_eq!(Keyword::from_value(&k), Some(Keyword { r#type: 3 }));
}

#[test]
fn zero_values_of_the_type_read_back() {
    let z = Value::zero(&Scan::signal_type());
    let s = Scan::from_value(&z).unwrap();
    assert_eq!(s.ranges, [0.0; 24]);
    assert_eq!(s.pose, Pose { x: 0.0, y: 0.0, theta: 0.0 });
}

#[test]
fn fields_are_found_by_name_whatever_their_order() {
    let v = record_value(vec![("theta", Value::F64(3.0)), ("x", Value::F64(1.0)), ("y", Value::F64(2.0))]);
    assert_eq!(Pose::from_value(&v), Some(Pose { x: 1.0, y: 2.0, theta: 3.0 }));
}

#[test]
fn wrong_values_read_as_none() {
    let missing = record_value(vec![("x", Value::F64(1.0)), ("y", Value::F64(2.0))]);
    assert_eq!(Pose::from_value(&missing), None);
    let mistyped = record_value(vec![("x", Value::F64(1.0)), ("y", Value::I64(2)), ("theta", Value::F64(0.0))]);
    assert_eq!(Pose::from_value(&mistyped), None);
    assert_eq!(Pose::from_value(&Value::F64(1.0)), None);

    // A nested record with a wrong field, and an array of the wrong length.
    let mut bad = scan();
    bad.pose.x = 7.0;
    let Value::Record(r) = bad.into_value() else { unreachable!() };
    let mut fields = r.fields.clone();
    fields[0].1 = record_value(vec![("x", Value::F64(1.0))]);
    let wrong_pose = Value::Record(Arc::new(situate::RecordValue { fields: fields.clone() }));
    assert_eq!(Scan::from_value(&wrong_pose), None);
    fields = r.fields.clone();
    fields[1].1 = Value::F32s(vec![0.0; 23].into());
    let short = Value::Record(Arc::new(situate::RecordValue { fields }));
    assert!(!short.conforms(&Scan::signal_type()));
    assert_eq!(Scan::from_value(&short), None);
}

#[test]
fn generic_records_take_their_field_types() {
    assert_eq!(Stamped::<Pose>::signal_type().to_string(), "{t: f64, value: {x: f64, y: f64, theta: f64}}");
    let s = Stamped { t: 1.0, value: [1i64, 2, 3] };
    let v = s.clone().into_value();
    assert!(v.conforms(&Stamped::<[i64; 3]>::signal_type()));
    assert_eq!(Stamped::from_value(&v), Some(s));
}
