//! The tree builder: `yaml-rust2`'s events made into a [`Node`] tree with
//! positions, refusing the YAML a robot file may not use, and its scanner's
//! errors made into messages at the right place.

use std::collections::HashMap;
use std::fmt;

use yaml_rust2::parser::{Event, Parser};
use yaml_rust2::scanner::{Marker, ScanError, TScalarStyle};

use super::lex::{check_control_characters, check_layout};
use super::{Node, Pos, Spanned, MAX_DEPTH};

/// A YAML error: the file is not YAML, or uses YAML a robot file may not.
/// It reads `LINE:COL: message` (the reader does not know the file); as a
/// [`Diagnostic`](crate::diagnostic::Diagnostic) (`Diagnostic::from`, then
/// `in_file`) it is a robot file's error like any other.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ParseError {
    pub pos: Pos,
    pub message: String,
}

impl ParseError {
    pub(super) fn new(pos: Pos, message: impl Into<String>) -> ParseError {
        ParseError { pos, message: message.into() }
    }
}

impl fmt::Display for ParseError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}: {}", self.pos, self.message)
    }
}

impl std::error::Error for ParseError {}

/// A list or mapping being built.
enum Frame {
    Seq {
        pos: Pos,
        items: Vec<Spanned<Node>>,
    },
    Map {
        pos: Pos,
        entries: Vec<(Spanned<String>, Spanned<Node>)>,
        key: Option<Spanned<String>>,
        /// Each key's line, to report duplicates.
        lines: HashMap<String, usize>,
    },
}

impl Frame {
    fn expects_key(&self) -> bool {
        matches!(self, Frame::Map { key: None, .. })
    }
}

/// Marks every position in `node` as one of source file `src` (see
/// [`Pos::src`]).
pub fn set_src(node: &mut Spanned<Node>, src: usize) {
    node.pos = node.pos.in_src(src);
    match &mut node.value {
        Node::Map(entries) => {
            for (key, value) in entries {
                key.pos = key.pos.in_src(src);
                set_src(value, src);
            }
        }
        Node::Seq(items) => {
            for item in items {
                set_src(item, src);
            }
        }
        _ => {}
    }
}

