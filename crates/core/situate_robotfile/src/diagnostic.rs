//! A message at a position: the one type of every problem found in a robot
//! file, a file it includes, a skill manifest, a robot built from them, or a
//! building's map (`situate_sim`'s reader and `situate map check`).
//!
//! A [`Diagnostic`] has a severity, the file it is in, a position (line and
//! column, both from 1; a column of 0 is not known), the element it is about
//! when the position alone does not say (`floor 4, door 2`) and a message,
//! and one rendering: `FILE:LINE:COL: error: ELEMENT: message` (`warning:`
//! for a warning), with the parts it lacks left out (`FILE: error: message`
//! for the file as a whole, `FILE:LINE: error: …` without a column). The
//! robot file's errors ([`ConfigError`](crate::error::ConfigError)) are
//! diagnostics; the YAML reader's [`ParseError`] and a manifest's problems
//! convert into them.
//!
//! The condition language's `ExprError` stays its own type: it is the error
//! of a one-line text (a monitor's condition sent over the link, answered
//! with its column and a caret line), with no file; where such a text sits
//! in a file (a manifest's port type), the reader places it and makes it a
//! diagnostic.

use std::fmt;

use crate::yaml::{ParseError, Pos};

/// How bad a diagnostic is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Severity {
    Error,
    Warning,
}

/// A problem found in a robot file, or while checking or building a robot.
#[derive(Debug, Clone, PartialEq)]
pub struct Diagnostic {
    pub severity: Severity,
    /// The file it is in, as shown in messages; `None` for a robot built in
    /// code, or text not yet known to be a file's.
    pub file: Option<String>,
    /// Where in the file; `None` for the file (or the robot) as a whole.
    pub pos: Option<Pos>,
    /// What the message is about, as the file's reader names it (`floor 4,
    /// door 2`, `mission, start`); `None` when the position says enough.
    pub element: Option<String>,
    pub message: String,
}

impl Diagnostic {
    /// An error at `pos` in `file` (a position on line 0 is none: the file
    /// as a whole).
    pub fn new(file: &str, pos: Pos, message: impl Into<String>) -> Diagnostic {
        Diagnostic {
            severity: Severity::Error,
            file: Some(file.to_string()),
            pos: (pos.line > 0).then_some(pos),
            element: None,
            message: message.into(),
        }
    }

    /// An error about the file as a whole (it cannot be read, it is too
    /// large): no position.
    pub fn whole_file(file: &str, message: impl Into<String>) -> Diagnostic {
        Diagnostic {
            severity: Severity::Error,
            file: Some(file.to_string()),
            pos: None,
            element: None,
            message: message.into(),
        }
    }

    /// An error at `pos` of a text whose file the caller knows (a manifest
    /// read from a file, a robot file's section): see [`Diagnostic::in_file`].
    pub fn at(pos: Pos, message: impl Into<String>) -> Diagnostic {
        Diagnostic { severity: Severity::Error, file: None, pos: Some(pos), element: None, message: message.into() }
    }

    /// An error with no place (a configuration built in code, not read from a file).
    pub fn without_place(message: impl Into<String>) -> Diagnostic {
        Diagnostic { severity: Severity::Error, file: None, pos: None, element: None, message: message.into() }
    }

    /// The same diagnostic, in `file`.
    pub fn in_file(self, file: &str) -> Diagnostic {
        Diagnostic { file: Some(file.to_string()), ..self }
    }

    /// The same diagnostic, about `element` (`floor 4, door 2`).
    pub fn about(self, element: impl Into<String>) -> Diagnostic {
        Diagnostic { element: Some(element.into()), ..self }
    }

    pub fn is_error(&self) -> bool {
        self.severity == Severity::Error
    }

    /// The line, from 1; 0 when there is no position.
    pub fn line(&self) -> usize {
        self.pos.map_or(0, |p| p.line)
    }

    /// The column, from 1, in characters; 0 when there is no position.
    pub fn col(&self) -> usize {
        self.pos.map_or(0, |p| p.col)
    }
}

impl fmt::Display for Diagnostic {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let level = match self.severity {
            Severity::Error => "error",
            Severity::Warning => "warning",
        };
        let mut place = String::new();
        if let Some(file) = &self.file {
            place.push_str(file);
        }
        if let Some(p) = self.pos {
            if !place.is_empty() {
                place.push(':');
            }
            place.push_str(&p.line.to_string());
            if p.col > 0 {
                place.push_str(&format!(":{}", p.col));
            }
        }
        if !place.is_empty() {
            write!(f, "{place}: ")?;
        }
        write!(f, "{level}: ")?;
        if let Some(element) = &self.element {
            write!(f, "{element}: ")?;
        }
        f.write_str(&self.message)
    }
}

impl std::error::Error for Diagnostic {}

/// A YAML error is an error at its place; [`Diagnostic::in_file`] names the
/// file.
impl From<ParseError> for Diagnostic {
    fn from(e: ParseError) -> Diagnostic {
        Diagnostic::at(e.pos, e.message)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn one_rendering_with_the_parts_a_diagnostic_has() {
        let at = Pos::new(3, 7);
        assert_eq!(Diagnostic::new("r.yaml", at, "bad").to_string(), "r.yaml:3:7: error: bad");
        assert_eq!(Diagnostic::whole_file("r.yaml", "gone").to_string(), "r.yaml: error: gone");
        assert_eq!(Diagnostic::new("r.yaml", Pos::new(0, 0), "gone").to_string(), "r.yaml: error: gone");
        assert_eq!(Diagnostic::at(at, "bad").to_string(), "3:7: error: bad");
        let warning =
            Diagnostic { severity: Severity::Warning, file: None, pos: None, element: None, message: "hm".into() };
        assert_eq!(warning.to_string(), "warning: hm");
        assert!(!warning.is_error());
        assert_eq!((warning.line(), warning.col()), (0, 0));
    }

    #[test]
    fn an_element_follows_the_level_and_a_column_of_0_is_left_out() {
        let d = Diagnostic::new("maps/x.yaml", Pos::new(20, 0), "segment has zero length").about("floor 0, wall 2");
        assert_eq!(d.to_string(), "maps/x.yaml:20: error: floor 0, wall 2: segment has zero length");
        assert_eq!((d.line(), d.col()), (20, 0));
        let d = Diagnostic::new("maps/x.yaml", Pos::new(3, 5), "bad").about("mission");
        assert_eq!(d.to_string(), "maps/x.yaml:3:5: error: mission: bad");
        assert_eq!(Diagnostic::whole_file("m.yaml", "gone").about("map").to_string(), "m.yaml: error: map: gone");
    }

    #[test]
    fn a_yaml_error_becomes_one_in_its_file() {
        let e = crate::yaml::parse("a: [1\n").expect_err("unclosed");
        let d = Diagnostic::from(e.clone()).in_file("m.yaml");
        assert_eq!((d.line(), d.col(), d.message.as_str()), (e.pos.line, e.pos.col, e.message.as_str()));
        assert_eq!(d.to_string(), format!("m.yaml:{}: error: {}", e.pos, e.message));
    }
}
