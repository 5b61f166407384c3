//! Python skills in the manager's cycle.
//!
//! `@situate.skill` (Python, `python/situate/skill.py`) reads a function's
//! (or a class's `step`'s) signature and hands [`declare`] the ports and
//! parameters; [`declare`] builds the [`SkillDecl`] — the same declaration a
//! Rust skill's derive produces — checking every type. A [`PySkill`] is one
//! instance: its [`Skill::step`] attaches to the interpreter, converts the
//! inputs (arrays without a copy, see [`crate::convert`]), calls the body,
//! and converts the returned outputs back with a type check. An exception
//! returns a [`SkillError`] carrying the traceback, so the manager faults
//! the skill and the cycle goes on. What the body prints to `sys.stdout` is
//! captured per call and becomes the skill's own prints.
//!
//! A class skill's optional `activate(self)` and `deactivate(self)` are its
//! [`Skill::activate`] and [`Skill::deactivate`]: called the same way (the
//! same thread state, the same capture of prints), an exception becomes the
//! [`SkillError`] a failed `step` would return.

use std::cell::{Cell, RefCell};
use std::sync::Arc;

use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::sync::PyOnceLock;
use pyo3::types::{PyDict, PyString, PyTuple};
use situate_core::{
    Context, Io, ParamSpec, ParamType, PortSpec, SignalType, Skill, SkillDecl, SkillError, SkillKind, SkillType, Value,
};

use crate::convert;

/// The claim every in-process Python skill holds: the parallel executor
/// never runs two of them at once (they would only queue on the GIL).
pub const PYTHON_CLAIM: &str = "python";

/// A declared Python skill type: the declaration and how the body is called.
#[pyclass(frozen, module = "situate._native", name = "Declaration")]
pub struct Declaration {
    pub decl: Arc<SkillDecl>,
    /// The call's arguments in order: (is_param, index, name).
    args: Vec<(bool, usize, String)>,
    positional: bool,
}

#[pymethods]
impl Declaration {
    #[getter]
    fn type_name(&self) -> &str {
        &self.decl.type_name
    }

    /// The declaration as `situate types` would print it.
    fn describe(&self) -> String {
        describe(&self.decl)
    }

    fn __repr__(&self) -> String {
        format!("<situate skill declaration `{}`>", self.decl.type_name)
    }
}

/// A declaration in words (one line per port and parameter).
pub fn describe(d: &SkillDecl) -> String {
    let mut s = format!("{} ({}, priority {})\n", d.type_name, d.kind, d.priority);
    for p in &d.inputs {
        let signal = if p.signal != p.name { format!(" <- {}", p.signal) } else { String::new() };
        s.push_str(&format!("  in  {}: {}{}{signal}\n", p.name, p.ty, if p.optional { " (optional)" } else { "" }));
    }
    for p in &d.outputs {
        let signal = if p.signal != p.name { format!(" -> {}", p.signal) } else { String::new() };
        s.push_str(&format!("  out {}: {}{signal}\n", p.name, p.ty));
    }
    for p in &d.params {
        let unit = if p.unit.is_empty() { String::new() } else { format!(" {}", p.unit) };
        s.push_str(&format!("  param {}: {} = {}{unit} ({})\n", p.name, p.ty.name(), p.default, p.expectation()));
    }
    s
}

fn parse_type(what: &str, text: &str) -> PyResult<SignalType> {
    SignalType::parse(text).map_err(|e| PyValueError::new_err(format!("{what}: bad type `{text}`: {e}")))
}

type InputArg = (String, String, String, bool, String);
type OutputArg = (String, String, String, String);
type ParamArg<'py> = (String, String, Bound<'py, PyAny>, Option<f64>, Option<f64>, String, String);

