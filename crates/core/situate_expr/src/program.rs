//! The program a source compiles into: a typed tree of enums in one arena,
//! and its evaluation.
//!
//! Every node's type is known after compilation, so evaluation dispatches on
//! the expected type (`bool_at`, `num_at`, `str_at`, ...) and never builds a
//! dynamically typed value. Children are indices into `nodes`; function
//! arguments of `min`/`max` are a range of `args`. Evaluation recurses at most
//! as deep as the tree, which is bounded by `MAX_NODES`.

use crate::Lookup;
use situate_core::Value;

#[derive(Debug, Clone, Default)]
pub(crate) struct Program {
    pub(crate) nodes: Vec<Node>,
    pub(crate) args: Vec<u32>,
    pub(crate) refs: Vec<usize>,
    pub(crate) root: u32,
}

#[derive(Debug, Clone)]
pub(crate) enum Node {
    Bool(bool),
    Num(f64),
    Str(Box<str>),
    /// The current value of `refs[slot]`; its type is the one the context expects.
    Ref(u32),
    Not(u32),
    And(u32, u32),
    Or(u32, u32),
    /// A comparison of two numbers.
    Cmp(CmpOp, u32, u32),
    /// `==` (true) or `!=` (false) of two bools.
    EqBool(bool, u32, u32),
    /// `==` (true) or `!=` (false) of two strings.
    EqStr(bool, u32, u32),
    Neg(u32),
    Arith(ArithOp, u32, u32),
    Abs(u32),
    /// `min` (false) or `max` (true) of `args[start..start + len]`.
    MinMax {
        max: bool,
        start: u32,
        len: u32,
    },
    /// Element of an array (a `Ref`) at a number.
    Index(u32, u32),
    /// Length of a string, array or bytes value of the given type.
    Len(u32, Ty),
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum CmpOp {
    Lt,
    Le,
    Gt,
    Ge,
    Eq,
    Ne,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum ArithOp {
    Add,
    Sub,
    Mul,
    Div,
    Rem,
}

/// The compile-time type of an expression.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Ty {
    Bool,
    Num,
    Str,
    Array,
    Bytes,
}

impl Ty {
    /// The type with an article, for messages.
    pub(crate) fn name(self) -> &'static str {
        match self {
            Ty::Bool => "a bool",
            Ty::Num => "a number",
            Ty::Str => "a string",
            Ty::Array => "an array",
            Ty::Bytes => "bytes",
        }
    }
}

/// A lookup without values: evaluating a number expression with it gives
/// `Some` exactly when the expression is a constant.
pub(crate) struct NoValues;

impl Lookup for NoValues {
    fn value(&self, _id: usize) -> Option<&Value> {
        None
    }
}

impl Program {
    fn node(&self, n: u32) -> Option<&Node> {
        self.nodes.get(n as usize)
    }

