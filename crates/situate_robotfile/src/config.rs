//! Robot files: the YAML file that says which skills a robot runs.
//!
//! [`RobotFile::parse`] reads a file into a model whose every name and value
//! keeps its position, and checks its shape: known keys, value types and
//! ranges, identifiers. It collects every such error it finds, in file order,
//! each reading `FILE:LINE:COL: error: message`. Whether skill types,
//! parameters and signals exist and fit together is checked later by the
//! manager against its registry; it reports through [`RobotFile::error`] in
//! the same format. The format is documented in `docs/robot-files.md`.

use std::path::{Path, PathBuf};

use situate_core::names::suggestion;
use situate_core::value::Value;

pub use crate::error::ConfigError;
use crate::include::base_dir;
pub use crate::include::{LoadOptions, SourceFile};
use crate::limits::{DEADLINE_RANGE, PERIOD_RANGE, RATE_RANGE};
pub use crate::limits::{
    DEFAULT_RATE_HZ, MAX_DEADLINE_MS, MAX_ENTRIES, MAX_NAME_CHARS, MAX_RATE_HZ, MAX_ROBOT_FILE_BYTES, MAX_THREADS,
    MIN_PERIOD_MS, MIN_RATE_HZ,
};
pub use crate::names::{is_identifier, is_robot_name, is_signal_name};
use crate::yaml;
pub use crate::yaml::{Node, Pos, Spanned};

const TOP_KEYS: &[&str] =
    &["robot", "include", "cycle", "libraries", "python", "simulator", "devices", "skills", "link", "gui", "ros2"];
const CYCLE_KEYS: &[&str] = &["rate_hz", "period_ms", "clock", "executor", "threads", "budget_ms", "liveness_ms"];
const ENTRY_KEYS: &[&str] = &[
    "name",
    "type",
    "remote",
    "timeout_ms",
    "active",
    "priority",
    "period_ms",
    "budget_ms",
    "liveness_ms",
    "params",
    "remap",
];

/// Which clock drives the cycle.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ClockKind {
    Wall,
    Simulated,
}

/// How the cycle runs the synchronous skills.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ExecutorKind {
    Serial,
    Parallel,
}

/// The `cycle:` section.
#[derive(Debug, Clone, PartialEq)]
pub struct CycleConfig {
    /// Seconds between cycles.
    pub period_s: f64,
    pub clock: ClockKind,
    pub executor: ExecutorKind,
    /// The parallel executor's pool size, if given.
    pub threads: Option<usize>,
    /// The default execution budget of a sync cskill's run, ms.
    pub budget_ms: Option<f64>,
    /// The default liveness deadline of an async cskill's or dskill's run, ms.
    pub liveness_ms: Option<f64>,
    /// Where `cycle:` is (1:1 if the file has none).
    pub pos: Pos,
}

impl CycleConfig {
    pub fn rate_hz(&self) -> f64 {
        1.0 / self.period_s
    }
}

impl Default for CycleConfig {
    fn default() -> CycleConfig {
        CycleConfig {
            period_s: 1.0 / DEFAULT_RATE_HZ,
            clock: ClockKind::Wall,
            executor: ExecutorKind::Serial,
            threads: None,
            budget_ms: None,
            liveness_ms: None,
            pos: Pos::START,
        }
    }
}

/// The list a skill entry came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Section {
    /// `devices:` — dskills.
    Devices,
    /// `skills:` — cskills.
    Skills,
}

impl Section {
    /// The section's key: `devices` or `skills`.
    pub fn key(self) -> &'static str {
        match self {
            Section::Devices => "devices",
            Section::Skills => "skills",
        }
    }

    /// What one entry is called in messages: `device` or `skill`.
    pub fn noun(self) -> &'static str {
        match self {
            Section::Devices => "device",
            Section::Skills => "skill",
        }
    }
}

/// One parameter value of an entry's `params:`.
#[derive(Debug, Clone, PartialEq)]
pub struct Param {
    /// The parameter's name, where its key is.
    pub name: Spanned<String>,
    /// Its value, where the value is.
    pub value: Spanned<Value>,
    /// The value as the file writes it, for messages (`1e300`, not its
    /// digits); `None` for a list.
    pub written: Option<String>,
}

/// One entry of `devices:` or `skills:`.
#[derive(Debug, Clone, PartialEq)]
pub struct SkillEntry {
    pub section: Section,
    /// Where the list item starts (its first key).
    pub pos: Pos,
    pub name: Spanned<String>,
    pub type_name: Spanned<String>,
    pub active: bool,
    pub priority: Option<Spanned<i32>>,
    /// A device's thread period, or an async skill's worker period.
    pub period_ms: Option<Spanned<f64>>,
    /// Execution budget of one in-cycle run, ms (overrides `cycle.budget_ms`).
    pub budget_ms: Option<Spanned<f64>>,
    /// Liveness deadline of one run of a threaded body, ms (overrides
    /// `cycle.liveness_ms`).
    pub liveness_ms: Option<Spanned<f64>>,
    /// Parameter values in file order.
    pub params: Vec<Param>,
    /// Port name → signal name, in file order.
    pub remap: Vec<(Spanned<String>, Spanned<String>)>,
    /// A remote skill's manifest (`remote:` instead of `type:`); its type
    /// name is then `remote.<name>`.
    pub remote: Option<Spanned<Node>>,
    /// A remote skill's deadline: once its process has answered, an answer
    /// awaited longer than this (wall-clock ms) faults the skill.
    pub timeout_ms: Option<Spanned<f64>>,
}

impl SkillEntry {
    /// `skill `runaway`` or `device `sonar``, for messages.
    pub fn label(&self) -> String {
        format!("{} `{}`", self.section.noun(), self.name.value)
    }

    /// The value given for parameter `name`.
    pub fn param(&self, name: &str) -> Option<&Spanned<Value>> {
        self.params.iter().find(|p| p.name.value == name).map(|p| &p.value)
    }
}

