//! `#[derive(Skill)]`.

use proc_macro2::{Span, TokenStream};
use quote::{quote, quote_spanned};
use syn::ext::IdentExt;
use syn::spanned::Spanned;
use syn::{Attribute, DeriveInput, Expr, Ident, Lit, LitFloat, Type};

use crate::util::{self, Errors, SignedLit};

const SKILL_KEYS: &[&str] = &["name", "kind", "priority", "claims"];
const PORT_KEYS: &[&str] = &["signal"];
const PARAM_KEYS: &[&str] = &["default", "min", "max", "unit"];
const RESOURCE_KEYS: &[&str] = &["name"];
/// A field's roles, each its own attribute.
const ROLES: [&str; 4] = ["input", "output", "param", "resource"];

/// An input or output port field.
struct Port {
    field: Ident,
    name: String,
    signal: String,
    /// The signal's Rust type (`T` of an `Option<T>` field).
    ty: Type,
    /// The field is an `Option<T>`.
    optional: bool,
    doc: TokenStream,
}

/// A parameter field.
struct Param {
    field: Ident,
    name: String,
    ty: Type,
    /// An expression of the field's type: the declared default.
    default: TokenStream,
    min: Option<f64>,
    max: Option<f64>,
    unit: String,
    doc: TokenStream,
}

/// A field the host's resources fill when an instance is made (`#[resource]`).
struct Resource {
    field: Ident,
    /// The resource's name: the field's, or `#[resource(name = "…")]`.
    name: String,
    ty: Type,
}

/// The parameter types the macro knows by name, to check literals early.
#[derive(Clone, Copy, PartialEq, Eq)]
enum ParamKind {
    F64,
    I64,
    Bool,
    Str,
    /// An alias or another `ParamValue` type: the compiler checks.
    Other,
}

impl ParamKind {
    fn of(ty: &Type) -> ParamKind {
        match util::simple_type_name(ty).as_deref() {
            Some("f64") => ParamKind::F64,
            Some("i64") => ParamKind::I64,
            Some("bool") => ParamKind::Bool,
            Some("String") => ParamKind::Str,
            _ => ParamKind::Other,
        }
    }

    fn name(self) -> &'static str {
        match self {
            ParamKind::F64 => "an f64",
            ParamKind::I64 => "an i64",
            ParamKind::Bool => "a bool",
            ParamKind::Str => "a String",
            ParamKind::Other => "of another type",
        }
    }

    fn numeric(self) -> bool {
        matches!(self, ParamKind::F64 | ParamKind::I64 | ParamKind::Other)
    }
}

/// The struct-level `#[skill(...)]` settings.
struct SkillAttrs {
    name: Option<String>,
    kind: Ident,
    priority: i32,
    claims: Vec<String>,
}

