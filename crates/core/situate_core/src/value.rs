//! Signal values.
//!
//! A [`Value`] is what travels on a signal during a cycle. Everything larger
//! than a machine word sits behind an `Arc`, so handing one value to several
//! consumers clones a pointer, never the data.
//!
//! Rust types convert to and from values through [`SignalValue`]; records are
//! Rust structs with `#[derive(Record)]` (see the `situate` facade).

use std::fmt;
use std::sync::Arc;

use crate::types::{ElemType, RecordType, SignalType};

/// One value of a signal.
#[derive(Debug, Clone, PartialEq)]
pub enum Value {
    Bool(bool),
    I64(i64),
    F64(f64),
    Str(Arc<str>),
    Bytes(Arc<[u8]>),
    F32s(Arc<[f32]>),
    F64s(Arc<[f64]>),
    I64s(Arc<[i64]>),
    Record(Arc<RecordValue>),
}

/// A value borrowed from where it is kept: a [`Value`] (`ValueRef::from`),
/// or a store that packs values without their `Arc`s, such as the frames a
/// manager hands to its taps. [`to_value`](Self::to_value) makes it owned.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ValueRef<'a> {
    Bool(bool),
    I64(i64),
    F64(f64),
    Str(&'a str),
    Bytes(&'a [u8]),
    F32s(&'a [f32]),
    F64s(&'a [f64]),
    I64s(&'a [i64]),
    Record(&'a RecordValue),
}

impl<'a> From<&'a Value> for ValueRef<'a> {
    fn from(v: &'a Value) -> Self {
        match v {
            Value::Bool(b) => ValueRef::Bool(*b),
            Value::I64(x) => ValueRef::I64(*x),
            Value::F64(x) => ValueRef::F64(*x),
            Value::Str(s) => ValueRef::Str(s),
            Value::Bytes(b) => ValueRef::Bytes(b),
            Value::F32s(a) => ValueRef::F32s(a),
            Value::F64s(a) => ValueRef::F64s(a),
            Value::I64s(a) => ValueRef::I64s(a),
            Value::Record(r) => ValueRef::Record(r),
        }
    }
}

impl ValueRef<'_> {
    /// The value, owned (arrays and strings copied; a record cloned, its
    /// fields' arrays by reference count).
    pub fn to_value(self) -> Value {
        match self {
            ValueRef::Bool(b) => Value::Bool(b),
            ValueRef::I64(x) => Value::I64(x),
            ValueRef::F64(x) => Value::F64(x),
            ValueRef::Str(s) => Value::Str(s.into()),
            ValueRef::Bytes(b) => Value::Bytes(b.into()),
            ValueRef::F32s(a) => Value::F32s(a.into()),
            ValueRef::F64s(a) => Value::F64s(a.into()),
            ValueRef::I64s(a) => Value::I64s(a.into()),
            ValueRef::Record(r) => Value::Record(Arc::new(r.clone())),
        }
    }
}

/// The field values of a record, in the order of its type's fields.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct RecordValue {
    pub fields: Vec<(Arc<str>, Value)>,
}

impl RecordValue {
    pub fn get(&self, name: &str) -> Option<&Value> {
        self.fields.iter().find(|(n, _)| &**n == name).map(|(_, v)| v)
    }
}

impl Value {
    /// A short name of the value's kind, for error messages.
    pub fn kind_name(&self) -> &'static str {
        match self {
            Value::Bool(_) => "bool",
            Value::I64(_) => "i64",
            Value::F64(_) => "f64",
            Value::Str(_) => "string",
            Value::Bytes(_) => "bytes",
            Value::F32s(_) => "f32 array",
            Value::F64s(_) => "f64 array",
            Value::I64s(_) => "i64 array",
            Value::Record(_) => "record",
        }
    }

    /// Whether this value is a valid value of type `t`.
    pub fn conforms(&self, t: &SignalType) -> bool {
        match (self, t) {
            (Value::Bool(_), SignalType::Bool)
            | (Value::I64(_), SignalType::I64)
            | (Value::F64(_), SignalType::F64)
            | (Value::Str(_), SignalType::Str)
            | (Value::Bytes(_), SignalType::Bytes) => true,
            (Value::F32s(a), SignalType::Array { elem: ElemType::F32, len }) => len.is_none_or(|n| n == a.len()),
            (Value::F64s(a), SignalType::Array { elem: ElemType::F64, len }) => len.is_none_or(|n| n == a.len()),
            (Value::I64s(a), SignalType::Array { elem: ElemType::I64, len }) => len.is_none_or(|n| n == a.len()),
            (Value::Record(r), SignalType::Record(rt)) => {
                r.fields.len() == rt.fields.len()
                    && r.fields.iter().zip(&rt.fields).all(|((n, v), (tn, tt))| **n == **tn && v.conforms(tt))
            }
            _ => false,
        }
    }

    /// The number as `f64`, for bools, integers and floats.
    pub fn as_f64(&self) -> Option<f64> {
        match self {
            Value::F64(x) => Some(*x),
            Value::I64(x) => Some(*x as f64),
            Value::Bool(b) => Some(f64::from(u8::from(*b))),
            _ => None,
        }
    }

    /// Element `i` of a numeric array, as `f64`.
    pub fn index_f64(&self, i: usize) -> Option<f64> {
        match self {
            Value::F32s(a) => a.get(i).map(|x| f64::from(*x)),
            Value::F64s(a) => a.get(i).copied(),
            Value::I64s(a) => a.get(i).map(|x| *x as f64),
            _ => None,
        }
    }

    /// Length of an array, string or bytes value.
    pub fn len(&self) -> Option<usize> {
        match self {
            Value::F32s(a) => Some(a.len()),
            Value::F64s(a) => Some(a.len()),
            Value::I64s(a) => Some(a.len()),
            Value::Str(s) => Some(s.len()),
            Value::Bytes(b) => Some(b.len()),
            _ => None,
        }
    }

    /// Whether an array, string or bytes value is empty (`None` for others).
    pub fn is_empty(&self) -> Option<bool> {
        self.len().map(|n| n == 0)
    }

    /// The value at a record field path (`&[]` is the value itself).
    pub fn at_path(&self, path: &[&str]) -> Option<&Value> {
        let mut v = self;
        for name in path {
            match v {
                Value::Record(r) => v = r.get(name)?,
                _ => return None,
            }
        }
        Some(v)
    }

    /// The zero value of a type: false, 0, empty string, arrays of zeros
    /// (of the fixed length, if any), records of zero fields.
    pub fn zero(t: &SignalType) -> Value {
        match t {
            SignalType::Bool => Value::Bool(false),
            SignalType::I64 => Value::I64(0),
            SignalType::F64 => Value::F64(0.0),
            SignalType::Str => Value::Str(Arc::from("")),
            SignalType::Bytes => Value::Bytes(Arc::from(Vec::new())),
            SignalType::Array { elem, len } => {
                let n = len.unwrap_or(0);
                match elem {
                    ElemType::F32 => Value::F32s(vec![0.0; n].into()),
                    ElemType::F64 => Value::F64s(vec![0.0; n].into()),
                    ElemType::I64 => Value::I64s(vec![0; n].into()),
                }
            }
            SignalType::Record(r) => Value::Record(Arc::new(RecordValue {
                fields: r.fields.iter().map(|(n, t)| (Arc::from(n.as_str()), Value::zero(t))).collect(),
            })),
        }
    }
}

impl fmt::Display for Value {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        fn list<T: fmt::Display>(f: &mut fmt::Formatter<'_>, items: &[T]) -> fmt::Result {
            f.write_str("[")?;
            for (i, x) in items.iter().enumerate() {
                if i > 0 {
                    f.write_str(", ")?;
                }
                write!(f, "{x}")?;
            }
            f.write_str("]")
        }
        match self {
            Value::Bool(b) => write!(f, "{b}"),
            Value::I64(x) => write!(f, "{x}"),
            Value::F64(x) => write!(f, "{x}"),
            Value::Str(s) => write!(f, "{s:?}"),
            Value::Bytes(b) => write!(f, "<{} bytes>", b.len()),
            Value::F32s(a) => list(f, a),
            Value::F64s(a) => list(f, a),
            Value::I64s(a) => list(f, a),
            Value::Record(r) => {
                f.write_str("{")?;
                for (i, (n, v)) in r.fields.iter().enumerate() {
                    if i > 0 {
                        f.write_str(", ")?;
                    }
                    write!(f, "{n}: {v}")?;
                }
                f.write_str("}")
            }
        }
    }
}