/// A parsed robot file.
#[derive(Debug, Clone, PartialEq)]
pub struct RobotFile {
    /// The path as given, used in messages.
    pub file: String,
    /// The directory of the file, absolute: relative paths written in the
    /// file start here (see [`RobotFile::resolve`]).
    pub dir: PathBuf,
    pub robot: Spanned<String>,
    pub cycle: CycleConfig,
    /// The devices, then the skills, each in file order.
    pub skills: Vec<SkillEntry>,
    /// The raw `link:` section, if any.
    pub link: Option<Spanned<Node>>,
    /// The raw `gui:` section, if any.
    pub gui: Option<Spanned<Node>>,
    /// The raw `ros2:` section, if any (read by `situate_ros2::Ros2Config::from_node`).
    pub ros2: Option<Spanned<Node>>,
    /// `libraries:`: shared libraries of C/C++ skill types, as written (see
    /// [`RobotFile::resolve`]).
    pub libraries: Vec<Spanned<String>>,
    /// `python:`: Python source files of `@situate.skill` types, as written.
    pub python: Vec<Spanned<String>>,
    /// The raw `simulator:` section, if any (read by the program that runs
    /// a simulator).
    pub simulator: Option<Spanned<Node>>,
    /// The files read: `[0]` is this file, then those it includes, in the
    /// order read; a position's [`Pos::src`] indexes it.
    pub sources: Vec<SourceFile>,
}

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
                Err(errs) => {
                    errors.extend(errs.into_iter().map(|(pos, msg)| self.error(pos, format!("skill `{skill}`: {msg}"))))
                }
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
            .map_err(|errs| errs.into_iter().map(|(pos, msg)| in_manifest(pos, msg)).collect())
    }

    /// Parses and shape-checks a robot file; `file` names it in messages.
    /// Returns every error found, in file order.
    pub fn parse(file: &str, source: &str) -> Result<RobotFile, Vec<ConfigError>> {
        RobotFile::parse_with(file, source, LoadOptions::default())
    }

    /// [`RobotFile::parse`], reading the files it includes (`include:`,
    /// relative to `file`'s directory) and substituting `${NAME}`s as
    /// `options` say. Errors come in file order: this file's, then each
    /// included file's.
    pub fn parse_with(file: &str, source: &str, options: LoadOptions<'_>) -> Result<RobotFile, Vec<ConfigError>> {
        let (tree, composer) = crate::include::Composer::compose(file, source, options);
        let mut cx = Checker { file, sources: composer.sources, errors: composer.errors, entries: 0 };
        let parsed = tree.and_then(|root| cx.robot_file(root));
        match parsed {
            Some(robot) if cx.errors.is_empty() => Ok(robot),
            _ => {
                cx.errors.sort_by_key(|(pos, _)| *pos);
                Err(cx.errors.into_iter().map(|(_, e)| e).collect())
            }
        }
    }

    /// Reads and parses a robot file of at most [`MAX_ROBOT_FILE_BYTES`]
    /// (a larger one is refused before it is read). A file that cannot be
    /// read, or is too large, is one error without a position; invalid
    /// UTF-8 one at its place.
    pub fn load(path: &Path) -> Result<RobotFile, Vec<ConfigError>> {
        RobotFile::load_with(path, LoadOptions::default())
    }

    /// [`RobotFile::load`] with [`RobotFile::parse_with`]'s options.
    pub fn load_with(path: &Path, options: LoadOptions<'_>) -> Result<RobotFile, Vec<ConfigError>> {
        let file = path.display().to_string();
        match yaml::read_source(path, "robot file", MAX_ROBOT_FILE_BYTES) {
            Ok(source) => RobotFile::parse_with(&file, &source, options),
            Err(e) => Err(vec![match e.pos() {
                Some(pos) => ConfigError::new(&file, pos, e.to_string()),
                None => ConfigError::whole_file(&file, e.to_string()),
            }]),
        }
    }

    /// A path written in this file, made absolute from the file's own
    /// directory whatever the current directory is (absolute paths stay as
    /// they are). A bare name is a file next to the robot file, never one
    /// searched for elsewhere (`libfoo.so` is not looked up on the system's
    /// library path).
    pub fn resolve(&self, path: &str) -> PathBuf {
        self.dir.join(path)
    }

    /// A path written at `pos`, made absolute from the directory of the
    /// file it is written in (this file or one it includes).
    pub fn resolve_at(&self, pos: Pos, path: &str) -> PathBuf {
        match self.sources.get(pos.src) {
            Some(source) if pos.src > 0 => source.dir.join(path),
            _ => self.resolve(path),
        }
    }

    /// The file a position is in, as shown in messages.
    pub fn file_of(&self, pos: Pos) -> &str {
        self.sources.get(pos.src).map_or(&self.file, |s| &s.file)
    }

    /// An error at `pos` in this file (or the included file it is in), for
    /// checks made after parsing.
    pub fn error(&self, pos: Pos, message: impl Into<String>) -> ConfigError {
        ConfigError::new(self.file_of(pos), pos, message)
    }

    /// The entries of one section, in file order.
    pub fn section(&self, section: Section) -> impl Iterator<Item = &SkillEntry> {
        self.skills.iter().filter(move |s| s.section == section)
    }
}

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
fn resolve_zenoh_paths(node: &mut Node, dir: &Path, zenoh: bool) {
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

/// Walks the node tree, collecting errors.
struct Checker<'a> {
    file: &'a str,
    /// The files read (this one and those it includes).
    sources: Vec<SourceFile>,
    /// Errors, each with its position for sorting.
    errors: Vec<(Pos, ConfigError)>,
    /// Entries of `devices` and `skills` read so far.
    entries: usize,
}

type Entries = Vec<(Spanned<String>, Spanned<Node>)>;

