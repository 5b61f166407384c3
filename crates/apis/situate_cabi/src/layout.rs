//! The C layout of a skill's inputs, outputs and parameters, computed from
//! its declaration with the C rules (each field at the next multiple of its
//! alignment, the struct padded to its largest alignment). The generator
//! writes structs with exactly these fields in this order, so the generated
//! structs *are* the buffers the runtime fills.
//!
//! - inputs: one field per port, in order; an optional input `x` is preceded
//!   by `bool has_x`;
//! - outputs: `bool has_x` then `x`, for every output;
//! - params: one field per parameter (`bool`, `int64_t`, `double`,
//!   `situate_str`);
//! - an empty struct holds one `uint8_t _situate_empty` (C and C++ agree on
//!   its size).
//!
//! Field types: `bool` → `bool`, `i64` → `int64_t`, `f64` → `double`,
//! `string` → `situate_str`, `bytes` → `situate_bytes`, `T[N]` → `T name[N]`
//! inline, `T[]` → `situate_T_slice`, a record → a nested struct.

use std::sync::Arc;

use situate_core::{ElemType, ParamType, SignalType, SkillDecl};

const PTR: usize = std::mem::size_of::<usize>();

/// The name of the flag field of an optional input or an output.
pub fn flag_name(port: &str) -> String {
    format!("has_{port}")
}

/// What a field holds.
#[derive(Debug, Clone, PartialEq)]
pub enum FieldKind {
    /// A `has_` flag (`bool`).
    Flag,
    Bool,
    I64,
    F64,
    Str,
    Bytes,
    /// `T name[len]`, inline.
    Fixed {
        elem: ElemType,
        len: usize,
    },
    /// `situate_T_slice`: pointer and length.
    Var {
        elem: ElemType,
    },
    /// A nested struct; `c_name` is its type name in the generated code.
    Record {
        c_name: String,
        layout: StructLayout,
    },
}

/// One field of a struct.
#[derive(Debug, Clone, PartialEq)]
pub struct Field {
    pub name: Arc<str>,
    pub offset: usize,
    pub size: usize,
    pub align: usize,
    pub kind: FieldKind,
}

/// A C struct: its fields in order, size and alignment.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct StructLayout {
    pub fields: Vec<Field>,
    pub size: usize,
    pub align: usize,
}

/// The three structs of one skill type.
#[derive(Debug, Clone, PartialEq)]
pub struct SkillLayout {
    /// The prefix of every generated name (`c_runaway` for `c.runaway`).
    pub prefix: String,
    pub inputs: StructLayout,
    pub outputs: StructLayout,
    pub params: StructLayout,
}

/// The C identifier prefix of a skill type name: every character that is not
/// a letter, a digit or `_` becomes `_` (`c.runaway` → `c_runaway`).
pub fn prefix_of(type_name: &str) -> String {
    let mut s: String =
        type_name.chars().map(|c| if c.is_ascii_alphanumeric() || c == '_' { c } else { '_' }).collect();
    if s.starts_with(|c: char| c.is_ascii_digit()) || s.is_empty() {
        s.insert(0, '_');
    }
    s
}

/// Words that cannot be field names in C or C++.
const KEYWORDS: &[&str] = &[
    "alignas",
    "alignof",
    "and",
    "asm",
    "auto",
    "bool",
    "break",
    "case",
    "catch",
    "char",
    "class",
    "const",
    "constexpr",
    "continue",
    "default",
    "delete",
    "do",
    "double",
    "else",
    "enum",
    "explicit",
    "export",
    "extern",
    "false",
    "float",
    "for",
    "friend",
    "goto",
    "if",
    "inline",
    "int",
    "long",
    "mutable",
    "namespace",
    "new",
    "noexcept",
    "not",
    "nullptr",
    "operator",
    "or",
    "private",
    "protected",
    "public",
    "register",
    "restrict",
    "return",
    "short",
    "signed",
    "sizeof",
    "static",
    "struct",
    "switch",
    "template",
    "this",
    "throw",
    "true",
    "try",
    "typedef",
    "typename",
    "union",
    "unsigned",
    "using",
    "virtual",
    "void",
    "volatile",
    "while",
    "xor",
];

