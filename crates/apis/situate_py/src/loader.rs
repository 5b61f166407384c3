//! The `situate_cli::PythonLoader`: a robot file's `python:` files, imported.
//!
//! Each file is imported by path under a module name of its own
//! (`situate._loader.load_file`, Python) and every `@situate.skill` found in
//! it becomes a [`SkillType`]. Errors name the file, and the line when Python
//! gives one (a syntax error, an exception while importing, a bad
//! declaration).

use std::path::Path;
use std::sync::Arc;

use pyo3::prelude::*;
use situate_core::SkillType;

use crate::skill::{skill_type, traceback_text};

/// Loads the skill types of one Python file (attaches to the interpreter).
pub fn load_file(path: &Path) -> Result<Vec<SkillType>, String> {
    Python::attach(|py| load_file_in(py, path))
}

fn load_file_in(py: Python<'_>, path: &Path) -> Result<Vec<SkillType>, String> {
    let loader =
        py.import("situate._loader").map_err(|e| format!("importing situate._loader: {}", traceback_text(py, &e)))?;
    let skills = match loader.call_method1("load_file", (path.to_string_lossy().to_string(),)) {
        Ok(s) => s,
        Err(e) => {
            // `SkillLoadError` messages are complete (file, line, what); anything else: the traceback.
            let is_load_error = loader
                .getattr("SkillLoadError")
                .map(|cls| e.get_type(py).is_subclass(&cls).unwrap_or(false))
                .unwrap_or(false);
            return Err(if is_load_error { e.value(py).to_string() } else { traceback_text(py, &e) });
        }
    };
    let mut types = Vec::new();
    let iter = skills.try_iter().map_err(|e| e.to_string())?;
    for item in iter {
        let item = item.map_err(|e| e.to_string())?;
        types.push(skill_type(py, &item).map_err(|e| format!("{}: {}", path.display(), e))?);
    }
    Ok(types)
}

/// The loader the `situate` program calls for each `python:` file.
pub fn python_loader() -> situate_cli::PythonLoader {
    Arc::new(|path: &Path| load_file(path))
}