/// Builds a skill declaration; every type and default is checked.
///
/// `inputs`: (name, type, signal, optional, doc); `outputs`: (name, type,
/// signal, doc); `params`: (name, type, default, min, max, unit, doc);
/// `call`: the body's arguments in order, as ("in" | "param", name);
/// `positional`: whether they are passed by position (else by keyword).
#[pyfunction]
#[pyo3(signature = (name, kind, priority, doc, inputs, outputs, params, call, positional))]
#[allow(clippy::too_many_arguments)]
pub fn declare(
    name: &str,
    kind: &str,
    priority: i32,
    doc: &str,
    inputs: Vec<InputArg>,
    outputs: Vec<OutputArg>,
    params: Vec<ParamArg<'_>>,
    call: Vec<(String, String)>,
    positional: bool,
) -> PyResult<Declaration> {
    let kind = match SkillKind::parse(kind) {
        Some(SkillKind::Device) | None => {
            return Err(PyValueError::new_err(format!(
                "skill `{name}`: kind must be \"sync\" or \"async\", got {kind:?}"
            )))
        }
        Some(k) => k,
    };
    if name.trim().is_empty() {
        return Err(PyValueError::new_err("a skill needs a name"));
    }
    let mut decl = SkillDecl::new(name, kind);
    decl.priority = priority;
    decl.doc = doc.to_string();
    decl.claims = vec![PYTHON_CLAIM.to_string()];
    for (port, ty, signal, optional, pdoc) in inputs {
        let mut p = PortSpec::new(&port, parse_type(&format!("skill `{name}`, input `{port}`"), &ty)?);
        p.signal = if signal.is_empty() { port.clone() } else { signal };
        p.optional = optional;
        p.doc = pdoc;
        decl.inputs.push(p);
    }
    for (port, ty, signal, pdoc) in outputs {
        if decl.outputs.iter().any(|o| o.name == port) {
            return Err(PyValueError::new_err(format!("skill `{name}`: output `{port}` is declared twice")));
        }
        let mut p = PortSpec::new(&port, parse_type(&format!("skill `{name}`, output `{port}`"), &ty)?);
        p.signal = if signal.is_empty() { port.clone() } else { signal };
        p.doc = pdoc;
        decl.outputs.push(p);
    }
    for (pname, ty, default, min, max, unit, pdoc) in params {
        let pty = match ty.as_str() {
            "bool" => ParamType::Bool,
            "i64" | "int" => ParamType::I64,
            "f64" | "float" => ParamType::F64,
            "string" | "str" => ParamType::Str,
            other => {
                return Err(PyValueError::new_err(format!(
                    "skill `{name}`, parameter `{pname}`: type must be bool, i64, f64 or string, got `{other}`"
                )))
            }
        };
        let what = format!("skill `{name}`, parameter `{pname}`");
        let default =
            convert::param_from_py(&default, pty).map_err(|e| PyValueError::new_err(format!("{what}: default {e}")))?;
        if let (Some(lo), Some(hi)) = (min, max) {
            if lo > hi {
                return Err(PyValueError::new_err(format!("{what}: min {lo:?} is above max {hi:?}")));
            }
        }
        let mut spec = ParamSpec::new(&pname, pty, default.clone()).range(min, max);
        spec.unit = unit;
        spec.doc = pdoc;
        let default = spec.check(&default).map_err(|e| PyValueError::new_err(format!("{what}: the default {e}")))?;
        spec.default = default;
        decl.params.push(spec);
    }
    let mut args = Vec::with_capacity(call.len());
    for (what, arg) in call {
        let found = if what == "param" {
            decl.params.iter().position(|p| p.name == arg).map(|i| (true, i))
        } else {
            decl.inputs.iter().position(|p| p.name == arg).map(|i| (false, i))
        };
        let Some((is_param, index)) = found else {
            return Err(PyValueError::new_err(format!("skill `{name}`: the body's argument `{arg}` is not declared")));
        };
        args.push((is_param, index, arg));
    }
    Ok(Declaration { decl: Arc::new(decl), args, positional })
}

// ----- the interpreter thread state and stdout capture ----------------------

thread_local! {
    /// Whether this (non-Python) thread keeps a Python thread state.
    static KEPT: Cell<bool> = const { Cell::new(false) };
    /// What a body printed during the current call on this thread.
    static CAPTURE: RefCell<Option<String>> = const { RefCell::new(None) };
}

