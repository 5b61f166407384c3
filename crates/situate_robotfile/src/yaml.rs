//! A small YAML node tree that remembers where every node came from.
//!
//! Robot files are YAML, and every error about them has to point at a line
//! and column. This module drives `yaml-rust2`'s event parser and builds a
//! tree of [`Node`]s, each wrapped in a [`Spanned`] that carries its 1-based
//! [`Pos`]. It accepts the plain subset of YAML that robot files need:
//!
//! * text only: no control characters but tab, line feed and the carriage
//!   return of a CRLF line end (a NUL would silently end the file);
//! * tabs only inside quoted strings, block scalars and comments, or at the
//!   end of a line; a fullwidth colon `：` only inside quotes and comments
//!   (see [`check_layout`]);
//! * one document per file (an empty file is a [`Node::Null`] document);
//! * mapping keys are scalars, and a key may appear once per mapping;
//! * no anchors, aliases or tags;
//! * at most [`MAX_DEPTH`] levels of nesting.
//!
//! Scalars keep their source text; [`Node::to_value`] types plain scalars by
//! the YAML 1.2 core schema (`true`, `3`, `0x1f`, `0.5`, `1e-3`, `.inf`, …),
//! while quoted and block scalars are always strings. Plain `null`, `~` and
//! empty values are [`Node::Null`] already in the tree.

use std::collections::HashMap;
use std::fmt;
use std::sync::Arc;

use situate_core::value::Value;
use yaml_rust2::parser::{Event, Parser};
use yaml_rust2::scanner::{Marker, ScanError, TScalarStyle};

pub use crate::limits::MAX_DEPTH;

/// A position in a source file; line and column both start at 1. Columns
/// count characters (not bytes). `src` says which file: 0 for the file
/// parsed, and for a robot file that includes others, the index of the
/// included file in [`RobotFile::sources`](crate::config::RobotFile::sources)
/// (positions order by file first).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct Pos {
    pub src: usize,
    pub line: usize,
    pub col: usize,
}

impl Pos {
    /// Line 1, column 1.
    pub const START: Pos = Pos { src: 0, line: 1, col: 1 };

    pub fn new(line: usize, col: usize) -> Pos {
        Pos { src: 0, line, col }
    }

    /// This position in source file `src`.
    pub fn in_src(self, src: usize) -> Pos {
        Pos { src, ..self }
    }

    /// `yaml-rust2` markers have a 1-based line and a 0-based column.
    fn from_marker(m: &Marker) -> Pos {
        Pos { src: 0, line: m.line().max(1), col: m.col() + 1 }
    }
}

impl Default for Pos {
    fn default() -> Pos {
        Pos::START
    }
}

impl fmt::Display for Pos {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}:{}", self.line, self.col)
    }
}

/// A value together with the position it was read from.
#[derive(Debug, Clone, PartialEq)]
pub struct Spanned<T> {
    pub value: T,
    pub pos: Pos,
}

impl<T> Spanned<T> {
    pub fn new(value: T, pos: Pos) -> Spanned<T> {
        Spanned { value, pos }
    }

    /// The same position with another value.
    pub fn map<U>(self, f: impl FnOnce(T) -> U) -> Spanned<U> {
        Spanned { value: f(self.value), pos: self.pos }
    }
}

/// One YAML node.
#[derive(Debug, Clone, PartialEq)]
pub enum Node {
    /// `null`, `~` or nothing at all.
    Null,
    /// A scalar's text; `plain` is false for quoted and block (`|`, `>`)
    /// scalars, which are always strings.
    Scalar { text: String, plain: bool },
    /// A list.
    Seq(Vec<Spanned<Node>>),
    /// A mapping, in file order; keys are unique.
    Map(Vec<(Spanned<String>, Spanned<Node>)>),
}

impl Node {
    /// A plain scalar, as typed by the YAML 1.2 core schema.
    pub fn plain(text: &str) -> Node {
        Node::Scalar { text: text.to_string(), plain: true }
    }