/// A Rust type that travels on a signal.
///
/// Implemented for `bool`, `i64`, `f64`, `String`, `Arc<str>`, `Arc<[u8]>`,
/// `Arc<[f32]>`, `Arc<[f64]>`, `Arc<[i64]>`, fixed arrays `[f32; N]`,
/// `[f64; N]`, `[i64; N]`, and by `#[derive(Record)]` for structs.
pub trait SignalValue: Sized {
    /// Whether every value [`SignalValue::into_value`] and
    /// [`SignalValue::into_output`] make is a value of
    /// [`SignalValue::signal_type`], by construction. True for the built-in
    /// types; an implementation of your own is checked by the manager
    /// unless it says so (and then it must hold).
    const ALWAYS_CONFORMS: bool = false;

    fn signal_type() -> SignalType;
    fn from_value(value: &Value) -> Option<Self>;
    fn into_value(self) -> Value;

    /// Reads an input port's value into `dst` (`#[derive(Skill)]`'s glue):
    /// false, `dst` untouched, if `value` is not one of this type. A
    /// fixed-size array copies itself straight into `dst`.
    #[inline]
    fn read_input(value: &Value, dst: &mut Self) -> bool {
        match Self::from_value(value) {
            Some(x) => {
                *dst = x;
                true
            }
            None => false,
        }
    }