fn check_name(name: &str, what: &str) -> Result<(), String> {
    if KEYWORDS.contains(&name) {
        return Err(format!("{what} `{name}` is a C/C++ keyword; rename it"));
    }
    if name.starts_with("_situate") {
        return Err(format!("{what} `{name}`: names starting with `_situate` are reserved"));
    }
    Ok(())
}

fn align_up(x: usize, a: usize) -> usize {
    x.div_ceil(a) * a
}

fn elem_size(elem: ElemType) -> usize {
    match elem {
        ElemType::F32 => 4,
        ElemType::F64 | ElemType::I64 => 8,
    }
}

/// The C name of an element type (`float`, `double`, `int64_t`).
pub fn elem_c(elem: ElemType) -> &'static str {
    match elem {
        ElemType::F32 => "float",
        ElemType::F64 => "double",
        ElemType::I64 => "int64_t",
    }
}

fn kind_of(ty: &SignalType, c_name: &str, what: &str) -> Result<(FieldKind, usize, usize), String> {
    Ok(match ty {
        SignalType::Bool => (FieldKind::Bool, 1, 1),
        SignalType::I64 => (FieldKind::I64, 8, 8),
        SignalType::F64 => (FieldKind::F64, 8, 8),
        SignalType::Str => (FieldKind::Str, 2 * PTR, PTR),
        SignalType::Bytes => (FieldKind::Bytes, 2 * PTR, PTR),
        SignalType::Array { elem, len: Some(0) } => {
            return Err(format!("{what}: a fixed array `{}[0]` has no C layout; give it a length ≥ 1", elem.name()))
        }
        SignalType::Array { elem, len: Some(n) } => {
            let size = n.checked_mul(elem_size(*elem)).ok_or_else(|| format!("{what}: array too large"))?;
            (FieldKind::Fixed { elem: *elem, len: *n }, size, elem_size(*elem))
        }
        SignalType::Array { elem, len: None } => (FieldKind::Var { elem: *elem }, 2 * PTR, PTR),
        SignalType::Record(r) => {
            if r.fields.is_empty() {
                return Err(format!("{what}: an empty record `{{}}` has no C layout"));
            }
            let mut s = Builder::default();
            for (name, t) in &r.fields {
                check_name(name, &format!("{what}: field"))?;
                let (kind, size, align) = kind_of(t, &format!("{c_name}_{name}"), &format!("{what}.{name}"))?;
                s.push(name, kind, size, align);
            }
            let layout = s.finish();
            let (size, align) = (layout.size, layout.align);
            (FieldKind::Record { c_name: c_name.to_string(), layout }, size, align)
        }
    })
}

#[derive(Default)]
struct Builder {
    fields: Vec<Field>,
    end: usize,
    align: usize,
}

impl Builder {
    fn push(&mut self, name: &str, kind: FieldKind, size: usize, align: usize) {
        let offset = align_up(self.end, align);
        self.end = offset + size;
        self.align = self.align.max(align);
        self.fields.push(Field { name: Arc::from(name), offset, size, align, kind });
    }

    fn finish(mut self) -> StructLayout {
        if self.fields.is_empty() {
            self.push("_situate_empty", FieldKind::Flag, 1, 1);
        }
        let align = self.align.max(1);
        StructLayout { size: align_up(self.end, align), align, fields: self.fields }
    }
}

