//! A message at a position: the one type of every problem found in a robot
//! file, a file it includes, a skill manifest, or a robot built from them.
//!
//! A [`Diagnostic`] has a severity, the file it is in, a position (line and
//! column, both from 1) and a message, and one rendering:
//! `FILE:LINE:COL: error: message` (`warning:` for a warning), with the
//! parts it lacks left out (`FILE: error: message` for the file as a whole).
//! The robot file's errors ([`ConfigError`](crate::error::ConfigError)) are
//! diagnostics; the YAML reader's [`ParseError`] and a manifest's problems
//! convert into them.

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
            message: message.into(),
        }
    }

    /// An error about the file as a whole (it cannot be read, it is too
    /// large): no position.
    pub fn whole_file(file: &str, message: impl Into<String>) -> Diagnostic {
        Diagnostic { severity: Severity::Error, file: Some(file.to_string()), pos: None, message: message.into() }
    }

    /// An error at `pos` of a text whose file the caller knows (a manifest
    /// read from a file, a robot file's section): see [`Diagnostic::in_file`].
    pub fn at(pos: Pos, message: impl Into<String>) -> Diagnostic {
        Diagnostic { severity: Severity::Error, file: None, pos: Some(pos), message: message.into() }
    }

    /// An error with no place (a configuration built in code, not read from a file).
    pub fn without_place(message: impl Into<String>) -> Diagnostic {
        Diagnostic { severity: Severity::Error, file: None, pos: None, message: message.into() }
    }

    /// The same diagnostic, in `file`.
    pub fn in_file(self, file: &str) -> Diagnostic {
        Diagnostic { file: Some(file.to_string()), ..self }
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
        match (&self.file, self.pos) {
            (Some(file), Some(p)) => write!(f, "{file}:{}:{}: {level}: {}", p.line, p.col, self.message),
            (Some(file), None) => write!(f, "{file}: {level}: {}", self.message),
            (None, Some(p)) => write!(f, "{}:{}: {level}: {}", p.line, p.col, self.message),
            (None, None) => write!(f, "{level}: {}", self.message),
        }
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
        let warning = Diagnostic { severity: Severity::Warning, file: None, pos: None, message: "hm".into() };
        assert_eq!(warning.to_string(), "warning: hm");
        assert!(!warning.is_error());
        assert_eq!((warning.line(), warning.col()), (0, 0));
    }

    #[test]
    fn a_yaml_error_becomes_one_in_its_file() {
        let e = crate::yaml::parse("a: [1\n").expect_err("unclosed");
        let d = Diagnostic::from(e.clone()).in_file("m.yaml");
        assert_eq!((d.line(), d.col(), d.message.as_str()), (e.pos.line, e.pos.col, e.message.as_str()));
        assert_eq!(d.to_string(), format!("m.yaml:{}: error: {}", e.pos, e.message));
    }
}
