//! What the checker refuses and says (functions, types, unknown names,
//! records), the names a condition reads, and formulas.

use super::*;

#[test]
fn function_errors() {
    assert_err("foo(1) > 0", 1, &["unknown function `foo`", "abs", "min", "max", "len"]);
    assert_err("1 < lenn(label)", 5, &["`lenn`", "did you mean `len`"]);
    assert_err("sonar.range(1) > 0", 1, &["unknown function `sonar.range`"]);
    assert_err("abs(1, 2) > 0", 1, &["`abs` takes one number", "2 arguments"]);
    assert_err("abs() > 0", 1, &["`abs`", "0 arguments"]);
    assert_err("min(1) > 0", 1, &["`min` takes two or more", "1 argument"]);
    assert_err("max() > 0", 1, &["`max`", "0 arguments"]);
    assert_err("len(label, raw) > 0", 1, &["`len` takes one"]);
    assert_err("abs('x') > 0", 5, &["`abs` needs a number", "a string"]);
    assert_err("min(1, true) > 0", 8, &["`min` needs numbers", "a bool"]);
    assert_err("max(1, 2, label) > 0", 11, &["`max`", "a string"]);
    assert_err("len(3) > 0", 5, &["`len` needs an array", "a number"]);
    assert_err("len(sonar.ok) > 0", 5, &["`len`", "a bool"]);
    assert_err("abs(1 2) > 0", 7, &["expected `,` or `)`", "`abs`", "`2`"]);
    assert_err("abs(1", 6, &["expected `,` or `)`", "end of the condition"]);
    assert_err("abs(,) > 0", 5, &["expected a value", "`,`"]);
    assert_err("abs(1) == 1 && min(", 20, &["expected a value"]);
}

#[test]
fn type_errors_name_operator_types_and_column() {
    assert_err("label < 3", 7, &["`<`", "two numbers", "a string and a number"]);
    assert_err("1 <= label", 3, &["`<=`", "a number and a string"]);
    assert_err("odom.speed > true", 12, &["`>`", "a number and a bool"]);
    assert_err("1 >= raw", 3, &["`>=`", "a number and bytes"]);
    assert_err("1 + true > 0", 3, &["`+`", "a number and a bool"]);
    assert_err("label - 1 > 0", 7, &["`-`", "a string and a number"]);
    assert_err("2 * sonar.range > 0", 3, &["`*`", "a number and an array"]);
    assert_err("2 / 'x' > 0", 3, &["`/`"]);
    assert_err("2 % 'x' > 0", 3, &["`%`"]);
    assert_err("label == 3", 7, &["`==`", "two bools, two numbers or two strings", "a string and a number"]);
    assert_err("true != 1", 6, &["`!=`", "a bool and a number"]);
    assert_err("sonar.range == sonar.range", 13, &["`==`", "an array and an array"]);
    assert_err("raw == raw", 5, &["`==`", "bytes and bytes"]);
    assert_err("sonar.ok && 1", 10, &["`&&`", "true or false", "a bool and a number"]);
    assert_err("label || true", 7, &["`||`", "a string and a bool"]);
    assert_err("!3", 1, &["`!`", "true or false", "a number"]);
    assert_err("true && !label", 9, &["`!`", "a string"]);
    assert_err("-true", 1, &["`-`", "a number", "a bool"]);
    assert_err("1 < -label", 5, &["`-`", "a string"]);
    // Columns count characters, not bytes.
    assert_err("'ééé' == 1", 7, &["`==`", "a string and a number"]);
}

#[test]
fn the_condition_must_be_a_bool() {
    assert_err("1 + 2", 1, &["a monitor condition must be true or false, this is a number"]);
    assert_err("  label", 3, &["must be true or false, this is a string"]);
    assert_err("sonar.range", 1, &["this is an array"]);
    assert_err("raw", 1, &["this is bytes"]);
    assert_err("(1 + 2) * 3", 1, &["this is a number"]);
    assert_eq!(eval("sonar.ok"), Some(true));
    assert_eq!(eval("(flag)"), Some(false));
}

