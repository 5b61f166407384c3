//! The type checker: each part the parser reads becomes a node of the
//! program here, typed as it is built, so a type error is reported at the
//! operator or name where it is written. Names are resolved through the
//! caller's `Resolver`; functions are checked by name and arguments.
//!
//! These helpers are kept out of line (`#[inline(never)]`): the parser's
//! recursive frames then stay small, even in debug builds.

use crate::lex::Tok;
use crate::parse::{BinOp, PResult, Parser, Typed};
use crate::program::{ArithOp, CmpOp, NoValues, Node, Ty};
use situate_core::SignalType;

const FUNCTIONS: [&str; 4] = ["abs", "min", "max", "len"];

impl Parser<'_, '_> {
    #[inline(never)]
    pub(crate) fn binary(&mut self, op: BinOp, at: usize, l: Typed, r: Typed) -> PResult<Typed> {
        let mismatch = |p: &Self, need: &str| {
            Err(p.err(at, format!("`{}` needs {need}, got {} and {}", op.text(), l.ty.name(), r.ty.name())))
        };
        let (node, ty) = match op {
            BinOp::Or | BinOp::And => {
                if l.ty != Ty::Bool || r.ty != Ty::Bool {
                    return mismatch(self, "true or false on both sides");
                }
                let node = if op == BinOp::Or { Node::Or(l.node, r.node) } else { Node::And(l.node, r.node) };
                (node, Ty::Bool)
            }
            BinOp::Eq | BinOp::Ne => {
                let eq = op == BinOp::Eq;
                let node = match (l.ty, r.ty) {
                    (Ty::Bool, Ty::Bool) => Node::EqBool(eq, l.node, r.node),
                    (Ty::Num, Ty::Num) => Node::Cmp(if eq { CmpOp::Eq } else { CmpOp::Ne }, l.node, r.node),
                    (Ty::Str, Ty::Str) => Node::EqStr(eq, l.node, r.node),
                    _ => return mismatch(self, "two bools, two numbers or two strings"),
                };
                (node, Ty::Bool)
            }
            BinOp::Lt | BinOp::Le | BinOp::Gt | BinOp::Ge => {
                if l.ty != Ty::Num || r.ty != Ty::Num {
                    return mismatch(self, "two numbers");
                }
                let cmp = match op {
                    BinOp::Lt => CmpOp::Lt,
                    BinOp::Le => CmpOp::Le,
                    BinOp::Gt => CmpOp::Gt,
                    _ => CmpOp::Ge,
                };
                (Node::Cmp(cmp, l.node, r.node), Ty::Bool)
            }
            BinOp::Add | BinOp::Sub | BinOp::Mul | BinOp::Div | BinOp::Rem => {
                if l.ty != Ty::Num || r.ty != Ty::Num {
                    return mismatch(self, "two numbers");
                }
                let arith = match op {
                    BinOp::Add => ArithOp::Add,
                    BinOp::Sub => ArithOp::Sub,
                    BinOp::Mul => ArithOp::Mul,
                    BinOp::Div => ArithOp::Div,
                    _ => ArithOp::Rem,
                };
                (Node::Arith(arith, l.node, r.node), Ty::Num)
            }
        };
        let node = self.push(node, at)?;
        Ok(Typed { node, ty, at: l.at })
    }

    #[inline(never)]
    pub(crate) fn unary(&mut self, not: bool, at: usize, e: Typed) -> PResult<Typed> {
        let (want, node) = if not { (Ty::Bool, Node::Not(e.node)) } else { (Ty::Num, Node::Neg(e.node)) };
        if e.ty != want {
            let (name, need) = if not { ("!", "true or false") } else { ("-", "a number") };
            return Err(self.err(at, format!("`{name}` needs {need}, got {}", e.ty.name())));
        }
        let node = self.push(node, at)?;
        Ok(Typed { node, ty: want, at })
    }

    #[inline(never)]
    pub(crate) fn check_indexable(&self, e: Typed, open: usize) -> PResult<()> {
        if e.ty != Ty::Array {
            return Err(self.err(open, format!("`[]` indexes an array, but this is {}", e.ty.name())));
        }
        Ok(())
    }

    #[inline(never)]
    pub(crate) fn index(&mut self, e: Typed, idx: Typed, open: usize) -> PResult<Typed> {
        if idx.ty != Ty::Num {
            return Err(self.err(idx.at, format!("`[]` needs a number as the index, got {}", idx.ty.name())));
        }
        if let Some(i) = self.program.num_at(idx.node, &NoValues) {
            if i < 0.0 {
                return Err(self.err(idx.at, format!("the index is negative ({i}); indexes count from 0")));
            }
            if !i.is_finite() || i.fract() != 0.0 {
                return Err(self.err(idx.at, format!("the index must be a whole number, this is {i}")));
            }
            if let Some((_, name, len)) = self.fixed.iter().find(|(n, _, _)| *n == e.node) {
                if i >= *len as f64 {
                    // It would never have a value: a monitor on it would silently never fire.
                    return Err(self.err(
                        idx.at,
                        format!(
                            "index {i} is out of range: `{name}` has {len} element{} (indexes 0 to {})",
                            if *len == 1 { "" } else { "s" },
                            len.saturating_sub(1)
                        ),
                    ));
                }
            }
        }
        let node = self.push(Node::Index(e.node, idx.node), open)?;
        Ok(Typed { node, ty: Ty::Num, at: e.at })
    }