    /// [`SignalValue::into_output`] from a reference (`#[derive(Skill)]`'s
    /// glue for an output field): a fixed-size array is copied straight
    /// from `self` into the spare's buffer; by default a clone is written.
    #[inline]
    fn write_output(&self, output: &mut Option<Value>)
    where
        Self: Clone,
    {
        self.clone().into_output(output);
    }

    /// Writes this value into an output port's buffer, which may hold a
    /// spare on entry: the value that this output's previous one replaced
    /// in its slot (see [`Skill::fills_outputs`](crate::Skill::fills_outputs)).
    /// A fixed-size array copies itself into the spare's buffer when nobody
    /// else holds it; by default the spare is handed back ([`recycle`]) and
    /// [`SignalValue::into_value`] makes the value.
    #[inline]
    fn into_output(self, output: &mut Option<Value>) {
        if let Some(spare) = output.take() {
            recycle(spare);
        }
        *output = Some(self.into_value());
    }
}

/// Writes an optional output (`#[derive(Skill)]`'s glue for an `Option<T>`
/// output port): `Some` through [`SignalValue::into_output`]; `None` leaves
/// the buffer empty, its spare handed back ([`recycle`]).
#[inline]
pub fn optional_output<T: SignalValue>(value: Option<T>, output: &mut Option<Value>) {
    match value {
        Some(v) => v.into_output(output),
        None => {
            if let Some(spare) = output.take() {
                recycle(spare);
            }
        }
    }
}

macro_rules! scalar_signal {
    ($t:ty, $variant:ident, $st:expr) => {
        impl SignalValue for $t {
            const ALWAYS_CONFORMS: bool = true;
            fn signal_type() -> SignalType {
                $st
            }
            fn from_value(value: &Value) -> Option<Self> {
                match value {
                    Value::$variant(x) => Some(x.clone()),
                    _ => None,
                }
            }
            fn into_value(self) -> Value {
                Value::$variant(self)
            }
        }
    };
}