/// Keeps a Python thread state for the calling thread for good, so that each
/// skill call only takes and releases the GIL instead of creating and
/// destroying a thread state (PyGILState_Ensure/Release on a thread Python
/// does not know). The state lives as long as the thread (one small leak per
/// manager thread that ever ran a Python skill).
fn keep_thread_state() {
    if KEPT.with(Cell::get) {
        return;
    }
    KEPT.with(|k| k.set(true));
    // SAFETY: called without the GIL held by this thread (the manager's
    // threads never hold it between calls); the interpreter is initialized
    // (a Python skill exists). Ensure attaches (creating the thread state),
    // SaveThread releases the GIL while keeping the state and the gilstate
    // counter at 1, so later Ensure/Release pairs never drop it.
    unsafe {
        if pyo3::ffi::Py_IsInitialized() == 0 {
            return;
        }
        let _ = pyo3::ffi::PyGILState_Ensure();
        let _ = pyo3::ffi::PyEval_SaveThread();
    }
}

/// `sys.stdout` while Python skills exist: inside a skill's call, writes go
/// to that call's capture; elsewhere (other threads, outside calls) to the
/// stream it replaced.
#[pyclass(module = "situate._native", name = "SkillStdout")]
pub struct SkillStdout {
    inner: Py<PyAny>,
}

#[pymethods]
impl SkillStdout {
    fn write(&self, py: Python<'_>, text: &str) -> PyResult<usize> {
        let captured = CAPTURE.with(|c| match c.borrow_mut().as_mut() {
            Some(buf) => {
                buf.push_str(text);
                true
            }
            None => false,
        });
        if captured {
            return Ok(text.chars().count());
        }
        self.inner.bind(py).call_method1("write", (text,))?.extract().or(Ok(text.len()))
    }

    fn flush(&self, py: Python<'_>) -> PyResult<()> {
        if CAPTURE.with(|c| c.borrow().is_some()) {
            return Ok(());
        }
        self.inner.bind(py).call_method0("flush").map(|_| ())
    }

    /// The stream it stands in front of.
    #[getter]
    fn wrapped(&self, py: Python<'_>) -> Py<PyAny> {
        self.inner.clone_ref(py)
    }

    fn __getattr__(&self, py: Python<'_>, name: &str) -> PyResult<Py<PyAny>> {
        self.inner.bind(py).getattr(name).map(Bound::unbind)
    }
}

static SYS_DICT: PyOnceLock<Py<PyDict>> = PyOnceLock::new();

/// Makes sure `sys.stdout` is a [`SkillStdout`] (someone may have replaced it since).
fn ensure_stdout(py: Python<'_>) -> PyResult<()> {
    // The fast path is one lookup in `sys.__dict__` with an interned key.
    let sys_dict = SYS_DICT.get_or_try_init(py, || {
        py.import("sys")?.getattr("__dict__")?.cast_into::<PyDict>().map(Bound::unbind).map_err(PyErr::from)
    })?;
    if let Some(current) = sys_dict.bind(py).get_item(pyo3::intern!(py, "stdout"))? {
        if current.is_instance_of::<SkillStdout>() || current.is_none() {
            return Ok(());
        }
    }
    let sys = py.import("sys")?;
    let current = sys.getattr("stdout")?;
    if current.is_none() {
        return Ok(());
    }
    let router = Bound::new(py, SkillStdout { inner: current.unbind() })?;
    sys.setattr("stdout", router)
}

/// Captures what the body prints while it runs on this thread.
struct Capture;

impl Capture {
    fn begin(py: Python<'_>) -> Capture {
        // Cheap check: `sys.stdout` changed only if someone replaced it.
        let _ = ensure_stdout(py);
        CAPTURE.with(|c| *c.borrow_mut() = Some(String::new()));
        Capture
    }

    fn end(self) -> String {
        CAPTURE.with(|c| c.borrow_mut().take()).unwrap_or_default()
    }
}

