//! The error of a robot file: a message at its file, line and column.

/// One error in a robot file: `FILE:LINE:COL: error: message`, or
/// `FILE: error: message` for the file as a whole. It is a [`Diagnostic`]
/// (of severity error, with a file): [`ConfigError::new`] and
/// [`ConfigError::whole_file`] make one.
///
/// [`Diagnostic`]: crate::diagnostic::Diagnostic
pub type ConfigError = crate::diagnostic::Diagnostic;
