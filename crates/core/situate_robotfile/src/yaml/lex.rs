//! The line lexer run before the YAML scanner: it refuses control
//! characters, tabs and fullwidth colons where YAML would misread them, at
//! their own line and column, and notes where the flow brackets are.

use super::{ParseError, Pos};

/// Refuses control characters, which editors hide and the scanner misreads
/// (it takes a NUL for the end of the file). Tab, line feed and the carriage
/// return of a CRLF line end are the only ones a robot file may contain.
pub(super) fn check_control_characters(source: &str) -> Result<(), ParseError> {
    let mut at = Pos::START;
    let mut chars = source.chars().peekable();
    while let Some(c) = chars.next() {
        match c {
            '\n' => {
                at = Pos::new(at.line + 1, 1);
                continue;
            }
            '\r' if chars.peek() == Some(&'\n') => {}
            '\t' => {}
            c if c.is_control() => return Err(ParseError::new(at, control_message(c))),
            _ => {}
        }
        at.col += 1;
    }
    Ok(())
}

const TAB_IN_INDENTATION: &str = "tab character in indentation; indent YAML with spaces";

/// Where the scanner of a line is, for [`check_layout`].
#[derive(Clone, Copy, PartialEq, Eq)]
enum Layout {
    /// Between tokens or in a plain scalar.
    Plain,
    /// Inside a `'…'` scalar that goes on to the next line.
    Single,
    /// Inside a `"…"` scalar that goes on to the next line.
    Double,
    /// In the text of a `|` or `>` block scalar whose owner (the key or `-`)
    /// is at column `owner` (0-based); `indent` is its text's indentation
    /// once known.
    Block { owner: usize, indent: Option<usize> },
}