impl Drop for Capture {
    fn drop(&mut self) {
        CAPTURE.with(|c| c.borrow_mut().take());
    }
}

static FORMAT_EXCEPTION: PyOnceLock<Py<PyAny>> = PyOnceLock::new();

/// The traceback of an exception, as Python prints it.
pub fn traceback_text(py: Python<'_>, err: &PyErr) -> String {
    let formatted = FORMAT_EXCEPTION
        .get_or_try_init(py, || py.import("traceback").and_then(|m| m.getattr("format_exception")).map(Bound::unbind))
        .and_then(|f| {
            let tb = err.traceback(py).map(Bound::into_any).unwrap_or_else(|| py.None().into_bound(py));
            f.bind(py).call1((err.get_type(py), err.value(py), tb))
        })
        .and_then(|lines| lines.extract::<Vec<String>>());
    match formatted {
        Ok(lines) => lines.concat().trim_end().to_string(),
        Err(_) => err.to_string(),
    }
}

// ----- one instance ---------------------------------------------------------

/// One instance of a Python skill type.
pub struct PySkill {
    decl: Arc<SkillDecl>,
    body: Py<PyAny>,
    /// The instance's `activate` and `deactivate` (a class skill's, when it
    /// defines them; a function skill has none).
    on_activate: Option<Py<PyAny>>,
    on_deactivate: Option<Py<PyAny>>,
    args: Vec<(bool, usize, Py<PyString>)>,
    positional: bool,
    params: Vec<Py<PyAny>>,
    outputs: Vec<Py<PyString>>,
}

impl PySkill {
    fn new(py: Python<'_>, d: &Declaration, made: Made) -> PyResult<PySkill> {
        let (body, on_activate, on_deactivate) = made;
        let params =
            d.decl.params.iter().map(|p| convert::to_py(py, &p.default).map(Bound::unbind)).collect::<PyResult<_>>()?;
        Ok(PySkill {
            decl: Arc::clone(&d.decl),
            body,
            on_activate,
            on_deactivate,
            args: d.args.iter().map(|(p, i, n)| (*p, *i, PyString::intern(py, n).unbind())).collect(),
            positional: d.positional,
            params,
            outputs: d.decl.outputs.iter().map(|o| PyString::intern(py, &o.name).unbind()).collect(),
        })
    }

