//! Evaluation: functions, indexes, missing values with Kleene's logic, and
//! `&&`/`||` stopping early.

use super::*;

#[test]
fn functions() {
    for (src, want) in [
        ("abs(-3) == 3", true),
        ("abs(odom.speed) == 0.75", true),
        ("min(3, 1, 2) == 1", true),
        ("max(3, 1, 2) == 3", true),
        ("min(sonar.range[0], sonar.range[1]) == 0.25", true),
        ("max(barcode.id, 2) == 3", true),
        ("len(label) == 4", true),
        ("len('héllo') == 6", true), // bytes
        ("len(raw) == 6", true),
        ("len(sonar.range) == 3", true),
        ("len(counts) == 3", true),
        ("len(gains) == 2", true),
        ("abs(min(-1, -2)) == 2", true),
        ("max( 1 , 2 ) == 2", true),
        ("len (label) == 4", true),
    ] {
        assert_eq!(eval(src), Some(want), "{src}");
    }
    // NaN propagates through min/max (and then compares as missing).
    assert_eq!(eval("min(0 / 0, 1) < 2"), None);
    assert_eq!(eval("max(1, 0 / 0) < 2"), None);
    // A missing argument makes the whole call missing.
    assert_eq!(eval_with("min(1, odom.speed) < 2", &Vals::default()), None);
    assert_eq!(eval_with("len(label) == 0", &Vals::default()), None);
}

#[test]
fn indexing() {
    assert_eq!(eval("sonar.range[0] == 0.5"), Some(true));
    assert_eq!(eval("sonar.range[2] == 2"), Some(true));
    assert_eq!(eval("sonar.range[1 + 1] == 2"), Some(true));
    assert_eq!(eval("sonar.range[barcode.id - 1] == 2"), Some(true));
    assert_eq!(eval("sonar.range[len(sonar.range) - 1] == 2"), Some(true));
    assert_eq!(eval("counts[2] == 9"), Some(true));
    assert_eq!(eval("gains[1] == 0.2"), Some(true));
    assert_eq!(eval("(sonar.range)[0] == 0.5"), Some(true));
    // Runtime: out of range, negative, fractional, NaN and infinite indexes are missing.
    assert_eq!(eval("sonar.range[3] < 100"), None);
    assert_eq!(eval("sonar.range[1e300] < 100"), None);
    assert_eq!(eval("sonar.range[barcode.id] < 100"), None);
    assert_eq!(eval("sonar.range[odom.speed] < 100"), None);
    assert_eq!(eval("sonar.range[odom.speed + 0.75] == 0.5"), Some(true));
    assert_eq!(eval("sonar.range[-barcode.id] < 100"), None);
    assert_eq!(eval("sonar.range[odom.speed * 2] < 100"), None);
    assert_eq!(eval("sonar.range[0 / 0 + barcode.id] < 100"), None);
    assert_eq!(eval("sonar.range[1 / 0 + barcode.id] < 100"), None);
    let empty = Vals::default().with("sonar.range", Value::F32s(Vec::new().into()));
    assert_eq!(eval_with("sonar.range[0] < 1", &empty), None);
    assert_eq!(eval_with("len(sonar.range) == 0", &empty), Some(true));
    // Compile time: a constant index past the end of a fixed-length array.
    assert_err("counts[3] > 0", 8, &["index 3 is out of range", "`counts` has 3 elements (indexes 0 to 2)"]);
    assert!(compile("counts[2] > 0").is_ok());
    assert!(compile("gains[300] > 0").is_ok(), "a variable-length array is checked at run time");
    // Compile time: constant negative or fractional indexes.
    assert_err("sonar.range[-1] < 1", 13, &["negative", "-1"]);
    assert_err("sonar.range[1 - 2] < 1", 13, &["negative"]);
    assert_err("sonar.range[0.5] < 1", 13, &["whole number", "0.5"]);
    assert_err("sonar.range[(1 / 3)] < 1", 13, &["whole number"]);
    assert_err("sonar.range[0 / 0] < 1", 13, &["whole number", "NaN"]);
    assert_err("sonar.range[1 / 0] < 1", 13, &["whole number", "inf"]);
    // Types.
    assert_err("barcode.id[0] == 1", 11, &["`[]`", "array", "a number"]);
    assert_err("label[0] == 1", 6, &["`[]`", "a string"]);
    assert_err("sonar.range['a'] < 1", 13, &["`[]`", "index", "a string"]);
    assert_err("sonar.range[0][1] < 1", 15, &["`[]`", "a number"]);
    assert_err("sonar.range[0 < 1", 18, &["`]` to close the `[` at column 12"]);
}