/// Refuses tabs and fullwidth colons where YAML would misread them, at their
/// own line and column. The scanner reports these late and elsewhere (a tab
/// after `-` even shifts the nested mapping silently), so this lexes the
/// file's lines first:
///
/// * a tab in a line's indentation (top level, nested mappings, continuation
///   lines of flow collections and scalars) or right after a block `-` or
///   `?` is "in indentation";
/// * any other tab outside quoted strings, block scalars and comments is an
///   error too, unless only blanks (or a comment) follow it on its line;
/// * a fullwidth colon `：` outside quotes and comments is a typo for `:`;
/// * so is other Unicode white space (no-break space, ideographic space) in
///   indentation.
///
/// Lines whose only content is blanks or a comment may hold tabs.
pub(super) fn check_layout(source: &str, brackets: &mut Vec<(char, Pos)>) -> Result<(), ParseError> {
    let mut mode = Layout::Plain;
    // Depth of `[` and `{`.
    let mut flow = 0usize;
    for (n, raw) in source.split('\n').enumerate() {
        let line: Vec<char> = raw.strip_suffix('\r').unwrap_or(raw).chars().collect();
        let at = |i: usize| Pos::new(n + 1, i + 1);
        let len = line.len();
        let spaces = line.iter().take_while(|c| **c == ' ').count();
        let lead = line.iter().take_while(|c| **c == ' ' || **c == '\t').count();
        if lead == len {
            continue; // blank
        }
        let first_tab = line[..lead].iter().position(|c| *c == '\t');
        if let Layout::Block { owner, indent } = mode {
            match indent {
                Some(k) if spaces >= k => continue,
                None if spaces > owner => {
                    mode = Layout::Block { owner, indent: Some(spaces) };
                    continue;
                }
                _ if line[spaces] == '\t' => return Err(ParseError::new(at(spaces), TAB_IN_INDENTATION)),
                _ => mode = Layout::Plain,
            }
        }
        if mode == Layout::Plain && line[lead] == '#' {
            continue; // a comment line
        }
        if let Some(t) = first_tab {
            return Err(ParseError::new(at(t), TAB_IN_INDENTATION));
        }
        if mode == Layout::Plain {
            let c = line[lead];
            if c.is_whitespace() {
                return Err(ParseError::new(
                    at(lead),
                    format!("{} (U+{:04X}) in indentation; indent YAML with spaces", space_name(c), c as u32),
                ));
            }
            if lead == 0 && c == '%' {
                continue; // a directive
            }
        }
        let blank_from = |i: usize| {
            let j = i + line[i..].iter().take_while(|c| **c == ' ' || **c == '\t').count();
            (j == len || line[j] == '#', j)
        };
        let ends_plain = |i: usize, flow: usize| {
            let next = line.get(i + 1).copied();
            next.is_none_or(|c| c == ' ' || c == '\t' || (flow > 0 && ",[]{}".contains(c)))
        };
        let mut i = lead;
        // At the start of a node: a quote or `|`/`>` opens a scalar here.
        let mut start = true;
        // The indicator just passed, for messages about the blanks after it.
        let mut after: Option<char> = None;
        // Where the last key, value or `-` on this line began.
        let mut owner = lead;
        if lead == 0 && (line.starts_with(&['-'; 3]) || line.starts_with(&['.'; 3])) && ends_plain(2, 0) {
            i = 3;
        }
        while i < len {
            match mode {
                Layout::Single => {
                    while i < len {
                        if line[i] == '\'' {
                            if line.get(i + 1) == Some(&'\'') {
                                i += 2;
                                continue;
                            }
                            mode = Layout::Plain;
                        }
                        i += 1;
                        if mode == Layout::Plain {
                            break;
                        }
                    }
                    (start, after) = (false, None);
                    continue;
                }
                Layout::Double => {
                    while i < len {
                        match line[i] {
                            '\\' => i += 2,
                            '"' => {
                                mode = Layout::Plain;
                                i += 1;
                                break;
                            }
                            _ => i += 1,
                        }
                    }
                    (start, after) = (false, None);
                    continue;
                }
                Layout::Block { .. } | Layout::Plain => {}
            }
            let c = line[i];
            match c {
                ' ' => i += 1,
                '\t' => {
                    let (trailing, j) = blank_from(i);
                    if trailing {
                        break;
                    }
                    let message = match after {
                        Some('-' | '?') if flow == 0 => TAB_IN_INDENTATION.to_string(),
                        Some(ind) => format!("tab character after `{ind}`; separate YAML with spaces"),
                        None if line[j] == ':' => "tab character before `:`; separate YAML with spaces".to_string(),
                        None => "tab character in an unquoted value; use spaces, or quote the value".to_string(),
                    };
                    return Err(ParseError::new(at(i), message));
                }
                '#' if i == 0 || line[i - 1] == ' ' || line[i - 1] == '\t' => break,
                '\'' | '"' if start => {
                    mode = if c == '\'' { Layout::Single } else { Layout::Double };
                    if after != Some(':') {
                        owner = i;
                    }
                    i += 1;
                }
                '|' | '>' if start && flow == 0 => {
                    let header: String = line[i + 1..].iter().take_while(|c| !c.is_whitespace()).collect();
                    let explicit = header.chars().find_map(|c| c.to_digit(10)).map(|d| owner + d as usize);
                    mode = Layout::Block { owner, indent: explicit };
                    break;
                }
                '[' | '{' => {
                    flow += 1;
                    brackets.push((c, at(i)));
                    (start, after) = (true, Some(c));
                    i += 1;
                }
                ']' | '}' => {
                    flow = flow.saturating_sub(1);
                    brackets.push((c, at(i)));
                    (start, after) = (false, None);
                    i += 1;
                }
                ',' if flow > 0 => {
                    (start, after) = (true, Some(c));
                    i += 1;
                }
                '-' | '?' if start && flow == 0 && ends_plain(i, 0) => {
                    owner = i;
                    (start, after) = (true, Some(c));
                    i += 1;
                }
                ':' if ends_plain(i, flow) => {
                    (start, after) = (true, Some(c));
                    i += 1;
                }
                '：' => return Err(fullwidth_colon(at(i))),
                _ => {
                    // A plain scalar (or an anchor, tag or alias): up to the
                    // next indicator, a comment or the end of the line.
                    if after != Some(':') {
                        owner = i;
                    }
                    (start, after) = (false, None);
                    i += 1;
                    while i < len {
                        match line[i] {
                            '：' => return Err(fullwidth_colon(at(i))),
                            ':' if ends_plain(i, flow) => break,
                            ',' | '[' | ']' | '{' | '}' if flow > 0 => break,
                            ' ' | '\t' => {
                                let (trailing, j) = blank_from(i);
                                if trailing || !line[i..j].contains(&'\t') {
                                    if trailing {
                                        break;
                                    }
                                    i = j;
                                    continue;
                                }
                                let tab = i + line[i..j].iter().position(|c| *c == '\t').unwrap_or(0);
                                let message = if line[j] == ':' && ends_plain(j, flow) {
                                    "tab character before `:`; separate YAML with spaces"
                                } else {
                                    "tab character in an unquoted value; use spaces, or quote the value"
                                };
                                return Err(ParseError::new(at(tab), message));
                            }
                            _ => i += 1,
                        }
                    }
                }
            }
        }
    }
    Ok(())
}

fn fullwidth_colon(pos: Pos) -> ParseError {
    ParseError::new(pos, "fullwidth colon `：` (U+FF1A); use ':' (or quote a value that should contain it)")
}