pub fn expand(input: &DeriveInput) -> syn::Result<TokenStream> {
    let fields = util::named_fields(input, "Skill", "its ports, params and state")?;

    let mut errors = Errors::default();
    let attrs = skill_attrs(&input.attrs, &mut errors);
    for attr in &input.attrs {
        if let Some(which) = ROLES.into_iter().find(|w| attr.path().is_ident(w)) {
            errors.spanned(attr, format!("#[{which}] goes on a field of the struct"));
        }
    }

    let mut inputs: Vec<Port> = Vec::new();
    let mut outputs: Vec<Port> = Vec::new();
    let mut params: Vec<Param> = Vec::new();
    let mut resources: Vec<Resource> = Vec::new();
    let mut all_fields: Vec<Ident> = Vec::new();
    for field in &fields.named {
        let Some(ident) = &field.ident else { continue };
        all_fields.push(ident.clone());
        let mut role: Option<&Attribute> = None;
        for attr in &field.attrs {
            if attr.path().is_ident("skill") {
                errors.spanned(attr, "#[skill(...)] goes on the struct, not on a field");
                continue;
            }
            let Some(which) = ROLES.into_iter().find(|w| attr.path().is_ident(w)) else {
                continue;
            };
            if let Some(first) = role {
                let first_name = first.path().get_ident().map(Ident::to_string).unwrap_or_default();
                let message = if first_name == which {
                    format!("duplicate #[{which}] on field `{}`", ident.unraw())
                } else {
                    format!(
                        "field `{}` is already #[{first_name}]: a field is an input, an output, a param or a resource, not several",
                        ident.unraw()
                    )
                };
                errors.spanned(attr, message);
                continue;
            }
            role = Some(attr);
        }
        let Some(attr) = role else { continue };
        let doc = util::doc(&field.attrs);
        if attr.path().is_ident("param") {
            if let Some(p) = param(ident, &field.ty, attr, doc, &mut errors) {
                params.push(p);
            }
        } else if attr.path().is_ident("resource") {
            if let Some(r) = resource(ident, &field.ty, attr, &mut errors) {
                resources.push(r);
            }
        } else {
            let is_input = attr.path().is_ident("input");
            if let Some(p) = port(ident, &field.ty, attr, doc, &mut errors) {
                if is_input {
                    inputs.push(p);
                } else {
                    outputs.push(p);
                }
            }
        }
    }

    // Port and param names are field names, so they are unique already; two
    // outputs writing the same signal would be a conflict inside one skill.
    for (j, out) in outputs.iter().enumerate() {
        if let Some(first) = outputs[..j].iter().find(|o| o.signal == out.signal) {
            errors.spanned(
                &out.field,
                format!("outputs `{}` and `{}` both write signal `{}`", first.name, out.name, out.signal),
            );
        }
    }

    errors.finish()?;
    Ok(generate(input, &attrs, &Fields { inputs, outputs, params, resources, all: all_fields }))
}

/// A skill struct's fields by role, and all of them in order.
struct Fields {
    inputs: Vec<Port>,
    outputs: Vec<Port>,
    params: Vec<Param>,
    resources: Vec<Resource>,
    all: Vec<Ident>,
}

fn resource(field: &Ident, ty: &Type, attr: &Attribute, errors: &mut Errors) -> Option<Resource> {
    let name = one_name(attr, RESOURCE_KEYS, "`name`", field.unraw().to_string(), errors)?;
    Some(Resource { field: field.clone(), name, ty: ty.clone() })
}

fn skill_attrs(attrs: &[Attribute], errors: &mut Errors) -> SkillAttrs {
    let mut out =
        SkillAttrs { name: None, kind: Ident::new("Sync", Span::call_site()), priority: 0, claims: Vec::new() };
    let mut seen = Vec::new();
    for attr in attrs.iter().filter(|a| a.path().is_ident("skill")) {
        for item in util::items(attr, SKILL_KEYS, &mut seen, errors) {
            let Some(value) = errors.ok(item.value()) else { continue };
            match item.key.to_string().as_str() {
                "name" => {
                    let r = util::string(value, "`name`").and_then(|s| util::check_name(&s, "`name`"));
                    out.name = errors.ok(r);
                }
                "kind" => {
                    let Some(s) = errors.ok(util::string(value, "`kind`")) else { continue };
                    let kind = match s.value().as_str() {
                        "sync" => "Sync",
                        "async" => "Async",
                        "device" => "Device",
                        other => {
                            errors.spanned(
                                &s,
                                format!("unknown kind `{other}`; expected \"sync\", \"async\" or \"device\""),
                            );
                            continue;
                        }
                    };
                    out.kind = Ident::new(kind, s.span());
                }
                "priority" => {
                    let r = priority(value);
                    if let Some(p) = errors.ok(r) {
                        out.priority = p;
                    }
                }
                "claims" => out.claims = claims(value, errors),
                _ => {}
            }
        }
    }
    out
}

