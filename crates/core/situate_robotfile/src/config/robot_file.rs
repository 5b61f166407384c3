//! The robot file: its model, how it is read (parsed, composed with its
//! includes, shape-checked), and its top level (`robot:` and which key
//! holds which section).

use std::path::{Path, PathBuf};

use super::check::Checker;
use super::paths::resolve_zenoh_paths;
use super::{ConfigError, CycleConfig, LoadOptions, Node, Pos, Section, SkillEntry, SourceFile, Spanned};
use crate::include::base_dir;
use crate::limits::MAX_ROBOT_FILE_BYTES;
use crate::names::is_robot_name;
use crate::yaml;

const TOP_KEYS: &[&str] =
    &["robot", "include", "cycle", "libraries", "python", "simulator", "devices", "skills", "link", "gui", "ros2"];

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

    /// A diagnostic about one of this file's sections (a section's own reader, which knows
    /// positions but not files: `link:`, `ros2:`), placed in the file that holds its position;
    /// one without a position is placed at `section`, the section's own.
    pub fn locate(&self, diagnostic: ConfigError, section: Pos) -> ConfigError {
        let pos = diagnostic.pos.unwrap_or(section);
        ConfigError { pos: (pos.line > 0).then_some(pos), ..diagnostic }.in_file(self.file_of(pos))
    }

    /// The entries of one section, in file order.
    pub fn section(&self, section: Section) -> impl Iterator<Item = &SkillEntry> {
        self.skills.iter().filter(move |s| s.section == section)
    }
}

impl Checker<'_> {
    pub(super) fn robot_file(&mut self, root: Spanned<Node>) -> Option<RobotFile> {
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

    pub(super) fn robot_name(&mut self, value: Spanned<Node>) -> Option<Spanned<String>> {
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
}
