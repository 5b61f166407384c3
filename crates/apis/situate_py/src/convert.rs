//! Values between the cycle and Python.
//!
//! Inputs go to Python as plain objects: `float`, `int`, `bool`, `str`,
//! `bytes`, `dict` for records, and **read-only numpy arrays sharing the
//! signal's buffer** for numeric arrays (no copy: the array's memory is the
//! `Arc<[f32]>` the producer wrote, kept alive by a small owner object that
//! numpy sees as the array's `base`, through numpy's `__array_interface__`).
//! Without numpy, arrays arrive as lists.
//!
//! Outputs come back with a type check against the port's declared type; a
//! mismatch is a [`Mismatch`] naming the place inside the value (`.v`,
//! `[3]`), what was expected and what was given.

use std::sync::Arc;

use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;
use pyo3::sync::PyOnceLock;
use pyo3::types::{PyBool, PyByteArray, PyBytes, PyDict, PyFloat, PyInt, PyList, PyString, PyTuple};
use situate_core::{ElemType, ParamType, RecordValue, SignalType, Value};

/// A value that does not fit its declared type.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{}expected {expected}, got {got}", if path.is_empty() { String::new() } else { format!("at `{path}`: ") })]
pub struct Mismatch {
    /// Where inside the value (`.v`, `[3]`); empty for the value itself.
    pub path: String,
    pub expected: String,
    pub got: String,
}

impl Mismatch {
    fn new(expected: &SignalType, got: String) -> Self {
        Mismatch { path: String::new(), expected: expected.to_string(), got }
    }

    fn within(mut self, prefix: &str) -> Self {
        self.path = format!("{prefix}{}", self.path);
        self
    }
}

/// The owner of an array's memory as numpy sees it: it holds the signal's
/// `Arc` and describes the buffer with `__array_interface__` (read-only).
#[pyclass(frozen, module = "situate._native", name = "SharedArray")]
pub struct SharedArray {
    data: ArrayData,
}

#[derive(Clone)]
enum ArrayData {
    F32(Arc<[f32]>),
    F64(Arc<[f64]>),
    I64(Arc<[i64]>),
}

impl ArrayData {
    fn ptr_len(&self) -> (usize, usize) {
        match self {
            ArrayData::F32(a) => (a.as_ptr() as usize, a.len()),
            ArrayData::F64(a) => (a.as_ptr() as usize, a.len()),
            ArrayData::I64(a) => (a.as_ptr() as usize, a.len()),
        }
    }

    fn typestr(&self) -> &'static str {
        let little = cfg!(target_endian = "little");
        match (self, little) {
            (ArrayData::F32(_), true) => "<f4",
            (ArrayData::F64(_), true) => "<f8",
            (ArrayData::I64(_), true) => "<i8",
            (ArrayData::F32(_), false) => ">f4",
            (ArrayData::F64(_), false) => ">f8",
            (ArrayData::I64(_), false) => ">i8",
        }
    }
}

#[pymethods]
impl SharedArray {
    /// numpy's array interface (version 3): a read-only, C-contiguous 1-d buffer.
    #[getter]
    fn __array_interface__<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let (ptr, len) = self.data.ptr_len();
        let d = PyDict::new(py);
        d.set_item("shape", (len,))?;
        d.set_item("typestr", self.data.typestr())?;
        d.set_item("data", (ptr, true))?;
        d.set_item("version", 3)?;
        Ok(d)
    }

    fn __len__(&self) -> usize {
        self.data.ptr_len().1
    }
}

static ASARRAY: PyOnceLock<Option<Py<PyAny>>> = PyOnceLock::new();
static ASCONTIGUOUS: PyOnceLock<Option<Py<PyAny>>> = PyOnceLock::new();
static NDARRAY: PyOnceLock<Option<Py<PyAny>>> = PyOnceLock::new();