/// Parses one YAML document into a node tree. An empty document (nothing but
/// comments and blanks) is `Null` at 1:1. A mapping's position is its first
/// key's (or its `{`); an empty mapping value (`key:` and nothing) is `Null`
/// at the key's position.
pub fn parse(source: &str) -> Result<Spanned<Node>, ParseError> {
    // yaml-rust2 does not skip a byte-order mark; editors do not show one.
    let source = source.strip_prefix('\u{feff}').unwrap_or(source);
    check_control_characters(source)?;
    let mut brackets = Vec::new();
    check_layout(source, &mut brackets)?;
    let mut parser = Parser::new_from_str(source);
    let mut stack: Vec<Frame> = Vec::new();
    let mut root: Option<Spanned<Node>> = None;
    let mut documents = 0usize;
    loop {
        let mut implicit_null = false;
        let (event, mark) = parser.next_token().map_err(|e| scan_error(source, &e, &brackets))?;
        let pos = Pos::from_marker(&mark);
        let done = match event {
            Event::StreamEnd => break,
            Event::Nothing | Event::StreamStart | Event::DocumentEnd => continue,
            Event::DocumentStart => {
                documents += 1;
                if documents > 1 {
                    return Err(ParseError::new(
                        pos,
                        "a robot file holds one YAML document, but a second one starts here",
                    ));
                }
                continue;
            }
            Event::Alias(_) => return Err(anchor_error(pos)),
            Event::Scalar(text, style, anchor, tag) => {
                if anchor != 0 {
                    return Err(anchor_error(anchor_pos(source, &mark)));
                }
                if tag.is_some() {
                    return Err(tag_error(pos));
                }
                if let Some(Frame::Map { key, lines, .. }) = stack.last_mut() {
                    if key.is_none() {
                        if let Some(first) = lines.insert(text.clone(), pos.line) {
                            return Err(ParseError::new(
                                pos,
                                format!("duplicate key `{text}` (first given on line {first})"),
                            ));
                        }
                        *key = Some(Spanned::new(text, pos));
                        continue;
                    }
                }
                let plain = style == TScalarStyle::Plain;
                implicit_null = plain && text.is_empty();
                let node = if plain && matches!(text.as_str(), "" | "~" | "null" | "Null" | "NULL") {
                    Node::Null
                } else {
                    Node::Scalar { text, plain }
                };
                Spanned::new(node, pos)
            }
            Event::SequenceStart(anchor, ref tag) | Event::MappingStart(anchor, ref tag) => {
                if anchor != 0 {
                    return Err(anchor_error(anchor_pos(source, &mark)));
                }
                if tag.is_some() {
                    return Err(tag_error(pos));
                }
                if stack.last().is_some_and(Frame::expects_key) {
                    return Err(ParseError::new(pos, "a mapping key must be a plain name, not a list or mapping"));
                }
                if stack.len() >= MAX_DEPTH {
                    return Err(ParseError::new(
                        pos,
                        format!("lists and mappings nest deeper than {MAX_DEPTH} levels"),
                    ));
                }
                // A block mapping's start marker sits at the `:` after its
                // first key, so `Map` takes the first key's position instead.
                stack.push(if matches!(event, Event::SequenceStart(..)) {
                    Frame::Seq { pos, items: Vec::new() }
                } else {
                    Frame::Map { pos, entries: Vec::new(), key: None, lines: HashMap::new() }
                });
                continue;
            }
            Event::SequenceEnd | Event::MappingEnd => match stack.pop() {
                Some(Frame::Seq { pos, items }) => Spanned::new(Node::Seq(items), pos),
                Some(Frame::Map { pos, entries, .. }) => {
                    let pos = entries.first().map_or(pos, |(k, _)| pos.min(k.pos));
                    Spanned::new(Node::Map(entries), pos)
                }
                None => return Err(ParseError::new(pos, "unbalanced YAML structure")),
            },
        };
        // `done` is a complete node: hand it to its parent.
        match stack.last_mut() {
            None => root = Some(done),
            Some(Frame::Seq { items, .. }) => items.push(done),
            Some(Frame::Map { entries, key, .. }) => match key.take() {
                // An empty value's marker is wherever the next token is;
                // the key is a better place to point at.
                Some(k) if done.value.is_null() && implicit_null => {
                    let pos = k.pos;
                    entries.push((k, Spanned::new(Node::Null, pos)));
                }
                Some(k) => entries.push((k, done)),
                None => return Err(ParseError::new(done.pos, "unbalanced YAML structure")),
            },
        }
    }
    Ok(match root {
        Some(root) if !root.value.is_null() => root,
        _ => Spanned::new(Node::Null, Pos::START),
    })
}

/// Where the `&` of the anchor on the node at `mark` is: the last `&` before
/// the node's marker (a block mapping's marker sits after its first key).
fn anchor_pos(source: &str, mark: &Marker) -> Pos {
    let mut found = Pos::from_marker(mark);
    let mut at = Pos::START;
    for c in source.chars().take(mark.index()) {
        if c == '&' {
            found = at;
        }
        if c == '\n' {
            at = Pos::new(at.line + 1, 1);
        } else {
            at.col += 1;
        }
    }
    found
}

fn anchor_error(pos: Pos) -> ParseError {
    ParseError::new(pos, "anchors and aliases (`&name`, `*name`) are not supported in robot files")
}

fn tag_error(pos: Pos) -> ParseError {
    ParseError::new(
        pos,
        "YAML tags (`!!str`, `!name`) are not supported in robot files; quote a value to make it a string",
    )
}

