//! A finding of `situate map check`: a [`Diagnostic`] at the element's line
//! in the map file (1 when it concerns the whole map), about the element,
//! rendered as the loader's errors are.

use situate_robotfile::diagnostic::Diagnostic;
use situate_robotfile::yaml::Pos;

/// A finding at `line`, about `element` (named as the loader names it:
/// `floor 4, door 2`); the caller names the file ([`Diagnostic::in_file`]).
pub(super) fn finding(line: usize, element: impl Into<String>, message: impl Into<String>) -> Diagnostic {
    Diagnostic::at(Pos::new(line.max(1), 0), message).about(element)
}