fn numpy_fn<'py>(
    py: Python<'py>,
    cell: &'static PyOnceLock<Option<Py<PyAny>>>,
    name: &str,
) -> Option<Bound<'py, PyAny>> {
    cell.get_or_init(py, || py.import("numpy").and_then(|m| m.getattr(name)).ok().map(Bound::unbind))
        .as_ref()
        .map(|f| f.bind(py).clone())
}

/// Whether numpy can be imported (arrays then arrive as numpy arrays).
pub fn have_numpy(py: Python<'_>) -> bool {
    numpy_fn(py, &ASARRAY, "asarray").is_some()
}

fn array_to_py<'py>(py: Python<'py>, data: ArrayData) -> PyResult<Bound<'py, PyAny>> {
    if let Some(asarray) = numpy_fn(py, &ASARRAY, "asarray") {
        let owner = Bound::new(py, SharedArray { data })?;
        return asarray.call1((owner,));
    }
    Ok(match data {
        ArrayData::F32(a) => PyList::new(py, a.iter().map(|x| f64::from(*x)))?.into_any(),
        ArrayData::F64(a) => PyList::new(py, a.iter())?.into_any(),
        ArrayData::I64(a) => PyList::new(py, a.iter())?.into_any(),
    })
}

/// A value as a Python object (arrays without a copy, see the module docs).
pub fn to_py<'py>(py: Python<'py>, v: &Value) -> PyResult<Bound<'py, PyAny>> {
    Ok(match v {
        Value::Bool(b) => PyBool::new(py, *b).to_owned().into_any(),
        Value::I64(x) => x.into_pyobject(py)?.into_any(),
        Value::F64(x) => PyFloat::new(py, *x).into_any(),
        Value::Str(s) => PyString::new(py, s).into_any(),
        Value::Bytes(b) => PyBytes::new(py, b).into_any(),
        Value::F32s(a) => array_to_py(py, ArrayData::F32(Arc::clone(a)))?,
        Value::F64s(a) => array_to_py(py, ArrayData::F64(Arc::clone(a)))?,
        Value::I64s(a) => array_to_py(py, ArrayData::I64(Arc::clone(a)))?,
        Value::Record(r) => {
            let d = PyDict::new(py);
            for (name, field) in &r.fields {
                d.set_item(PyString::new(py, name), to_py(py, field)?)?;
            }
            d.into_any()
        }
    })
}

fn type_name(obj: &Bound<'_, PyAny>) -> String {
    obj.get_type().name().map(|n| n.to_string()).unwrap_or_else(|_| "?".to_string())
}

/// What an object is, for error messages: `str`, `a list of 23`, `a float64 array of 3`.
fn describe(obj: &Bound<'_, PyAny>) -> String {
    let name = type_name(obj);
    if obj.is_instance_of::<PyList>() || obj.is_instance_of::<PyTuple>() {
        let n = obj.len().unwrap_or(0);
        return format!("a {name} of {n}");
    }
    if name == "ndarray" {
        let dtype = obj.getattr("dtype").map(|d| d.to_string()).unwrap_or_default();
        let shape = obj.getattr("shape").map(|s| s.to_string()).unwrap_or_default();
        return format!("a {dtype} array of shape {shape}");
    }
    if obj.is_none() {
        return "None".to_string();
    }
    name
}

fn to_f64(obj: &Bound<'_, PyAny>, ty: &SignalType) -> Result<f64, Mismatch> {
    if let Ok(f) = obj.cast::<PyFloat>() {
        return Ok(f.value());
    }
    if obj.is_instance_of::<PyBool>() || obj.is_instance_of::<PyString>() {
        return Err(Mismatch::new(ty, describe(obj)));
    }
    if obj.is_instance_of::<PyInt>() {
        return obj.extract::<f64>().map_err(|_| Mismatch::new(ty, "an int too large for f64".into()));
    }
    // numpy scalars (float32, int64, ...) convert through `__float__`.
    if type_name(obj) != "ndarray" && obj.hasattr("__float__").unwrap_or(false) && obj.hasattr("dtype").unwrap_or(false)
    {
        if let Ok(x) = obj.extract::<f64>() {
            return Ok(x);
        }
    }
    Err(Mismatch::new(ty, describe(obj)))
}

