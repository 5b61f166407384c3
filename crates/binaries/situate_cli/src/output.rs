//! The program's output contract (docs/cli.md): what goes to stdout and
//! stderr, the exit codes, and errors as JSON under `--json`.
//!
//! A command's result goes to stdout (one JSON value, or one per line for
//! streams, under `--json`); notes on its progress (`situate: …`) go to
//! stderr and `-q` silences them. A command that fails returns a
//! [`Problem`]: its [`Exit`] kind picks the exit code, and [`Out::fail`]
//! prints it once, as text on stderr or, under `--json`, as one JSON object
//! `{"error": {…}}` on stdout.

use std::io::Write;

use serde_json::{json, Value as Json};

/// Writes a result to stdout (the `stdout!`/`stdoutln!` macros), flushed at once.
///
/// A reader that went away (`situate schema robot | head -c1`) ends the program there, quietly and
/// with exit status 0, as ripgrep does: what it asked for was read. `println!` would panic instead
/// (Rust ignores SIGPIPE, so the write fails with `EPIPE`); the Python package's `situate`, which
/// runs this in the interpreter, would show that panic as a traceback. Any other failure to write
/// (a full disk under `> file`) is said on stderr and ends the program with exit status 1.
pub(crate) fn write_stdout(args: std::fmt::Arguments<'_>) {
    let mut out = std::io::stdout().lock();
    if let Err(e) = out.write_fmt(args).and_then(|()| out.flush()) {
        if e.kind() == std::io::ErrorKind::BrokenPipe {
            std::process::exit(Exit::Ok.code().into());
        }
        eprintln!("situate: writing to stdout: {e}");
        std::process::exit(Exit::Failure.code().into());
    }
}

/// Why the program ended: each kind its own exit code.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Exit {
    /// 0: done.
    Ok,
    /// 1: the command ran and failed (a stop that did not complete, a
    /// mission not delivered, a file that could not be written).
    Failure,
    /// 2: the command line is wrong (an unknown verb or option, a bad value).
    Usage,
    /// 3: a file given is wrong: a robot file, a manifest, a map, a
    /// parameter file, a library (every problem is reported with its place).
    BadFile,
    /// 4: no robot answered (nothing at the endpoint, a timeout, several
    /// robots and no `--robot`).
    NoRobot,
    /// 5: the robot answered and refused the request (an unknown skill, a
    /// bad parameter value, a bad condition).
    Refused,
}

impl Exit {
    /// The process exit code.
    pub fn code(self) -> u8 {
        match self {
            Exit::Ok => 0,
            Exit::Failure => 1,
            Exit::Usage => 2,
            Exit::BadFile => 3,
            Exit::NoRobot => 4,
            Exit::Refused => 5,
        }
    }

    /// The kind's name in JSON errors: `failure`, `usage`, `bad_file`, `no_robot`, `refused`.
    pub fn name(self) -> &'static str {
        match self {
            Exit::Ok => "ok",
            Exit::Failure => "failure",
            Exit::Usage => "usage",
            Exit::BadFile => "bad_file",
            Exit::NoRobot => "no_robot",
            Exit::Refused => "refused",
        }
    }

    /// Every kind, in code order (for docs and tests).
    pub const ALL: [Exit; 6] = [Exit::Ok, Exit::Failure, Exit::Usage, Exit::BadFile, Exit::NoRobot, Exit::Refused];
}

/// A failure said once, by [`Out::fail`]: its kind, the sentence, and the
/// lines before it (a file's problems, each `FILE:LINE:COL: message`).
#[derive(Debug, thiserror::Error)]
#[error("{message}")]
pub struct Problem {
    pub kind: Exit,
    /// One sentence (without the `situate:` or `error:` prefix).
    pub message: String,
    /// The problems behind it, one per line, said before the sentence.
    pub lines: Vec<String>,
    /// Lines said after the sentence (a condition's pointer line).
    pub after: Vec<String>,
    /// How the text form starts the sentence.
    pub prefix: &'static str,
    /// More for the JSON form (the manager's error object, a file's name).
    pub detail: Json,
}

impl Problem {
    pub fn new(kind: Exit, message: impl Into<String>) -> Problem {
        Problem {
            kind,
            message: message.into(),
            lines: Vec::new(),
            after: Vec::new(),
            prefix: "error: ",
            detail: Json::Null,
        }
    }

    /// A file's problems, then the count line `FILE: N errors`.
    pub fn bad_file(file: &std::path::Path, lines: Vec<String>) -> Problem {
        let n = lines.len();
        Problem {
            kind: Exit::BadFile,
            message: format!("{}: {n} error{}", file.display(), if n == 1 { "" } else { "s" }),
            lines,
            after: Vec::new(),
            prefix: "",
            detail: json!({"file": file.display().to_string()}),
        }
    }

    /// One problem of a file, said as it is (`FILE: …` or `FILE:LINE:COL: …`).
    pub fn file_problem(message: impl Into<String>) -> Problem {
        Problem { prefix: "", ..Problem::new(Exit::BadFile, message) }
    }