    fn value<'a>(&self, slot: u32, lk: &'a dyn Lookup) -> Option<&'a Value> {
        let id = *self.refs.get(slot as usize)?;
        lk.value(id)
    }

    pub(crate) fn bool_at(&self, n: u32, lk: &dyn Lookup) -> Option<bool> {
        match self.node(n)? {
            Node::Bool(b) => Some(*b),
            Node::Ref(slot) => match self.value(*slot, lk)? {
                Value::Bool(b) => Some(*b),
                _ => None,
            },
            Node::Not(a) => self.bool_at(*a, lk).map(|b| !b),
            Node::And(l, r) => match self.bool_at(*l, lk) {
                Some(false) => Some(false),
                left => match self.bool_at(*r, lk) {
                    Some(false) => Some(false),
                    Some(true) => left,
                    None => None,
                },
            },
            Node::Or(l, r) => match self.bool_at(*l, lk) {
                Some(true) => Some(true),
                left => match self.bool_at(*r, lk) {
                    Some(true) => Some(true),
                    Some(false) => left,
                    None => None,
                },
            },
            Node::Cmp(op, l, r) => {
                let a = self.num_at(*l, lk)?;
                let b = self.num_at(*r, lk)?;
                let ord = a.partial_cmp(&b)?;
                Some(match op {
                    CmpOp::Lt => ord.is_lt(),
                    CmpOp::Le => ord.is_le(),
                    CmpOp::Gt => ord.is_gt(),
                    CmpOp::Ge => ord.is_ge(),
                    CmpOp::Eq => ord.is_eq(),
                    CmpOp::Ne => ord.is_ne(),
                })
            }
            Node::EqBool(eq, l, r) => {
                let a = self.bool_at(*l, lk)?;
                let b = self.bool_at(*r, lk)?;
                Some((a == b) == *eq)
            }
            Node::EqStr(eq, l, r) => {
                let a = self.str_at(*l, lk)?;
                let b = self.str_at(*r, lk)?;
                Some((a == b) == *eq)
            }
            _ => None,
        }
    }

    pub(crate) fn num_at(&self, n: u32, lk: &dyn Lookup) -> Option<f64> {
        match self.node(n)? {
            Node::Num(x) => Some(*x),
            Node::Ref(slot) => match self.value(*slot, lk)? {
                Value::F64(x) => Some(*x),
                Value::I64(x) => Some(*x as f64),
                _ => None,
            },
            Node::Neg(a) => self.num_at(*a, lk).map(|x| -x),
            Node::Abs(a) => self.num_at(*a, lk).map(f64::abs),
            Node::Arith(op, l, r) => {
                let a = self.num_at(*l, lk)?;
                let b = self.num_at(*r, lk)?;
                Some(match op {
                    ArithOp::Add => a + b,
                    ArithOp::Sub => a - b,
                    ArithOp::Mul => a * b,
                    ArithOp::Div => a / b,
                    ArithOp::Rem => a % b,
                })
            }
            Node::MinMax { max, start, len } => {
                let start = *start as usize;
                let args = self.args.get(start..start.checked_add(*len as usize)?)?;
                let mut acc: Option<f64> = None;
                for &arg in args {
                    let x = self.num_at(arg, lk)?;
                    acc = Some(match acc {
                        None => x,
                        Some(a) if a.is_nan() || x.is_nan() => f64::NAN,
                        Some(a) if *max => a.max(x),
                        Some(a) => a.min(x),
                    });
                }
                acc
            }
            Node::Index(arr, idx) => {
                let i = self.num_at(*idx, lk)?;
                // Infinities fail too: their fractional part is NaN.
                if i.is_nan() || i < 0.0 || i.fract() != 0.0 {
                    return None;
                }
                // Saturates for huge indexes, which are then out of range.
                let i = i as usize;
                match self.val_at(*arr, lk)? {
                    v @ (Value::F32s(_) | Value::F64s(_) | Value::I64s(_)) => v.index_f64(i),
                    _ => None,
                }
            }
            Node::Len(a, ty) => {
                let len = match ty {
                    Ty::Str => self.str_at(*a, lk)?.len(),
                    Ty::Array => match self.val_at(*a, lk)? {
                        v @ (Value::F32s(_) | Value::F64s(_) | Value::I64s(_)) => v.len()?,
                        _ => return None,
                    },
                    Ty::Bytes => match self.val_at(*a, lk)? {
                        Value::Bytes(b) => b.len(),
                        _ => return None,
                    },
                    Ty::Bool | Ty::Num => return None,
                };
                Some(len as f64)
            }
            _ => None,
        }
    }

    fn str_at<'a>(&'a self, n: u32, lk: &'a dyn Lookup) -> Option<&'a str> {
        match self.node(n)? {
            Node::Str(s) => Some(s),
            Node::Ref(slot) => match self.value(*slot, lk)? {
                Value::Str(s) => Some(s),
                _ => None,
            },
            _ => None,
        }
    }

    /// The value of an array or bytes expression (always a `Ref`).
    fn val_at<'a>(&self, n: u32, lk: &'a dyn Lookup) -> Option<&'a Value> {
        match self.node(n)? {
            Node::Ref(slot) => self.value(*slot, lk),
            _ => None,
        }
    }
}