fn to_i64(obj: &Bound<'_, PyAny>, ty: &SignalType) -> Result<i64, Mismatch> {
    if obj.is_instance_of::<PyBool>() || obj.is_instance_of::<PyFloat>() {
        return Err(Mismatch::new(ty, describe(obj)));
    }
    if obj.is_instance_of::<PyInt>() || obj.hasattr("__index__").unwrap_or(false) {
        return obj.extract::<i64>().map_err(|_| Mismatch::new(ty, "an int out of the i64 range".into()));
    }
    Err(Mismatch::new(ty, describe(obj)))
}

fn to_bool(obj: &Bound<'_, PyAny>, ty: &SignalType) -> Result<bool, Mismatch> {
    if let Ok(b) = obj.cast::<PyBool>() {
        return Ok(b.is_true());
    }
    // numpy.bool_
    if matches!(type_name(obj).as_str(), "bool_" | "bool") {
        if let Ok(b) = obj.is_truthy() {
            return Ok(b);
        }
    }
    Err(Mismatch::new(ty, describe(obj)))
}

/// A numpy array's element data, if `obj` is a 1-d numpy array: (kind, size,
/// typestr, pointer, contiguous, read through `__array_interface__`).
struct ArrayView {
    typestr: String,
    ptr: usize,
    len: usize,
    contiguous: bool,
    ndim: usize,
}

fn array_view(obj: &Bound<'_, PyAny>) -> Option<ArrayView> {
    // Only numpy's own arrays: their interface describes memory they own or keep alive.
    let ndarray = numpy_fn(obj.py(), &NDARRAY, "ndarray")?;
    if !obj.is_instance(&ndarray).unwrap_or(false) {
        return None;
    }
    let iface = obj.getattr("__array_interface__").ok()?;
    let iface = iface.cast::<PyDict>().ok()?;
    let shape: Vec<usize> = iface.get_item("shape").ok()??.extract().ok()?;
    let typestr: String = iface.get_item("typestr").ok()??.extract().ok()?;
    let (ptr, _ro): (usize, bool) = iface.get_item("data").ok()??.extract().ok()?;
    let contiguous = iface.get_item("strides").ok()?.is_none_or(|s| s.is_none());
    Some(ArrayView { typestr, ptr, len: shape.first().copied().unwrap_or(0), contiguous, ndim: shape.len() })
}

fn native(typestr: &str) -> &'static str {
    let n = if cfg!(target_endian = "little") { '<' } else { '>' };
    match (typestr.chars().next(), typestr.get(1..).unwrap_or("")) {
        (Some(c), "f4") if c == n || c == '=' => "f4",
        (Some(c), "f8") if c == n || c == '=' => "f8",
        (Some(c), "i8") if c == n || c == '=' => "i8",
        _ => "",
    }
}

