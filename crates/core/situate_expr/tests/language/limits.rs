//! The limits on size and nesting, a small stack, and no panic on garbled
//! or arbitrary input.

use super::*;

#[test]
fn limits() {
    // Source length.
    let ok = format!("{:<width$}", "flag", width = MAX_SOURCE_BYTES);
    assert_eq!(ok.len(), MAX_SOURCE_BYTES);
    assert!(compile(&ok).is_ok());
    let long = format!("{ok} ");
    assert_err(&long, 1, &["too long", "4097 bytes", "4096"]);
    assert!(compile(&"(".repeat(1_000_000)).is_err());

    // Nesting depth: parentheses.
    let nest = |n: usize| format!("{}flag{}", "(".repeat(n), ")".repeat(n));
    assert_eq!(eval(&nest(MAX_DEPTH)), Some(false));
    assert_err(&nest(MAX_DEPTH + 1), MAX_DEPTH + 1, &["nests too deeply", "64"]);
    assert_err(&"(".repeat(4000), MAX_DEPTH + 1, &["nests too deeply"]);
    // Unary operators, brackets and calls count too.
    let nots = |n: usize| format!("{}flag", "!".repeat(n));
    assert_eq!(eval(&nots(MAX_DEPTH)), Some(false));
    assert_err(&nots(MAX_DEPTH + 1), MAX_DEPTH + 1, &["nests too deeply"]);
    assert_err(&"-".repeat(4000), MAX_DEPTH + 1, &["nests too deeply"]);
    let calls = |n: usize| format!("{}1{} > 0", "abs(".repeat(n), ")".repeat(n));
    assert_eq!(eval(&calls(MAX_DEPTH)), Some(true));
    assert_err(&calls(MAX_DEPTH + 1), 4 * MAX_DEPTH + 4, &["nests too deeply"]);
    let index = |n: usize| format!("{}0{} >= 0", "counts[".repeat(n), "]".repeat(n));
    assert!(compile(&index(MAX_DEPTH)).is_ok());
    assert_err(&index(MAX_DEPTH + 1), 7 * MAX_DEPTH + 7, &["nests too deeply"]);
    // The deepest parser recursion: every precedence level at every nesting level.
    let mut worst = String::from("1");
    for _ in 0..MAX_DEPTH / 2 {
        worst = format!("flag || flag && flag == 1 < 1 + 1 * -({worst})");
    }
    assert!(compile(&worst).is_err());

    // Node count: `1 + 1 + … + 1 > 0` with k ones has 2k + 1 nodes.
    let sum = |k: usize| format!("{} > 0", vec!["1"; k].join(" + "));
    assert_eq!(eval(&sum(127)), Some(true));
    let e = err(&sum(128));
    assert!(e.message.contains("too large") && e.message.contains("256"), "{e}");
    assert_eq!(e.column, sum(128).find('>').unwrap() + 1);
    // Many nodes evaluate without trouble (a left-leaning chain of 255).
    let ors = format!("{} || true", vec!["flag"; 127].join(" || "));
    assert_eq!(eval(&ors), Some(true));
    assert_eq!(eval_with(&ors, &Vals::default()), Some(true));
}

#[test]
fn deep_conditions_fit_a_small_stack() {
    // The deepest parser recursion the limits allow, on a 512 KiB stack
    // (a quarter of a default thread's), in debug builds too.
    let handle = std::thread::Builder::new()
        .stack_size(512 * 1024)
        .spawn(|| {
            let d = MAX_DEPTH;
            let parens = format!("{}flag{}", "(".repeat(d), ")".repeat(d));
            let calls = format!("{}1{} > 0", "abs(".repeat(d), ")".repeat(d));
            let mins = format!("{}1{} > 0", "min(1, ".repeat(d), ")".repeat(d));
            let index = format!("{}0{} >= 0", "counts[".repeat(d), "]".repeat(d));
            let mut chain = String::from("1");
            for _ in 0..d {
                chain = format!("flag || flag && flag == 1 < 1 + 1 * ({chain})");
            }
            let mut right = String::from("flag");
            for _ in 0..d {
                right = format!("flag && ({right})");
            }
            let mut results = Vec::new();
            for src in [&parens, &calls, &mins, &index, &chain, &right] {
                results.push(compile(src).ok().and_then(|c| c.eval(&standard())));
            }
            results
        })
        .unwrap();
    let results = handle.join().unwrap();
    // `counts[counts[…]]` runs out of range (counts[0] is 7); the chain does not type-check.
    assert_eq!(results, [Some(false), Some(true), Some(true), None, None, Some(false)]);
}