fn priority(value: &Expr) -> syn::Result<i32> {
    let Some(SignedLit { negative, lit: Lit::Int(i) }) = util::signed_lit(value) else {
        return Err(syn::Error::new_spanned(value, "`priority` must be an integer literal (higher wins)"));
    };
    let digits = if negative { format!("-{}", i.base10_digits()) } else { i.base10_digits().to_string() };
    digits.parse::<i32>().map_err(|_| syn::Error::new_spanned(value, "`priority` must fit in an i32"))
}

fn claims(value: &Expr, errors: &mut Errors) -> Vec<String> {
    let one = |e: &Expr| util::string(e, "a claim").and_then(|s| util::check_name(&s, "a claim"));
    match util::peel(value) {
        Expr::Array(a) => a.elems.iter().filter_map(|e| errors.ok(one(e))).collect(),
        Expr::Lit(_) => errors.ok(one(value)).into_iter().collect(),
        _ => {
            errors.spanned(value, "`claims` must be a list of string literals (`[\"python\"]`)");
            Vec::new()
        }
    }
}

/// The value of an attribute whose one key (`keys[0]`, `what` in messages) names something:
/// `default` without it; `None` after an error (pushed).
fn one_name(attr: &Attribute, keys: &[&str], what: &str, default: String, errors: &mut Errors) -> Option<String> {
    let mut name = Some(default);
    for item in util::items(attr, keys, &mut Vec::new(), errors) {
        let r = item.value().and_then(|v| util::string(v, what)).and_then(|s| util::check_name(&s, what));
        match r {
            Ok(s) => name = name.map(|_| s),
            Err(e) => {
                errors.push(e);
                name = None;
            }
        }
    }
    name
}

fn port(field: &Ident, ty: &Type, attr: &Attribute, doc: TokenStream, errors: &mut Errors) -> Option<Port> {
    let name = field.unraw().to_string();
    let signal = one_name(attr, PORT_KEYS, "`signal`", name.clone(), errors)?;
    let (inner, optional) = match util::option_inner(ty) {
        Some(t) => (t.clone(), true),
        None => (ty.clone(), false),
    };
    Some(Port { field: field.clone(), name, signal, ty: inner, optional, doc })
}

fn param(field: &Ident, ty: &Type, attr: &Attribute, doc: TokenStream, errors: &mut Errors) -> Option<Param> {
    let name = field.unraw().to_string();
    let kind = ParamKind::of(ty);
    if let Some(t) = util::simple_type_name(ty) {
        let off = ["f32", "i8", "i16", "i32", "i128", "isize", "u8", "u16", "u32", "u64", "u128", "usize", "str"];
        if off.contains(&t.as_str()) {
            errors.spanned(ty, format!("param `{name}`: params are f64, i64, bool or String, not {t}"));
            return None;
        }
    }
    let mut default: Option<&Expr> = None;
    let mut min = None;
    let mut max = None;
    let mut unit = String::new();
    let mut ok = true;
    let items = util::items(attr, PARAM_KEYS, &mut Vec::new(), errors);
    for item in &items {
        let Some(value) = errors.ok(item.value()) else {
            ok = false;
            continue;
        };
        let key = item.key.to_string();
        let r = match key.as_str() {
            "default" => {
                default = Some(value);
                Ok(())
            }
            "min" | "max" => {
                if kind.numeric() {
                    util::number(value, &format!("`{key}`")).map(|x| {
                        if key == "min" {
                            min = Some((x, value));
                        } else {
                            max = Some((x, value));
                        }
                    })
                } else {
                    Err(syn::Error::new_spanned(
                        &item.meta,
                        format!("param `{name}` is {}: `{key}` only applies to numbers", kind.name()),
                    ))
                }
            }
            "unit" => util::string(value, "`unit`").map(|s| unit = s.value()),
            _ => Ok(()),
        };
        if let Err(e) = r {
            errors.push(e);
            ok = false;
        }
    }
    if let (Some((lo, _)), Some((hi, hi_expr))) = (min, max) {
        if lo > hi {
            errors.spanned(hi_expr, format!("param `{name}`: `max` ({hi:?}) is below `min` ({lo:?})"));
            return None;
        }
    }
    let default_tokens = match default_expr(&name, ty, kind, default) {
        Ok(t) => t,
        Err(e) => {
            errors.push(e);
            return None;
        }
    };
    // A numeric default must lie in the declared range.
    let value = match default {
        Some(e) => util::number(e, "").ok().map(|x| (x, Some(e))),
        None if matches!(kind, ParamKind::F64 | ParamKind::I64) => Some((0.0, None)),
        None => None,
    };
    if let Some((x, at)) = value {
        let below = min.is_some_and(|(lo, _)| x < lo);
        let above = max.is_some_and(|(hi, _)| x > hi);
        if below || above {
            let range = format!(
                "[{}, {}]",
                min.map_or("-inf".to_string(), |(lo, _)| format!("{lo:?}")),
                max.map_or("inf".to_string(), |(hi, _)| format!("{hi:?}"))
            );
            match at {
                Some(e) => errors.spanned(e, format!("param `{name}`: default {x:?} is outside its range {range}")),
                None => errors.spanned(
                    &attr.meta,
                    format!("param `{name}`: without `default` it defaults to 0, outside its range {range}; give `default = ...`"),
                ),
            }
            ok = false;
        }
    }
    ok.then(|| Param {
        field: field.clone(),
        name,
        ty: ty.clone(),
        default: default_tokens,
        min: min.map(|(x, _)| x),
        max: max.map(|(x, _)| x),
        unit,
        doc,
    })
}

