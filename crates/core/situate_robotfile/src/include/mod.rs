//! Robot files that compose: `include:`, and `${ENV}` substitution.
//!
//! A robot file may say `include: [base.yaml, sensors.yaml]` at the top
//! level; the paths are relative to the including file. Each included file
//! is read (its own includes first), and the files are merged in order, the
//! including file last, by one rule: **what comes later wins**.
//!
//! - `devices:` and `skills:`: entries are concatenated, included ones
//!   first. An entry whose `name` is already defined by an earlier file (in
//!   the same section) overrides it in place, key by key: the keys it gives
//!   replace those of the earlier entry, and its `params:` and `remap:` are
//!   merged name by name (a `type:` drops an earlier `remote:`, and the other
//!   way round). Two entries of one name in the same file stay a duplicate.
//! - `libraries:` and `python:`: concatenated, included ones first.
//! - Every other section (`robot`, `cycle`, `link`, `gui`, `ros2`,
//!   `simulator`): the later file's section replaces the earlier's as a
//!   whole.
//!
//! Every position in the merged tree keeps the file it was read from
//! ([`Pos::src`], an index into [`RobotFile::sources`](crate::config::RobotFile::sources)),
//! so errors name the included file's own line; a missing or unreadable
//! included file, and a cycle of includes, are errors at the `include:`
//! item. The format is documented in `docs/robot-files.md`.
//!
//! This file reads the files and composes them; `merge.rs` holds the merge
//! rules and `env.rs` the `${NAME}` substitution.

use std::path::{Path, PathBuf};

use crate::error::ConfigError;
use crate::limits::MAX_ROBOT_FILE_BYTES;
pub use crate::limits::{MAX_INCLUDE_DEPTH, MAX_SOURCE_FILES};
use crate::yaml::{self, Node, Pos, Spanned};

mod env;
mod merge;

pub use env::{substitute_env, EnvLookup};
use merge::merge;

/// One file a robot file was read from: the file itself, or one it
/// includes.
#[derive(Debug, Clone, PartialEq)]
pub struct SourceFile {
    /// The path shown in messages: the robot file's as given; an included
    /// file's joined to its includer's directory as shown.
    pub file: String,
    /// The file's directory, absolute: relative paths written in it start
    /// here.
    pub dir: PathBuf,
    /// Where it is included (the `include:` item), `None` for the robot
    /// file itself.
    pub included_at: Option<Pos>,
}

/// How a robot file is read.
#[derive(Clone, Copy, Default)]
pub struct LoadOptions<'a> {
    /// When given, `${NAME}` in the file and in every file it includes is
    /// replaced from this lookup (see [`substitute_env`]); usually
    /// `std::env::var(name).ok()`.
    pub env: Option<EnvLookup<'a>>,
}

type Entries = Vec<(Spanned<String>, Spanned<Node>)>;

/// Reads the includes of a robot file and merges them.
pub(crate) struct Composer<'a> {
    pub(crate) sources: Vec<SourceFile>,
    /// Errors, each with its position for sorting.
    pub(crate) errors: Vec<(Pos, ConfigError)>,
    options: LoadOptions<'a>,
    /// The files being read, outermost first (canonical path, shown path),
    /// to find cycles.
    chain: Vec<(PathBuf, String)>,
}

impl<'a> Composer<'a> {
    /// The tree of robot file `file` (text `source`) with its includes
    /// merged in; `None` when the file itself cannot be parsed. Errors are
    /// left in `errors`.
    pub(crate) fn compose(file: &str, source: &str, options: LoadOptions<'a>) -> (Option<Spanned<Node>>, Composer<'a>) {
        let dir = base_dir(file);
        let mut cx = Composer {
            sources: vec![SourceFile { file: file.to_string(), dir, included_at: None }],
            errors: Vec::new(),
            options,
            chain: Vec::new(),
        };
        let path = Path::new(file);
        let canonical = std::fs::canonicalize(path).unwrap_or_else(|_| std::path::absolute(path).unwrap_or_default());
        cx.chain.push((canonical, file.to_string()));
        let tree = cx.tree(0, source);
        (tree, cx)
    }

    fn push(&mut self, pos: Pos, message: impl Into<String>) {
        let file = &self.sources[pos.src].file;
        self.errors.push((pos, ConfigError::new(file, pos, message)));
    }

    /// The tree of source `src`, its includes merged in.
    fn tree(&mut self, src: usize, source: &str) -> Option<Spanned<Node>> {
        let substituted;
        let source = match self.options.env {
            Some(env) => match substitute_env(source, env) {
                Ok(s) => {
                    substituted = s;
                    substituted.as_str()
                }
                Err((line, col, message)) => {
                    self.push(Pos::new(line, col).in_src(src), message);
                    return None;
                }
            },
            None => source,
        };
        let mut root = match yaml::parse(source) {
            Ok(root) => root,
            Err(e) => {
                self.push(e.pos.in_src(src), e.message);
                return None;
            }
        };
        yaml::set_src(&mut root, src);
        let entries = match root.value {
            Node::Map(entries) => entries,
            Node::Null if src > 0 => Vec::new(),
            other if src > 0 => {
                self.push(root.pos, format!("an included robot file is a mapping, got {}", other.describe()));
                return None;
            }
            // The robot file's own shape is the checker's to report.
            other => return Some(Spanned::new(other, root.pos)),
        };
        let (includes, own): (Entries, Entries) = entries.into_iter().partition(|(k, _)| k.value == "include");
        let mut merged = Vec::new();
        for (_, value) in includes {
            for (path, pos) in self.include_paths(&value) {
                if let Some(included) = self.include(src, &path, pos) {
                    merged = merge(merged, included);
                }
            }
        }
        Some(Spanned::new(Node::Map(merge(merged, own)), root.pos))
    }