impl SkillLayout {
    /// The layout of a declaration's structs, or why it has none (a C/C++
    /// keyword as a name, a zero-length array, a name clash with a flag).
    pub fn of(decl: &SkillDecl) -> Result<SkillLayout, String> {
        let prefix = prefix_of(&decl.type_name);
        let mut names = std::collections::HashSet::new();
        let mut inputs = Builder::default();
        for p in &decl.inputs {
            check_name(&p.name, "input")?;
            if p.optional {
                inputs.push(&flag_name(&p.name), FieldKind::Flag, 1, 1);
            }
            let what = format!("input `{}`", p.name);
            let (kind, size, align) = kind_of(&p.ty, &format!("{prefix}_{}", p.name), &what)?;
            inputs.push(&p.name, kind, size, align);
        }
        check_unique(&inputs.fields, "inputs")?;
        let mut outputs = Builder::default();
        for p in &decl.outputs {
            check_name(&p.name, "output")?;
            outputs.push(&flag_name(&p.name), FieldKind::Flag, 1, 1);
            let what = format!("output `{}`", p.name);
            let (kind, size, align) = kind_of(&p.ty, &format!("{prefix}_{}", p.name), &what)?;
            outputs.push(&p.name, kind, size, align);
        }
        check_unique(&outputs.fields, "outputs")?;
        // Record type names must not clash between inputs and outputs of different types.
        for f in inputs.fields.iter().chain(&outputs.fields) {
            if let FieldKind::Record { c_name, layout } = &f.kind {
                collect_records(c_name, layout, &mut names)?;
            }
        }
        let mut params = Builder::default();
        for p in &decl.params {
            check_name(&p.name, "parameter")?;
            let (kind, size, align) = match p.ty {
                ParamType::Bool => (FieldKind::Bool, 1, 1),
                ParamType::I64 => (FieldKind::I64, 8, 8),
                ParamType::F64 => (FieldKind::F64, 8, 8),
                ParamType::Str => (FieldKind::Str, 2 * PTR, PTR),
            };
            params.push(&p.name, kind, size, align);
        }
        Ok(SkillLayout { prefix, inputs: inputs.finish(), outputs: outputs.finish(), params: params.finish() })
    }
}

fn check_unique(fields: &[Field], what: &str) -> Result<(), String> {
    for (i, f) in fields.iter().enumerate() {
        if fields[..i].iter().any(|g| g.name == f.name) {
            return Err(format!("the {what} have two fields named `{}` (a port clashes with a `has_` flag)", f.name));
        }
    }
    Ok(())
}

