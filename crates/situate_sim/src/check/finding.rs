//! A finding of `situate map check`: the element, its line in the map file
//! and what is wrong with it, rendered as the loader's errors or as JSON.

use serde_json::{json, Value as Json};

/// One problem found: the element, its line in the map file and what is wrong.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Finding {
    /// The map line of the element (1 when it concerns the whole map).
    pub line: usize,
    /// The element, named as the loader names it (`floor 4, door 2`).
    pub element: String,
    pub message: String,
}

impl Finding {
    pub(super) fn new(line: usize, element: impl Into<String>, message: impl Into<String>) -> Finding {
        Finding { line: line.max(1), element: element.into(), message: message.into() }
    }

    /// `FILE:LINE: ELEMENT: MESSAGE`, as the loader's errors.
    pub fn render(&self, file: &str) -> String {
        format!("{file}:{}: {}: {}", self.line, self.element, self.message)
    }

    /// `{"line": …, "element": …, "message": …}`.
    pub fn to_json(&self) -> Json {
        json!({"line": self.line, "element": self.element, "message": self.message})
    }
}