/// The flow collection a scanner error at `at` comes from not closing, if
/// any: given the brackets [`check_layout`](super::lex::check_layout) found in order (outside quotes
/// and comments), the first `[` or `{` closed by the wrong bracket before
/// `at`, or else the innermost one still open at `at` when it was opened on
/// an earlier line (or the scanner says it expected the closing bracket).
fn unclosed_bracket(brackets: &[(char, Pos)], at: Pos, info: &str) -> Option<ParseError> {
    let closer = |open: char| if open == '[' { ']' } else { '}' };
    let mut open: Vec<(char, Pos)> = Vec::new();
    for &(c, p) in brackets.iter().take_while(|(_, p)| (p.line, p.col) < (at.line, at.col)) {
        match c {
            '[' | '{' => open.push((c, p)),
            _ => match open.pop() {
                Some((o, q)) if closer(o) != c => {
                    return Some(ParseError::new(
                        q,
                        format!(
                            "missing `{}` to close the `{o}` at line {}, column {} (the `{c}` at line {}, column {} \
                             comes first)",
                            closer(o),
                            q.line,
                            q.col,
                            p.line,
                            p.col
                        ),
                    ));
                }
                _ => {}
            },
        }
    }
    let (o, q) = open.last().copied()?;
    let expected = info.contains(&format!("'{}'", closer(o)));
    if q.line >= at.line && !expected {
        return None;
    }
    Some(ParseError::new(
        q,
        format!(
            "missing `{}` to close the `{o}` at line {}, column {} (the YAML parser stopped at line {}, column {}: {info})",
            closer(o),
            q.line,
            q.col,
            at.line,
            at.col
        ),
    ))
}

/// Turns a scanner error into a `ParseError`. Tabs in indentation get their
/// own message, at the tab itself (the scanner reports the character after);
/// a `[` or `{` left open is named, at its own line and column (the scanner
/// stops somewhere after it, often on the next line).
fn scan_error(source: &str, e: &ScanError, brackets: &[(char, Pos)]) -> ParseError {
    let pos = Pos::from_marker(e.marker());
    if e.info().contains("unknown anchor") {
        return anchor_error(pos);
    }
    if !e.info().contains("quoted") && !e.info().contains("block scalar") && !e.info().contains("tab") {
        if let Some(err) = unclosed_bracket(brackets, pos, e.info()) {
            return err;
        }
    }
    if e.info().contains("tab") {
        if let Some(line) = source.lines().nth(pos.line - 1) {
            let indent = line.chars().take_while(|c| *c == ' ' || *c == '\t');
            if let Some(i) = indent.into_iter().position(|c| c == '\t') {
                return ParseError::new(
                    Pos::new(pos.line, i + 1),
                    "tab character in indentation; indent YAML with spaces",
                );
            }
        }
    }
    ParseError::new(pos, format!("invalid YAML: {}", e.info()))
}

#[cfg(test)]
mod tests {
    use super::*;
    use situate_core::value::Value;

    fn p(line: usize, col: usize) -> Pos {
        Pos::new(line, col)
    }

    fn err(source: &str) -> String {
        parse(source).expect_err("expected an error").to_string()
    }

    #[test]
    fn builds_a_tree_with_exact_positions() {
        let src = "robot: toybot\ncycle:\n  rate_hz: 20\ndevices:\n  - name: sonar\n    params: {noise_m: 0.01, xs: [1, 2.5]}\n";
        let root = parse(src).unwrap();
        assert_eq!(root.pos, p(1, 1));
        let map = root.value.as_map().unwrap();
        let keys: Vec<_> = map.iter().map(|(k, _)| (k.value.as_str(), k.pos)).collect();
        assert_eq!(keys, [("robot", p(1, 1)), ("cycle", p(2, 1)), ("devices", p(4, 1))]);
        assert_eq!(map[0].1, Spanned::new(Node::plain("toybot"), p(1, 8)));
        let cycle = root.value.get("cycle").unwrap();
        assert_eq!(cycle.pos, p(3, 3));
        let rate = cycle.value.get("rate_hz").unwrap();
        assert_eq!((rate.pos, rate.value.to_value()), (p(3, 12), Some(Value::I64(20))));
        let devices = root.value.get("devices").unwrap();
        assert_eq!(devices.pos, p(5, 3));
        let item = &devices.value.as_seq().unwrap()[0];
        assert_eq!(item.pos, p(5, 5));
        let params = item.value.get("params").unwrap();
        assert_eq!(params.pos, p(6, 13));
        let (k, v) = &params.value.as_map().unwrap()[1];
        assert_eq!((k.value.as_str(), k.pos, v.pos), ("xs", p(6, 29), p(6, 33)));
        assert_eq!(v.value.to_f64s(), Some(Value::F64s(vec![1.0, 2.5].into())));
        assert_eq!(v.value.as_seq().unwrap()[1].pos, p(6, 37));
    }

