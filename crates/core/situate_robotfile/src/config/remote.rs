//! Remote skills: the declarations of the `remote:` entries, each read from
//! its manifest, written in the robot file or in a file of its own.

use super::{ConfigError, Node, Pos, RobotFile, Spanned};
use crate::limits::MAX_ROBOT_FILE_BYTES;
use crate::yaml;

impl RobotFile {
    /// The declarations of the file's remote skills (`remote:` entries), as
    /// `(instance name, declaration of type remote.<name>)`.
    pub fn remote_decls(&self) -> Result<Vec<(String, situate_core::SkillDecl)>, Vec<ConfigError>> {
        let mut out = Vec::new();
        let mut errors = Vec::new();
        for e in &self.skills {
            let Some(manifest) = &e.remote else { continue };
            let skill = &e.name.value;
            if let Some(path) = manifest.value.as_text() {
                match self.manifest_file(path, manifest.pos, &e.type_name.value, skill) {
                    Ok(decl) => out.push((skill.clone(), decl)),
                    Err(errs) => errors.extend(errs),
                }
                continue;
            }
            match crate::manifest::decl_from_node(manifest, &e.type_name.value, situate_core::SkillKind::Async) {
                Ok(decl) => out.push((skill.clone(), decl)),
                Err(errs) => errors.extend(
                    errs.into_iter()
                        .map(|d| self.error(d.pos.unwrap_or(manifest.pos), format!("skill `{skill}`: {}", d.message))),
                ),
            }
        }
        if errors.is_empty() {
            Ok(out)
        } else {
            Err(errors)
        }
    }

    /// A remote skill's manifest read from a file (`remote: path.yaml`): the
    /// same manifest a C, C++ or Python skill type is declared with, so the
    /// declaration is written once. Its `name` and `kind` are ignored (a
    /// remote skill is an asynchronous cskill named by the robot file);
    /// errors name the manifest file's line.
    fn manifest_file(
        &self,
        path: &str,
        pos: Pos,
        type_name: &str,
        skill: &str,
    ) -> Result<situate_core::SkillDecl, Vec<ConfigError>> {
        let resolved = self.resolve_at(pos, path.trim());
        let shown = resolved.display().to_string();
        let in_manifest = |pos: Pos, msg: String| ConfigError::new(&shown, pos, format!("skill `{skill}`: {msg}"));
        let text = yaml::read_source(&resolved, "skill manifest", MAX_ROBOT_FILE_BYTES).map_err(|e| {
            vec![match e {
                yaml::ReadError::Io { source, .. } => {
                    self.error(pos, format!("skill `{skill}`: cannot read the manifest `{shown}`: {source}"))
                }
                yaml::ReadError::NotUtf8 { pos, .. } => in_manifest(pos, e.to_string()),
                e => self.error(pos, format!("skill `{skill}`: the manifest `{shown}`: {e}")),
            }]
        })?;
        let tree = yaml::parse(&text).map_err(|e| vec![in_manifest(e.pos, e.message)])?;
        let node = match &tree.value {
            Node::Map(entries) => Spanned::new(
                Node::Map(
                    entries.iter().filter(|(k, _)| !matches!(k.value.as_str(), "name" | "kind")).cloned().collect(),
                ),
                tree.pos,
            ),
            other => {
                return Err(vec![in_manifest(
                    tree.pos,
                    format!("a skill manifest is a mapping, got {}", other.describe()),
                )])
            }
        };
        crate::manifest::decl_from_node(&node, type_name, situate_core::SkillKind::Async)
            .map_err(|errs| errs.into_iter().map(|d| in_manifest(d.pos.unwrap_or(tree.pos), d.message)).collect())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::tests::error;

    #[test]
    fn a_remote_manifest_can_be_a_file_whose_errors_name_its_own_lines() {
        let dir = std::env::temp_dir().join(format!("situate-remote-manifest-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(
            dir.join("scale.yaml"),
            "name: c.scale\nkind: sync\ninputs: {x: f64}\noutputs: {y: f64}\nparams:\n  gain: {type: f64, default: 2.0, min: 0, max: 10}\n",
        )
        .unwrap();
        std::fs::write(dir.join("bad.yaml"), "name: c.bad\ninputs: {x: f64}\noutputs: {y: nonsense}\n").unwrap();
        let file = dir.join("robot.yaml").display().to_string();
        let src = "robot: r\nskills:\n  - {name: scale, remote: scale.yaml}\n";
        let decls = RobotFile::parse(&file, src).unwrap().remote_decls().unwrap();
        let (name, decl) = &decls[0];
        assert_eq!(name, "scale");
        assert_eq!(decl.type_name, "remote.scale");
        assert_eq!(decl.kind, situate_core::SkillKind::Async, "served out of process it is asynchronous");
        assert_eq!((decl.inputs[0].name.as_str(), decl.outputs[0].name.as_str()), ("x", "y"));
        assert_eq!(decl.params[0].max, Some(10.0));

        let src = "robot: r\nskills:\n  - {name: bad, remote: bad.yaml}\n  - {name: gone, remote: nowhere.yaml}\n";
        let errors: Vec<String> =
            RobotFile::parse(&file, src).unwrap().remote_decls().unwrap_err().iter().map(|e| e.to_string()).collect();
        let bad = dir.join("bad.yaml").display().to_string();
        assert!(errors[0].starts_with(&format!("{bad}:3:")) && errors[0].contains("skill `bad`"), "{errors:?}");
        assert!(errors[1].starts_with(&format!("{file}:4:")) && errors[1].contains("nowhere.yaml"), "{errors:?}");
        let _ = std::fs::remove_dir_all(&dir);

        assert!(error("robot: r\nskills:\n  - {name: x, remote: [a, b]}\n").contains("or the path of a manifest file"));
        assert_eq!(
            error("robot: r\nskills:\n  - {name: x, type: toy.wander, timeout_ms: 500}\n"),
            "robot.yaml:3:45: error: `timeout_ms` in skill `x` is for remote skills (how long an answer may take)"
        );
        assert!(error("robot: r\nskills:\n  - {name: x, remote: x.yaml, timeout_ms: 0}\n").contains("timeout_ms"));
    }
}