scalar_signal!(bool, Bool, SignalType::Bool);
scalar_signal!(i64, I64, SignalType::I64);
scalar_signal!(f64, F64, SignalType::F64);
scalar_signal!(Arc<str>, Str, SignalType::Str);
scalar_signal!(Arc<[u8]>, Bytes, SignalType::Bytes);
scalar_signal!(Arc<[f32]>, F32s, SignalType::array(ElemType::F32, None));
scalar_signal!(Arc<[f64]>, F64s, SignalType::array(ElemType::F64, None));
scalar_signal!(Arc<[i64]>, I64s, SignalType::array(ElemType::I64, None));

impl SignalValue for String {
    const ALWAYS_CONFORMS: bool = true;
    fn signal_type() -> SignalType {
        SignalType::Str
    }
    fn from_value(value: &Value) -> Option<Self> {
        match value {
            Value::Str(s) => Some(s.to_string()),
            _ => None,
        }
    }
    fn into_value(self) -> Value {
        Value::Str(Arc::from(self))
    }
}

macro_rules! fixed_array_signal {
    ($t:ty, $variant:ident, $elem:expr) => {
        impl<const N: usize> SignalValue for [$t; N] {
            const ALWAYS_CONFORMS: bool = true;

            fn signal_type() -> SignalType {
                SignalType::array($elem, Some(N))
            }
            fn from_value(value: &Value) -> Option<Self> {
                match value {
                    Value::$variant(a) => <[$t; N]>::try_from(&a[..]).ok(),
                    _ => None,
                }
            }
            fn into_value(self) -> Value {
                // A buffer the manager gave back (see [`recycle`]) saves an
                // allocation per produced array in a steady cycle.
                let spare = SPARE.with(|s| s.take_where(|v| matches!(v, Value::$variant(a) if a.len() == N)));
                if let Some(Value::$variant(mut a)) = spare {
                    if let Some(buf) = unique_mut(&mut a) {
                        buf.copy_from_slice(&self);
                        return Value::$variant(a);
                    }
                }
                Value::$variant(Arc::from(&self[..]))
            }

            #[inline]
            fn into_output(self, output: &mut Option<Value>) {
                self.write_output(output);
            }

            #[inline]
            fn read_input(value: &Value, dst: &mut Self) -> bool {
                match value {
                    Value::$variant(a) if a.len() == N => {
                        dst.copy_from_slice(a);
                        true
                    }
                    _ => false,
                }
            }

            #[inline]
            fn write_output(&self, output: &mut Option<Value>) {
                // The output's own spare first: no trip through the
                // thread's spare list, and no copy of `self` on the way.
                if let Some(Value::$variant(a)) = output {
                    if a.len() == N {
                        if let Some(buf) = unique_mut(a) {
                            buf.copy_from_slice(self);
                            return;
                        }
                    }
                }
                if let Some(spare) = output.take() {
                    recycle(spare);
                }
                *output = Some((*self).into_value());
            }
        }
    };
}

/// The contents of `a` to write when nobody else holds them: `Arc::get_mut`
/// without its `lock cmpxchg` on the weak count (which drains the store
/// buffer before the copy into the buffer that follows: about 4 ns per
/// output in a chain of skills).
///
/// The lock in `Arc::get_mut` guards against a `Weak` being upgraded while
/// the counts are read. With no `Weak` at all (weak count 0) and this the
/// only strong reference (held here through `&mut`), no other thread can
/// reach the contents or make a new reference to them: cloning needs a
/// strong reference, upgrading needs a `Weak`. The acquire fence pairs with
/// the release decrement of the last other reference dropped, as the
/// acquire load in `Arc::get_mut` does, so its reads happen before our writes.
#[inline]
fn unique_mut<T: ?Sized>(a: &mut Arc<T>) -> Option<&mut T> {
    if Arc::strong_count(a) == 1 && Arc::weak_count(a) == 0 {
        std::sync::atomic::fence(std::sync::atomic::Ordering::Acquire);
        // SAFETY: sole owner (see above); `as_ptr` points at the live
        // contents with the allocation's provenance, and the borrow of `a`
        // keeps it alive and unshared for the returned lifetime.
        Some(unsafe { &mut *(Arc::as_ptr(a) as *mut T) })
    } else {
        None
    }
}