#[test]
fn missing_values_and_kleene_logic() {
    let none = Vals::default();
    let cases = [
        ("sonar.ok", None),
        ("!sonar.ok", None),
        ("sonar.ok || true", Some(true)),
        ("true || sonar.ok", Some(true)),
        ("sonar.ok || false", None),
        ("false || sonar.ok", None),
        ("sonar.ok && false", Some(false)),
        ("false && sonar.ok", Some(false)),
        ("sonar.ok && true", None),
        ("true && sonar.ok", None),
        ("sonar.ok || flag", None),
        ("sonar.ok == true", None),
        ("odom.speed < 1", None),
        ("odom.speed == odom.speed", None),
        ("odom.speed + 1 > 0", None),
        ("-odom.speed > 0", None),
        ("abs(odom.speed) > 0", None),
        ("label == 'x'", None),
        ("label != 'x'", None),
        ("sonar.range[0] < 1", None),
        ("len(raw) > 0", None),
        ("odom.speed < 1 || 1 < 2", Some(true)),
        ("!(odom.speed < 1 && 1 > 2)", Some(true)),
    ];
    for (src, want) in cases {
        assert_eq!(eval_with(src, &none), want, "{src}");
    }
    // NaN compares as missing, also for `==` and `!=`.
    let nan = Vals::default().with("odom.speed", Value::F64(f64::NAN));
    for src in ["odom.speed < 1", "odom.speed >= 1", "odom.speed == 1", "odom.speed != 1", "odom.speed == odom.speed"] {
        assert_eq!(eval_with(src, &nan), None, "{src}");
    }
    assert_eq!(eval_with("odom.speed < 1 || true", &nan), Some(true));
    // Division by zero follows IEEE and never panics.
    assert_eq!(eval("1 / 0 > 1e300"), Some(true));
    assert_eq!(eval("-1 / 0 < -1e300"), Some(true));
    assert_eq!(eval("0 / 0 == 0"), None);
    assert_eq!(eval("5 % 0 == 0"), None);
    assert_eq!(eval("barcode.id / 0 > 0"), Some(true));
    // A value of the wrong kind is missing.
    let wrong = Vals::default()
        .with("odom.speed", Value::Str(Arc::from("fast")))
        .with("sonar.ok", Value::I64(1))
        .with("label", Value::F64(1.0))
        .with("sonar.range", Value::Bytes(vec![1].into()))
        .with("raw", Value::F32s(vec![1.0].into()));
    for src in [
        "odom.speed > 0",
        "sonar.ok",
        "label == 'x'",
        "sonar.range[0] > 0",
        "len(sonar.range) > 0",
        "len(raw) > 0",
        "len(label) > 0",
    ] {
        assert_eq!(eval_with(src, &wrong), None, "{src}");
    }
    // i64 values convert to numbers.
    let big = Vals::default().with("barcode.id", Value::I64(1 << 53));
    assert_eq!(eval_with("barcode.id == 9007199254740992", &big), Some(true));
}

#[test]
fn and_or_short_circuit() {
    let c = compile("false && sonar.ok").unwrap();
    let vals = standard();
    assert_eq!(c.eval(&vals), Some(false));
    assert_eq!(vals.reads.get(), 0);
    let c = compile("sonar.ok || odom.speed > 0 || barcode.id == 3").unwrap();
    let vals = standard();
    assert_eq!(c.eval(&vals), Some(true));
    assert_eq!(vals.reads.get(), 1);
    let c = compile("flag && odom.speed > 0").unwrap();
    let vals = standard();
    assert_eq!(c.eval(&vals), Some(false));
    assert_eq!(vals.reads.get(), 1);
}