    #[inline(never)]
    pub(crate) fn literal(&mut self) -> PResult<Typed> {
        let at = self.peek().start;
        let (node, ty) = match &self.peek().tok {
            Tok::Num(x) => (Node::Num(*x), Ty::Num),
            Tok::Str(s) => (Node::Str(s.as_str().into()), Ty::Str),
            Tok::True => (Node::Bool(true), Ty::Bool),
            Tok::False => (Node::Bool(false), Ty::Bool),
            _ => return Err(self.unexpected("a value (a number, a string, `true`, `false`, a name or `(`)")),
        };
        self.bump();
        let node = self.push(node, at)?;
        Ok(Typed { node, ty, at })
    }

    #[inline(never)]
    pub(crate) fn reference(&mut self, name: &str, at: usize) -> PResult<Typed> {
        let (id, st) = self.resolver.resolve(name).map_err(|m| self.err(at, m))?;
        let ty = match &st {
            SignalType::Bool => Ty::Bool,
            SignalType::I64 | SignalType::F64 => Ty::Num,
            SignalType::Str => Ty::Str,
            SignalType::Bytes => Ty::Bytes,
            SignalType::Array { .. } => Ty::Array,
            SignalType::Record(r) => {
                let message = if r.fields.is_empty() {
                    format!("`{name}` is a record without fields; it cannot be used in a condition")
                } else {
                    let fields: Vec<&str> = r.fields.iter().map(|(n, _)| n.as_str()).collect();
                    format!("`{name}` is a record; name one of its fields: {}", fields.join(", "))
                };
                return Err(self.err(at, message));
            }
        };
        let slot = match self.program.refs.iter().position(|&r| r == id) {
            Some(slot) => slot,
            None => {
                self.program.refs.push(id);
                self.ref_names.push(name.to_string());
                self.program.refs.len() - 1
            }
        };
        let node = self.push(Node::Ref(slot as u32), at)?;
        if let SignalType::Array { len: Some(len), .. } = st {
            self.fixed.push((node, name.to_string(), len));
        }
        Ok(Typed { node, ty, at })
    }

    #[inline(never)]
    pub(crate) fn check_function(&self, name: &str, at: usize) -> PResult<()> {
        if FUNCTIONS.contains(&name) {
            return Ok(());
        }
        let hint = situate_core::suggestion(name, FUNCTIONS);
        Err(self.err(
            at,
            format!("unknown function `{name}`{hint}; the functions are abs(x), min(a, b, …), max(a, b, …) and len(x)"),
        ))
    }

    #[inline(never)]
    pub(crate) fn build_call(&mut self, name: &str, at: usize, args: &[Typed]) -> PResult<Typed> {
        let count = |n: usize| if n == 1 { "1 argument".to_string() } else { format!("{n} arguments") };
        let node = match (name, args) {
            ("abs", [a]) => {
                if a.ty != Ty::Num {
                    return Err(self.err(a.at, format!("`abs` needs a number, got {}", a.ty.name())));
                }
                Node::Abs(a.node)
            }
            ("len", [a]) => {
                if !matches!(a.ty, Ty::Str | Ty::Array | Ty::Bytes) {
                    return Err(self.err(a.at, format!("`len` needs an array, a string or bytes, got {}", a.ty.name())));
                }
                Node::Len(a.node, a.ty)
            }
            ("abs", _) => return Err(self.err(at, format!("`abs` takes one number, got {}", count(args.len())))),
            ("len", _) => {
                let got = count(args.len());
                return Err(self.err(at, format!("`len` takes one array, string or bytes value, got {got}")));
            }
            (_, [_, _, ..]) => {
                if let Some(a) = args.iter().find(|a| a.ty != Ty::Num) {
                    return Err(self.err(a.at, format!("`{name}` needs numbers, got {}", a.ty.name())));
                }
                let start = self.program.args.len() as u32;
                self.program.args.extend(args.iter().map(|a| a.node));
                Node::MinMax { max: name == "max", start, len: args.len() as u32 }
            }
            _ => return Err(self.err(at, format!("`{name}` takes two or more numbers, got {}", count(args.len())))),
        };
        let node = self.push(node, at)?;
        Ok(Typed { node, ty: Ty::Num, at })
    }
}