/// Spare array buffers of this thread, reused by the next array made: a
/// few entries, looked at in place (their tags are read, and only the one
/// taken or filled is moved), so that taking and giving back cost a few
/// loads and stores.
struct Spares(std::cell::RefCell<[Option<Value>; SPARES]>);

/// At most this many spare buffers per thread.
const SPARES: usize = 4;

impl Spares {
    #[inline]
    fn take_where(&self, want: impl Fn(&Value) -> bool) -> Option<Value> {
        let mut spares = self.0.try_borrow_mut().ok()?;
        spares.iter_mut().find(|s| s.as_ref().is_some_and(&want))?.take()
    }

    #[inline]
    fn give(&self, value: Value) {
        let Ok(mut spares) = self.0.try_borrow_mut() else { return };
        if let Some(free) = spares.iter_mut().find(|s| s.is_none()) {
            *free = Some(value);
        }
    }
}

thread_local! {
    static SPARE: Spares = const { Spares(std::cell::RefCell::new([const { None }; SPARES])) };
}

/// Hands back a value that is no longer needed. When it is an array that
/// nobody else holds, its buffer is kept (a few per thread) and reused by
/// the next fixed-size array of that length made on this thread
/// ([`SignalValue::into_value`] of `[f32; N]`, `[f64; N]`, `[i64; N]`), so a
/// cycle that replaces one array by another allocates nothing. Anything
/// else is dropped as usual.
#[inline]
pub fn recycle(value: Value) {
    let unique = match &value {
        Value::F32s(a) => Arc::strong_count(a) == 1 && Arc::weak_count(a) == 0,
        Value::F64s(a) => Arc::strong_count(a) == 1 && Arc::weak_count(a) == 0,
        Value::I64s(a) => Arc::strong_count(a) == 1 && Arc::weak_count(a) == 0,
        _ => false,
    };
    if unique {
        let _ = SPARE.try_with(|s| s.give(value));
    }
}

fixed_array_signal!(f32, F32s, ElemType::F32);
fixed_array_signal!(f64, F64s, ElemType::F64);
fixed_array_signal!(i64, I64s, ElemType::I64);

/// Builds a record value from field values.
pub fn record_value(fields: Vec<(&'static str, Value)>) -> Value {
    Value::Record(Arc::new(RecordValue { fields: fields.into_iter().map(|(n, v)| (Arc::from(n), v)).collect() }))
}

/// A record type's field names, made once and then shared by every value
/// of it (`#[derive(Record)]`'s glue: a value costs no allocation per name).
#[doc(hidden)]
pub fn record_names(cell: &'static std::sync::OnceLock<Box<[Arc<str>]>>, names: &[&str]) -> &'static [Arc<str>] {
    cell.get_or_init(|| names.iter().map(|&n| Arc::from(n)).collect())
}

/// A record value of the fields `names` (from [`record_names`]) with
/// `values`, in that order (`#[derive(Record)]`'s glue).
#[doc(hidden)]
pub fn record_of<const N: usize>(names: &[Arc<str>], values: [Value; N]) -> Value {
    Value::Record(Arc::new(RecordValue { fields: names.iter().cloned().zip(values).collect() }))
}

/// The fields of the record in an output buffer, to be written in place,
/// when the buffer holds a spare record (see
/// [`Skill::fills_outputs`](crate::Skill::fills_outputs)) that nobody else
/// holds and that has exactly the fields `names`, in that order; else
/// `None` (`#[derive(Record)]`'s glue).
#[doc(hidden)]
#[inline]
pub fn record_fields_to_fill<'o>(output: &'o mut Option<Value>, names: &[&str]) -> Option<&'o mut [(Arc<str>, Value)]> {
    let Some(Value::Record(record)) = output else { return None };
    let record = Arc::get_mut(record)?;
    let same = record.fields.len() == names.len() && record.fields.iter().zip(names).all(|((n, _), m)| &**n == *m);
    same.then_some(&mut record.fields[..])
}

