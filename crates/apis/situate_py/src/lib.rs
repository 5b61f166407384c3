//! `situate._native`: the `situate` program, and Python skills in the cycle.
//!
//! - [`main`] runs the `situate` program ([`situate_cli::main_with`], the very
//!   program the Rust build installs) with a Python loader, so robot files run
//!   from the Python package can list `python:` files of `@situate.skill`
//!   types. The GIL is released while the program runs: the manager's threads
//!   take it for each Python skill call, and other Python threads keep going.
//! - [`skill`]: the declaration of a Python skill ([`skill::declare`]) and its
//!   instances in the cycle ([`skill::PySkill`]).
//! - [`convert`]: values between the cycle and Python (arrays without a copy).
//! - [`loader`]: the `python:` files of a robot file, imported.
//! - [`robot`]: a robot file run in process (`situate.LocalRobot`).
//! - [`elevator`]: the 2-D simulator's elevator logic, for the physics robot.

use pyo3::prelude::*;

pub mod bench;
pub mod convert;
pub mod elevator;
pub mod loader;
pub mod robot;
pub mod skill;
pub mod traffic;

/// Runs the `situate` program with `argv` (the first item is the program
/// name, as in `sys.argv`) and returns its exit code. `interpreter` is the
/// Python that runs the demo's sequencer (`sys.executable`); `data_dir` holds
/// the package's `demo/`, `maps/` and `examples/`.
#[pyfunction]
#[pyo3(signature = (argv, interpreter=None, data_dir=None))]
fn main(
    py: Python<'_>,
    argv: Vec<String>,
    interpreter: Option<std::path::PathBuf>,
    data_dir: Option<std::path::PathBuf>,
) -> i32 {
    // Other extensions (added by the program later) keep their defaults.
    #[allow(clippy::needless_update)]
    let ext =
        situate_cli::Extensions { python: Some(loader::python_loader()), interpreter, data_dir, ..Default::default() };
    i32::from(py.detach(move || situate_cli::main_with(argv, ext)))
}

/// The version of the `situate` program built into this module.
#[pyfunction]
fn version() -> &'static str {
    env!("CARGO_PKG_VERSION")
}

/// The skill types of one Python file, described (what `python:` would load);
/// raises `ValueError` with the loader's message.
#[pyfunction]
fn load_file(py: Python<'_>, path: std::path::PathBuf) -> PyResult<Vec<String>> {
    let types = py.detach(|| loader::load_file(&path)).map_err(pyo3::exceptions::PyValueError::new_err)?;
    Ok(types.iter().map(|t| skill::describe(&t.decl)).collect())
}

/// The building of a map file as JSON (what `situate map show` prints); raises `ValueError`
/// with the loader's message (file and line).
#[pyfunction]
fn map_json(py: Python<'_>, path: std::path::PathBuf) -> PyResult<String> {
    py.detach(|| situate_cli::building_json(&path)).map_err(pyo3::exceptions::PyValueError::new_err)
}

#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(main, m)?)?;
    m.add_function(wrap_pyfunction!(version, m)?)?;
    m.add_function(wrap_pyfunction!(load_file, m)?)?;
    m.add_function(wrap_pyfunction!(map_json, m)?)?;
    m.add_function(wrap_pyfunction!(skill::declare, m)?)?;
    m.add_function(wrap_pyfunction!(convert_check, m)?)?;
    m.add_class::<skill::Declaration>()?;
    m.add_class::<skill::SkillStdout>()?;
    m.add_class::<convert::SharedArray>()?;
    m.add_class::<robot::LocalRobot>()?;
    m.add_class::<elevator::Elevator>()?;
    m.add_class::<traffic::Traffic>()?;
    Ok(())
}

/// Converts `value` to signal type `ty` and back, as a skill's output would
/// be (for tests of the conversions); raises `TypeError` on a mismatch.
#[pyfunction]
fn convert_check<'py>(value: &Bound<'py, PyAny>, ty: &str) -> PyResult<Bound<'py, PyAny>> {
    let st = situate_core::SignalType::parse(ty).map_err(|e| pyo3::exceptions::PyValueError::new_err(e.to_string()))?;
    let v = convert::from_py(value, &st).map_err(|m| pyo3::exceptions::PyTypeError::new_err(m.to_string()))?;
    convert::to_py(value.py(), &v)
}
