//! The error of a robot file: a message at its file, line and column.

use crate::yaml::Pos;

/// One error in a robot file: `FILE:LINE:COL: error: message`, or
/// `FILE: error: message` for the file as a whole (line and column 0).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{file}{}: error: {message}", at(*.line, *.col))]
pub struct ConfigError {
    pub file: String,
    pub line: usize,
    pub col: usize,
    pub message: String,
}

/// `:LINE:COL`, or nothing for line 0.
fn at(line: usize, col: usize) -> String {
    if line == 0 {
        String::new()
    } else {
        format!(":{line}:{col}")
    }
}

impl ConfigError {
    pub fn new(file: &str, pos: Pos, message: impl Into<String>) -> ConfigError {
        ConfigError { file: file.to_string(), line: pos.line, col: pos.col, message: message.into() }
    }

    /// An error about the file as a whole (it cannot be read, it is too
    /// large): no position.
    pub fn whole_file(file: &str, message: impl Into<String>) -> ConfigError {
        ConfigError { file: file.to_string(), line: 0, col: 0, message: message.into() }
    }

    pub fn pos(&self) -> Pos {
        Pos::new(self.line, self.col)
    }
}
