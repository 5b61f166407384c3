//! Syntax: precedence, every operator, literals and lexing, and how an
//! error points at its column.

use super::*;

#[test]
fn precedence_and_associativity() {
    for (src, want) in [
        ("1 + 2 * 3 == 7", true),
        ("(1 + 2) * 3 == 9", true),
        ("10 - 4 - 3 == 3", true),
        ("16 / 4 / 2 == 2", true),
        ("2 * 3 % 4 == 2", true),
        ("7 % 4 * 2 == 6", true),
        ("-2 * 3 == -6", true),
        ("- 2 - -3 == 1", true),
        ("--2 == 2", true),
        ("1 + 1 < 3", true),
        ("3 > 1 + 1", true),
        ("1 < 2 == true", true),
        ("true == 1 < 2", true),
        ("1 < 2 == 3 < 4", true),
        ("true || false && false", true),
        ("false && false || true", true),
        ("!false && false", false),
        ("!(false && false)", true),
        ("!true == false", true),
    ] {
        assert_eq!(eval(src), Some(want), "{src}");
    }
    assert_eq!(eval("-sonar.range[1] == -0.25"), Some(true));
    assert_eq!(eval("counts[0] + counts[1] * counts[2] == 79"), Some(true));
}

#[test]
fn comparisons_do_not_chain() {
    assert_err("1 < 2 < 3", 7, &["`<`", "chain", "&&"]);
    assert_err("1 < 2 + 1 >= 3", 11, &["`>=`", "`<`"]);
    assert_err("true == false != true", 15, &["`!=`", "`==`"]);
    assert_err("1 == 1 == true", 8, &["chain"]);
    // Parentheses make them legal.
    assert_eq!(eval("(1 < 2) == (3 < 4)"), Some(true));
    assert_eq!(eval("(false == false) == true"), Some(true));
}

#[test]
fn every_operator() {
    for (src, want) in [
        ("!true", false),
        ("!false", true),
        ("true && true", true),
        ("true && false", false),
        ("false || false", false),
        ("false || true", true),
        ("true == true", true),
        ("true != true", false),
        ("1 == 1", true),
        ("1 != 1", false),
        ("1 != 2", true),
        ("'a' == \"a\"", true),
        ("'a' != 'b'", true),
        ("'a' == 'b'", false),
        ("1 < 2", true),
        ("2 < 2", false),
        ("2 <= 2", true),
        ("3 <= 2", false),
        ("3 > 2", true),
        ("2 > 2", false),
        ("2 >= 2", true),
        ("1 >= 2", false),
        ("1 + 2 == 3", true),
        ("1 - 2 == -1", true),
        ("2 * 3 == 6", true),
        ("7 / 2 == 3.5", true),
        ("7 % 4 == 3", true),
        ("-7 % 4 == -3", true),
        ("-(1) == 0 - 1", true),
        ("1e-3 == 0.001", true),
        ("2.5E+2 == 250", true),
        ("-0 == 0", true),
    ] {
        assert_eq!(eval(src), Some(want), "{src}");
    }
}

#[test]
fn literals_and_lexing() {
    assert_eq!(eval(r#"label == "dock""#), Some(true));
    assert_eq!(eval("label == 'dock'"), Some(true));
    assert_eq!(eval(r#"'it\'s' == "it's""#), Some(true));
    assert_eq!(eval(r#""say \"hi\"" == 'say "hi"'"#), Some(true));
    assert_eq!(eval(r#"len('a\\b') == 3"#), Some(true));
    assert_eq!(eval("len('') == 0"), Some(true));
    assert_eq!(eval("\tbarcode.id\n==\r\n3 "), Some(true));
    assert_eq!(eval("0.25 == 25e-2"), Some(true));
    assert_eq!(eval("007 == 7"), Some(true));
    assert_err(".5 < 1", 1, &["`0.5`, not `.5`"]);
    assert_err("3. < 1", 3, &["digits after the decimal point"]);
    assert_err("1e < 1", 3, &["exponent"]);
    assert_err("1e+ < 1", 4, &["exponent"]);
    assert_err("3abc < 1", 2, &["unexpected `a` right after a number"]);
    assert_err("1.2.3 < 1", 4, &["unexpected `.`"]);
    assert_err("1e999 < 1", 1, &["too large"]);
    assert_err("label == 'dock", 10, &["not closed"]);
    assert_err("label == 'dock\\", 10, &["not closed"]);
    assert_err(r"label == 'a\nb'", 12, &[r"unknown escape `\n`"]);
    assert_err("a = 1", 3, &["`=`", "`==`"]);
    assert_err("flag & flag", 6, &["`&&`"]);
    assert_err("flag | flag", 6, &["`||`"]);
    assert_err("flag # 1", 6, &["unexpected character `#`"]);
    assert_err("flag ∧ flag", 6, &["unexpected character `∧`"]);
    assert_err("sonar. range", 7, &["field name after `.`"]);
    assert_err("sonar.3", 7, &["field name after `.`"]);
    assert_err("", 1, &["empty"]);
    assert_err("   ", 1, &["empty"]);
    assert_err("flag flag", 6, &["expected an operator or the end", "`flag`"]);
    assert_err("(flag", 6, &["`)` to close the `(` at column 1", "end of the condition"]);
    assert_err("flag)", 5, &["expected an operator", "`)`"]);
    assert_err("flag &&", 8, &["expected a value", "end of the condition"]);
    assert_err("&& flag", 1, &["expected a value", "`&&`"]);
    assert_err("()", 2, &["expected a value", "`)`"]);
    assert_err("flag [", 6, &["`[]` indexes an array", "a bool"]);
    let long = format!("flag '{}'", "x".repeat(40));
    assert_err(&long, 6, &["…`"]);
}

#[test]
fn pointer_and_display() {
    let src = "label < 3";
    let e = err(src);
    assert_eq!(e.to_string(), "column 7: `<` needs two numbers, got a string and a number");
    assert_eq!(e.pointer(src), "label < 3\n      ^");
    let e = ExprError { column: 1, message: String::new() };
    assert_eq!(e.pointer("x"), "x\n^");
    // Past the end, e.g. "expected a value, found the end".
    let src = "flag &&";
    assert_eq!(err(src).pointer(src), "flag &&\n       ^");
    // Characters, tabs and line breaks keep the caret in place.
    let src = "'é'\t== 1";
    assert_eq!(err(src).pointer(src), "'é'\t== 1\n   \t^");
    let src = "flag &&\n3";
    assert_eq!(err(src).pointer(src), "flag && 3\n     ^");
}
