//! `situate._native`: the `situate` program, callable from Python.
//!
//! The Python package's console script `situate` hands its arguments to
//! [`main`], which runs [`situate_cli::main`] — the very program the Rust
//! build installs as the `situate` binary — so both installs behave the
//! same. The GIL is released while the program runs: `situate run` can
//! serve a robot for hours, and other Python threads (a remote skill, a
//! sequencer in the same process) keep running meanwhile.

use pyo3::prelude::*;

/// Runs the `situate` program with `argv` (the first item is the program
/// name, as in `sys.argv`) and returns its exit code.
#[pyfunction]
fn main(py: Python<'_>, argv: Vec<String>) -> i32 {
    let code = py.detach(move || situate_cli::main(argv));
    exit_code_to_int(code)
}

/// The version of the `situate` program built into this module.
#[pyfunction]
fn version() -> &'static str {
    env!("CARGO_PKG_VERSION")
}

/// `ExitCode` is opaque; its `Debug` form is the only portable window on
/// the number (`ExitCode(unix_exit_status(1))`), so read the digits from it.
fn exit_code_to_int(code: std::process::ExitCode) -> i32 {
    if code == std::process::ExitCode::SUCCESS {
        return 0;
    }
    let text = format!("{code:?}");
    let digits: String = text.chars().filter(char::is_ascii_digit).collect();
    digits.parse().unwrap_or(1)
}

#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(main, m)?)?;
    m.add_function(wrap_pyfunction!(version, m)?)?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::process::ExitCode;

    #[test]
    fn exit_codes_keep_their_number() {
        assert_eq!(exit_code_to_int(ExitCode::SUCCESS), 0);
        assert_eq!(exit_code_to_int(ExitCode::FAILURE), 1);
        assert_eq!(exit_code_to_int(ExitCode::from(2)), 2);
    }
}