#[test]
fn unknown_names_report_the_resolver_message_at_the_name() {
    assert_err("sonr.range[0] < 1", 1, &["unknown signal `sonr` — did you mean `sonar`?"]);
    let e = err("sonar.ok && barcod.id == 3");
    assert_eq!(e.column, 13);
    assert_eq!(e.message, "unknown signal `barcod` — did you mean `barcode`?");
    assert_err("1 < 2 && (abs(nothing_like_it) > 0)", 15, &["unknown signal `nothing_like_it`"]);
    // A keyword inside a dotted name is just part of the name.
    assert_err("true.x", 1, &["unknown signal `true`"]);
}

#[test]
fn records_need_a_field() {
    let e = err("pose > 1");
    assert_eq!(e.column, 1);
    assert_eq!(e.message, "`pose` is a record; name one of its fields: x, y");
    assert_err("1 < 2 && pose", 10, &["`pose` is a record", "x, y"]);
    assert_err("empty", 1, &["`empty` is a record without fields"]);
    assert_eq!(eval("pose.x > 1"), Some(true));
}

#[test]
fn refs_are_unique_in_first_use_order() {
    let c = compile("sonar.range[0] < 1 && barcode.id == 3 && sonar.range[1] < 2 || flag").unwrap();
    assert_eq!(c.refs(), &[id("sonar.range"), id("barcode.id"), id("flag")]);
    assert_eq!(c.ref_names(), &["sonar.range", "barcode.id", "flag"]);
    assert_eq!(c.source(), "sonar.range[0] < 1 && barcode.id == 3 && sonar.range[1] < 2 || flag");
    let c = compile("1 < 2").unwrap();
    assert!(c.refs().is_empty() && c.ref_names().is_empty());
    let c = compile("len(label) > 0 && min(pose.x, odom.speed, pose.x) < 1").unwrap();
    assert_eq!(c.ref_names(), &["label", "pose.x", "odom.speed"]);
    assert_eq!(c.refs(), &[id("label"), id("pose.x"), id("odom.speed")]);
    // A compiled condition clones.
    let d = c.clone();
    assert_eq!(d.eval(&standard()), c.eval(&standard()));
}

#[test]
fn a_formula_is_a_number_or_a_bool_read_as_one_or_zero() {
    let sigs = Sigs(signals());
    let f = |src: &str| Formula::compile(src, &sigs).unwrap_or_else(|e| panic!("{src}: {e}"));
    let vals = standard();
    assert_eq!(f("abs(odom.speed) * 2").eval(&vals), Some(1.5));
    assert_eq!(f("sonar.range[1] + barcode.id").eval(&vals), Some(3.25));
    assert_eq!(f("pose.x").eval(&vals), Some(1.5));
    assert_eq!(f("sonar.range[0] < 0.25").eval(&vals), Some(0.0));
    assert_eq!(f("sonar.ok && barcode.id == 3").eval(&vals), Some(1.0));
    // Missing (no value, out of range) and not finite (a division by zero): no point.
    assert_eq!(f("sonar.range[7] * 2").eval(&vals), None);
    assert_eq!(f("pose.x + 1").eval(&Vals::default()), None);
    assert_eq!(f("odom.speed / 0").eval(&vals), None);
    let formula = f("min(pose.x, odom.speed)");
    assert_eq!(formula.source(), "min(pose.x, odom.speed)");
    assert_eq!(formula.ref_names(), ["pose.x", "odom.speed"]);
    assert_eq!(formula.refs(), [id("pose.x"), id("odom.speed")]);
    // What is not a number nor a bool is refused, naming the type and the column.
    let e = Formula::compile("label", &sigs).unwrap_err();
    assert_eq!(e.column, 1);
    assert!(e.message.contains("must be a number or true/false, this is a string"), "{e}");
    let e = Formula::compile("odom.speed + lable", &sigs).unwrap_err();
    assert_eq!(e.column, 14);
    assert!(e.message.contains("unknown signal `lable`"), "{e}");
    // Its messages say formula, not condition.
    assert!(Formula::compile("", &sigs).unwrap_err().message.contains("the formula is empty"));
    assert!(Formula::compile("(pose.x", &sigs).unwrap_err().message.contains("the end of the formula"));
    // A condition is still only a bool.
    assert!(Condition::compile("odom.speed", &sigs).is_err());
}