    /// A quoted scalar: always a string.
    pub fn quoted(text: &str) -> Node {
        Node::Scalar { text: text.to_string(), plain: false }
    }

    /// The scalar's value: `Bool`, `I64`, `F64` or `Str`. `None` for null,
    /// lists and mappings.
    pub fn to_value(&self) -> Option<Value> {
        match self {
            Node::Scalar { text, plain: true } => Some(type_plain(text)),
            Node::Scalar { text, plain: false } => Some(Value::Str(Arc::from(text.as_str()))),
            _ => None,
        }
    }

    /// A list of numbers as `Value::F64s` (integers widen); `None` if this is
    /// not a list or an item is not a number.
    pub fn to_f64s(&self) -> Option<Value> {
        match self {
            Node::Seq(items) => {
                let xs: Option<Vec<f64>> = items.iter().map(|n| n.value.as_f64()).collect();
                xs.map(|xs| Value::F64s(xs.into()))
            }
            _ => None,
        }
    }

    /// A scalar number (integer or float) as `f64`.
    pub fn as_f64(&self) -> Option<f64> {
        match self.to_value()? {
            Value::I64(x) => Some(x as f64),
            Value::F64(x) => Some(x),
            _ => None,
        }
    }

    /// A scalar integer.
    pub fn as_i64(&self) -> Option<i64> {
        match self.to_value()? {
            Value::I64(x) => Some(x),
            _ => None,
        }
    }

    /// A scalar boolean.
    pub fn as_bool(&self) -> Option<bool> {
        match self.to_value()? {
            Value::Bool(b) => Some(b),
            _ => None,
        }
    }

    /// A plain scalar written as an integer (`42`, `-7`, `0x1f`, `0o17`),
    /// whether or not it fits in 64 bits.
    pub fn is_integer_literal(&self) -> bool {
        let Node::Scalar { text, plain: true } = self else { return false };
        let digits = |s: &str, radix: u32| !s.is_empty() && s.chars().all(|c| c.is_digit(radix));
        match (text.strip_prefix("0x"), text.strip_prefix("0o")) {
            (Some(hex), _) => digits(hex, 16),
            (_, Some(oct)) => digits(oct, 8),
            _ => digits(text.strip_prefix(['-', '+']).unwrap_or(text), 10),
        }
    }

    /// The source text of any scalar (plain or quoted, whatever its type).
    pub fn as_text(&self) -> Option<&str> {
        match self {
            Node::Scalar { text, .. } => Some(text),
            _ => None,
        }
    }

    pub fn is_null(&self) -> bool {
        matches!(self, Node::Null)
    }

    /// The entries of a mapping.
    pub fn as_map(&self) -> Option<&[(Spanned<String>, Spanned<Node>)]> {
        match self {
            Node::Map(entries) => Some(entries),
            _ => None,
        }
    }

    /// The items of a list.
    pub fn as_seq(&self) -> Option<&[Spanned<Node>]> {
        match self {
            Node::Seq(items) => Some(items),
            _ => None,
        }
    }

    /// A mapping's value for `key`.
    pub fn get(&self, key: &str) -> Option<&Spanned<Node>> {
        self.as_map()?.iter().find(|(k, _)| k.value == key).map(|(_, v)| v)
    }

    /// What kind of node this is, with an article: "a list", "a string", …
    pub fn kind_name(&self) -> &'static str {
        match self {
            Node::Null => "null",
            Node::Seq(_) => "a list",
            Node::Map(_) => "a mapping",
            Node::Scalar { .. } => match self.to_value() {
                Some(Value::Bool(_)) => "a boolean",
                Some(Value::I64(_)) => "an integer",
                Some(Value::F64(_)) => "a number",
                _ => "a string",
            },
        }
    }

    /// How the node reads in an error message after "got": scalars as
    /// written (strings quoted, long ones shortened), others by kind.
    pub fn describe(&self) -> String {
        match self {
            Node::Scalar { text, .. } => match self.to_value() {
                Some(Value::Str(_)) => {
                    let short: String = text.chars().take(40).collect();
                    if short.len() < text.len() {
                        format!("{:?}", short + "…")
                    } else {
                        format!("{text:?}")
                    }
                }
                _ => text.clone(),
            },
            other => other.kind_name().to_string(),
        }
    }
}