macro_rules! take_array {
    ($obj:expr, $ty:expr, $t:ty, $code:literal, $owned:ident, $variant:ident, $scalar:expr) => {{
        let obj: &Bound<'_, PyAny> = $obj;
        let ty: &SignalType = $ty;
        if let Some(view) = array_view(obj) {
            if view.ndim != 1 {
                return Err(Mismatch::new(ty, describe(obj)));
            }
            let kind = view.typestr.as_bytes().get(1).copied().unwrap_or(b'?');
            let castable = match $code {
                "i8" => matches!(kind, b'i' | b'u'),
                _ => matches!(kind, b'f' | b'i' | b'u'),
            };
            if !castable {
                return Err(Mismatch::new(ty, describe(obj)));
            }
            // The buffer we handed out, passed through untouched: share it again.
            if let Ok(base) = obj.getattr("base") {
                if let Ok(owner) = base.cast::<SharedArray>() {
                    if let ArrayData::$owned(a) = &owner.get().data {
                        if a.as_ptr() as usize == view.ptr
                            && a.len() == view.len
                            && view.contiguous
                            && native(&view.typestr) == $code
                        {
                            return Ok(Value::$variant(Arc::clone(a)));
                        }
                    }
                }
            }
            let aligned = view.ptr % std::mem::align_of::<$t>() == 0;
            if native(&view.typestr) == $code && view.contiguous && aligned && (view.ptr != 0 || view.len == 0) {
                let data: Arc<[$t]> = if view.len == 0 {
                    Arc::from(Vec::new())
                } else {
                    // SAFETY: a C-contiguous, aligned numpy buffer of `len`
                    // elements of this type, kept alive by `obj` (held, GIL held).
                    unsafe { Arc::from(std::slice::from_raw_parts(view.ptr as *const $t, view.len)) }
                };
                return Ok(Value::$variant(data));
            }
            // Another dtype or layout: let numpy make a contiguous copy of the right type.
            if let Some(f) = numpy_fn(obj.py(), &ASCONTIGUOUS, "ascontiguousarray") {
                let dtype = if cfg!(target_endian = "little") { concat!("<", $code) } else { concat!(">", $code) };
                if let Ok(copy) = f.call1((obj, dtype)) {
                    if native(&array_view(&copy).map(|v| v.typestr).unwrap_or_default()) == $code {
                        return take_elems(&copy, ty);
                    }
                }
            }
            return Err(Mismatch::new(ty, describe(obj)));
        }
        if obj.is_instance_of::<PyList>() || obj.is_instance_of::<PyTuple>() {
            let n = obj.len().unwrap_or(0);
            let mut out: Vec<$t> = Vec::with_capacity(n);
            let elem_ty = match $code {
                "i8" => SignalType::I64,
                _ => SignalType::F64,
            };
            for (i, item) in obj.try_iter().map_err(|_| Mismatch::new(ty, describe(obj)))?.enumerate() {
                let item = item.map_err(|_| Mismatch::new(ty, describe(obj)))?;
                let x = ($scalar)(&item, &elem_ty).map_err(|m: Mismatch| m.within(&format!("[{i}]")))?;
                out.push(x);
            }
            return Ok(Value::$variant(out.into()));
        }
        Err(Mismatch::new(ty, describe(obj)))
    }};
}

/// The elements of an array-typed value (length checked by the caller).
fn take_elems(obj: &Bound<'_, PyAny>, ty: &SignalType) -> Result<Value, Mismatch> {
    match ty {
        SignalType::Array { elem: ElemType::F32, .. } => {
            take_array!(obj, ty, f32, "f4", F32, F32s, |o: &Bound<'_, PyAny>, t: &SignalType| to_f64(o, t)
                .map(|x| x as f32))
        }
        SignalType::Array { elem: ElemType::F64, .. } => take_array!(obj, ty, f64, "f8", F64, F64s, to_f64),
        SignalType::Array { elem: ElemType::I64, .. } => take_array!(obj, ty, i64, "i8", I64, I64s, to_i64),
        _ => Err(Mismatch::new(ty, describe(obj))),
    }
}

