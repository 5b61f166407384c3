//! Paths written in a robot file: `libraries:` and `python:`, and the file
//! paths inside `link.zenoh`, each made absolute from the directory of the
//! file it is written in.

use std::path::{Path, PathBuf};

use super::check::Checker;
use super::{Node, Pos, Spanned};
use crate::include::base_dir;

/// The keys of Zenoh's configuration whose values are file paths (TLS keys
/// and certificates, the user/password dictionary, public-key files).
pub const ZENOH_PATH_KEYS: &[&str] = &[
    "root_ca_certificate",
    "listen_private_key",
    "listen_certificate",
    "connect_private_key",
    "connect_certificate",
    "dictionary_file",
    "public_key_file",
    "private_key_file",
    "known_keys_file",
];

/// Makes the file paths of `link.zenoh` ([`ZENOH_PATH_KEYS`]) absolute from
/// the robot file's directory, as every other path in the file; Zenoh would
/// take them from the current directory. `zenoh` says whether `node` is
/// inside `link.zenoh` already.
pub(super) fn resolve_zenoh_paths(node: &mut Node, dir: &Path, zenoh: bool) {
    match node {
        Node::Map(entries) => {
            for (key, value) in entries {
                match &mut value.value {
                    Node::Scalar { text, .. } if zenoh && ZENOH_PATH_KEYS.contains(&key.value.as_str()) => {
                        if !text.trim().is_empty() && Path::new(text.as_str()).is_relative() {
                            *text = dir.join(text.as_str()).display().to_string();
                        }
                    }
                    other => resolve_zenoh_paths(other, dir, zenoh || key.value == "zenoh"),
                }
            }
        }
        Node::Seq(items) if zenoh => {
            for item in items {
                resolve_zenoh_paths(&mut item.value, dir, zenoh);
            }
        }
        _ => {}
    }
}