impl Checker<'_> {
    fn push(&mut self, pos: Pos, message: impl Into<String>) {
        let file = self.sources.get(pos.src).map_or(self.file, |s| s.file.as_str());
        self.errors.push((pos, ConfigError::new(file, pos, message)));
    }

    /// The directory relative paths written at `pos` start from.
    fn dir_of(&self, pos: Pos) -> PathBuf {
        match self.sources.get(pos.src) {
            Some(source) => source.dir.clone(),
            None => base_dir(self.file),
        }
    }

    /// Paths written once: the same file named again (by this file and one
    /// it includes, say) is dropped.
    fn dedup_paths(&self, paths: Vec<Spanned<String>>) -> Vec<Spanned<String>> {
        let mut seen = std::collections::HashSet::new();
        paths.into_iter().filter(|p| seen.insert(self.dir_of(p.pos).join(&p.value))).collect()
    }

    fn unknown_key(&mut self, key: &Spanned<String>, place: &str, allowed: &[&str]) {
        let hint = suggestion(&key.value, allowed.iter().copied());
        self.push(key.pos, format!("unknown key `{}` {place}{hint}", key.value));
    }

    /// A mapping's entries; null is an empty mapping. Anything else is an
    /// error "`key` expects {what}, got …".
    fn mapping(&mut self, key: &str, node: Spanned<Node>, what: &str) -> Option<Entries> {
        match node.value {
            Node::Map(entries) => Some(entries),
            Node::Null => Some(Vec::new()),
            other => {
                self.push(node.pos, format!("`{key}` expects {what}, got {}", other.describe()));
                None
            }
        }
    }

    fn robot_file(&mut self, root: Spanned<Node>) -> Option<RobotFile> {
        let entries = match root.value {
            Node::Map(entries) => entries,
            Node::Null => Vec::new(),
            other => {
                self.push(
                    root.pos,
                    format!(
                        "a robot file is a mapping with keys `robot:`, `cycle:`, `devices:` and `skills:`, got {}",
                        other.describe()
                    ),
                );
                return None;
            }
        };
        let mut robot = None;
        let mut robot_given = false;
        let mut cycle = CycleConfig::default();
        let mut devices = Vec::new();
        let mut skills = Vec::new();
        let mut link = None;
        let mut gui = None;
        let mut ros2 = None;
        let mut libraries = Vec::new();
        let mut python = Vec::new();
        let mut simulator = None;
        for (key, value) in entries {
            match key.value.as_str() {
                "robot" => {
                    robot_given = true;
                    robot = self.robot_name(value);
                }
                "cycle" => cycle = self.cycle(key.pos, value),
                "devices" => devices = self.section(Section::Devices, value),
                "skills" => skills = self.section(Section::Skills, value),
                "link" => link = Some(value),
                "gui" => gui = Some(value),
                "ros2" => ros2 = Some(value),
                "libraries" => libraries = self.paths("libraries", "shared libraries of C/C++ skills", value),
                "python" => python = self.paths("python", "Python files of `@situate.skill` types", value),
                "simulator" => simulator = Some(value),
                _ => self.unknown_key(&key, "at the top level", TOP_KEYS),
            }
        }
        if !robot_given {
            self.push(root.pos, "missing required key `robot`");
        }
        devices.append(&mut skills);
        let dir = base_dir(self.file);
        if let Some(link) = &mut link {
            let link_dir = self.dir_of(link.pos);
            resolve_zenoh_paths(&mut link.value, &link_dir, false);
        }
        let libraries = self.dedup_paths(libraries);
        let python = self.dedup_paths(python);
        Some(RobotFile {
            file: self.file.to_string(),
            dir,
            robot: robot?,
            cycle,
            skills: devices,
            link,
            gui,
            ros2,
            libraries,
            python,
            simulator,
            sources: std::mem::take(&mut self.sources),
        })
    }

    /// A list of paths: `key: [a, b]` or one per line.
    fn paths(&mut self, key: &str, what: &str, value: Spanned<Node>) -> Vec<Spanned<String>> {
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

    /// Whether `text`, a `what`, is longer than [`MAX_NAME_CHARS`] (then an
    /// error at `pos`, which does not quote it).
    fn too_long(&mut self, what: &str, text: &str, pos: Pos) -> bool {
        let n = text.chars().count();
        if n > MAX_NAME_CHARS {
            self.push(pos, format!("{what} is {n} characters long; a name may have at most {MAX_NAME_CHARS}"));
        }
        n > MAX_NAME_CHARS
    }

    fn robot_name(&mut self, value: Spanned<Node>) -> Option<Spanned<String>> {
        match value.value.as_text() {
            Some(name) if self.too_long("the robot name", name, value.pos) => None,
            Some(name) if is_robot_name(name) => Some(Spanned::new(name.to_string(), value.pos)),
            Some(name) => {
                self.push(value.pos, format!("robot name `{name}` may only contain letters, digits, `_` and `-`"));
                None
            }
            None => {
                self.push(value.pos, format!("`robot` expects a name, got {}", value.value.describe()));
                None
            }
        }
    }

    fn cycle(&mut self, key_pos: Pos, node: Spanned<Node>) -> CycleConfig {
        let mut cycle = CycleConfig { pos: key_pos, ..CycleConfig::default() };
        let Some(entries) = self.mapping("cycle", node, "a mapping (`rate_hz:`, `clock:`, `executor:`, …)") else {
            return cycle;
        };
        let mut rate_key: Option<&str> = None;
        for (key, value) in &entries {
            let k = key.value.as_str();
            match k {
                "rate_hz" | "period_ms" => {
                    if let Some(first) = rate_key {
                        self.push(
                            key.pos,
                            format!("`cycle` takes either `rate_hz` or `period_ms`, not both (`{first}` is given too)"),
                        );
                        continue;
                    }
                    rate_key = Some(if k == "rate_hz" { "rate_hz" } else { "period_ms" });
                    if k == "rate_hz" {
                        if value.value.as_f64().is_some_and(|x| x > 0.0 && x < MIN_RATE_HZ) {
                            self.push(
                                value.pos,
                                format!(
                                    "`rate_hz` is out of range: the cycle must run at least once a day \
                                     (rate_hz ≥ 0.0000116), got {}",
                                    value.value.describe()
                                ),
                            );
                        } else if let Some(hz) = self.number(k, value, |x| x > 0.0 && x <= MAX_RATE_HZ, RATE_RANGE) {
                            cycle.period_s = 1.0 / hz;
                        }
                    } else if let Some(ms) = self.period(k, value) {
                        cycle.period_s = ms / 1000.0;
                    }
                }
                "clock" => {
                    if let Some(c) =
                        self.choice(k, value, &[("wall", ClockKind::Wall), ("simulated", ClockKind::Simulated)])
                    {
                        cycle.clock = c;
                    }
                }
                "executor" => {
                    if let Some(e) =
                        self.choice(k, value, &[("serial", ExecutorKind::Serial), ("parallel", ExecutorKind::Parallel)])
                    {
                        cycle.executor = e;
                    }
                }
                "threads" => {
                    cycle.threads = self.integer(k, value, 1, MAX_THREADS as i64).map(|n| n as usize);
                }
                "budget_ms" => cycle.budget_ms = self.deadline(k, value),
                "liveness_ms" => cycle.liveness_ms = self.deadline(k, value),
                _ => self.unknown_key(key, "in `cycle`", CYCLE_KEYS),
            }
        }
        cycle
    }

    /// A number that `ok` accepts; messages say it `expects` and quote the
    /// value as written (`1e300`, not its digits), at the value.
    fn number(&mut self, key: &str, value: &Spanned<Node>, ok: impl Fn(f64) -> bool, expects: &str) -> Option<f64> {
        let Some(x) = value.value.as_f64() else {
            self.push(value.pos, format!("`{key}` expects a number > 0, got {}", value.value.describe()));
            return None;
        };
        if ok(x) {
            Some(x)
        } else {
            self.push(value.pos, format!("`{key}` is out of range: expects {expects}, got {}", value.value.describe()));
            None
        }
    }

    /// A period in ms: 10 µs to a day.
    fn period(&mut self, key: &str, value: &Spanned<Node>) -> Option<f64> {
        self.number(key, value, |x| (MIN_PERIOD_MS..=MAX_DEADLINE_MS).contains(&x), PERIOD_RANGE)
    }

    /// A deadline in ms: > 0, at most a day.
    fn deadline(&mut self, key: &str, value: &Spanned<Node>) -> Option<f64> {
        self.number(key, value, |x| x > 0.0 && x <= MAX_DEADLINE_MS, DEADLINE_RANGE)
    }

    /// An integer in `min..=max`. An integer too large for 64 bits is out of
    /// range too, not "not an integer".
    fn integer(&mut self, key: &str, value: &Spanned<Node>, min: i64, max: i64) -> Option<i64> {
        let n = value.value.as_i64();
        if n.is_none() && !value.value.is_integer_literal() {
            self.push(value.pos, format!("`{key}` expects an integer, got {}", value.value.describe()));
            return None;
        }
        match n.filter(|n| (min..=max).contains(n)) {
            Some(n) => Some(n),
            None => {
                self.push(
                    value.pos,
                    format!(
                        "`{key}` is out of range: expects an integer from {min} to {max}, got {}",
                        value.value.describe()
                    ),
                );
                None
            }
        }
    }

    /// One of a few words.
    fn choice<T: Copy>(&mut self, key: &str, value: &Spanned<Node>, options: &[(&'static str, T)]) -> Option<T> {
        let text = value.value.as_text();
        if let Some(&(_, v)) = options.iter().find(|(w, _)| Some(*w) == text) {
            return Some(v);
        }
        let words: Vec<String> = options.iter().map(|(w, _)| format!("`{w}`")).collect();
        let hint = text.map(|t| suggestion(t, options.iter().map(|(w, _)| *w))).unwrap_or_default();
        self.push(value.pos, format!("`{key}` expects {}, got {}{hint}", words.join(" or "), value.value.describe()));
        None
    }

    fn section(&mut self, section: Section, node: Spanned<Node>) -> Vec<SkillEntry> {
        let items = match node.value {
            Node::Seq(items) => items,
            Node::Null => Vec::new(),
            other => {
                self.push(
                    node.pos,
                    format!(
                        "`{}` expects a list of {}s (`- name: …`), got {}",
                        section.key(),
                        section.noun(),
                        other.describe()
                    ),
                );
                return Vec::new();
            }
        };
        let mut out = Vec::new();
        for (i, item) in items.into_iter().enumerate() {
            if self.entries == MAX_ENTRIES {
                self.push(
                    item.pos,
                    format!(
                        "too many entries: `devices` and `skills` may hold at most {MAX_ENTRIES} together; \
                         this is entry {} of `{}`",
                        i + 1,
                        section.key()
                    ),
                );
                self.entries += 1;
            }
            if self.entries > MAX_ENTRIES {
                break;
            }
            self.entries += 1;
            out.extend(self.entry(section, i, item));
        }
        out
    }

    fn entry(&mut self, section: Section, index: usize, item: Spanned<Node>) -> Option<SkillEntry> {
        let Node::Map(entries) = item.value else {
            self.push(
                item.pos,
                format!(
                    "each entry of `{}` must be a mapping with `name:` and `type:`, got {}",
                    section.key(),
                    item.value.describe()
                ),
            );
            return None;
        };
        let name_node = entries.iter().find(|(k, _)| k.value == "name").map(|(_, v)| v);
        let name = name_node.and_then(|v| self.entry_name(section, v));
        let place = match &name {
            Some(n) => format!("{} `{}`", section.noun(), n.value),
            None => format!("entry {} of `{}`", index + 1, section.key()),
        };
        let mut type_name = None;
        let mut type_given = false;
        let mut active = true;
        let mut priority = None;
        let mut period_ms = None;
        let mut timeout_ms = None;
        let mut budget_ms = None;
        let mut liveness_ms = None;
        let mut params = Vec::new();
        let mut remap = Vec::new();
        let mut remote = None;
        for (key, value) in entries.iter() {
            let k = key.value.as_str();
            match k {
                "name" => {}
                "remote" => {
                    if section == Section::Devices {
                        self.push(
                            key.pos,
                            "a remote skill is an asynchronous cskill: list it under `skills:`".to_string(),
                        );
                    } else if !matches!(value.value, Node::Map(_))
                        && value.value.as_text().is_none_or(|t| t.trim().is_empty())
                    {
                        self.push(
                            value.pos,
                            format!(
                                "`remote` expects the skill's manifest (inputs, outputs, params) or the path of a \
                                 manifest file, got {}",
                                value.value.describe()
                            ),
                        );
                    } else {
                        remote = Some(value.clone());
                    }
                }
                "type" => {
                    type_given = true;
                    type_name = match value.value.as_text() {
                        Some(t) if self.too_long("the type name", t, value.pos) => None,
                        Some(t) if !t.trim().is_empty() => Some(Spanned::new(t.to_string(), value.pos)),
                        _ => {
                            self.push(
                                value.pos,
                                format!("`type` expects a skill type name, got {}", value.value.describe()),
                            );
                            None
                        }
                    };
                }
                "active" => match value.value.as_bool() {
                    Some(b) => active = b,
                    None => {
                        self.push(value.pos, format!("`active` expects true or false, got {}", value.value.describe()))
                    }
                },
                "priority" => {
                    priority = self
                        .integer(k, value, i32::MIN.into(), i32::MAX.into())
                        .and_then(|p| i32::try_from(p).ok())
                        .map(|p| Spanned::new(p, value.pos));
                }
                "period_ms" => {
                    period_ms = self.period(k, value).map(|ms| Spanned::new(ms, value.pos));
                }
                "timeout_ms" => {
                    timeout_ms = self.deadline(k, value).map(|ms| Spanned::new(ms, value.pos));
                }
                "budget_ms" => {
                    budget_ms = self.deadline(k, value).map(|ms| Spanned::new(ms, value.pos));
                }
                "liveness_ms" => {
                    liveness_ms = self.deadline(k, value).map(|ms| Spanned::new(ms, value.pos));
                }
                "params" => params = self.params(value.clone()),
                "remap" => remap = self.remap(value.clone()),
                _ => self.unknown_key(key, &format!("in {place}"), ENTRY_KEYS),
            }
        }
        if name_node.is_none() {
            self.push(item.pos, format!("missing required key `name` in {place}"));
        }
        let remote_given = entries.iter().any(|(k, _)| k.value == "remote");
        if type_given && remote_given {
            self.push(item.pos, format!("{place} has both `type` and `remote`; a remote skill has no type"));
        } else if !type_given && !remote_given {
            self.push(item.pos, format!("missing required key `type` in {place}"));
        }
        if let (Some(r), Some(n)) = (&remote, &name) {
            type_name = Some(Spanned::new(format!("remote.{}", n.value), r.pos));
        }
        if let (Some(t), false) = (&timeout_ms, remote_given) {
            self.push(t.pos, format!("`timeout_ms` in {place} is for remote skills (how long an answer may take)"));
        }
        Some(SkillEntry {
            section,
            pos: item.pos,
            name: name?,
            type_name: type_name?,
            active,
            priority,
            period_ms,
            budget_ms,
            liveness_ms,
            params,
            remap,
            remote,
            timeout_ms,
        })
    }

    fn entry_name(&mut self, section: Section, value: &Spanned<Node>) -> Option<Spanned<String>> {
        match value.value.as_text() {
            Some(name) if self.too_long(&format!("the {} name", section.noun()), name, value.pos) => None,
            Some(name) if is_identifier(name) => Some(Spanned::new(name.to_string(), value.pos)),
            Some(name) => {
                self.push(
                    value.pos,
                    format!(
                        "{} name `{name}` is not an identifier (letters, digits and `_`, not starting with a digit)",
                        section.noun()
                    ),
                );
                None
            }
            None => {
                self.push(value.pos, format!("`name` expects a name, got {}", value.value.describe()));
                None
            }
        }
    }

    fn params(&mut self, node: Spanned<Node>) -> Vec<Param> {
        let Some(entries) = self.mapping("params", node, "a mapping of parameter names to values") else {
            return Vec::new();
        };
        let mut out = Vec::new();
        for (key, value) in entries {
            let name = &key.value;
            if self.too_long("the parameter name", name, key.pos) {
                continue;
            }
            let v = match &value.value {
                Node::Scalar { .. } => value.value.to_value(),
                Node::Seq(items) => {
                    let mut ok = true;
                    for item in items.iter().filter(|i| i.value.as_f64().is_none()) {
                        ok = false;
                        self.push(
                            item.pos,
                            format!(
                                "parameter `{name}` expects a list of numbers, got {} in it",
                                item.value.describe()
                            ),
                        );
                    }
                    if ok {
                        value.value.to_f64s()
                    } else {
                        None
                    }
                }
                Node::Null => {
                    self.push(value.pos, format!("parameter `{name}` has no value"));
                    None
                }
                Node::Map(_) => {
                    self.push(
                        value.pos,
                        format!("parameter `{name}` expects a scalar or a list of numbers, got a mapping"),
                    );
                    None
                }
            };
            if let Some(v) = v {
                let written = matches!(value.value, Node::Scalar { .. }).then(|| value.value.describe());
                out.push(Param { name: key, value: Spanned::new(v, value.pos), written });
            }
        }
        out
    }

    fn remap(&mut self, node: Spanned<Node>) -> Vec<(Spanned<String>, Spanned<String>)> {
        let Some(entries) = self.mapping("remap", node, "a mapping of port names to signal names") else {
            return Vec::new();
        };
        let mut out = Vec::new();
        for (port, target) in entries {
            if self.too_long("the port name", &port.value, port.pos) {
                continue;
            }
            match target.value.as_text() {
                Some(signal) if self.too_long("the signal name", signal, target.pos) => {}
                Some(signal) if is_signal_name(signal) => {
                    let signal = Spanned::new(signal.to_string(), target.pos);
                    out.push((port, signal));
                }
                Some(signal) => self.push(
                    target.pos,
                    format!(
                        "remap target `{signal}` of port `{}` is not a signal name (identifiers joined by `.`, like `sonar.range`)",
                        port.value
                    ),
                ),
                None => self.push(
                    target.pos,
                    format!(
                        "remap of port `{}` expects a signal name, got {}",
                        port.value,
                        target.value.describe()
                    ),
                ),
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const FULL: &str = "\
# toybot: a sonar and two behaviours
robot: toybot
cycle:
  rate_hz: 50
  clock: simulated
  executor: parallel
  threads: 2
devices:
  - name: sonar
    type: toy.sonar
    period_ms: 20
    params: {noise_m: 0.01, beams: [0.1, 0.2, 3]}
    remap: {range: sonar.range}
skills:
  - name: wander
    type: toy.wander
    active: false
    priority: -5
  - name: runaway
    type: toy.runaway
    priority: 10
    params:
      safe_distance: 0.5
      label: \"near\"
      verbose: true
      retries: 3
    remap:
      sonar_range: sonar.range
link:
  peers: [a]
gui: {port: 8080}
";

    fn p(line: usize, col: usize) -> Pos {
        Pos::new(line, col)
    }

    fn s<T>(value: T, line: usize, col: usize) -> Spanned<T> {
        Spanned::new(value, p(line, col))
    }

    /// The error lines for `source`, parsed as `robot.yaml`.
    fn errors(source: &str) -> Vec<String> {
        match RobotFile::parse("robot.yaml", source) {
            Ok(r) => panic!("expected errors, got {r:?}"),
            Err(errors) => errors.iter().map(ToString::to_string).collect(),
        }
    }

    /// The only error for `source`.
    fn error(source: &str) -> String {
        let errors = errors(source);
        assert_eq!(errors.len(), 1, "{errors:#?}");
        errors.into_iter().next().unwrap()
    }

    /// A valid file whose one skill entry gets `extra` lines.
    fn skill(extra: &str) -> String {
        format!("robot: r\nskills:\n  - name: runaway\n    type: toy.runaway\n{extra}")
    }

    #[test]
    fn a_full_file_reads_into_the_model_with_positions() {
        let r = RobotFile::parse("toybot.yaml", FULL).unwrap();
        assert_eq!(r.file, "toybot.yaml");
        assert_eq!(r.robot, s("toybot".to_string(), 2, 8));
        assert_eq!(
            r.cycle,
            CycleConfig {
                period_s: 0.02,
                clock: ClockKind::Simulated,
                executor: ExecutorKind::Parallel,
                threads: Some(2),
                budget_ms: None,
                liveness_ms: None,
                pos: p(3, 1),
            }
        );
        assert_eq!(r.skills.len(), 3);

        let sonar = &r.skills[0];
        assert_eq!(sonar.section, Section::Devices);
        assert_eq!(sonar.pos, p(9, 5));
        assert_eq!(sonar.name, s("sonar".to_string(), 9, 11));
        assert_eq!(sonar.type_name, s("toy.sonar".to_string(), 10, 11));
        assert!(sonar.active);
        assert_eq!(sonar.priority, None);
        assert_eq!(sonar.period_ms, Some(s(20.0, 11, 16)));
        assert_eq!(
            sonar.params,
            vec![
                Param {
                    name: s("noise_m".to_string(), 12, 14),
                    value: s(Value::F64(0.01), 12, 23),
                    written: Some("0.01".into())
                },
                Param {
                    name: s("beams".to_string(), 12, 29),
                    value: s(Value::F64s(vec![0.1, 0.2, 3.0].into()), 12, 36),
                    written: None
                },
            ]
        );
        assert_eq!(sonar.remap, vec![(s("range".to_string(), 13, 13), s("sonar.range".to_string(), 13, 20))]);
        assert_eq!(sonar.label(), "device `sonar`");

        let wander = &r.skills[1];
        assert_eq!(wander.section, Section::Skills);
        assert_eq!((wander.pos, wander.active), (p(15, 5), false));
        assert_eq!(wander.priority, Some(s(-5, 18, 15)));
        assert!(wander.params.is_empty() && wander.remap.is_empty());

        let runaway = &r.skills[2];
        assert_eq!(runaway.pos, p(19, 5));
        assert_eq!(runaway.priority, Some(s(10, 21, 15)));
        let params: Vec<_> = runaway
            .params
            .iter()
            .map(|p| (p.name.value.as_str(), p.name.pos, p.value.value.clone(), p.value.pos))
            .collect();
        assert_eq!(
            params,
            vec![
                ("safe_distance", p(23, 7), Value::F64(0.5), p(23, 22)),
                ("label", p(24, 7), Value::Str("near".into()), p(24, 14)),
                ("verbose", p(25, 7), Value::Bool(true), p(25, 16)),
                ("retries", p(26, 7), Value::I64(3), p(26, 16)),
            ]
        );
        assert_eq!(runaway.param("retries").unwrap().value, Value::I64(3));
        assert_eq!(runaway.remap, vec![(s("sonar_range".to_string(), 28, 7), s("sonar.range".to_string(), 28, 20))]);
        assert_eq!(r.link.as_ref().unwrap().pos, p(30, 3));
        let gui = r.gui.as_ref().unwrap();
        assert_eq!(gui.pos, p(31, 6));
        assert_eq!(gui.value.get("port").unwrap().value.as_i64(), Some(8080));
        assert_eq!(r.section(Section::Skills).count(), 2);
        assert_eq!(r.error(runaway.name.pos, "no such thing").to_string(), "toybot.yaml:19:11: error: no such thing");
    }

    #[test]
    fn defaults_and_section_order() {
        let r = RobotFile::parse(
            "r.yaml",
            "robot: my-bot_2\nskills:\n  - {name: b, type: t.b}\ndevices:\n  - {name: a, type: t.a}\n",
        )
        .unwrap();
        assert_eq!(r.cycle, CycleConfig::default());
        assert_eq!(r.cycle.rate_hz(), 20.0);
        let names: Vec<_> = r.skills.iter().map(|e| e.name.value.as_str()).collect();
        assert_eq!(names, ["a", "b"]);
        assert_eq!(r.skills[0].pos, p(5, 5));
        assert!(r.link.is_none() && r.gui.is_none());
        let r = RobotFile::parse("r.yaml", "robot: r\ncycle:\n  period_ms: 4\ndevices:\n").unwrap();
        assert_eq!(r.cycle.period_s, 0.004);
        assert!(r.skills.is_empty());
    }

    #[test]
    fn empty_file_misses_robot_at_the_start() {
        assert_eq!(error(""), "robot.yaml:1:1: error: missing required key `robot`");
        assert_eq!(error("# nothing yet\n"), "robot.yaml:1:1: error: missing required key `robot`");
        assert_eq!(error("\ncycle: {rate_hz: 5}\n"), "robot.yaml:2:1: error: missing required key `robot`");
    }

    #[test]
    fn yaml_syntax_errors_are_reported_alone() {
        assert_eq!(
            error("robot: r\nskills: [a, b\n"),
            "robot.yaml:2:9: error: missing `]` to close the `[` at line 2, column 9 (the YAML parser stopped at line 3, \
             column 1: while parsing a flow sequence, expected ',' or ']')"
        );
        assert_eq!(
            error("robot: r\ncycle:\n\trate_hz: 5\n"),
            "robot.yaml:3:1: error: tab character in indentation; indent YAML with spaces"
        );
        assert_eq!(
            error("robot: r\ncycle:\n  rate_hz: 5\n  rate_hz: 6\n"),
            "robot.yaml:4:3: error: duplicate key `rate_hz` (first given on line 3)"
        );
        assert_eq!(
            error("robot: &name r\n"),
            "robot.yaml:1:8: error: anchors and aliases (`&name`, `*name`) are not supported in robot files"
        );
    }

    #[test]
    fn a_control_character_is_an_error_at_its_place_not_the_end_of_the_file() {
        // Before, the NUL ended the file: `robot: r` alone read cleanly.
        assert_eq!(
            error("robot: r\n\0skills:\n  - {name: w, type: toy.wander}\n"),
            "robot.yaml:2:1: error: control character U+0000 (NUL): a robot file is UTF-8 text (is this one UTF-16, \
             or binary?)"
        );
        assert!(error("robot: r\ncycle: {rate_hz: 5\u{c}}\n")
            .starts_with("robot.yaml:2:19: error: control character U+000C"));
        assert!(RobotFile::parse("r.yaml", "robot: r\r\ncycle: {rate_hz: 5}\r\n").is_ok(), "CRLF is fine");
    }

    #[test]
    fn tabs_and_fullwidth_colons_are_errors_at_their_own_place() {
        let indent = "error: tab character in indentation; indent YAML with spaces";
        // Accepted before: the tab after `-` silently set the mapping's column.
        assert_eq!(error("robot: r\nskills:\n-\tname: w\n  type: toy.wander\n"), format!("robot.yaml:3:2: {indent}"));
        // Blamed on line 4 before.
        assert_eq!(
            error("robot: r\nskills:\n  -\tname: w\n    type: toy.wander\n"),
            format!("robot.yaml:3:4: {indent}")
        );
        // Blamed on line 1 before.
        assert_eq!(error("robot: r\n\tskills: []\n"), format!("robot.yaml:2:1: {indent}"));
        // Blamed on line 5 before.
        assert_eq!(
            error("robot: r\nskills:\n  - name: w\n    type： toy.wander\n"),
            "robot.yaml:4:9: error: fullwidth colon `：` (U+FF1A); use ':' (or quote a value that should contain it)"
        );
    }

    #[test]
    fn unknown_keys_suggest_the_closest() {
        assert_eq!(
            error(&skill("    actve: false\n")),
            "robot.yaml:5:5: error: unknown key `actve` in skill `runaway` — did you mean `active`?"
        );
        assert_eq!(
            errors("robt: r\n"),
            [
                "robot.yaml:1:1: error: unknown key `robt` at the top level — did you mean `robot`?",
                "robot.yaml:1:1: error: missing required key `robot`",
            ]
        );
        assert_eq!(
            errors("robot: r\nskils: []\ncycle: {rate_hz: 5, frobnicate: 1}\n"),
            [
                "robot.yaml:2:1: error: unknown key `skils` at the top level — did you mean `skills`?",
                "robot.yaml:3:21: error: unknown key `frobnicate` in `cycle`",
            ]
        );
        assert_eq!(
            error("robot: r\ndevices:\n  - name: 1sonar\n    type: t\n"),
            "robot.yaml:3:11: error: device name `1sonar` is not an identifier (letters, digits and `_`, not starting with a digit)"
        );
    }

    #[test]
    fn unknown_key_in_an_unnamed_entry_names_its_index() {
        assert_eq!(
            errors("robot: r\ndevices:\n  - {name: a, type: t}\n  - type: t\n    remp: {}\n"),
            [
                "robot.yaml:4:5: error: missing required key `name` in entry 2 of `devices`",
                "robot.yaml:5:5: error: unknown key `remp` in entry 2 of `devices` — did you mean `remap`?",
            ]
        );
    }

    #[test]
    fn wrong_value_types() {
        assert_eq!(
            error("robot: r\ncycle:\n  rate_hz: fast\n"),
            "robot.yaml:3:12: error: `rate_hz` expects a number > 0, got \"fast\""
        );
        assert_eq!(
            error(&skill("    active: yes\n")),
            "robot.yaml:5:13: error: `active` expects true or false, got \"yes\""
        );
        assert_eq!(
            error(&skill("    priority: 1.5\n")),
            "robot.yaml:5:15: error: `priority` expects an integer, got 1.5"
        );
        assert_eq!(
            error(&skill("    priority: 3000000000\n")),
            "robot.yaml:5:15: error: `priority` is out of range: expects an integer from -2147483648 to 2147483647, got 3000000000"
        );
        assert_eq!(
            error("robot: r\ncycle: {clock: wal}\n"),
            "robot.yaml:2:16: error: `clock` expects `wall` or `simulated`, got \"wal\" — did you mean `wall`?"
        );
        assert_eq!(
            error("robot: r\ncycle: {executor: [serial]}\n"),
            "robot.yaml:2:19: error: `executor` expects `serial` or `parallel`, got a list"
        );
        assert_eq!(
            error("robot: r\ncycle: {threads: 0}\n"),
            "robot.yaml:2:18: error: `threads` is out of range: expects an integer from 1 to 64, got 0"
        );
        assert_eq!(error("robot: [a]\n"), "robot.yaml:1:8: error: `robot` expects a name, got a list");
        assert_eq!(
            error("robot: r\ncycle: fast\n"),
            "robot.yaml:2:8: error: `cycle` expects a mapping (`rate_hz:`, `clock:`, `executor:`, …), got \"fast\""
        );
        assert_eq!(
            error("- robot: r\n"),
            "robot.yaml:1:1: error: a robot file is a mapping with keys `robot:`, `cycle:`, `devices:` and `skills:`, got a list"
        );
    }

    #[test]
    fn rates_and_periods_are_range_checked() {
        assert_eq!(
            error("robot: r\ncycle:\n  rate_hz: 0\n"),
            "robot.yaml:3:12: error: `rate_hz` is out of range: expects a number > 0 and ≤ 100000, got 0"
        );
        assert_eq!(
            error("robot: r\ncycle:\n  rate_hz: 200000\n"),
            "robot.yaml:3:12: error: `rate_hz` is out of range: expects a number > 0 and ≤ 100000, got 200000"
        );
        assert_eq!(
            error("robot: r\ncycle:\n  rate_hz: .nan\n"),
            "robot.yaml:3:12: error: `rate_hz` is out of range: expects a number > 0 and ≤ 100000, got .nan"
        );
        assert_eq!(
            error("robot: r\ncycle: {period_ms: -5}\n"),
            "robot.yaml:2:20: error: `period_ms` is out of range: expects a number from 0.01 to 86400000 (10 µs to a day), got -5"
        );
        assert_eq!(
            error(&skill("    period_ms: .inf\n")),
            "robot.yaml:5:16: error: `period_ms` is out of range: expects a number from 0.01 to 86400000 (10 µs to a day), got .inf"
        );
        assert_eq!(
            error(&skill("    period_ms: \"50\"\n")),
            "robot.yaml:5:16: error: `period_ms` expects a number > 0, got \"50\""
        );
    }

    #[test]
    fn numbers_out_of_range_are_quoted_as_written_at_their_place() {
        let period = "expects a number from 0.01 to 86400000 (10 µs to a day)";
        let deadline = "expects a number > 0 and ≤ 86400000 (a day)";
        // Before: accepted here, then "cycle period must be > 0 s and at most
        // a day, got 1e297 s" with no position.
        assert_eq!(
            error("robot: r\ncycle: {period_ms: 1e300}\n"),
            format!("robot.yaml:2:20: error: `period_ms` is out of range: {period}, got 1e300")
        );
        assert_eq!(
            error("robot: r\ncycle:\n  period_ms: 0.001\n"),
            format!("robot.yaml:3:14: error: `period_ms` is out of range: {period}, got 0.001")
        );
        assert_eq!(
            error("robot: r\ncycle: {rate_hz: 1e-300}\n"),
            "robot.yaml:2:18: error: `rate_hz` is out of range: the cycle must run at least once a day \
             (rate_hz ≥ 0.0000116), got 1e-300"
        );
        assert_eq!(
            error(&skill("    period_ms: 1E+300\n")),
            format!("robot.yaml:5:16: error: `period_ms` is out of range: {period}, got 1E+300")
        );
        assert_eq!(
            error(&skill("    budget_ms: 0x7fffffff\n")),
            format!("robot.yaml:5:16: error: `budget_ms` is out of range: {deadline}, got 0x7fffffff")
        );
        assert_eq!(
            error(&skill("    liveness_ms: 1e9\n")),
            format!("robot.yaml:5:18: error: `liveness_ms` is out of range: {deadline}, got 1e9")
        );
        assert_eq!(
            error("robot: r\ncycle: {budget_ms: -0.0}\n"),
            format!("robot.yaml:2:20: error: `budget_ms` is out of range: {deadline}, got -0.0")
        );
        // Before: accepted (and silently cut to a day by `situate run`).
        assert_eq!(
            error("robot: r\nskills:\n  - {name: x, remote: x.yaml, timeout_ms: 1e300}\n"),
            format!("robot.yaml:3:43: error: `timeout_ms` is out of range: {deadline}, got 1e300")
        );
        // Integers too large for 64 bits are out of range, not "not an integer".
        let int32 = "expects an integer from -2147483648 to 2147483647";
        assert_eq!(
            error(&skill("    priority: 99999999999999999999\n")),
            format!("robot.yaml:5:15: error: `priority` is out of range: {int32}, got 99999999999999999999")
        );
        assert_eq!(
            error(&skill("    priority: -0x80000001\n")),
            "robot.yaml:5:15: error: `priority` expects an integer, got \"-0x80000001\""
        );
        assert_eq!(
            error(&skill("    priority: 0x80000000\n")),
            format!("robot.yaml:5:15: error: `priority` is out of range: {int32}, got 0x80000000")
        );
        assert_eq!(
            error("robot: r\ncycle: {threads: 0o777}\n"),
            "robot.yaml:2:18: error: `threads` is out of range: expects an integer from 1 to 64, got 0o777"
        );
    }

    #[test]
    fn rate_and_period_together_is_an_error_at_the_second() {
        assert_eq!(
            error("robot: r\ncycle:\n  period_ms: 10\n  rate_hz: 100\n"),
            "robot.yaml:4:3: error: `cycle` takes either `rate_hz` or `period_ms`, not both (`period_ms` is given too)"
        );
    }

    #[test]
    fn missing_required_keys() {
        assert_eq!(
            error("robot: r\nskills:\n  - name: runaway\n    active: true\n"),
            "robot.yaml:3:5: error: missing required key `type` in skill `runaway`"
        );
        assert_eq!(error("cycle: {}\n"), "robot.yaml:1:1: error: missing required key `robot`");
    }

    #[test]
    fn bad_names() {
        assert_eq!(
            error("robot: my bot\n"),
            "robot.yaml:1:8: error: robot name `my bot` may only contain letters, digits, `_` and `-`"
        );
        assert_eq!(
            error("robot: r\nskills:\n  - name: run-away\n    type: t\n"),
            "robot.yaml:3:11: error: skill name `run-away` is not an identifier (letters, digits and `_`, not starting with a digit)"
        );
        assert_eq!(
            error("robot: r\nskills:\n  - name: {a: 1}\n    type: t\n"),
            "robot.yaml:3:11: error: `name` expects a name, got a mapping"
        );
        assert_eq!(
            error("robot: r\nskills:\n  - name: a\n    type: \"\"\n"),
            "robot.yaml:4:11: error: `type` expects a skill type name, got \"\""
        );
    }

    #[test]
    fn bad_remap_targets() {
        assert_eq!(
            error(&skill("    remap: {sonar_range: sonar..range}\n")),
            "robot.yaml:5:26: error: remap target `sonar..range` of port `sonar_range` is not a signal name (identifiers joined by `.`, like `sonar.range`)"
        );
        assert_eq!(
            error(&skill("    remap:\n      sonar_range: [a]\n")),
            "robot.yaml:6:20: error: remap of port `sonar_range` expects a signal name, got a list"
        );
        assert_eq!(
            error(&skill("    remap: [a]\n")),
            "robot.yaml:5:12: error: `remap` expects a mapping of port names to signal names, got a list"
        );
    }

    #[test]
    fn bad_param_values() {
        assert_eq!(
            errors(&skill(
                "    params:\n      gains: [1, x, 2, {a: 1}]\n      nested: {a: 1}\n      none:\n      ok: [1, 2]\n"
            )),
            [
                "robot.yaml:6:18: error: parameter `gains` expects a list of numbers, got \"x\" in it",
                "robot.yaml:6:24: error: parameter `gains` expects a list of numbers, got a mapping in it",
                "robot.yaml:7:15: error: parameter `nested` expects a scalar or a list of numbers, got a mapping",
                "robot.yaml:8:7: error: parameter `none` has no value",
            ]
        );
        assert_eq!(
            error(&skill("    params: 5\n")),
            "robot.yaml:5:13: error: `params` expects a mapping of parameter names to values, got 5"
        );
    }

    #[test]
    fn list_shapes() {
        assert_eq!(
            error("robot: r\nskills:\n  - runaway\n"),
            "robot.yaml:3:5: error: each entry of `skills` must be a mapping with `name:` and `type:`, got \"runaway\""
        );
        assert_eq!(
            error("robot: r\nskills:\n  runaway: {type: t}\n"),
            "robot.yaml:3:3: error: `skills` expects a list of skills (`- name: …`), got a mapping"
        );
        assert_eq!(
            error("robot: r\ndevices: sonar\n"),
            "robot.yaml:2:10: error: `devices` expects a list of devices (`- name: …`), got \"sonar\""
        );
    }

    #[test]
    fn many_errors_come_together_in_file_order() {
        let src = "\
robot: r
skills:
  - name: runaway
    type: toy.runaway
    actve: true
    priority: high
  - name: b@d
    type: t
devices:
  - sonar
cycle:
  rate_hz: 0
  clock: sundial
";
        assert_eq!(
            errors(src),
            [
                "robot.yaml:5:5: error: unknown key `actve` in skill `runaway` — did you mean `active`?",
                "robot.yaml:6:15: error: `priority` expects an integer, got \"high\"",
                "robot.yaml:7:11: error: skill name `b@d` is not an identifier (letters, digits and `_`, not starting with a digit)",
                "robot.yaml:10:5: error: each entry of `devices` must be a mapping with `name:` and `type:`, got \"sonar\"",
                "robot.yaml:12:12: error: `rate_hz` is out of range: expects a number > 0 and ≤ 100000, got 0",
                "robot.yaml:13:10: error: `clock` expects `wall` or `simulated`, got \"sundial\"",
            ]
        );
    }

    #[test]
    fn load_reads_files_and_reports_read_errors() {
        let dir = std::env::temp_dir().join(format!("situate-config-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("toybot.yaml");
        std::fs::write(&path, FULL).unwrap();
        let r = RobotFile::load(&path).unwrap();
        assert_eq!(r.file, path.display().to_string());
        let missing = dir.join("nope.yaml");
        let errors = RobotFile::load(&missing).unwrap_err();
        assert_eq!(errors.len(), 1);
        let text = errors[0].to_string();
        // A file that does not read has no line and column.
        let prefix = format!("{}: error: cannot read robot file: ", missing.display());
        assert!(text.starts_with(&prefix), "{text}");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn a_file_over_the_size_cap_is_refused_by_its_size_before_it_is_read() {
        let dir = std::env::temp_dir().join(format!("situate-config-cap-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        // 50 MiB, sparse: refused from its size, not read (it took ~3 s and
        // 2 GB to parse such a file).
        let big = dir.join("big.yaml");
        std::fs::File::create(&big).unwrap().set_len(50 << 20).unwrap();
        let started = std::time::Instant::now();
        let errors = RobotFile::load(&big).unwrap_err();
        assert!(started.elapsed() < std::time::Duration::from_secs(1));
        assert_eq!(
            errors[0].to_string(),
            format!(
                "{}: error: the file is 52428800 bytes (50 MiB); a robot file may be at most 1048576 bytes (1 MiB)",
                big.display()
            )
        );
        // Exactly at the cap is fine (a comment, then a valid robot).
        let at_cap = dir.join("at_cap.yaml");
        let head = "robot: r\n#";
        let text = format!("{head}{}\n", "x".repeat(MAX_ROBOT_FILE_BYTES as usize - head.len() - 1));
        std::fs::write(&at_cap, &text).unwrap();
        assert!(RobotFile::load(&at_cap).is_ok());
        std::fs::write(&at_cap, text + "\n").unwrap();
        assert!(RobotFile::load(&at_cap).unwrap_err()[0].message.starts_with("the file is 1048577 bytes (1.0 MiB);"));
        // Invalid UTF-8 is an error at its place; UTF-16 is named.
        let latin1 = dir.join("latin1.yaml");
        std::fs::write(&latin1, b"robot: r\n# caf\xe9\n").unwrap();
        assert_eq!(
            RobotFile::load(&latin1).unwrap_err()[0].to_string(),
            format!(
                "{}:2:6: error: invalid UTF-8 (byte 0xE9): a robot file is UTF-8 text; save it as UTF-8",
                latin1.display()
            )
        );
        let utf16 = dir.join("utf16.yaml");
        std::fs::write(&utf16, b"\xff\xfer\0o\0").unwrap();
        assert!(RobotFile::load(&utf16).unwrap_err()[0].message.starts_with("the file is UTF-16 text"));
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn entries_and_names_are_capped() {
        let mut src = String::from("robot: r\ndevices:\n  - {name: d, type: t}\nskills:\n");
        for i in 0..MAX_ENTRIES + 5 {
            src.push_str(&format!("  - {{name: s{i}, type: t}}\n"));
        }
        assert_eq!(
            error(&src),
            "robot.yaml:1028:5: error: too many entries: `devices` and `skills` may hold at most 1024 together; \
             this is entry 1024 of `skills`"
        );
        let long = "x".repeat(MAX_NAME_CHARS + 1);
        let too_long = |what: &str| format!("{what} is 257 characters long; a name may have at most 256");
        assert_eq!(
            error(&format!("robot: {long}\n")),
            format!("robot.yaml:1:8: error: {}", too_long("the robot name"))
        );
        assert_eq!(
            errors(&skill(&format!("    params: {{{long}: 1}}\n    remap: {{a: {long}}}\n"))),
            [
                format!("robot.yaml:5:14: error: {}", too_long("the parameter name")),
                format!("robot.yaml:6:16: error: {}", too_long("the signal name")),
            ]
        );
        let errors =
            errors(&format!("robot: r\nskills:\n  - {{name: {long}, type: {long}, remap: {{p: a.{long}}}}}\n"));
        assert_eq!(
            errors,
            [
                format!("robot.yaml:3:12: error: {}", too_long("the skill name")),
                format!("robot.yaml:3:277: error: {}", too_long("the type name")),
                "robot.yaml:3:547: error: the signal name is 259 characters long; a name may have at most 256"
                    .to_string(),
            ]
        );
    }

    #[test]
    fn no_input_panics() {
        for (i, _) in FULL.char_indices() {
            let _ = RobotFile::parse("t.yaml", &FULL[..i]);
        }
        // Random edits of the full file: replace one character at a time
        // with YAML-significant ones, and random lines of keys and values.
        let chars: Vec<char> = FULL.chars().collect();
        let alphabet: Vec<char> = " \n\t-:?,[]{}#&*!|>'\".~0a1é：\0\r".chars().collect();
        let words = [
            "robot:",
            "cycle:",
            "rate_hz:",
            "period_ms:",
            "skills:",
            "devices:",
            "- ",
            "name:",
            "type:",
            "params:",
            "remap:",
            "[",
            "]",
            "{",
            "}",
            "0",
            "-1",
            "1e9",
            "x.y",
            "\n  ",
            "\n",
            "priority:",
            "threads:",
            ".nan",
            "\"\"",
            "~",
            "active:",
            ", ",
        ];
        let mut seed: u64 = 0x2545_f491_4f6c_dd1d;
        let mut next = move || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            seed
        };
        for _ in 0..3000 {
            let mut edited = chars.clone();
            for _ in 0..3 {
                let at = next() as usize % edited.len();
                edited[at] = alphabet[next() as usize % alphabet.len()];
            }
            let text: String = edited.into_iter().collect();
            let _ = RobotFile::parse("t.yaml", &text);
        }
        for _ in 0..5000 {
            let n = next() as usize % 16;
            let text: String = (0..n).map(|_| words[next() as usize % words.len()]).collect();
            let _ = RobotFile::parse("t.yaml", &text);
        }
    }

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