    #[test]
    fn columns_count_characters_not_bytes() {
        let root = parse("héllo: wörld\nb: 1\n").unwrap();
        let (k, v) = &root.value.as_map().unwrap()[0];
        assert_eq!((k.pos, v.pos), (p(1, 1), p(1, 8)));
    }

    #[test]
    fn empty_documents_are_null_at_the_start() {
        for src in ["", "\n\n", "# only a comment\n", "---\n", "---\n...\n"] {
            assert_eq!(parse(src).unwrap(), Spanned::new(Node::Null, Pos::START), "{src:?}");
        }
    }

    #[test]
    fn a_byte_order_mark_is_skipped() {
        let root = parse("\u{feff}a: 1\n").unwrap();
        assert_eq!(root.value.as_map().unwrap()[0].0, Spanned::new("a".to_string(), p(1, 1)));
    }

    #[test]
    fn top_level_scalars_and_lists_are_returned_as_such() {
        assert_eq!(parse("hello\n").unwrap(), Spanned::new(Node::plain("hello"), p(1, 1)));
        let root = parse("- a\n- b\n").unwrap();
        assert_eq!(root.pos, p(1, 1));
        assert_eq!(root.value.as_seq().unwrap()[1].pos, p(2, 3));
    }

    #[test]
    fn syntax_errors_carry_the_scanner_position() {
        assert_eq!(
            err("a: [1, b: c: d]\n"),
            "1:13: invalid YAML: while parsing a flow mapping, did not find expected ',' or '}'"
        );
        assert_eq!(
            err("a: \"open\n"),
            "1:4: invalid YAML: while scanning a quoted scalar, found unexpected end of stream"
        );
    }

    #[test]
    fn a_bracket_left_open_is_named_where_it_was_opened() {
        // The scanner stops on the next line; the `[` is on this one.
        assert_eq!(
            err("a: [1, 2\n"),
            "1:4: missing `]` to close the `[` at line 1, column 4 (the YAML parser stopped at line 2, column 1: \
             while parsing a flow sequence, expected ',' or ']')"
        );
        // In a block list, the next item.
        assert_eq!(
            err("w:\n  - [0, 0, 4.4, 0\n  - [1, 2]\n"),
            "2:5: missing `]` to close the `[` at line 2, column 5 (the YAML parser stopped at line 3, column 5: \
             while parsing a flow sequence, expected ',' or ']')"
        );
        // Closed by the wrong bracket: both places.
        assert_eq!(
            err("cars:\n  - {rect: [0, 0, 1, 1, door: south}\n  - {rect: [2, 0, 3, 1]}\n"),
            "2:12: missing `]` to close the `[` at line 2, column 12 (the `}` at line 2, column 36 comes first)"
        );
        assert_eq!(
            err("a: {b: 1\nc: 2\n"),
            "1:4: missing `}` to close the `{` at line 1, column 4 (the YAML parser stopped at line 2, column 2: \
             while parsing a flow mapping, did not find expected ',' or '}')"
        );
        // Brackets in quotes and comments are not brackets; a list may span lines.
        assert_eq!(
            err("a: '['  # [\nb: [1,\n  2]\nc: [3\n"),
            "4:4: missing `]` to close the `[` at line 4, column 4 (the YAML parser stopped at line 5, column 1: \
             while parsing a flow sequence, expected ',' or ']')"
        );
        // A quote left open inside a list is the quote's error.
        assert_eq!(
            err("a: [1, \"x]\n"),
            "1:8: invalid YAML: while scanning a quoted scalar, found unexpected end of stream"
        );
    }