/// Writes a record's field in place, its old value the spare
/// ([`SignalValue::into_output`]; `#[derive(Record)]`'s glue).
#[doc(hidden)]
#[inline]
pub fn fill_field<T: SignalValue>(value: T, field: &mut Value) {
    let mut out = Some(std::mem::replace(field, Value::Bool(false)));
    value.into_output(&mut out);
    if let Some(v) = out {
        *field = v;
    }
}

/// Builds a record type from field types; used by `#[derive(Record)]`.
pub fn record_type(fields: Vec<(&'static str, SignalType)>) -> SignalType {
    SignalType::Record(Arc::new(RecordType::new(fields.into_iter().map(|(n, t)| (n.to_string(), t)).collect())))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn conformance_checks_fixed_lengths_and_record_fields() {
        let t = SignalType::array(ElemType::F32, Some(3));
        assert!(Value::F32s(vec![1.0, 2.0, 3.0].into()).conforms(&t));
        assert!(!Value::F32s(vec![1.0].into()).conforms(&t));
        let rt = SignalType::record(vec![("x", SignalType::F64), ("ok", SignalType::Bool)]);
        let good = record_value(vec![("x", Value::F64(1.0)), ("ok", Value::Bool(true))]);
        let bad = record_value(vec![("x", Value::F64(1.0)), ("ok", Value::I64(1))]);
        assert!(good.conforms(&rt));
        assert!(!bad.conforms(&rt));
        assert!(Value::zero(&rt).conforms(&rt));
    }

    #[test]
    fn cloning_an_array_value_shares_the_buffer() {
        let v = Value::F32s(vec![0.0; 1024].into());
        let w = v.clone();
        match (&v, &w) {
            (Value::F32s(a), Value::F32s(b)) => assert!(Arc::ptr_eq(a, b)),
            _ => unreachable!(),
        }
    }

    #[test]
    fn an_output_reuses_its_spare_only_when_nobody_else_holds_it() {
        let ptr = |v: &Option<Value>| match v {
            Some(Value::F32s(a)) => a.as_ptr(),
            _ => unreachable!(),
        };
        let mut out = Some([0.0f32; 3].into_value());
        let before = ptr(&out);
        [1.0f32, 2.0, 3.0].into_output(&mut out);
        assert_eq!(ptr(&out), before, "a unique spare of the right length is written in place");
        assert_eq!(<[f32; 3]>::from_value(out.as_ref().unwrap()), Some([1.0, 2.0, 3.0]));
        let held = out.clone();
        [4.0f32, 5.0, 6.0].into_output(&mut out);
        assert_ne!(ptr(&out), before, "a shared spare is left alone");
        assert_eq!(<[f32; 3]>::from_value(held.as_ref().unwrap()), Some([1.0, 2.0, 3.0]));
        assert_eq!(<[f32; 3]>::from_value(out.as_ref().unwrap()), Some([4.0, 5.0, 6.0]));
        let mut wrong = Some(Value::F64(1.0));
        [7.0f32].into_output(&mut wrong);
        assert_eq!(wrong, Some(Value::F32s(vec![7.0].into())));
        optional_output::<[f32; 1]>(None, &mut wrong);
        assert_eq!(wrong, None);
        optional_output(Some(2.0f64), &mut wrong);
        assert_eq!(wrong, Some(Value::F64(2.0)));
    }

    #[test]
    fn fixed_arrays_round_trip_and_reject_wrong_lengths() {
        let v = [1.0f32, 2.0, 3.0].into_value();
        assert_eq!(<[f32; 3]>::from_value(&v), Some([1.0, 2.0, 3.0]));
        assert_eq!(<[f32; 2]>::from_value(&v), None);
    }
}
