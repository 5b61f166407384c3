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
//!   (see `lex.rs`);
//! * one document per file (an empty file is a [`Node::Null`] document);
//! * mapping keys are scalars, and a key may appear once per mapping;
//! * no anchors, aliases or tags;
//! * at most [`MAX_DEPTH`] levels of nesting.
//!
//! Scalars keep their source text; [`Node::to_value`] types plain scalars by
//! the YAML 1.2 core schema (`true`, `3`, `0x1f`, `0.5`, `1e-3`, `.inf`, …),
//! while quoted and block scalars are always strings. Plain `null`, `~` and
//! empty values are [`Node::Null`] already in the tree.

mod lex;
mod node;
mod parse;
mod read;

pub use crate::limits::MAX_DEPTH;
pub use node::{Node, Pos, Spanned};
pub use parse::{parse, set_src, ParseError};
pub use read::{read_source, ReadError};