/// The default of a param as an expression of the field's type.
fn default_expr(name: &str, ty: &Type, kind: ParamKind, value: Option<&Expr>) -> syn::Result<TokenStream> {
    let Some(value) = value else {
        return Ok(quote_spanned!(ty.span()=> <#ty as ::core::default::Default>::default()));
    };
    let typed = |e: TokenStream, span: Span| quote_spanned!(span=> ::core::convert::identity::<#ty>(#e));
    let refuse = |what: &str| {
        syn::Error::new_spanned(value, format!("param `{name}` is {}: its default must be {what}", kind.name()))
    };
    let span = value.span();
    let Some(SignedLit { negative, lit }) = util::signed_lit(value) else {
        // Not a literal: a constant or expression of the field's type.
        return Ok(typed(quote!(#value), span));
    };
    let neg = negative.then(|| quote_spanned!(span=> -));
    match (lit, kind) {
        (Lit::Int(i), ParamKind::F64) if i.suffix().is_empty() => {
            let f = LitFloat::new(&format!("{}.0", i.base10_digits()), i.span());
            Ok(typed(quote!(#neg #f), span))
        }
        (Lit::Int(i), ParamKind::F64 | ParamKind::I64) => Ok(typed(quote!(#neg #i), span)),
        (Lit::Int(i), ParamKind::Other) => {
            // An alias of f64 or i64, most likely: only `as` converts an
            // integer to both. The `i64` suffix keeps large literals whole.
            let i = if i.suffix().is_empty() {
                syn::LitInt::new(&format!("{}i64", i.base10_digits()), i.span())
            } else {
                i.clone()
            };
            Ok(quote_spanned!(span=> (#neg #i) as #ty))
        }
        (Lit::Float(_), ParamKind::I64) => Err(refuse("an integer literal")),
        (Lit::Float(f), ParamKind::F64 | ParamKind::Other) => Ok(typed(quote!(#neg #f), span)),
        (Lit::Bool(b), ParamKind::Bool | ParamKind::Other) => Ok(typed(quote!(#b), span)),
        (Lit::Str(s), ParamKind::Str | ParamKind::Other) => {
            Ok(quote_spanned!(span=> <#ty as ::core::convert::From<&'static str>>::from(#s)))
        }
        (_, ParamKind::F64) => Err(refuse("a number literal")),
        (_, ParamKind::I64) => Err(refuse("an integer literal")),
        (_, ParamKind::Bool) => Err(refuse("`true` or `false`")),
        (_, ParamKind::Str) => Err(refuse("a string literal")),
        (_, ParamKind::Other) => Err(syn::Error::new_spanned(
            value,
            format!("param `{name}`: the default must be a number, bool or string literal"),
        )),
    }
}

fn opt_f64(x: Option<f64>) -> TokenStream {
    match x {
        Some(x) => {
            let lit = proc_macro2::Literal::f64_suffixed(x);
            quote!(::core::option::Option::Some(#lit))
        }
        None => quote!(::core::option::Option::None),
    }
}

fn generate(input: &DeriveInput, attrs: &SkillAttrs, fields: &Fields) -> TokenStream {
    let Fields { inputs, outputs, params, resources, all } = fields;
    let core = quote!(::situate::__core);
    // Locals the user's default expressions can't see or shadow.
    let [decl, port, param, skill, io, outs, value, x, slot, index, ty_param, provided] =
        ["decl", "port", "param", "skill", "io", "outputs", "value", "x", "slot", "index", "ty", "resources"]
            .map(util::local);
    let ident = &input.ident;
    let (impl_generics, ty_generics, where_clause) = input.generics.split_for_impl();

    let type_name = attrs.name.clone().unwrap_or_else(|| util::snake_case(&ident.unraw().to_string()));
    let doc = util::doc(&input.attrs);
    let kind = &attrs.kind;
    let priority = proc_macro2::Literal::i32_suffixed(attrs.priority);
    let claims = &attrs.claims;

    // `optional` is a property of inputs: an `Option` output is a plain
    // output the body doesn't write every run.
    let port_spec = |p: &Port, is_input: bool| {
        let Port { name, signal, ty, doc, .. } = p;
        let optional = is_input && p.optional;
        let signal_type = quote_spanned!(ty.span()=> <#ty as #core::SignalValue>::signal_type());
        quote! {{
            let mut #port = #core::PortSpec::new(#name, #signal_type);
            #port.signal = ::std::string::String::from(#signal);
            #port.optional = #optional;
            #port.doc = #doc;
            #port
        }}
    };
    let input_specs: Vec<TokenStream> = inputs.iter().map(|p| port_spec(p, true)).collect();
    let output_specs: Vec<TokenStream> = outputs.iter().map(|p| port_spec(p, false)).collect();
    let param_specs: Vec<TokenStream> = params
        .iter()
        .map(|p| {
            let Param { name, ty, default, unit, doc, .. } = p;
            let (min, max) = (opt_f64(p.min), opt_f64(p.max));
            let param_type = quote_spanned!(ty.span()=> <#ty as #core::ParamValue>::param_type());
            let into = quote_spanned!(ty.span()=> <#ty as #core::ParamValue>::into_param);
            quote! {{
                let mut #param = #core::ParamSpec::new(#name, #param_type, #into(#default));
                #param.min = #min;
                #param.max = #max;
                #param.unit = ::std::string::String::from(#unit);
                #param.doc = #doc;
                #param
            }}
        })
        .collect();

    let set_defaults = params.iter().map(|p| {
        let Param { field, default, .. } = p;
        quote!(#skill.#field = #default;)
    });
    let skill_binding = if params.is_empty() { quote!(#skill) } else { quote!(mut #skill) };
    // Without resources, the struct's own `Default`; with them, field by field: each resource
    // from the host's, every other field its type's `Default` (the struct needs none).
    let made = if resources.is_empty() {
        quote!(<Self as ::core::default::Default>::default())
    } else {
        let inits = all.iter().map(|f| match resources.iter().find(|r| &r.field == f) {
            Some(Resource { field, name, ty }) => {
                let get = quote_spanned!(ty.span()=> #provided.get::<#ty>(#name));
                quote! {
                    #field: ::core::clone::Clone::clone(#get.map_err(|e| {
                        #core::SkillError::new(::std::format!("`{}` {}", #type_name, e))
                    })?)
                }
            }
            None => quote!(#f: ::core::default::Default::default()),
        });
        quote!(Self { #(#inits),* })
    };
    let provided_binding = if resources.is_empty() { quote!(_) } else { quote!(#provided) };

    let read_inputs: Vec<TokenStream> = inputs
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let Port { field, name, ty, .. } = p;
            let from = quote_spanned!(ty.span()=> <#ty as #core::SignalValue>::from_value);
            let signal_type = quote_spanned!(ty.span()=> <#ty as #core::SignalValue>::signal_type());
            let input = quote!(#io.inputs.get(#i).and_then(::core::option::Option::as_ref));
            if p.optional {
                quote! {
                    self.#field = match #input {
                        ::core::option::Option::None => ::core::option::Option::None,
                        ::core::option::Option::Some(#value) => match #from(#value) {
                            ::core::option::Option::Some(#x) => ::core::option::Option::Some(#x),
                            ::core::option::Option::None => {
                                return ::core::result::Result::Err(#core::SkillError::new(::std::format!(
                                    "input `{}`: not a {}", #name, #signal_type
                                )));
                            }
                        },
                    };
                }
            } else {
                // Read straight into the field (no copy through a temporary).
                let read = quote_spanned!(ty.span()=> <#ty as #core::SignalValue>::read_input);
                quote! {
                    match #input {
                        ::core::option::Option::Some(#value) if #read(#value, &mut self.#field) => {}
                        _ => {
                            return ::core::result::Result::Err(#core::SkillError::new(::std::format!(
                                "input `{}`: missing or not a {}", #name, #signal_type
                            )));
                        }
                    }
                }
            }
        })
        .collect();

    let write_outputs: Vec<TokenStream> = outputs
        .iter()
        .enumerate()
        .map(|(j, p)| {
            let Port { field, ty, .. } = p;
            // The output may hold a spare on entry (see `fills_outputs`): the
            // value is written into its buffer when it can be.
            if p.optional {
                let put = quote_spanned!(ty.span()=> #core::value::optional_output::<#ty>);
                quote! {
                    let #value = ::core::option::Option::take(&mut self.#field);
                    if let ::core::option::Option::Some(#slot) = #outs.get_mut(#j) {
                        #put(#value, #slot);
                    }
                }
            } else {
                // Written from the field itself: a fixed-size array is copied
                // straight into the spare's buffer, not through a clone.
                let write = quote_spanned!(ty.span()=> <#ty as #core::SignalValue>::write_output);
                quote! {
                    if let ::core::option::Option::Some(#slot) = #outs.get_mut(#j) {
                        #write(&self.#field, #slot);
                    }
                }
            }
        })
        .collect();

    // The outputs every `Ok` run sets to `Some` (see `Skill::writes_output`):
    // those that are not an `Option`. `usize::MAX` matches no port.
    let mut required_outputs: Vec<TokenStream> =
        outputs.iter().enumerate().filter(|(_, p)| !p.optional).map(|(j, _)| quote!(#j)).collect();
    if required_outputs.is_empty() {
        required_outputs.push(quote!(::core::primitive::usize::MAX));
    }

    // Whether an output's values are of the port's type by construction
    // (see `Skill::output_typed`).
    let typed_arms = outputs.iter().enumerate().map(|(j, p)| {
        let ty = &p.ty;
        let conforms = quote_spanned!(ty.span()=> <#ty as #core::SignalValue>::ALWAYS_CONFORMS);
        let signal_type = quote_spanned!(ty.span()=> <#ty as #core::SignalValue>::signal_type());
        quote!(#j => #conforms && #core::SignalType::feeds(&#signal_type, #ty_param),)
    });

    let set_param = if params.is_empty() {
        quote!(let _ = (#index, #value);)
    } else {
        let arms = params.iter().enumerate().map(|(k, p)| {
            let Param { field, ty, .. } = p;
            let from = quote_spanned!(ty.span()=> <#ty as #core::ParamValue>::from_param);
            quote! {
                #k => {
                    if let ::core::option::Option::Some(#x) = #from(#value) {
                        self.#field = #x;
                    }
                }
            }
        });
        quote! {
            match #index {
                #(#arms)*
                _ => {}
            }
        }
    };

    // An integer default for a param whose type is an alias is cast with
    // `as` (see `default_expr`); that cast is the user's intent.
    let allow_casts = quote! {
        #[allow(
            trivial_numeric_casts,
            clippy::cast_lossless,
            clippy::cast_precision_loss,
            clippy::unnecessary_cast
        )]
    };
    quote! {
        #[automatically_derived]
        impl #impl_generics #core::Declare for #ident #ty_generics #where_clause {
            #allow_casts
            fn declaration() -> #core::SkillDecl {
                let mut #decl = #core::SkillDecl::new(#type_name, #core::SkillKind::#kind);
                #decl.doc = #doc;
                #decl.inputs = ::std::vec![#(#input_specs),*];
                #decl.outputs = ::std::vec![#(#output_specs),*];
                #decl.params = ::std::vec![#(#param_specs),*];
                #decl.priority = #priority;
                #decl.claims = ::std::vec![#(::std::string::String::from(#claims)),*];
                #decl
            }

            #allow_casts
            fn create(
                #provided_binding: &#core::Resources,
            ) -> ::core::result::Result<::std::boxed::Box<dyn #core::Skill>, #core::SkillError> {
                let #skill_binding = #made;
                #(#set_defaults)*
                ::core::result::Result::Ok(::std::boxed::Box::new(#skill))
            }
        }

        #[automatically_derived]
        impl #impl_generics #core::Skill for #ident #ty_generics #where_clause {
            fn step(
                &mut self,
                #io: &mut #core::Io<'_>,
            ) -> ::core::result::Result<(), #core::SkillError> {
                // `run_unwritten` then `write_outputs`, written out: one call.
                #(#read_inputs)*
                <Self as #core::Body>::step(self, &mut *#io.cx)?;
                let #outs = &mut *#io.outputs;
                #(#write_outputs)*
                ::core::result::Result::Ok(())
            }

            fn run_unwritten(
                &mut self,
                #io: &mut #core::Io<'_>,
            ) -> ::core::result::Result<(), #core::SkillError> {
                #(#read_inputs)*
                <Self as #core::Body>::step(self, &mut *#io.cx)
            }

            fn write_outputs(&mut self, #outs: &mut [::core::option::Option<#core::Value>]) {
                #(#write_outputs)*
            }

            fn set_param(&mut self, #index: ::core::primitive::usize, #value: &#core::Value) {
                #set_param
            }

            fn activate(
                &mut self,
                cx: &mut #core::Context,
            ) -> ::core::result::Result<(), #core::SkillError> {
                <Self as #core::Body>::activate(self, cx)
            }

            fn deactivate(
                &mut self,
                cx: &mut #core::Context,
            ) -> ::core::result::Result<(), #core::SkillError> {
                <Self as #core::Body>::deactivate(self, cx)
            }

            fn fills_outputs(&self) -> bool {
                true
            }

            fn writes_output(&self, #index: ::core::primitive::usize) -> bool {
                ::core::matches!(#index, #(#required_outputs)|*)
            }

            fn output_typed(
                &self,
                #index: ::core::primitive::usize,
                #ty_param: &#core::SignalType,
            ) -> bool {
                match #index {
                    #(#typed_arms)*
                    _ => {
                        let _ = #ty_param;
                        false
                    }
                }
            }
        }
    }
}