fn collect_records(
    c_name: &str,
    layout: &StructLayout,
    seen: &mut std::collections::HashSet<(String, String)>,
) -> Result<(), String> {
    let shape = format!("{layout:?}");
    if seen.iter().any(|(n, s)| n == c_name && *s != shape) {
        return Err(format!("an input and an output named alike have different record types (`{c_name}`)"));
    }
    seen.insert((c_name.to_string(), shape));
    for f in &layout.fields {
        if let FieldKind::Record { c_name, layout } = &f.kind {
            collect_records(c_name, layout, seen)?;
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use situate_core::{PortSpec, SkillKind};

    #[test]
    fn c_rules_pad_fields_and_structs() {
        let mut d = SkillDecl::new("c.t", SkillKind::Sync);
        d.inputs.push(PortSpec::new("flag", SignalType::Bool));
        d.inputs.push(PortSpec::new("x", SignalType::F64));
        d.inputs.push(PortSpec::new("r", SignalType::parse("f32[3]").unwrap()).optional());
        d.outputs.push(PortSpec::new("drive", SignalType::parse("{v: f64, w: f64}").unwrap()));
        let l = SkillLayout::of(&d).unwrap();
        let offs: Vec<(&str, usize)> = l.inputs.fields.iter().map(|f| (&*f.name, f.offset)).collect();
        assert_eq!(offs, [("flag", 0), ("x", 8), ("has_r", 16), ("r", 20)]);
        assert_eq!((l.inputs.size, l.inputs.align), (32, 8));
        assert_eq!(l.outputs.fields[1].offset, 8);
        assert_eq!(l.outputs.size, 24);
        assert_eq!(l.params.size, 1, "an empty struct holds one byte");
        assert_eq!(l.prefix, "c_t");
    }

    #[test]
    fn names_c_cannot_hold_are_refused() {
        let mut d = SkillDecl::new("c.t", SkillKind::Sync);
        d.inputs.push(PortSpec::new("default", SignalType::F64));
        assert!(SkillLayout::of(&d).unwrap_err().contains("keyword"));
        let mut d = SkillDecl::new("c.t", SkillKind::Sync);
        d.outputs.push(PortSpec::new("x", SignalType::F64));
        d.outputs.push(PortSpec::new("has_x", SignalType::F64));
        assert!(SkillLayout::of(&d).unwrap_err().contains("has_"));
    }
}

/// One field of a struct as the ABI's field tables list it
/// ([`crate::abi::situate_field`]): records flattened with dotted names and
/// offsets from the top-level struct; a fixed array is one field of `count`
/// elements.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct FlatField {
    /// `sonar.range`: also the C member designator (`offsetof(T, sonar.range)`).
    pub name: String,
    /// `SITUATE_FIELD_*` of the field, or of the elements of a fixed array.
    pub code: u32,
    pub count: u32,
    pub offset: usize,
    pub size: usize,
    /// A fixed array (`T name[N]`).
    pub fixed: bool,
}

/// The C type a `SITUATE_FIELD_*` code stands for (for messages).
pub fn code_c(code: u32) -> &'static str {
    use crate::abi::*;
    match code {
        SITUATE_FIELD_BOOL => "bool",
        SITUATE_FIELD_I64 => "int64_t",
        SITUATE_FIELD_F64 => "double",
        SITUATE_FIELD_F32 => "float",
        SITUATE_FIELD_STR => "situate_str",
        SITUATE_FIELD_BYTES => "situate_bytes",
        SITUATE_FIELD_F32_SLICE => "situate_f32_slice",
        SITUATE_FIELD_F64_SLICE => "situate_f64_slice",
        SITUATE_FIELD_I64_SLICE => "situate_i64_slice",
        SITUATE_FIELD_U8 => "uint8_t",
        _ => "a type situate does not know",
    }
}

fn elem_code(elem: ElemType) -> u32 {
    use crate::abi::*;
    match elem {
        ElemType::F32 => SITUATE_FIELD_F32,
        ElemType::F64 => SITUATE_FIELD_F64,
        ElemType::I64 => SITUATE_FIELD_I64,
    }
}

impl StructLayout {
    /// The fields as the ABI's field tables list them, in order.
    pub fn flat(&self) -> Vec<FlatField> {
        let mut out = Vec::new();
        flatten(self, "", 0, &mut out);
        out
    }
}

fn flatten(layout: &StructLayout, prefix: &str, base: usize, out: &mut Vec<FlatField>) {
    use crate::abi::*;
    for f in &layout.fields {
        let name = format!("{prefix}{}", f.name);
        let (code, count, fixed) = match &f.kind {
            FieldKind::Record { layout, .. } => {
                flatten(layout, &format!("{name}."), base + f.offset, out);
                continue;
            }
            FieldKind::Flag | FieldKind::Bool => (SITUATE_FIELD_BOOL, 1, false),
            FieldKind::I64 => (SITUATE_FIELD_I64, 1, false),
            FieldKind::F64 => (SITUATE_FIELD_F64, 1, false),
            FieldKind::Str => (SITUATE_FIELD_STR, 1, false),
            FieldKind::Bytes => (SITUATE_FIELD_BYTES, 1, false),
            FieldKind::Fixed { elem, len } => (elem_code(*elem), u32::try_from(*len).unwrap_or(u32::MAX), true),
            FieldKind::Var { elem } => (
                match elem {
                    ElemType::F32 => SITUATE_FIELD_F32_SLICE,
                    ElemType::F64 => SITUATE_FIELD_F64_SLICE,
                    ElemType::I64 => SITUATE_FIELD_I64_SLICE,
                },
                1,
                false,
            ),
        };
        out.push(FlatField { name, code, count, offset: base + f.offset, size: f.size, fixed });
    }
}
