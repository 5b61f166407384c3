//! The lexer: a source cut into tokens, each with its byte offsets, so that
//! every later error can point at the column where its part is written.

use crate::ExprError;

#[derive(Debug, Clone, PartialEq)]
pub(crate) enum Tok {
    Num(f64),
    Str(String),
    Name(String),
    True,
    False,
    OrOr,
    AndAnd,
    EqEq,
    NotEq,
    Lt,
    Le,
    Gt,
    Ge,
    Plus,
    Minus,
    Star,
    Slash,
    Percent,
    Bang,
    LParen,
    RParen,
    LBracket,
    RBracket,
    Comma,
    End,
}

#[derive(Debug, Clone)]
pub(crate) struct Token {
    pub(crate) tok: Tok,
    /// Byte offsets into the source.
    pub(crate) start: usize,
    pub(crate) end: usize,
}

/// The 1-based character column of a byte offset.
pub(crate) fn column_of(src: &str, at: usize) -> usize {
    src.get(..at).map_or(at, |s| s.chars().count()) + 1
}

pub(crate) fn lex_err(src: &str, at: usize, message: impl Into<String>) -> ExprError {
    ExprError { column: column_of(src, at), message: message.into() }
}

fn is_ident_start(c: u8) -> bool {
    c.is_ascii_alphabetic() || c == b'_'
}

fn is_ident(c: u8) -> bool {
    c.is_ascii_alphanumeric() || c == b'_'
}

pub(crate) fn lex(src: &str) -> Result<Vec<Token>, ExprError> {
    let b = src.as_bytes();
    let n = b.len();
    let at = |i: usize| b.get(i).copied();
    let mut out = Vec::new();
    let mut i = 0;
    while i < n {
        let c = b[i];
        let start = i;
        let tok = match c {
            b' ' | b'\t' | b'\n' | b'\r' => {
                i += 1;
                continue;
            }
            b'0'..=b'9' => {
                while at(i).is_some_and(|c| c.is_ascii_digit()) {
                    i += 1;
                }
                if at(i) == Some(b'.') {
                    if !at(i + 1).is_some_and(|c| c.is_ascii_digit()) {
                        return Err(lex_err(src, i + 1, "expected digits after the decimal point"));
                    }
                    i += 1;
                    while at(i).is_some_and(|c| c.is_ascii_digit()) {
                        i += 1;
                    }
                }
                if matches!(at(i), Some(b'e' | b'E')) {
                    let mut j = i + 1;
                    if matches!(at(j), Some(b'+' | b'-')) {
                        j += 1;
                    }
                    if !at(j).is_some_and(|c| c.is_ascii_digit()) {
                        return Err(lex_err(src, j, "expected the digits of the exponent"));
                    }
                    i = j;
                    while at(i).is_some_and(|c| c.is_ascii_digit()) {
                        i += 1;
                    }
                }
                if let Some(c) = at(i).filter(|&c| is_ident(c) || c == b'.') {
                    return Err(lex_err(src, i, format!("unexpected `{}` right after a number", char::from(c))));
                }
                match src[start..i].parse::<f64>() {
                    Ok(x) if x.is_finite() => Tok::Num(x),
                    _ => return Err(lex_err(src, start, "this number is too large")),
                }
            }
            b'.' => {
                if at(i + 1).is_some_and(|c| c.is_ascii_digit()) {
                    return Err(lex_err(src, i, "a number needs a digit before its decimal point (`0.5`, not `.5`)"));
                }
                return Err(lex_err(src, i, "unexpected `.`"));
            }
            b'"' | b'\'' => {
                let quote = c;
                let mut s = String::new();
                i += 1;
                loop {
                    let Some(ch) = src.get(i..).and_then(|rest| rest.chars().next()) else {
                        return Err(lex_err(src, start, "this string is not closed"));
                    };
                    if ch == char::from(quote) {
                        i += 1;
                        break;
                    }
                    if ch == '\\' {
                        match src.get(i + 1..).and_then(|rest| rest.chars().next()) {
                            Some(e @ ('\\' | '"' | '\'')) => {
                                s.push(e);
                                i += 2;
                            }
                            Some(e) => {
                                return Err(lex_err(
                                    src,
                                    i,
                                    format!("unknown escape `\\{e}` in a string (the escapes are \\\\, \\\" and \\')"),
                                ))
                            }
                            None => return Err(lex_err(src, start, "this string is not closed")),
                        }
                        continue;
                    }
                    s.push(ch);
                    i += ch.len_utf8();
                }
                Tok::Str(s)
            }
            c if is_ident_start(c) => {
                loop {
                    while at(i).is_some_and(is_ident) {
                        i += 1;
                    }
                    if at(i) != Some(b'.') {
                        break;
                    }
                    if !at(i + 1).is_some_and(is_ident_start) {
                        return Err(lex_err(src, i + 1, "expected a field name after `.`"));
                    }
                    i += 1;
                }
                match &src[start..i] {
                    "true" => Tok::True,
                    "false" => Tok::False,
                    name => Tok::Name(name.to_string()),
                }
            }
            _ => {
                let next = at(i + 1);
                let (tok, len) = match (c, next) {
                    (b'|', Some(b'|')) => (Tok::OrOr, 2),
                    (b'&', Some(b'&')) => (Tok::AndAnd, 2),
                    (b'=', Some(b'=')) => (Tok::EqEq, 2),
                    (b'!', Some(b'=')) => (Tok::NotEq, 2),
                    (b'<', Some(b'=')) => (Tok::Le, 2),
                    (b'>', Some(b'=')) => (Tok::Ge, 2),
                    (b'|', _) => return Err(lex_err(src, i, "`|` is not an operator; for \"or\" write `||`")),
                    (b'&', _) => return Err(lex_err(src, i, "`&` is not an operator; for \"and\" write `&&`")),
                    (b'=', _) => return Err(lex_err(src, i, "`=` is not an operator; to compare, write `==`")),
                    (b'!', _) => (Tok::Bang, 1),
                    (b'<', _) => (Tok::Lt, 1),
                    (b'>', _) => (Tok::Gt, 1),
                    (b'+', _) => (Tok::Plus, 1),
                    (b'-', _) => (Tok::Minus, 1),
                    (b'*', _) => (Tok::Star, 1),
                    (b'/', _) => (Tok::Slash, 1),
                    (b'%', _) => (Tok::Percent, 1),
                    (b'(', _) => (Tok::LParen, 1),
                    (b')', _) => (Tok::RParen, 1),
                    (b'[', _) => (Tok::LBracket, 1),
                    (b']', _) => (Tok::RBracket, 1),
                    (b',', _) => (Tok::Comma, 1),
                    _ => {
                        let ch = src.get(i..).and_then(|r| r.chars().next()).unwrap_or('?');
                        return Err(lex_err(src, i, format!("unexpected character `{}`", ch.escape_debug())));
                    }
                };
                i += len;
                tok
            }
        };
        out.push(Token { tok, start, end: i });
    }
    out.push(Token { tok: Tok::End, start: n, end: n });
    Ok(out)
}
