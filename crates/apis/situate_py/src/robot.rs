//! A robot file run in process, for tests and scripts (`situate.LocalRobot`).
//!
//! The manager is built from the file as `situate run` builds it (every
//! skill type the program knows: the toys, `std.*`, the simulator's `sim.*`
//! for a file with a `simulator:`, the file's `libraries:` and `python:`
//! files), but is not spawned: the caller
//! steps it, and asks it anything with the link protocol's verbs — the very
//! JSON the link serves (`situate_link::json`), so the Python side decodes
//! replies and events with the client's own code. The GIL is released while
//! the manager works, so Python skills can run in its cycle.

use std::path::PathBuf;
use std::sync::Mutex;

use crossbeam_channel::Receiver;
use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use serde_json::{json, Value as Json};
use situate_link::json as wire;
use situate_manager::{ClockKind, Event, ExecutorKind, Manager, Registry, Request, RobotFile, RobotSpec};

use crate::loader;

/// A robot file's manager, in this process.
#[pyclass(module = "situate._native", name = "LocalRobot")]
pub struct LocalRobot {
    manager: Mutex<Manager>,
    events: Receiver<Event>,
    robot: String,
}

fn lines(errors: impl IntoIterator<Item = String>) -> String {
    errors.into_iter().collect::<Vec<_>>().join("\n")
}

/// The skill types `situate run` gives the file (the built-ins, the simulator's devices for a file
/// with a `simulator:`, its `libraries:` and `python:` files), and the benchmark's types.
fn registry_for(py: Python<'_>, file: &RobotFile) -> Result<Registry, String> {
    let ext = situate_cli::Extensions { python: Some(loader::python_loader()), ..Default::default() }
        .skills(crate::bench::register);
    // The GIL is released: the Python loader takes it for each file it loads.
    py.detach(|| situate_cli::robot_registry(file, &ext)).map_err(lines)
}

/// Runs `n` cycles; with `record`, the readings after each.
fn run_chunk(m: &mut Manager, n: u64, record: &[String]) -> Result<Vec<Json>, Json> {
    if record.is_empty() {
        m.run_cycles(n);
        return Ok(Vec::new());
    }
    let mut rows = Vec::with_capacity(n as usize);
    for _ in 0..n {
        m.run_cycles(1);
        let mut row = Vec::with_capacity(record.len());
        for signal in record {
            match m.request(Request::QuerySignal { signal: signal.clone() }) {
                Ok(situate_manager::Reply::Signal(r)) => row.push(wire::reading_to_json(&r)),
                Ok(_) => row.push(Json::Null),
                Err(e) => return Err(wire::control_error(&e)),
            }
        }
        rows.push(Json::Array(row));
    }
    Ok(rows)
}

impl LocalRobot {
    fn lock(&self) -> PyResult<std::sync::MutexGuard<'_, Manager>> {
        self.manager.lock().map_err(|_| PyRuntimeError::new_err("the manager panicked earlier"))
    }
}

#[pymethods]
impl LocalRobot {
    /// Loads and builds the robot file (`clock`: "wall" | "simulated", `executor`: "serial" |
    /// "parallel"; `resources`: objects class skills are made with, by name).
    #[new]
    #[pyo3(signature = (path, clock = None, executor = None, resources = None))]
    fn new(
        py: Python<'_>,
        path: PathBuf,
        clock: Option<&str>,
        executor: Option<&str>,
        resources: Option<&Bound<'_, pyo3::types::PyDict>>,
    ) -> PyResult<Self> {
        let file = RobotFile::load(&path)
            .map_err(|errors| PyValueError::new_err(lines(errors.iter().map(|e| e.to_string()))))?;
        if let Ok(remote) = file.remote_decls() {
            if let Some((name, _)) = remote.first() {
                return Err(PyValueError::new_err(format!(
                    "{}: remote skill `{name}` needs the link: run the file with `situate run`",
                    path.display()
                )));
            }
        }
        let mut registry = registry_for(py, &file).map_err(PyValueError::new_err)?;
        for (name, value) in resources.into_iter().flat_map(|d| d.iter()) {
            let name: String = name
                .extract()
                .map_err(|_| PyValueError::new_err(format!("a resource's name must be a str, got {name}")))?;
            registry.provide(name, crate::skill::PyResource(value.unbind()));
        }
        let mut spec = RobotSpec::from_file(&file);
        match clock {
            None => {}
            Some("wall") => spec.clock = ClockKind::Wall,
            Some("simulated") => spec.clock = ClockKind::Simulated,
            Some(other) => {
                return Err(PyValueError::new_err(format!("clock must be \"wall\" or \"simulated\", got {other:?}")))
            }
        }
        match executor {
            None => {}
            Some("serial") => spec.executor = ExecutorKind::Serial,
            Some("parallel") => spec.executor = ExecutorKind::Parallel,
            Some(other) => {
                return Err(PyValueError::new_err(format!(
                    "executor must be \"serial\" or \"parallel\", got {other:?}"
                )))
            }
        }
        let manager =
            py.detach(|| Manager::build(&spec, &registry)).map_err(|e| PyValueError::new_err(e.to_string()))?;
        let events = manager.events();
        Ok(LocalRobot { robot: spec.robot.clone(), manager: Mutex::new(manager), events })
    }

    /// The robot's name.
    #[getter]
    fn name(&self) -> &str {
        &self.robot
    }

    /// Runs `cycles` cycles (paced by the clock) with the GIL released. With
    /// `record`, returns after each cycle the readings of those signals, as
    /// JSON: `[[reading, ...] per cycle]` (or a protocol error object).
    /// Ctrl-C (a pending signal) is honoured between chunks of cycles.
    #[pyo3(signature = (cycles, record = Vec::new()))]
    fn step(&self, py: Python<'_>, cycles: u64, record: Vec<String>) -> PyResult<String> {
        const CHUNK: u64 = 50;
        let mut rows = Vec::new();
        let mut done = 0;
        while done < cycles {
            let n = (cycles - done).min(CHUNK);
            let chunk = py.detach(|| -> PyResult<Result<Vec<Json>, Json>> {
                let mut m = self.lock()?;
                Ok(run_chunk(&mut m, n, &record))
            })?;
            match chunk {
                Ok(r) => rows.extend(r),
                Err(error) => return Ok(error.to_string()),
            }
            done += n;
            py.check_signals()?;
        }
        Ok(Json::Array(rows).to_string())
    }

    /// Answers one protocol request (`verb`, JSON `payload`) as the link
    /// would: `{"ok": ...}` or `{"error": {...}}`, as JSON.
    fn request(&self, py: Python<'_>, verb: &str, payload: &str) -> PyResult<String> {
        let decoded = match wire::decode_request(verb, payload.as_bytes()) {
            Ok(situate_link::json::Decoded::Manager(r)) => r,
            Ok(_) => {
                return Ok(json!({"error": {"kind": "invalid", "message": format!("`{verb}` is a link verb, not served in process")}})
                    .to_string())
            }
            Err(e) => return Ok(wire::wire_error(&e).to_string()),
        };
        // The lock is taken without the GIL: a Python skill in a running cycle may need it.
        let reply = py.detach(|| -> PyResult<_> { Ok(self.lock()?.request(decoded)) })?;
        Ok(match reply {
            Ok(r) => wire::ok(wire::reply_to_json(&r)).to_string(),
            Err(e) => wire::control_error(&e).to_string(),
        })
    }

    /// The events since the last call, as JSON objects (oldest first).
    fn events(&self) -> Vec<String> {
        self.events.try_iter().map(|e| wire::event_to_json(&e).1.to_string()).collect()
    }
}