    /// The paths of an `include:` value: one path or a list of paths.
    fn include_paths(&mut self, value: &Spanned<Node>) -> Vec<(String, Pos)> {
        let items: Vec<&Spanned<Node>> = match &value.value {
            Node::Null => return Vec::new(),
            Node::Scalar { .. } => vec![value],
            Node::Seq(items) => items.iter().collect(),
            Node::Map(_) => {
                self.push(value.pos, "`include` expects a list of robot file paths, got a mapping");
                return Vec::new();
            }
        };
        let mut out = Vec::new();
        for item in items {
            match item.value.as_text() {
                Some(text) if !text.trim().is_empty() => out.push((text.trim().to_string(), item.pos)),
                _ => self
                    .push(item.pos, format!("`include` expects paths of robot files, got {}", item.value.describe())),
            }
        }
        out
    }

    /// Reads and composes the file `path` included by source `from` at
    /// `pos`; its top-level entries.
    fn include(&mut self, from: usize, path: &str, pos: Pos) -> Option<Entries> {
        let resolved = self.sources[from].dir.join(path);
        let shown = match Path::new(&self.sources[from].file).parent() {
            Some(parent) => tidy(&parent.join(path)),
            None => path.to_string(),
        };
        let canonical = match std::fs::canonicalize(&resolved) {
            Ok(c) => c,
            Err(e) => {
                let why = match e.kind() {
                    std::io::ErrorKind::NotFound => "no such file".to_string(),
                    _ => e.to_string(),
                };
                self.push(pos, format!("cannot read the included file `{shown}`: {why}"));
                return None;
            }
        };
        if let Some(at) = self.chain.iter().position(|(c, _)| *c == canonical) {
            let mut names: Vec<&str> = self.chain[at..].iter().map(|(_, s)| s.as_str()).collect();
            names.push(&shown);
            self.push(pos, format!("include cycle: {}", names.join(" → ")));
            return None;
        }
        if self.chain.len() >= MAX_INCLUDE_DEPTH {
            self.push(pos, format!("includes nest more than {MAX_INCLUDE_DEPTH} deep here (`{shown}`)"));
            return None;
        }
        if self.sources.len() >= MAX_SOURCE_FILES {
            self.push(pos, format!("a robot file may read at most {MAX_SOURCE_FILES} files with its includes"));
            return None;
        }
        let src = self.sources.len();
        let dir = resolved.parent().map(Path::to_path_buf).unwrap_or_default();
        self.sources.push(SourceFile { file: shown.clone(), dir, included_at: Some(pos) });
        let text = match yaml::read_source(&resolved, "robot file", MAX_ROBOT_FILE_BYTES) {
            Ok(text) => text,
            Err(e) => {
                match e.pos() {
                    // Invalid UTF-8: at its place in the included file.
                    Some(at) => self.push(at.in_src(src), e.to_string()),
                    None => self.push(pos, format!("the included file `{shown}`: {e}")),
                }
                return None;
            }
        };
        self.chain.push((canonical, shown));
        let tree = self.tree(src, &text);
        self.chain.pop();
        match tree?.value {
            Node::Map(entries) => Some(entries),
            _ => None,
        }
    }
}

/// The absolute directory of the robot file named `file` (relative to the
/// current directory when `file` is).
pub(crate) fn base_dir(file: &str) -> PathBuf {
    let file = Path::new(file);
    let dir = file.parent().unwrap_or(Path::new(""));
    let dir = if dir.as_os_str().is_empty() { Path::new(".") } else { dir };
    std::path::absolute(dir).unwrap_or_else(|_| dir.to_path_buf())
}

/// A path as shown: `common/../lab.yaml` as `lab.yaml` (lexically: `x/..`
/// dropped where `x` is a name, `.` dropped).
fn tidy(path: &Path) -> String {
    use std::path::Component;
    let mut out: Vec<Component<'_>> = Vec::new();
    for c in path.components() {
        match c {
            Component::CurDir => {}
            Component::ParentDir if matches!(out.last(), Some(Component::Normal(_))) => {
                out.pop();
            }
            c => out.push(c),
        }
    }
    if out.is_empty() {
        return ".".to_string();
    }
    out.iter().collect::<PathBuf>().display().to_string()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shown_paths_are_tidied_lexically() {
        assert_eq!(tidy(Path::new("common/../lab.yaml")), "lab.yaml");
        assert_eq!(tidy(Path::new("./a/./b.yaml")), "a/b.yaml");
        assert_eq!(tidy(Path::new("../up.yaml")), "../up.yaml");
        assert_eq!(tidy(Path::new("/r/x/../y.yaml")), "/r/y.yaml");
    }
}
