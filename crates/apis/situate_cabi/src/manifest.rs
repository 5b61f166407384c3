//! A foreign skill's manifest: the format of
//! `situate_robotfile::manifest` (doc, priority, inputs, outputs, params) plus
//! `name` (required: the type name robot files use) and `kind` (`sync`, the
//! default, `async` or `device`).
//!
//! ```yaml
//! name: c.runaway
//! priority: 50
//! inputs:  {sonar_range: f32[24]}
//! outputs: {drive: "{v: f64, w: f64}"}
//! params:
//!   safe_distance: {type: f64, default: 0.5, min: 0.1, max: 3.0, unit: m}
//! ```

use std::fmt;

use situate_core::{SkillDecl, SkillKind};
use situate_robotfile::diagnostic::Diagnostic;
use situate_robotfile::yaml::{self, Node, Pos, Spanned};

/// One problem in a manifest, at a 1-based line and column of its text.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ManifestProblem {
    pub line: usize,
    pub col: usize,
    pub message: String,
}

/// Every problem of a manifest that does not declare a skill.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub struct ManifestError {
    pub problems: Vec<ManifestProblem>,
}

impl fmt::Display for ManifestError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for (i, p) in self.problems.iter().enumerate() {
            if i > 0 {
                f.write_str("; ")?;
            }
            write!(f, "line {}, column {}: {}", p.line, p.col, p.message)?;
        }
        Ok(())
    }
}

/// A manifest's problem as the front end reports it (a diagnostic at its
/// place).
impl From<Diagnostic> for ManifestProblem {
    fn from(d: Diagnostic) -> ManifestProblem {
        ManifestProblem { line: d.line(), col: d.col(), message: d.message }
    }
}

fn problem(pos: Pos, message: impl Into<String>) -> ManifestError {
    ManifestError { problems: vec![ManifestProblem { line: pos.line, col: pos.col, message: message.into() }] }
}

/// Reads a manifest's text into a declaration.
pub fn parse_manifest(text: &str) -> Result<SkillDecl, ManifestError> {
    let tree = yaml::parse(text).map_err(|e| ManifestError { problems: vec![Diagnostic::from(e).into()] })?;
    let Some(entries) = tree.value.as_map() else {
        return Err(problem(tree.pos, format!("a skill manifest is a mapping, got {}", tree.value.describe())));
    };
    let mut name = None;
    let mut kind = SkillKind::Sync;
    let mut rest = Vec::new();
    for (key, value) in entries {
        match key.value.as_str() {
            "name" => match value.value.as_text().map(str::trim).filter(|t| is_type_name(t)) {
                Some(t) => name = Some(t.to_string()),
                None => {
                    return Err(problem(
                        value.pos,
                        format!(
                        "`name` expects a skill type name such as c.runaway (letters, digits, `_`, `.`, `-`), got {}",
                        value.value.describe()
                    ),
                    ))
                }
            },
            "kind" => match value.value.as_text().and_then(SkillKind::parse) {
                Some(k) => kind = k,
                None => {
                    return Err(problem(
                        value.pos,
                        format!("`kind` is sync, async or device, got {}", value.value.describe()),
                    ))
                }
            },
            _ => rest.push((key.clone(), value.clone())),
        }
    }
    let Some(name) = name else {
        return Err(problem(tree.pos, "the manifest has no `name` (the skill type's name, such as c.runaway)"));
    };
    let node = Spanned::new(Node::Map(rest), tree.pos);
    situate_robotfile::manifest::decl_from_node(&node, &name, kind)
        .map_err(|errors| ManifestError { problems: errors.into_iter().map(ManifestProblem::from).collect() })
}

fn is_type_name(s: &str) -> bool {
    !s.is_empty() && s.chars().all(|c| c.is_ascii_alphanumeric() || matches!(c, '_' | '.' | '-'))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn name_and_kind_come_with_the_declaration() {
        let d = parse_manifest("name: c.t\nkind: async\npriority: 3\ninputs: {x: f64}\noutputs: {y: f64}\n").unwrap();
        assert_eq!((d.type_name.as_str(), d.kind, d.priority), ("c.t", SkillKind::Async, 3));
        assert_eq!(d.inputs[0].name, "x");
    }

    #[test]
    fn problems_name_the_line() {
        let e = parse_manifest("name: c.t\ninputs: {x: f46}\n").unwrap_err();
        assert_eq!(e.problems[0].line, 2);
        assert!(e.to_string().starts_with("line 2, column 13: port `x`: unknown type `f46`"), "{e}");
        let e = parse_manifest("inputs: {x: f64}\n").unwrap_err();
        assert!(e.to_string().contains("no `name`"), "{e}");
        let e = parse_manifest("name: c.t\nkind: sometimes\n").unwrap_err();
        assert_eq!(e.problems[0].line, 2);
    }
}