/// What a Unicode space is called, for messages.
fn space_name(c: char) -> &'static str {
    match c {
        '\u{a0}' => "no-break space",
        '\u{3000}' => "ideographic (fullwidth) space",
        _ => "a Unicode space",
    }
}

/// "control character U+0000 (NUL): …", with a hint at the likely cause.
fn control_message(c: char) -> String {
    let name = match c {
        '\0' => " (NUL)",
        '\u{7}' => " (bell)",
        '\u{8}' => " (backspace)",
        '\u{b}' => " (vertical tab)",
        '\u{c}' => " (form feed)",
        '\r' => " (carriage return)",
        '\u{1b}' => " (escape)",
        '\u{7f}' => " (delete)",
        '\u{85}' => " (next line)",
        _ => "",
    };
    let hint = match c {
        '\0' => ": a robot file is UTF-8 text (is this one UTF-16, or binary?)",
        '\r' => " without a line feed: end lines with LF or CRLF",
        _ => ": a robot file may contain tabs and line breaks, but no other control characters; delete it",
    };
    format!("control character U+{:04X}{name}{hint}", c as u32)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::yaml::{parse, Node, Spanned};

    fn p(line: usize, col: usize) -> Pos {
        Pos::new(line, col)
    }

    fn err(source: &str) -> String {
        parse(source).expect_err("expected an error").to_string()
    }

    #[test]
    fn tab_indentation_points_at_the_tab() {
        assert_eq!(err("a:\n\tb: 1\n"), "2:1: tab character in indentation; indent YAML with spaces");
        assert_eq!(err("a:\n  b:\n  \tc: 1\n"), "3:3: tab character in indentation; indent YAML with spaces");
    }

    #[test]
    fn control_characters_are_refused_where_they_are() {
        let nul = "control character U+0000 (NUL): a robot file is UTF-8 text (is this one UTF-16, or binary?)";
        // A NUL used to end the file there: the rest was silently dropped.
        assert_eq!(err("robot: r\n\0skills: [a]\n"), format!("2:1: {nul}"));
        assert_eq!(err("a: 1 # note \0\n"), format!("1:13: {nul}"));
        assert_eq!(err("a: \"x\0y\"\n"), format!("1:6: {nul}"));
        assert_eq!(err("\0"), format!("1:1: {nul}"));
        let other = ": a robot file may contain tabs and line breaks, but no other control characters; delete it";
        assert_eq!(err("a: x\u{1b}[0m\n"), format!("1:5: control character U+001B (escape){other}"));
        assert_eq!(err("a: [1]\nb: \u{7f}\n"), format!("2:4: control character U+007F (delete){other}"));
        assert_eq!(err("a: é\u{85}\n"), format!("1:5: control character U+0085 (next line){other}"));
        assert_eq!(err("a: \u{1}\n"), format!("1:4: control character U+0001{other}"));
        // Columns after a multi-byte character and a tab count characters.
        assert_eq!(err("# ：\t\u{7}\n"), format!("1:5: control character U+0007 (bell){other}"));
        assert_eq!(
            err("a: 1\rb: 2\n"),
            "1:5: control character U+000D (carriage return) without a line feed: end lines with LF or CRLF"
        );
    }

    #[test]
    fn crlf_line_ends_are_fine_and_positions_stay_right() {
        let root = parse("a: 1\r\nb:\r\n  c: x\r\n").unwrap();
        let b = root.value.get("b").unwrap();
        assert_eq!(b.pos, p(3, 3));
        assert_eq!(b.value.get("c").unwrap(), &Spanned::new(Node::plain("x"), p(3, 6)));
        assert_eq!(err("a: 1\r\nb: \u{0}\r\n"), format!("2:4: {}", control_message('\0')));
    }

    #[test]
    fn a_tab_in_indentation_is_refused_wherever_it_is() {
        let indent = "tab character in indentation; indent YAML with spaces";
        let cases: &[(&str, Pos)] = &[
            // Top level: the first line was accepted, a later one blamed line 1.
            ("\trobot: r\n", p(1, 1)),
            ("robot: r\n\tskills: []\n", p(2, 1)),
            // Nested mappings, also after spaces and after a sibling.
            ("a:\n\tb: 1\n", p(2, 1)),
            ("a:\n  b: 1\n\tc: 2\n", p(3, 1)),
            ("a:\n  - b: 1\n  \t c: 2\n", p(3, 3)),
            ("a:\n  - b: 1\n\t    c: 2\n", p(3, 1)),
            // After a sequence's `-`: accepted, or blamed on the next line.
            ("s:\n-\tname: w\n  type: t\n", p(2, 2)),
            ("s:\n  -\tname: w\n    type: t\n", p(2, 4)),
            ("s:\n  - \tname: w\n    type: t\n", p(2, 5)),
            ("- - \tx\n", p(1, 5)),
            ("? \ta\n: 1\n", p(1, 3)),
            // Continuation lines of flow collections and scalars.
            ("s: [\n\t{a: 1}]\n", p(2, 1)),
            ("c: {a: 5,\n\tb: 6}\n", p(2, 1)),
            ("c: {a: 5,\n  \tb: 6}\n", p(2, 3)),
            ("a: one\n\ttwo\n", p(2, 1)),
            ("a: \"one\n\ttwo\"\n", p(2, 1)),
            ("a: 'one\n \ttwo'\n", p(2, 2)),
            // A block scalar's text may not start with one.
            ("a: >\n\tfoo\n", p(2, 1)),
            ("a: |\n  x\n \ty\n", p(3, 2)),
            // After multi-byte characters, columns count characters.
            ("é: [\n  é,\n\té]\n", p(3, 1)),
        ];
        for (src, pos) in cases {
            let e = parse(src).expect_err(src);
            assert_eq!((e.pos, e.message.as_str()), (*pos, indent), "{src:?}");
        }
    }

    #[test]
    fn other_tabs_outside_quotes_are_refused_with_their_place() {
        assert_eq!(err("key:\tvalue\n"), "1:5: tab character after `:`; separate YAML with spaces");
        assert_eq!(err("a:\n  key: \tvalue\n"), "2:8: tab character after `:`; separate YAML with spaces");
        assert_eq!(err("a: [1,\t2]\n"), "1:7: tab character after `,`; separate YAML with spaces");
        assert_eq!(err("a: {\tb: 1}\n"), "1:5: tab character after `{`; separate YAML with spaces");
        assert_eq!(err("key\t: value\n"), "1:4: tab character before `:`; separate YAML with spaces");
        assert_eq!(err("a: b\tc\n"), "1:5: tab character in an unquoted value; use spaces, or quote the value");
        assert_eq!(err("ééé:\tx\n"), "1:5: tab character after `:`; separate YAML with spaces");
    }

    #[test]
    fn tabs_inside_quotes_block_scalars_comments_and_at_line_ends_are_fine() {
        let src = "# a\tcomment\n\t# an indented comment\na: \"x\ty\" # c\td\n\t\nb: 'p\tq'\t\nc: |\n  one\n  \ttwo\nd: [1, 2]\t# e\n";
        let root = parse(src).unwrap();
        let text = |k: &str| root.value.get(k).unwrap().value.as_text().unwrap().to_string();
        assert_eq!((text("a"), text("b"), text("c")), ("x\ty".into(), "p\tq".into(), "one\n\ttwo\n".into()));
        let d = root.value.get("d").unwrap();
        assert_eq!(d.pos, p(9, 4));
    }

    #[test]
    fn a_fullwidth_colon_is_refused_with_a_hint() {
        let msg = "fullwidth colon `：` (U+FF1A); use ':' (or quote a value that should contain it)";
        // Read as a scalar key, or blamed on the next line.
        assert_eq!(err("robot： r\n"), format!("1:6: {msg}"));
        assert_eq!(err("a:\n  b： 1\n  c: 2\n"), format!("2:4: {msg}"));
        assert_eq!(err("a:\n  - n: w\n    type： t\n"), format!("3:9: {msg}"));
        assert_eq!(err("cycle：\n  rate_hz: 5\n"), format!("1:6: {msg}"));
        assert_eq!(err("c: {rate_hz： 5, clock: wall}\n"), format!("1:12: {msg}"));
        assert_eq!(err("c:\n  clock：wall\n"), format!("2:8: {msg}"));
        // Quoted or in a comment it is text.
        let root = parse("a: \"x：y\" # ：\nb: 'z：'\n").unwrap();
        assert_eq!(root.value.get("b").unwrap().value.as_text(), Some("z："));
        assert_eq!(
            err("a:\n\u{3000}b: 1\n"),
            "2:1: ideographic (fullwidth) space (U+3000) in indentation; indent YAML with spaces"
        );
    }

    #[test]
    fn errors_after_tabs_and_wide_characters_keep_their_line_and_column() {
        // Tabs and fullwidth characters the file may hold do not shift what follows.
        assert_eq!(
            err("# ：\t：\na: \"：\t\"\t# \t\nb: [1, 2\n"),
            "3:4: missing `]` to close the `[` at line 3, column 4 (the YAML parser stopped at line 4, column 1: \
             while parsing a flow sequence, expected ',' or ']')"
        );
        assert_eq!(
            err("a: '：\t'\nb: ：\n"),
            "2:4: fullwidth colon `：` (U+FF1A); use ':' (or quote a value that should contain it)"
        );
    }
}