    #[test]
    fn duplicate_keys_name_the_first_line() {
        assert_eq!(err("a: 1\nb:\n  x: 1\n  y: 2\n  x: 3\n"), "5:3: duplicate key `x` (first given on line 3)");
        // Keys in different mappings do not clash.
        assert!(parse("a: {x: 1}\nb: {x: 2}\n").is_ok());
    }

    #[test]
    fn anchors_aliases_and_tags_are_rejected() {
        let msg = "anchors and aliases (`&name`, `*name`) are not supported in robot files";
        assert_eq!(err("a: &x 1\n"), format!("1:4: {msg}"));
        assert_eq!(err("a: &x\n  b: 1\n"), format!("1:4: {msg}"));
        assert_eq!(err("a:\n  &x b: 1\n"), format!("2:3: {msg}"));
        assert_eq!(err("a: *x\n"), format!("1:4: {msg}"));
        assert_eq!(err("- &x [1]\n- *x\n"), format!("1:3: {msg}"));
        assert!(err("a: !!str 5\n").starts_with("1:10: YAML tags"));
    }

    #[test]
    fn non_scalar_keys_and_second_documents_are_rejected() {
        assert_eq!(err("? [a]\n: 1\n"), "1:3: a mapping key must be a plain name, not a list or mapping");
        assert_eq!(err("a: 1\n---\nb: 2\n"), "2:1: a robot file holds one YAML document, but a second one starts here");
    }

    #[test]
    fn deep_nesting_is_an_error_not_a_crash() {
        let deep = "[".repeat(200) + &"]".repeat(200);
        assert_eq!(err(&deep), "1:65: lists and mappings nest deeper than 64 levels");
        let ok = "[".repeat(MAX_DEPTH) + &"]".repeat(MAX_DEPTH);
        assert!(parse(&ok).is_ok());
    }

    #[test]
    fn no_input_panics() {
        // Truncations of a realistic file, then random strings made of YAML's
        // significant characters.
        let src = "robot: toybot # c\ncycle: {rate_hz: 20}\ndevices:\n  - name: \"sonar\"\n    params: {noise_m: 0.01, v: [1, 2]}\n    remap:\n      range: sonar.range\n  - |\n    text\n  - 'q''s'\n";
        for (i, _) in src.char_indices() {
            let _ = parse(&src[..i]);
        }
        let alphabet: Vec<char> = " \n\t-:?,[]{}#&*!|>'\"%@`.~0a1eé：\\x".chars().collect();
        let mut seed: u64 = 0x9e37_79b9_7f4a_7c15;
        for _ in 0..20_000 {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            let len = (seed % 40) as usize;
            let mut s = String::new();
            let mut r = seed;
            for _ in 0..len {
                r = r.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
                s.push(alphabet[(r >> 33) as usize % alphabet.len()]);
            }
            let _ = parse(&s);
        }
        // Random bytes (NUL, CR, tabs, broken UTF-8 made lossy), mostly ASCII.
        for _ in 0..5_000 {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            let mut r = seed;
            let bytes: Vec<u8> = (0..seed % 48)
                .map(|_| {
                    r = r.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
                    let b = (r >> 33) as u8;
                    if b & 0x80 == 0 || r >> 62 == 0 {
                        b
                    } else {
                        b"\t\n\r :-[{"[b as usize % 8]
                    }
                })
                .collect();
            let _ = parse(&String::from_utf8_lossy(&bytes));
        }
    }
}