    /// The text form starts with `situate: ` (the client verbs' sentences).
    pub fn said_by_situate(mut self) -> Problem {
        self.prefix = "situate: ";
        self
    }

    pub fn with_detail(mut self, detail: Json) -> Problem {
        self.detail = detail;
        self
    }

    /// The JSON form: `{"error": {"kind", "exit", "message", "lines", …detail}}`.
    pub fn to_json(&self) -> Json {
        let mut error = json!({
            "kind": self.kind.name(),
            "exit": self.kind.code(),
            "message": self.message,
            "lines": self.lines.iter().chain(&self.after).collect::<Vec<_>>(),
        });
        if let (Some(map), Json::Object(extra)) = (error.as_object_mut(), &self.detail) {
            for (k, v) in extra {
                map.entry(k.clone()).or_insert_with(|| v.clone());
            }
        }
        json!({ "error": error })
    }
}

/// Shorthand: fail with a problem of this kind.
pub fn problem(kind: Exit, message: impl Into<String>) -> anyhow::Error {
    Problem::new(kind, message).into()
}

/// How this run of the program speaks (the global `--json`, `-q`, `-v`).
#[derive(Debug, Clone, Copy, Default)]
pub struct Out {
    /// Results and errors as JSON on stdout.
    pub json: bool,
    /// No progress notes on stderr.
    pub quiet: bool,
}

impl Out {
    /// A progress note on stderr (`situate: …`), unless `-q`.
    pub fn note(&self, text: impl std::fmt::Display) {
        if !self.quiet {
            eprintln!("situate: {text}");
        }
    }

    /// A warning about the input (a file's warning line), unless `-q`; under
    /// `--json` it is part of the result instead, so it is not printed.
    pub fn warn(&self, text: impl std::fmt::Display) {
        if !self.quiet && !self.json {
            eprintln!("{text}");
        }
    }

    /// A result: `value` under `--json`, else the text `text` gives.
    pub fn result(&self, value: &Json, text: impl FnOnce() -> String) {
        if self.json {
            stdoutln!("{value}");
        } else {
            let text = text();
            if !text.is_empty() {
                stdoutln!("{text}");
            }
        }
    }

    /// Says an error once, in the form asked for, and returns its exit code.
    pub fn fail(&self, e: &anyhow::Error) -> u8 {
        let owned;
        let problem = match e.downcast_ref::<Problem>() {
            Some(p) => p,
            None => {
                owned = Problem::new(Exit::Failure, format!("{e:#}"));
                &owned
            }
        };
        if self.json {
            stdoutln!("{}", problem.to_json());
        } else {
            for line in &problem.lines {
                eprintln!("{line}");
            }
            eprintln!("{}{}", problem.prefix, clean(&problem.message));
            for line in &problem.after {
                eprintln!("{line}");
            }
        }
        problem.kind.code()
    }
}

/// A message without the build machine's source paths that some Zenoh
/// errors carry (`… at /home/…/zenoh-1.x/src/x.rs:12.`).
pub fn clean(message: &str) -> String {
    let mut out = String::with_capacity(message.len());
    for (i, word) in message.split(' ').enumerate() {
        let bare = word.trim_end_matches(['.', ',', ')', ';']);
        let is_source_path = bare.starts_with('/') && bare.contains(".rs:") || bare.contains("/.cargo/registry/");
        if is_source_path {
            // `at /x.rs:1` and `(/x.rs:1)`: drop the path and a preceding `at`.
            if out.ends_with(" at") {
                out.truncate(out.len() - 3);
            }
            out.push_str(&word[bare.len()..]);
            continue;
        }
        if i > 0 {
            out.push(' ');
        }
        out.push_str(word);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exit_codes_are_distinct_and_named() {
        let codes: std::collections::BTreeSet<u8> = Exit::ALL.iter().map(|e| e.code()).collect();
        assert_eq!(codes.len(), Exit::ALL.len());
        let names: std::collections::BTreeSet<&str> = Exit::ALL.iter().map(|e| e.name()).collect();
        assert_eq!(names.len(), Exit::ALL.len());
    }

    #[test]
    fn a_problem_as_json_has_its_kind_code_and_lines() {
        let p = Problem::bad_file(std::path::Path::new("r.yaml"), vec!["r.yaml:1:1: bad".into()]);
        let j = p.to_json();
        assert_eq!(j["error"]["kind"], "bad_file");
        assert_eq!(j["error"]["exit"], 3);
        assert_eq!(j["error"]["message"], "r.yaml: 1 error");
        assert_eq!(j["error"]["lines"][0], "r.yaml:1:1: bad");
        assert_eq!(j["error"]["file"], "r.yaml");
    }

    #[test]
    fn source_paths_of_the_build_machine_are_dropped() {
        assert_eq!(
            clean("Can not create a new TCP listener: Address in use at /root/.cargo/registry/src/x/zenoh-1.0/src/a.rs:12."),
            "Can not create a new TCP listener: Address in use."
        );
        assert_eq!(clean("no robot (is it running?)"), "no robot (is it running?)");
    }
}