/// Compiles `src` (which must not panic) and, if it compiles, evaluates it
/// against several lookups; checks the error column is inside the source.
fn exercise(src: &str) {
    match compile(src) {
        Ok(c) => {
            let bad = Vals::default()
                .with("sonar.range", Value::Str(Arc::from("")))
                .with("barcode.id", Value::F64(f64::NAN))
                .with("odom.speed", Value::F64(f64::INFINITY))
                .with("label", Value::I64(i64::MIN))
                .with("counts", Value::I64s(Vec::new().into()))
                .with("raw", Value::Bool(true))
                .with("flag", Value::Record(Arc::default()));
            for vals in [standard(), Vals::default(), bad] {
                let _ = c.eval(&vals);
            }
            assert!(c.refs().len() == c.ref_names().len());
        }
        Err(e) => {
            assert!(e.column >= 1 && e.column <= src.chars().count() + 1, "`{src}`: {e}");
            let _ = e.pointer(src);
        }
    }
}

const FRAGMENTS: &[&str] = &[
    "sonar.range",
    "sonar.ok",
    "barcode.id",
    "odom.speed",
    "label",
    "raw",
    "pose",
    "pose.x",
    "counts",
    "gains",
    "flag",
    "nope",
    "abs",
    "min",
    "max",
    "len",
    "true",
    "false",
    "0",
    "1",
    "-1",
    "2.5",
    "1e3",
    "1e400",
    ".5",
    "'s'",
    "\"t\"",
    "'\\''",
    "'",
    "\"",
    "\\",
    "(",
    ")",
    "[",
    "]",
    ",",
    "!",
    "-",
    "+",
    "*",
    "/",
    "%",
    "<",
    "<=",
    ">",
    ">=",
    "==",
    "!=",
    "=",
    "&&",
    "||",
    "&",
    "|",
    " ",
    "\t",
    "\n",
    ".",
    "é",
    "∧",
    "_",
    "x",
    "9",
];

/// Deterministic garbling of valid conditions and random token soup.
#[test]
fn no_panic_on_garbled_inputs() {
    let seeds = [
        "sonar.range[0] < 0.25 && barcode.id == 3",
        "min(sonar.range[0], sonar.range[1], 2) < abs(odom.speed) || !sonar.ok",
        "len(label) > 2 && label != 'dock' && counts[barcode.id - 1] % 2 == 1",
        "(((gains[1] + 1) * 2 - 3 / (odom.speed)) >= max(1, 2, pose.x)) == flag",
    ];
    let mut state: u64 = 0x9e37_79b9_7f4a_7c15;
    let mut rand = move |n: usize| {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state % n as u64) as usize
    };
    for _ in 0..3000 {
        let seed: Vec<char> = seeds[rand(seeds.len())].chars().collect();
        let mut chars = seed.clone();
        for _ in 0..=rand(4) {
            let at = rand(chars.len() + 1);
            match rand(3) {
                0 if at < chars.len() => {
                    chars.remove(at);
                }
                1 => chars.insert(at, seed[rand(seed.len())]),
                _ => {
                    let frag = FRAGMENTS[rand(FRAGMENTS.len())];
                    for (k, c) in frag.chars().enumerate() {
                        chars.insert(at + k, c);
                    }
                }
            }
        }
        exercise(&chars.into_iter().collect::<String>());
        let soup: String = (0..rand(30)).map(|_| FRAGMENTS[rand(FRAGMENTS.len())]).collect();
        exercise(&soup);
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(1000))]

    #[test]
    fn no_panic_on_arbitrary_strings(src in any::<String>()) {
        exercise(&src);
    }

    #[test]
    fn no_panic_on_token_soup(parts in prop::collection::vec(prop::sample::select(FRAGMENTS), 0..40)) {
        exercise(&parts.concat());
        exercise(&parts.join(" "));
    }

    #[test]
    fn arithmetic_matches_f64(a in -1e6f64..1e6, b in -1e6f64..1e6) {
        let src = format!("{a:e} + {b:e} * 2 - {a:e} / 4 > {b:e}");
        prop_assert_eq!(eval(&src), Some(a + b * 2.0 - a / 4.0 > b));
    }
}