impl Checker<'_> {
    /// A list of paths: `key: [a, b]` or one per line.
    pub(super) fn paths(&mut self, key: &str, what: &str, value: Spanned<Node>) -> Vec<Spanned<String>> {
        if value.value.is_null() {
            return Vec::new();
        }
        let Some(items) = value.value.as_seq() else {
            self.push(value.pos, format!("`{key}` expects a list of paths ({what}), got {}", value.value.describe()));
            return Vec::new();
        };
        let mut out = Vec::new();
        for item in items {
            match item.value.as_text() {
                Some(text) if !text.trim().is_empty() => out.push(Spanned::new(text.to_string(), item.pos)),
                _ => self.push(item.pos, format!("`{key}` expects paths, got {}", item.value.describe())),
            }
        }
        out
    }

    /// The directory relative paths written at `pos` start from.
    pub(super) fn dir_of(&self, pos: Pos) -> PathBuf {
        match self.sources.get(pos.src) {
            Some(source) => source.dir.clone(),
            None => base_dir(self.file),
        }
    }

    /// Paths written once: the same file named again (by this file and one
    /// it includes, say) is dropped.
    pub(super) fn dedup_paths(&self, paths: Vec<Spanned<String>>) -> Vec<Spanned<String>> {
        let mut seen = std::collections::HashSet::new();
        paths.into_iter().filter(|p| seen.insert(self.dir_of(p.pos).join(&p.value))).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::tests::{error, p, s};
    use crate::config::RobotFile;

    #[test]
    fn libraries_python_and_simulator_sections_are_kept_and_paths_resolve_from_the_file() {
        let src = "robot: r\nlibraries: [build/librunaway.so, /abs/lib.so]\npython:\n  - skills/runaway.py\nsimulator: {map: maps/default.yaml, seed: 3}\n";
        let r = RobotFile::parse("robots/r.yaml", src).unwrap();
        assert_eq!(r.libraries, vec![s("build/librunaway.so".to_string(), 2, 13), s("/abs/lib.so".to_string(), 2, 34)]);
        assert_eq!(r.python, vec![s("skills/runaway.py".to_string(), 4, 5)]);
        let cwd = std::env::current_dir().unwrap();
        assert_eq!(r.dir, cwd.join("robots"));
        assert_eq!(r.resolve(&r.libraries[0].value), cwd.join("robots/build/librunaway.so"));
        assert_eq!(r.resolve(&r.python[0].value), cwd.join("robots/skills/runaway.py"));
        assert_eq!(r.resolve(&r.libraries[1].value), PathBuf::from("/abs/lib.so"));
        let sim = r.simulator.as_ref().unwrap();
        assert_eq!(sim.value.get("seed").and_then(|n| n.value.as_i64()), Some(3));
    }

    #[test]
    fn a_bare_name_is_a_file_next_to_the_robot_file_not_one_searched_for() {
        // Before: `libfoo.so` stayed a bare name, which the dynamic loader
        // looks for on the system's library path, not next to the file.
        let r = RobotFile::parse("r.yaml", "robot: r\nlibraries: [libfoo.so]\npython: [skills.py]\n").unwrap();
        let cwd = std::env::current_dir().unwrap();
        assert_eq!(r.resolve(&r.libraries[0].value), cwd.join("libfoo.so"));
        assert_eq!(r.resolve(&r.python[0].value), cwd.join("skills.py"));
        assert!(r.resolve("x").is_absolute());
        let r = RobotFile::parse("/etc/robots/r.yaml", "robot: r\n").unwrap();
        assert_eq!(r.resolve("../maps/m.yaml"), PathBuf::from("/etc/robots/../maps/m.yaml"));
    }

    #[test]
    fn zenoh_file_paths_resolve_from_the_robot_file_too() {
        let src = "\
robot: r
link:
  listen: [tls/127.0.0.1:7447]
  zenoh:
    transport:
      link:
        tls: {listen_certificate: certs/robot.crt, root_ca_certificate: /etc/ca.crt, enable_mtls: true}
      auth:
        usrpwd: {dictionary_file: users.txt, user: certs/not-a-path}
";
        let r = RobotFile::parse("/srv/robots/r.yaml", src).unwrap();
        let link = &r.link.as_ref().unwrap().value;
        let zenoh = &link.get("zenoh").unwrap().value;
        let transport = &zenoh.get("transport").unwrap().value;
        let tls = &transport.get("link").unwrap().value.get("tls").unwrap();
        let text = |n: &Spanned<Node>, k: &str| n.value.get(k).unwrap().value.as_text().map(str::to_string);
        assert_eq!(text(tls, "listen_certificate").as_deref(), Some("/srv/robots/certs/robot.crt"));
        assert_eq!(text(tls, "root_ca_certificate").as_deref(), Some("/etc/ca.crt"));
        assert_eq!(tls.value.get("listen_certificate").unwrap().pos, p(7, 35), "positions stay");
        let usrpwd = transport.get("auth").unwrap().value.get("usrpwd").unwrap();
        assert_eq!(text(usrpwd, "dictionary_file").as_deref(), Some("/srv/robots/users.txt"));
        assert_eq!(text(usrpwd, "user").as_deref(), Some("certs/not-a-path"));
        let listen = link.get("listen").unwrap().value.as_seq().unwrap()[0].value.as_text().unwrap();
        assert_eq!(listen, "tls/127.0.0.1:7447");
    }

    #[test]
    fn a_library_list_that_is_not_a_list_of_paths_is_an_error_at_its_place() {
        assert_eq!(
            error("robot: r\nlibraries: 3\n"),
            "robot.yaml:2:12: error: `libraries` expects a list of paths (shared libraries of C/C++ skills), got 3"
        );
        assert_eq!(
            error("robot: r\npython: [a.py, {x: 1}]\n"),
            "robot.yaml:2:16: error: `python` expects paths, got a mapping"
        );
    }
}