/// A Python object as a value of type `ty`, checked.
pub fn from_py(obj: &Bound<'_, PyAny>, ty: &SignalType) -> Result<Value, Mismatch> {
    Ok(match ty {
        SignalType::F64 => Value::F64(to_f64(obj, ty)?),
        SignalType::I64 => Value::I64(to_i64(obj, ty)?),
        SignalType::Bool => Value::Bool(to_bool(obj, ty)?),
        SignalType::Str => match obj.cast::<PyString>() {
            Ok(s) => Value::Str(Arc::from(
                s.to_cow().map_err(|_| Mismatch::new(ty, "a str that is not UTF-8".into()))?.as_ref(),
            )),
            Err(_) => return Err(Mismatch::new(ty, describe(obj))),
        },
        SignalType::Bytes => {
            if let Ok(b) = obj.cast::<PyBytes>() {
                Value::Bytes(Arc::from(b.as_bytes()))
            } else if let Ok(b) = obj.cast::<PyByteArray>() {
                Value::Bytes(Arc::from(b.to_vec()))
            } else {
                return Err(Mismatch::new(ty, describe(obj)));
            }
        }
        SignalType::Array { len, .. } => {
            let v = take_elems(obj, ty)?;
            if let (Some(n), Some(got)) = (len, v.len()) {
                if *n != got {
                    return Err(Mismatch::new(ty, format!("{} of {got}", describe_kind(obj))));
                }
            }
            v
        }
        SignalType::Record(rt) => {
            let Ok(d) = obj.cast::<PyDict>() else {
                return Err(Mismatch::new(ty, describe(obj)));
            };
            let mut fields = Vec::with_capacity(rt.fields.len());
            for (name, fty) in &rt.fields {
                let item = d.get_item(name).ok().flatten().ok_or_else(|| Mismatch {
                    path: String::new(),
                    expected: ty.to_string(),
                    got: format!("a dict without `{name}`"),
                })?;
                let v = from_py(&item, fty).map_err(|m| m.within(&format!(".{name}")))?;
                fields.push((Arc::from(name.as_str()), v));
            }
            if d.len() != rt.fields.len() {
                for key in d.keys() {
                    let k = key.str().map(|s| s.to_string()).unwrap_or_default();
                    if rt.field(&k).is_none() {
                        return Err(Mismatch {
                            path: String::new(),
                            expected: ty.to_string(),
                            got: format!("a dict with an unknown field `{k}`"),
                        });
                    }
                }
            }
            Value::Record(Arc::new(RecordValue { fields }))
        }
    })
}

fn describe_kind(obj: &Bound<'_, PyAny>) -> String {
    if type_name(obj) == "ndarray" {
        "an array".into()
    } else {
        format!("a {}", type_name(obj))
    }
}

/// A parameter value from Python, in the parameter's type (before the range check).
pub fn param_from_py(obj: &Bound<'_, PyAny>, ty: ParamType) -> PyResult<Value> {
    let st = match ty {
        ParamType::Bool => SignalType::Bool,
        ParamType::I64 => SignalType::I64,
        ParamType::F64 => SignalType::F64,
        ParamType::Str => SignalType::Str,
    };
    from_py(obj, &st).map_err(|m| PyTypeError::new_err(format!("expected {}, got {}", ty.name(), m.got)))
}

/// A value from Python whose type is not declared (parameters set through the
/// in-process robot: the manager checks them against their declaration).
pub fn untyped_from_py(obj: &Bound<'_, PyAny>) -> PyResult<Value> {
    if let Ok(b) = obj.cast::<PyBool>() {
        return Ok(Value::Bool(b.is_true()));
    }
    if obj.is_instance_of::<PyInt>() {
        return Ok(Value::I64(obj.extract()?));
    }
    if let Ok(f) = obj.cast::<PyFloat>() {
        return Ok(Value::F64(f.value()));
    }
    if let Ok(s) = obj.cast::<PyString>() {
        return Ok(Value::Str(Arc::from(s.to_cow()?.as_ref())));
    }
    Err(PyTypeError::new_err(format!("expected a bool, int, float or str, got {}", describe(obj))))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mismatches_name_the_place_the_expectation_and_the_value() {
        let t = SignalType::parse("{v: f64, w: f64}").unwrap();
        let m = Mismatch::new(&SignalType::F64, "str".into()).within(".w");
        assert_eq!(m.to_string(), "at `.w`: expected f64, got str");
        assert_eq!(Mismatch::new(&t, "int".into()).to_string(), "expected {v: f64, w: f64}, got int");
    }

    #[test]
    fn only_native_typestrs_are_read_in_place() {
        let n = if cfg!(target_endian = "little") { "<" } else { ">" };
        assert_eq!(native(&format!("{n}f4")), "f4");
        assert_eq!(native("=f8"), "f8");
        assert_eq!(native("|b1"), "");
        assert_eq!(native(""), "");
        assert_eq!(native("é8"), "");
    }
}