    fn arg<'py>(
        &self,
        py: Python<'py>,
        inputs: &[Option<Value>],
        is_param: bool,
        i: usize,
    ) -> PyResult<Bound<'py, PyAny>> {
        if is_param {
            return Ok(self.params[i].bind(py).clone());
        }
        match inputs.get(i).and_then(Option::as_ref) {
            Some(v) => convert::to_py(py, v),
            None => Ok(py.None().into_bound(py)),
        }
    }

    fn call<'py>(&self, py: Python<'py>, inputs: &[Option<Value>]) -> PyResult<Bound<'py, PyAny>> {
        let body = self.body.bind(py);
        if self.positional {
            let arg = |k: usize| {
                let (is_param, i, _) = &self.args[k];
                self.arg(py, inputs, *is_param, *i)
            };
            // The common small arities without a temporary vector.
            match self.args.len() {
                0 => body.call0(),
                1 => body.call1((arg(0)?,)),
                2 => body.call1((arg(0)?, arg(1)?)),
                3 => body.call1((arg(0)?, arg(1)?, arg(2)?)),
                n => body.call1(PyTuple::new(py, (0..n).map(arg).collect::<PyResult<Vec<_>>>()?)?),
            }
        } else {
            let kwargs = PyDict::new(py);
            for (is_param, i, name) in &self.args {
                kwargs.set_item(name.bind(py), self.arg(py, inputs, *is_param, *i)?)?;
            }
            body.call((), Some(&kwargs))
        }
    }

    fn fail(&self, message: String) -> SkillError {
        SkillError::new(format!("python skill `{}`: {message}", self.decl.type_name))
    }

    /// Calls a hook (`activate` or `deactivate`) with no arguments, as
    /// [`Skill::step`] calls the body: what it prints becomes the skill's
    /// prints, an exception the error (the manager names the hook). No hook:
    /// nothing, without attaching to the interpreter.
    fn call_hook(&self, hook: Option<&Py<PyAny>>, cx: &mut Context) -> Result<(), SkillError> {
        let Some(hook) = hook else { return Ok(()) };
        keep_thread_state();
        Python::attach(|py| {
            let capture = Capture::begin(py);
            let result = hook.bind(py).call0();
            print_lines(cx, &capture.end());
            match result {
                Ok(_) => Ok(()),
                Err(e) => Err(self.fail(format!("raised {}", traceback_text(py, &e)))),
            }
        })
    }

    /// Converts the body's result into the outputs, checking every type.
    fn take_outputs(&self, result: &Bound<'_, PyAny>, outputs: &mut [Option<Value>]) -> Result<(), SkillError> {
        if result.is_none() {
            return Ok(());
        }
        let names = || self.decl.outputs.iter().map(|o| format!("`{}`", o.name)).collect::<Vec<_>>().join(", ");
        let Ok(d) = result.cast::<PyDict>() else {
            return Err(self.fail(format!(
                "the body returned a {}; return a dict of outputs ({}) or None",
                result.get_type().name().map(|n| n.to_string()).unwrap_or_default(),
                if self.decl.outputs.is_empty() { "none declared".to_string() } else { names() }
            )));
        };
        let mut found = 0;
        for (j, (name, port)) in self.outputs.iter().zip(&self.decl.outputs).enumerate() {
            let item = d.get_item(name.bind(result.py())).map_err(|e| self.fail(e.to_string()))?;
            let Some(item) = item else { continue };
            found += 1;
            if item.is_none() {
                continue;
            }
            let value = convert::from_py(&item, &port.ty).map_err(|m| {
                let at = if m.path.is_empty() { String::new() } else { m.path.clone() };
                self.fail(format!("output `{}{at}`: expected {}, got {}", port.name, m.expected, m.got))
            })?;
            if let Some(slot) = outputs.get_mut(j) {
                *slot = Some(value);
            }
        }
        if found != d.len() {
            for key in d.keys() {
                let k = key.str().map(|s| s.to_string()).unwrap_or_default();
                if !self.decl.outputs.iter().any(|o| o.name == k) {
                    return Err(self.fail(format!(
                        "the body returned an unknown output `{k}`; its outputs are {}",
                        if self.decl.outputs.is_empty() { "none".to_string() } else { names() }
                    )));
                }
            }
        }
        Ok(())
    }
}

/// What a call printed, one print per line (a last newline ends the last line).
fn print_lines(cx: &mut Context, printed: &str) {
    if printed.is_empty() {
        return;
    }
    let text = printed.strip_suffix('\n').unwrap_or(printed);
    for line in text.split('\n') {
        cx.print(line);
    }
}

impl Skill for PySkill {
    fn step(&mut self, io: &mut Io<'_>) -> Result<(), SkillError> {
        keep_thread_state();
        Python::attach(|py| {
            let capture = Capture::begin(py);
            let result = self.call(py, io.inputs);
            print_lines(io.cx, &capture.end());
            match result {
                Ok(r) => self.take_outputs(&r, io.outputs),
                Err(e) => Err(self.fail(format!("raised {}", traceback_text(py, &e)))),
            }
        })
    }

    fn activate(&mut self, cx: &mut Context) -> Result<(), SkillError> {
        self.call_hook(self.on_activate.as_ref(), cx)
    }

    fn deactivate(&mut self, cx: &mut Context) -> Result<(), SkillError> {
        self.call_hook(self.on_deactivate.as_ref(), cx)
    }

    fn set_param(&mut self, index: usize, value: &Value) {
        Python::attach(|py| {
            if let (Some(slot), Ok(v)) = (self.params.get_mut(index), convert::to_py(py, value)) {
                *slot = v.unbind();
            }
        });
    }
}