/// Types a plain scalar by the YAML 1.2 core schema (null is handled by the
/// tree builder).
fn type_plain(text: &str) -> Value {
    match text {
        "true" | "True" | "TRUE" => return Value::Bool(true),
        "false" | "False" | "FALSE" => return Value::Bool(false),
        ".inf" | ".Inf" | ".INF" | "+.inf" | "+.Inf" | "+.INF" => return Value::F64(f64::INFINITY),
        "-.inf" | "-.Inf" | "-.INF" => return Value::F64(f64::NEG_INFINITY),
        ".nan" | ".NaN" | ".NAN" => return Value::F64(f64::NAN),
        _ => {}
    }
    let radix = |prefix: &str, radix: u32| {
        text.strip_prefix(prefix)
            .filter(|d| !d.is_empty() && d.chars().all(|c| c.is_digit(radix)))
            .and_then(|d| i64::from_str_radix(d, radix).ok())
    };
    if let Some(x) = radix("0x", 16).or_else(|| radix("0o", 8)) {
        return Value::I64(x);
    }
    let digits = text.strip_prefix(['-', '+']).unwrap_or(text);
    if !digits.is_empty() && digits.bytes().all(|b| b.is_ascii_digit()) {
        return match text.parse::<i64>() {
            Ok(x) => Value::I64(x),
            // Too large for i64: keep the magnitude as a float.
            Err(_) => Value::F64(text.parse::<f64>().unwrap_or(f64::NAN)),
        };
    }
    if is_core_float(digits) {
        if let Ok(x) = text.parse::<f64>() {
            return Value::F64(x);
        }
    }
    Value::Str(Arc::from(text))
}

/// `(\.[0-9]+|[0-9]+(\.[0-9]*)?)([eE][-+]?[0-9]+)?`, the sign already removed.
fn is_core_float(s: &str) -> bool {
    fn digits(s: &str) -> usize {
        s.bytes().take_while(u8::is_ascii_digit).count()
    }
    let int = digits(s);
    let mut rest = &s[int..];
    let mut frac = 0;
    if let Some(r) = rest.strip_prefix('.') {
        frac = digits(r);
        rest = &r[frac..];
    }
    if int == 0 && frac == 0 {
        return false;
    }
    if let Some(r) = rest.strip_prefix(['e', 'E']) {
        let r = r.strip_prefix(['-', '+']).unwrap_or(r);
        let exp = digits(r);
        return exp > 0 && exp == r.len();
    }
    rest.is_empty()
}

