//! The request decoder's tests: every verb's arguments, the bounds and the errors that name them.

use super::*;
use serde_json::json;

#[test]
fn requests_decode_and_bad_ones_say_why() {
    assert_eq!(
        decode_request("activate", br#"{"skills": ["wander", "runaway"]}"#).unwrap(),
        Decoded::Manager(Request::Activate { skills: vec!["wander".into(), "runaway".into()], with_providers: false })
    );
    assert_eq!(decode_request("stats", b"").unwrap(), Decoded::Manager(Request::QueryStats));
    let e = decode_request("activte", b"{}").unwrap_err();
    assert_eq!((e.kind, e.message.as_str()), ("unknown_verb", "unknown request `activte` — did you mean `activate`?"));
    let e = decode_request("activate", b"{\"skills\": 3}").unwrap_err();
    assert_eq!(e.message, "`activate`: argument `skills`: expected a list of strings (skill names), got 3");
    let e = decode_request("step", b"{\"cycles\": 0}").unwrap_err();
    assert_eq!(e.message, "`step`: argument `cycles`: expected an integer in [1, 1000000], got 0");
    let e = decode_request("stats", b"[1]").unwrap_err();
    assert_eq!(e.message, "`stats`: the payload must be a JSON object, got an array");
    let e = decode_request("stats", b"{\"protocol\": 2}").unwrap_err();
    assert_eq!(e.kind, "protocol");
    let e = decode_request("query", b"{\"signal\": \"x\", \"extra\": 1}").unwrap_err();
    assert_eq!(e.message, "`query`: unknown argument `extra`");
    let e = decode_request("set_param", b"{\"skill\": \"r\", \"param\": \"p\", \"value\": null}").unwrap_err();
    assert_eq!(e.kind, "bad_request");
    assert!(e.message.starts_with("`set_param`: argument `value`: expected a value: a bool, number,"), "{}", e.message);
}

fn refused(verb: &str, payload: &str) -> WireError {
    match decode_request(verb, payload.as_bytes()) {
        Ok(d) => panic!("`{verb}` {payload} was accepted as {d:?}"),
        Err(e) => e,
    }
}

#[test]
fn a_string_is_not_a_list_of_one() {
    for (verb, payload, arg) in [
        ("activate", r#"{"skills": "wander"}"#, "skills"),
        ("deactivate", r#"{"skills": "wander"}"#, "skills"),
        ("monitor_add", r#"{"condition": "cycle > 3", "report": "x"}"#, "report"),
        ("telemetry", r#"{"signals": "x"}"#, "signals"),
    ] {
        let e = refused(verb, payload);
        assert_eq!(e.kind, "bad_request", "{verb} {payload}");
        assert!(
            e.message.starts_with(&format!("`{verb}`: argument `{arg}`: expected a list of strings (")),
            "{}",
            e.message
        );
        assert!(e.message.contains(r#"(a list of one is written ["#), "{}", e.message);
    }
    // Objects, numbers and lists of other things are refused the same way.
    for payload in [r#"{"skills": {"a": 1}}"#, r#"{"skills": ["a", 1]}"#, r#"{"skills": null}"#] {
        let e = refused("deactivate", payload);
        assert!(e.message.starts_with("`deactivate`: argument `skills`: expected a list of strings"), "{}", e.message);
    }
    assert_eq!(
        decode_request("deactivate", br#"{"skills": ["wander"]}"#).unwrap(),
        Decoded::Manager(Request::Deactivate { skills: vec!["wander".into()] })
    );
    assert_eq!(
        decode_request("phase", br#"{"text": "leaving the lab", "client": "deliver"}"#).unwrap(),
        Decoded::Manager(Request::Phase { text: "leaving the lab".into(), client: Some("deliver".into()) })
    );
}

#[test]
fn every_argument_is_refused_in_a_wrong_type() {
    for (verb, payload, arg, expected) in [
        ("activate", r#"{"skills": [], "with_providers": "yes"}"#, "with_providers", "true or false"),
        ("set_param", r#"{"skill": ["r"], "param": "p", "value": 1}"#, "skill", "a string"),
        ("set_param", r#"{"skill": "r", "param": 3, "value": 1}"#, "param", "a string"),
        ("get_param", r#"{"skill": "r", "param": null}"#, "param", "a string"),
        ("set_priority", r#"{"skill": "r", "priority": 2.0}"#, "priority", "an integer in ["),
        ("set_priority", r#"{"skill": "r", "priority": "2"}"#, "priority", "an integer in ["),
        ("set_priority", r#"{"skill": "r", "priority": 1e400}"#, "priority", "an integer in ["),
        ("set_verbose", r#"{"skill": "r", "verbose": 1}"#, "verbose", "true or false"),
        ("phase", r#"{"text": 1}"#, "text", "a string"),
        ("phase", r#"{"text": "a", "client": true}"#, "client", "a string"),
        ("query", r#"{"signal": ["odom"]}"#, "signal", "a string"),
        ("skill", r#"{"skill": 1}"#, "skill", "a string"),
        ("monitor_add", r#"{"condition": 1}"#, "condition", "a string"),
        ("monitor_add", r#"{"condition": "cycle > 1", "mode": 1}"#, "mode", "\"once\""),
        ("monitor_add", r#"{"condition": "cycle > 1", "pause": "true"}"#, "pause", "true or false"),
        ("monitor_cancel", r#"{"monitor": 1.0}"#, "monitor", "an integer in ["),
        ("monitor_cancel", r#"{"monitor": "1"}"#, "monitor", "an integer in ["),
        ("monitor_cancel", r#"{"monitor": 18446744073709551615}"#, "monitor", "an integer in ["),
        ("telemetry", r#"{"signals": [], "rate_hz": "5"}"#, "rate_hz", "a number from 0.01 to 100"),
        ("telemetry", r#"{"signals": [], "rate_hz": 1e400}"#, "rate_hz", "a number from 0.01 to 100"),
        ("step", r#"{"cycles": 2.0}"#, "cycles", "an integer in [1, 1000000]"),
        ("step", r#"{"cycles": "2"}"#, "cycles", "an integer in [1, 1000000]"),
        ("step", r#"{"cycles": 1e400}"#, "cycles", "an integer in [1, 1000000]"),
        ("stats", r#"{"protocol": "1"}"#, "protocol", "an integer"),
        ("stats", r#"{"protocol": 1.0}"#, "protocol", "an integer"),
    ] {
        let e = refused(verb, payload);
        assert_eq!(e.kind, "bad_request", "{verb} {payload}: {}", e.message);
        let start = format!("`{verb}`: argument `{arg}`: expected {expected}");
        assert!(e.message.starts_with(&start), "{verb} {payload}: {}", e.message);
    }
    let e = refused("step", r#"{"cycles": 1e400}"#);
    assert_eq!(
        e.message,
        "`step`: argument `cycles`: expected an integer in [1, 1000000], got 1e400 (beyond the range of a 64-bit float)"
    );
    // A number beyond a float's range in an argument that is not a number
    // is named by its argument too, and an unknown one is still unknown.
    let e = refused("activate", r#"{"skills": ["a", -1e999]}"#);
    assert!(e.message.starts_with("`activate`: argument `skills`: expected a list of strings"), "{}", e.message);
    let e = refused("stats", r#"{"big": 1e400}"#);
    assert_eq!(e.message, "`stats`: unknown argument `big`");
    let e = refused("stats", r#"{"protocol": 2}"#);
    assert_eq!(
        (e.kind, e.message.as_str()),
        ("protocol", "protocol 2 is not supported; this manager speaks protocol 1")
    );
}

fn set_param_value(value: &str) -> Result<Value, WireError> {
    let payload = format!(r#"{{"skill": "s", "param": "p", "value": {value}}}"#);
    match decode_request("set_param", payload.as_bytes())? {
        Decoded::Manager(Request::SetParam { value, .. }) => Ok(value),
        other => panic!("{other:?}"),
    }
}

#[test]
fn a_parameter_value_of_any_type_reaches_the_manager_to_be_checked() {
    // The manager checks it against the parameter (and refuses it as
    // `bad_param` naming the expected type and range): the link only
    // reads the value.
    assert_eq!(set_param_value("2").unwrap(), Value::I64(2));
    assert_eq!(set_param_value("2.0").unwrap(), Value::F64(2.0));
    assert_eq!(set_param_value("\"far\"").unwrap(), Value::Str("far".into()));
    assert_eq!(set_param_value("[1, 2]").unwrap(), Value::I64s(vec![1, 2].into()));
    assert_eq!(set_param_value("[1, 2.5, \"inf\"]").unwrap(), Value::F64s(vec![1.0, 2.5, f64::INFINITY].into()));
    assert_eq!(set_param_value(r#"{"$bytes": "AP8H"}"#).unwrap(), Value::Bytes(vec![0u8, 255, 7].into()));
    assert!(matches!(set_param_value(r#"{"x": 1}"#).unwrap(), Value::Record(_)));
    // Beyond 64 bits: a float, which no integer parameter takes.
    assert_eq!(set_param_value("9223372036854775808").unwrap(), Value::F64(9_223_372_036_854_775_808.0));
    assert_eq!(set_param_value("-1e20").unwrap(), Value::F64(-1e20));
    // Beyond a float's range: infinite, which no parameter takes.
    assert_eq!(set_param_value("1e400").unwrap(), Value::F64(f64::INFINITY));
    assert_eq!(set_param_value("-1e400").unwrap(), Value::F64(f64::NEG_INFINITY));
    // JSON that is no value of any type is a wrongly typed argument.
    for bad in ["null", "[\"a\"]", "[[1]]", r#"{"x": null}"#, "[1e400]"] {
        let e = set_param_value(bad).unwrap_err();
        assert_eq!(e.kind, "bad_request", "{bad}");
        assert!(e.message.starts_with("`set_param`: argument `value`: expected a value"), "{bad}: {}", e.message);
    }
}

#[test]
fn a_number_beyond_a_float_still_leaves_bad_json_refused() {
    let e = refused("set_param", r#"{"skill": "s", "param": "p", "value": 1e400"#);
    assert!(e.message.starts_with("`set_param`: the payload is not JSON: "), "{}", e.message);
    let e = refused("set_param", r#"[1e400]"#);
    assert!(e.message.starts_with("`set_param`: the payload is not JSON: "), "{}", e.message);
}

#[test]
fn oversized_requests_are_refused_with_the_limit() {
    let long = "x".repeat(MAX_NAME_CHARS + 1);
    let e = decode_request("query", format!(r#"{{"signal": "{long}"}}"#).as_bytes()).unwrap_err();
    assert_eq!(
        (e.kind, e.message.as_str()),
        ("bad_request", "`query`: argument `signal` is 257 characters long, at most 256 are taken")
    );
    let e = decode_request("deactivate", format!(r#"{{"skills": ["a", "{long}"]}}"#).as_bytes()).unwrap_err();
    assert!(e.message.contains("argument `skills` is 257 characters long"), "{}", e.message);
    let many = vec!["a"; MAX_LIST_ITEMS + 1];
    let e = decode_request("activate", json!({"skills": many}).to_string().as_bytes()).unwrap_err();
    assert!(e.message.contains("has 1025 items, at most 1024 are taken"), "{}", e.message);
    let huge = format!(r#"{{"signal": "{}"}}"#, "y".repeat(MAX_PAYLOAD_BYTES));
    let e = decode_request("query", huge.as_bytes()).unwrap_err();
    assert!(e.message.contains("at most 65536 are taken"), "{}", e.message);
    // A long condition is fine up to its own limit; a name of exactly the limit too.
    let cond = format!(r#"{{"condition": "{} > 1"}}"#, "a".repeat(1000));
    assert!(decode_request("monitor_add", cond.as_bytes()).is_ok());
    let edge = format!(r#"{{"signal": "{}"}}"#, "x".repeat(MAX_NAME_CHARS));
    assert!(decode_request("query", edge.as_bytes()).is_ok());
}

fn query_many(payload: &str) -> Result<Vec<String>, WireError> {
    match decode_request("query_many", payload.as_bytes())? {
        Decoded::Manager(Request::QuerySignals { signals }) => Ok(signals),
        other => panic!("{other:?}"),
    }
}

#[test]
fn query_many_takes_1_to_256_signal_names_in_order_repeats_too() {
    assert_eq!(
        query_many(r#"{"signals": ["odom", "sonar.range[3]", "odom"], "protocol": 1}"#).unwrap(),
        ["odom", "sonar.range[3]", "odom"]
    );
    let most = json!({"signals": vec!["odom"; MAX_QUERY_SIGNALS]}).to_string();
    assert_eq!(query_many(&most).unwrap().len(), 256);
    let edge = "x".repeat(MAX_NAME_CHARS);
    assert_eq!(query_many(&json!({"signals": ["a", edge]}).to_string()).unwrap()[1], edge);
    // Each refusal is a `bad_request` naming the argument, or the item, and the limit.
    let long = "x".repeat(MAX_NAME_CHARS + 1);
    for (payload, message) in [
        (
            json!({"signals": vec!["odom"; MAX_QUERY_SIGNALS + 1]}).to_string(),
            "`query_many`: argument `signals` has 257 signal names, it takes 1 to 256",
        ),
        (r#"{"signals": []}"#.into(), "`query_many`: argument `signals` has 0 signal names, it takes 1 to 256"),
        (
            json!({"signals": ["odom", long]}).to_string(),
            "`query_many`: argument `signals[1]` is 257 characters long, at most 256 are taken",
        ),
        (
            r#"{"signals": ["odom", 1]}"#.into(),
            "`query_many`: argument `signals[1]`: expected a string (a signal name), got 1",
        ),
        (
            r#"{"signals": [["odom"]]}"#.into(),
            "`query_many`: argument `signals[0]`: expected a string (a signal name), got an array",
        ),
        (
            r#"{"signals": "odom"}"#.into(),
            r#"`query_many`: argument `signals`: expected a list of 1 to 256 strings (signal names), got the string "odom" (a list of one is written ["odom"])"#,
        ),
        (
            r#"{"signals": {"odom": 1}}"#.into(),
            "`query_many`: argument `signals`: expected a list of 1 to 256 strings (signal names), got an object",
        ),
        (
            r#"{"signals": null}"#.into(),
            "`query_many`: argument `signals`: expected a list of 1 to 256 strings (signal names), got null",
        ),
        (
            r#"{"signals": 1e400}"#.into(),
            "`query_many`: argument `signals`: expected a list of 1 to 256 strings (signal names), got 1e400 (beyond the range of a 64-bit float)",
        ),
        (
            r#"{"signal": "odom"}"#.into(),
            "`query_many`: missing argument `signals` (a list of 1 to 256 strings (signal names))",
        ),
        (r#"{"signals": ["odom"], "signal": "odom"}"#.into(), "`query_many`: unknown argument `signal`"),
        (r#"{"signals": ["odom"], "cycle": 3}"#.into(), "`query_many`: unknown argument `cycle`"),
    ] {
        let e = query_many(&payload).unwrap_err();
        assert_eq!((e.kind, e.message.as_str()), ("bad_request", message), "{payload}");
    }
    // However the names are, the whole request stays within the payload cap.
    let e =
        query_many(&json!({"signals": vec!["x".repeat(MAX_NAME_CHARS); MAX_QUERY_SIGNALS]}).to_string()).unwrap_err();
    assert!(e.message.contains("at most 65536 are taken"), "{}", e.message);
}

fn monitor_condition(payload: &str) -> Result<MonitorCondition, WireError> {
    match decode_request("monitor_add", payload.as_bytes())? {
        Decoded::Manager(Request::AddMonitor { condition, .. }) => Ok(condition),
        other => panic!("{other:?}"),
    }
}

#[test]
fn monitor_add_takes_one_condition_or_any_of_several() {
    assert_eq!(monitor_condition(r#"{"condition": "cycle > 3"}"#).unwrap(), MonitorCondition::One("cycle > 3".into()));
    assert_eq!(
        decode_request(
            "monitor_add",
            br#"{"any": ["a.b", "cycle > 3"], "mode": "edge", "pause": true, "session": "aaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaa"}"#
        )
        .unwrap(),
        Decoded::Manager(Request::AddMonitor {
            condition: MonitorCondition::Any(vec!["a.b".into(), "cycle > 3".into()]),
            mode: MonitorMode::Edge,
            pause: true,
            report: Vec::new(),
            // The public id of the secret, never the secret itself.
            session: Some("2eee42b299cb44bb3d5dd0a02210ce29".into()),
            client: None,
        })
    );
    let sixty_four = json!({"any": vec!["cycle > 1"; MAX_ANY_CONDITIONS]}).to_string();
    assert!(matches!(monitor_condition(&sixty_four).unwrap(), MonitorCondition::Any(l) if l.len() == 64));
    for (payload, message) in [
        (
            r#"{"condition": "cycle > 1", "any": ["cycle > 2"]}"#,
            "`monitor_add`: give either `condition` (one) or `any` (a list), not both",
        ),
        (
            r#"{"mode": "edge"}"#,
            "`monitor_add`: missing argument `condition` (a string, or instead `any`: a list of 1 to 64 strings)",
        ),
        (r#"{"any": []}"#, "`monitor_add`: argument `any` has 0 conditions, it takes 1 to 64"),
        (r#"{"any": ["a", 3]}"#, "`monitor_add`: argument `any[1]`: expected a string (a condition), got 3"),
        (
            r#"{"any": "cycle > 1"}"#,
            r#"`monitor_add`: argument `any`: expected a list of 1 to 64 strings (conditions), got the string "cycle > 1" (a list of one is written ["cycle > 1"])"#,
        ),
        (
            r#"{"any": {"a": 1}}"#,
            "`monitor_add`: argument `any`: expected a list of 1 to 64 strings (conditions), got an object",
        ),
        (
            r#"{"any": null}"#,
            "`monitor_add`: argument `any`: expected a list of 1 to 64 strings (conditions), got null",
        ),
    ] {
        let e = refused("monitor_add", payload);
        assert_eq!((e.kind, e.message.as_str()), ("bad_request", message), "{payload}");
    }
    // The count and each condition's length are capped like a condition's.
    let e = refused("monitor_add", &json!({"any": vec!["cycle > 1"; MAX_ANY_CONDITIONS + 1]}).to_string());
    assert_eq!(e.message, "`monitor_add`: argument `any` has 65 conditions, it takes 1 to 64");
    let long = format!("{} > 1", "a".repeat(MAX_CONDITION_CHARS));
    let e = refused("monitor_add", &json!({"any": ["cycle > 1", long]}).to_string());
    assert_eq!(e.message, "`monitor_add`: argument `any[1]` is 4100 characters long, at most 4096 are taken");
    // However many, the whole request stays within the payload cap.
    let big = "a".repeat(MAX_CONDITION_CHARS - 4) + " > 1";
    let e = refused("monitor_add", &json!({"any": vec![big; 16]}).to_string());
    assert!(e.message.contains("at most 65536 are taken"), "{}", e.message);
}

#[test]
fn a_program_verbs_arguments_are_an_object_or_refused_saying_why() {
    let args = |payload: &[u8]| decode_args("mission", payload);
    assert_eq!(args(b"").unwrap(), json!({}));
    assert_eq!(args(b" \n\t").unwrap(), json!({}));
    assert_eq!(args(br#"{"goal": "dock", "speed": 0.5}"#).unwrap(), json!({"goal": "dock", "speed": 0.5}));
    // Every refusal is a `bad_request` naming the verb.
    let refused = |payload: &[u8]| {
        let e = args(payload).unwrap_err();
        assert_eq!(e.kind, "bad_request", "{}", e.message);
        e.message
    };
    // The size is checked before parsing, whatever the bytes.
    for filler in [b' ', b'x'] {
        let mut big = vec![filler; MAX_PAYLOAD_BYTES + 1];
        if filler == b' ' {
            big[..2].copy_from_slice(b"{}");
        }
        assert_eq!(refused(&big), "`mission`: the request is 65537 bytes, more than 65536");
    }
    let edge = format!(r#"{{"goal": "{}"}}"#, "x".repeat(MAX_PAYLOAD_BYTES - 12));
    assert_eq!(edge.len(), MAX_PAYLOAD_BYTES);
    assert!(args(edge.as_bytes()).is_ok());
    for payload in [&b"[1]"[..], b"3", b"\"dock\"", b"null"] {
        assert_eq!(refused(payload), "`mission`: the arguments must be a JSON object");
    }
    for payload in [&b"{"[..], b"{\"goal\": }", b"goal=dock", b"{\"speed\": 1e400}"] {
        let serde = serde_json::from_slice::<Json>(payload).unwrap_err();
        assert_eq!(refused(payload), format!("`mission`: the arguments are not JSON: {serde}"));
    }
}

#[test]
fn random_bytes_never_panic_the_decoder() {
    let mut x: u64 = 0x243F_6A88_85A3_08D3;
    for i in 0..20_000 {
        let len = i % 64;
        let bytes: Vec<u8> = (0..len)
            .map(|_| {
                x ^= x << 13;
                x ^= x >> 7;
                x ^= x << 17;
                (x & 0xff) as u8
            })
            .collect();
        let verb = VERBS[i % VERBS.len()];
        let _ = decode_request(verb, &bytes);
    }
}