/// What `_make_body()` returns for one new instance: the body callable and
/// the instance's `activate` and `deactivate` hooks (`None` when absent).
type Made = (Py<PyAny>, Option<Py<PyAny>>, Option<Py<PyAny>>);

/// A Python object provided as a resource (`LocalRobot(..., resources=...)`): what a class
/// skill's `__init__` is given by name.
pub struct PyResource(pub Py<PyAny>);

/// The skill type of a `@situate.skill` object: its `_declaration` and its
/// `_make_body(resources)` (a fresh body callable and its hooks per instance,
/// a class made with the resources its `__init__` names).
pub fn skill_type(py: Python<'_>, obj: &Bound<'_, PyAny>) -> PyResult<SkillType> {
    let declaration = obj.getattr("_declaration")?;
    let declaration = declaration.cast::<Declaration>()?;
    let d = declaration.get();
    let decl = (*d.decl).clone();
    let factory = obj.getattr("_make_body")?.unbind();
    let declaration = declaration.clone().unbind();
    // Install the stdout router now, from a Python thread.
    ensure_stdout(py)?;
    // Arrays cross as numpy arrays: import numpy now, at load, not in the body's first timed
    // run (an import takes 100–200 ms, past a tight `budget_ms`).
    if decl.inputs.iter().chain(&decl.outputs).any(|p| has_array(&p.ty)) {
        convert::have_numpy(py);
    }
    Ok(SkillType::with_resources(decl, move |resources| {
        Python::attach(|py| {
            let d = declaration.bind(py).get();
            // The Python objects among the resources (others, the simulator's world say, are
            // not for Python).
            let given = PyDict::new(py);
            for name in resources.names() {
                if let Some(r) = resources.get_any(name).and_then(|a| a.downcast_ref::<PyResource>()) {
                    given.set_item(name, r.0.clone_ref(py)).map_err(|e| e.to_string())?;
                }
            }
            let made = factory.bind(py).call1((given,)).and_then(|made| made.extract::<Made>()).map_err(|e| {
                if is_missing_resource(py, &e) {
                    // A resource it needs is missing: the message says which (a `KeyError` of
                    // the class's own `__init__` is its fault, and gets its traceback).
                    e.value(py).to_string()
                } else {
                    format!("creating python skill `{}`: {}", d.decl.type_name, traceback_text(py, &e))
                }
            })?;
            let skill = PySkill::new(py, d, made).map_err(|e| e.to_string())?;
            Ok(Box::new(skill) as Box<dyn Skill>)
        })
    }))
}

/// Whether `e` is `situate.skill.MissingResource` (`_make_body`'s: a resource not provided).
fn is_missing_resource(py: Python<'_>, e: &PyErr) -> bool {
    py.import("situate.skill")
        .and_then(|m| m.getattr("MissingResource"))
        .is_ok_and(|class| e.value(py).is_instance(&class).unwrap_or(false))
}

/// Whether values of type `t` hold a numeric array (a record may hold one in a field).
fn has_array(t: &SignalType) -> bool {
    match t {
        SignalType::Array { .. } => true,
        SignalType::Record(r) => r.fields.iter().any(|(_, t)| has_array(t)),
        _ => false,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_declaration_is_described_with_signals_ranges_and_units() {
        let mut d = SkillDecl::new("py.runaway", SkillKind::Sync);
        d.priority = 50;
        d.inputs.push(PortSpec::new("sonar_range", SignalType::parse("f32[24]").unwrap()).signal("sonar.range"));
        d.outputs.push(PortSpec::new("drive", SignalType::parse("{v: f64, w: f64}").unwrap()));
        let mut p = ParamSpec::new("safe_distance", ParamType::F64, Value::F64(0.5)).range(Some(0.1), Some(3.0));
        p.unit = "m".into();
        d.params.push(p);
        assert_eq!(
            describe(&d),
            "py.runaway (sync, priority 50)\n  in  sonar_range: f32[24] <- sonar.range\n  out drive: {v: f64, w: f64}\n  \
             param safe_distance: f64 = 0.5 m (a number in [0.1, 3.0])\n"
        );
    }
}