/// Why a YAML source file could not be read as text.
#[derive(Debug, thiserror::Error)]
pub enum ReadError {
    /// The file cannot be opened or read.
    #[error("cannot read {what}: {source}")]
    Io {
        what: &'static str,
        #[source]
        source: std::io::Error,
    },
    /// The file is larger than its cap (`size` is `None` when only "more
    /// than the cap" is known: the reader stopped there).
    #[error("the file is {}; a {what} may be at most {}", size.map_or(format!("more than {}", bytes(*max)), bytes), bytes(*max))]
    TooLarge { what: &'static str, size: Option<u64>, max: u64 },
    /// A byte sequence that is not UTF-8, at `pos`.
    #[error("invalid UTF-8 (byte 0x{byte:02X}): a {what} is UTF-8 text; save it as UTF-8")]
    NotUtf8 { what: &'static str, pos: Pos, byte: u8 },
    /// The file starts with a UTF-16 byte-order mark.
    #[error("the file is UTF-16 text; a {what} is UTF-8 text: save it as UTF-8")]
    Utf16 { what: &'static str },
}

impl ReadError {
    /// Where in the file the problem is; `None` for the file as a whole.
    pub fn pos(&self) -> Option<Pos> {
        match self {
            ReadError::NotUtf8 { pos, .. } => Some(*pos),
            _ => None,
        }
    }
}

/// "1048576 bytes (1 MiB)".
fn bytes(n: u64) -> String {
    const MIB: u64 = 1 << 20;
    match n {
        n if n >= MIB && n % MIB == 0 => format!("{n} bytes ({} MiB)", n / MIB),
        n if n >= MIB => format!("{n} bytes ({:.1} MiB)", n as f64 / MIB as f64),
        n => format!("{n} bytes"),
    }
}

/// Reads a YAML source file (a `what`: "robot file", "map file", …) of at
/// most `max` bytes as UTF-8 text. A larger file is refused by its size
/// before it is read, and the reader never takes more than `max + 1` bytes
/// (a file that grows, a pipe, a device). Invalid UTF-8 is an error at its
/// line and column.
pub fn read_source(path: &std::path::Path, what: &'static str, max: u64) -> Result<String, ReadError> {
    use std::io::Read;
    let io = |source| ReadError::Io { what, source };
    let file = std::fs::File::open(path).map_err(io)?;
    let meta = file.metadata().map_err(io)?;
    if meta.is_file() && meta.len() > max {
        return Err(ReadError::TooLarge { what, size: Some(meta.len()), max });
    }
    let mut buf = Vec::new();
    file.take(max.saturating_add(1)).read_to_end(&mut buf).map_err(io)?;
    if buf.len() as u64 > max {
        return Err(ReadError::TooLarge { what, size: None, max });
    }
    if buf.starts_with(&[0xff, 0xfe]) || buf.starts_with(&[0xfe, 0xff]) {
        return Err(ReadError::Utf16 { what });
    }
    String::from_utf8(buf).map_err(|e| {
        let at = e.utf8_error().valid_up_to();
        let bytes = e.as_bytes();
        let valid = std::str::from_utf8(&bytes[..at]).unwrap_or_default();
        let line = valid.matches('\n').count() + 1;
        let col = valid.rsplit('\n').next().unwrap_or_default().chars().count() + 1;
        ReadError::NotUtf8 { what, pos: Pos::new(line, col), byte: bytes[at] }
    })
}

/// A YAML error: the file is not YAML, or uses YAML a robot file may not.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ParseError {
    pub pos: Pos,
    pub message: String,
}

impl ParseError {
    fn new(pos: Pos, message: impl Into<String>) -> ParseError {
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

/// Refuses control characters, which editors hide and the scanner misreads
/// (it takes a NUL for the end of the file). Tab, line feed and the carriage
/// return of a CRLF line end are the only ones a robot file may contain.
fn check_control_characters(source: &str) -> Result<(), ParseError> {
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
fn check_layout(source: &str, brackets: &mut Vec<(char, Pos)>) -> Result<(), ParseError> {
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
/// any: given the brackets [`check_layout`] found in order (outside quotes
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
    fn plain_scalars_follow_the_core_schema() {
        let cases: &[(&str, Option<Value>)] = &[
            ("true", Some(Value::Bool(true))),
            ("FALSE", Some(Value::Bool(false))),
            ("-3", Some(Value::I64(-3))),
            ("+7", Some(Value::I64(7))),
            ("0x1f", Some(Value::I64(31))),
            ("0o17", Some(Value::I64(15))),
            ("0.5", Some(Value::F64(0.5))),
            ("1e-3", Some(Value::F64(1e-3))),
            ("-.5E+2", Some(Value::F64(-50.0))),
            ("3.", Some(Value::F64(3.0))),
            (".inf", Some(Value::F64(f64::INFINITY))),
            ("-.inf", Some(Value::F64(f64::NEG_INFINITY))),
            ("inf", Some(Value::Str("inf".into()))),
            ("nan", Some(Value::Str("nan".into()))),
            ("1e", Some(Value::Str("1e".into()))),
            (".", Some(Value::Str(".".into()))),
            ("0x", Some(Value::Str("0x".into()))),
            ("yes", Some(Value::Str("yes".into()))),
            ("toy.sonar", Some(Value::Str("toy.sonar".into()))),
            ("99999999999999999999", Some(Value::F64(1e20))),
        ];
        for (text, want) in cases {
            let src = format!("v: {text}\n");
            let root = parse(&src).unwrap();
            assert_eq!(&root.value.get("v").unwrap().value.to_value(), want, "{text}");
        }
        let root = parse("v: .nan\n").unwrap();
        assert!(root.value.get("v").unwrap().value.as_f64().unwrap().is_nan());
        // An empty value sits at its key; an explicit null where it is.
        let root = parse("a:\n  b:\n  c: ~\n").unwrap();
        let a = &root.value.get("a").unwrap().value;
        assert_eq!(a.get("b"), Some(&Spanned::new(Node::Null, p(2, 3))));
        assert_eq!(a.get("c"), Some(&Spanned::new(Node::Null, p(3, 6))));
        for text in ["", "~", "null", "Null", "NULL"] {
            let root = parse(&format!("v: {text}\n")).unwrap();
            assert_eq!(root.value.get("v").unwrap().value, Node::Null, "{text:?}");
        }
    }

    #[test]
    fn quoted_and_block_scalars_are_strings() {
        let root = parse("a: \"3\"\nb: 'true'\nc: \"null\"\nd: |\n  5\n").unwrap();
        let v = |k: &str| root.value.get(k).unwrap().value.to_value();
        assert_eq!(v("a"), Some(Value::Str("3".into())));
        assert_eq!(v("b"), Some(Value::Str("true".into())));
        assert_eq!(v("c"), Some(Value::Str("null".into())));
        assert_eq!(v("d"), Some(Value::Str("5\n".into())));
        assert_eq!(root.value.get("a").unwrap().pos, p(1, 4));
        assert_eq!(root.value.get("d").unwrap().pos, p(5, 3));
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

    #[test]
    fn read_source_stops_at_its_cap() {
        // A device that never ends is refused after cap + 1 bytes, not read on.
        #[cfg(unix)]
        {
            let e = read_source(std::path::Path::new("/dev/zero"), "test file", 16).unwrap_err();
            assert_eq!(e.to_string(), "the file is more than 16 bytes; a test file may be at most 16 bytes");
            assert_eq!(e.pos(), None);
        }
        let path = std::env::temp_dir().join(format!("situate-yaml-read-{}.yaml", std::process::id()));
        std::fs::write(&path, [b"a: \xc3\xa9\nbc: ".as_slice(), &[0xff]].concat()).unwrap();
        let e = read_source(&path, "robot file", 1 << 20).unwrap_err();
        assert_eq!(e.pos(), Some(p(2, 5)));
        std::fs::write(&path, "a: é\n").unwrap();
        assert_eq!(read_source(&path, "robot file", 6).unwrap(), "a: é\n");
        assert!(matches!(read_source(&path, "robot file", 5), Err(ReadError::TooLarge { size: Some(6), .. })));
        let _ = std::fs::remove_file(&path);
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
    fn describe_quotes_strings_only() {
        assert_eq!(Node::plain("fast").describe(), "\"fast\"");
        assert_eq!(Node::plain("0").describe(), "0");
        assert_eq!(Node::quoted("0").describe(), "\"0\"");
        assert_eq!(Node::Seq(vec![]).describe(), "a list");
        assert_eq!(Node::Null.describe(), "null");
        let long = Node::plain(&"x".repeat(100)).describe();
        assert_eq!(long, format!("\"{}…\"", "x".repeat(40)));
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
