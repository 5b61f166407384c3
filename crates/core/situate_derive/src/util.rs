//! Shared pieces: error collection, helper-attribute parsing, doc comments,
//! literal reading and type shapes.

use proc_macro2::TokenStream;
use quote::{quote, ToTokens};
use syn::punctuated::Punctuated;
use syn::{Attribute, Expr, ExprLit, Ident, Lit, LitStr, Meta, Token, Type, UnOp};

/// Collects errors so that one expansion reports all of them at once.
#[derive(Default)]
pub struct Errors(Option<syn::Error>);

impl Errors {
    pub fn push(&mut self, e: syn::Error) {
        match &mut self.0 {
            Some(all) => all.combine(e),
            None => self.0 = Some(e),
        }
    }

    pub fn spanned(&mut self, tokens: impl ToTokens, message: impl std::fmt::Display) {
        self.push(syn::Error::new_spanned(tokens, message));
    }

    /// Keeps the value of `r`, or records its error.
    pub fn ok<T>(&mut self, r: syn::Result<T>) -> Option<T> {
        r.map_err(|e| self.push(e)).ok()
    }

    pub fn finish(self) -> syn::Result<()> {
        self.0.map_or(Ok(()), Err)
    }
}

/// One `key` or `key = value` item of a helper attribute.
pub struct Item {
    pub key: Ident,
    pub value: Option<Expr>,
    /// The whole item, for error spans.
    pub meta: Meta,
}

impl Item {
    /// The value of a `key = value` item; an error on a bare `key`.
    pub fn value(&self) -> syn::Result<&Expr> {
        self.value.as_ref().ok_or_else(|| syn::Error::new_spanned(&self.meta, format!("expected `{} = ...`", self.key)))
    }
}

/// Reads the items of one helper attribute (`#[input]`, `#[input()]`,
/// `#[input(signal = "x")]`), checking every key against `allowed`.
/// Unknown and repeated keys are recorded in `errors` and left out.
pub fn items(attr: &Attribute, allowed: &[&str], seen: &mut Vec<String>, errors: &mut Errors) -> Vec<Item> {
    let name = attr.path().get_ident().map(Ident::to_string).unwrap_or_default();
    let metas = match &attr.meta {
        Meta::Path(_) => return Vec::new(),
        Meta::List(list) => match list.parse_args_with(Punctuated::<Meta, Token![,]>::parse_terminated) {
            Ok(metas) => metas,
            Err(e) => {
                errors.push(e);
                return Vec::new();
            }
        },
        Meta::NameValue(nv) => {
            errors.spanned(nv, format!("expected `#[{name}(key = value, ...)]`; {}", keys_hint(allowed)));
            return Vec::new();
        }
    };
    let mut out = Vec::new();
    for meta in metas {
        let (path, value) = match &meta {
            Meta::Path(p) => (p, None),
            Meta::NameValue(nv) => (&nv.path, Some(nv.value.clone())),
            Meta::List(l) => {
                errors.spanned(l, format!("expected `key = value` in #[{name}]; {}", keys_hint(allowed)));
                continue;
            }
        };
        let Some(key) = path.get_ident().cloned() else {
            errors.spanned(path, format!("expected a key in #[{name}]; {}", keys_hint(allowed)));
            continue;
        };
        let key_text = key.to_string();
        if !allowed.contains(&key_text.as_str()) {
            let hint = closest(&key_text, allowed).map(|c| format!(" (did you mean `{c}`?)")).unwrap_or_default();
            errors.spanned(&key, format!("unknown key `{key_text}` in #[{name}]{hint}; {}", keys_hint(allowed)));
            continue;
        }
        if seen.contains(&key_text) {
            errors.spanned(&key, format!("duplicate key `{key_text}` in #[{name}]"));
            continue;
        }
        seen.push(key_text);
        out.push(Item { key, value, meta });
    }
    out
}

fn keys_hint(allowed: &[&str]) -> String {
    match allowed {
        [] => "it takes no keys".to_string(),
        [one] => format!("the allowed key is `{one}`"),
        _ => {
            let list: Vec<String> = allowed.iter().map(|k| format!("`{k}`")).collect();
            format!("the allowed keys are {}", list.join(", "))
        }
    }
}

/// The allowed key closest to a misspelt one, if it is close.
fn closest<'a>(key: &str, allowed: &[&'a str]) -> Option<&'a str> {
    let limit = (key.chars().count() / 3).max(1);
    allowed
        .iter()
        .map(|c| (edit_distance(key, c), *c))
        .filter(|(d, _)| *d <= limit)
        .min_by_key(|(d, _)| *d)
        .map(|(_, c)| c)
}

fn edit_distance(a: &str, b: &str) -> usize {
    let b: Vec<char> = b.chars().collect();
    let mut prev: Vec<usize> = (0..=b.len()).collect();
    let mut cur = vec![0; b.len() + 1];
    for (i, ca) in a.chars().enumerate() {
        cur[0] = i + 1;
        for (j, cb) in b.iter().enumerate() {
            let cost = usize::from(ca != *cb);
            cur[j + 1] = (prev[j] + cost).min(prev[j + 1] + 1).min(cur[j] + 1);
        }
        std::mem::swap(&mut prev, &mut cur);
    }
    prev[b.len()]
}

/// A name for a local of generated code. Prefixed, so that constants of the
/// user's (which `let` patterns and match arms would pick up) can't collide,
/// and mixed-site, so that the user's default expressions can't see it.
pub fn local(name: &str) -> proc_macro2::Ident {
    proc_macro2::Ident::new(&format!("__situate_{name}"), proc_macro2::Span::mixed_site())
}

/// Strips invisible groups and parentheses (macro_rules wraps `$e:expr`).
pub fn peel(mut e: &Expr) -> &Expr {
    loop {
        match e {
            Expr::Group(g) => e = &g.expr,
            Expr::Paren(p) => e = &p.expr,
            _ => return e,
        }
    }
}

/// A literal, possibly negated: `0.5`, `-1`, `"m"`, `true`.
pub struct SignedLit<'a> {
    pub negative: bool,
    pub lit: &'a Lit,
}

pub fn signed_lit(e: &Expr) -> Option<SignedLit<'_>> {
    match peel(e) {
        Expr::Lit(ExprLit { lit, .. }) => Some(SignedLit { negative: false, lit }),
        Expr::Unary(u) if matches!(u.op, UnOp::Neg(_)) => match peel(&u.expr) {
            Expr::Lit(ExprLit { lit: lit @ (Lit::Int(_) | Lit::Float(_)), .. }) => {
                Some(SignedLit { negative: true, lit })
            }
            _ => None,
        },
        _ => None,
    }
}

/// An int or float literal, possibly negated, as `f64`.
pub fn number(e: &Expr, what: &str) -> syn::Result<f64> {
    let bad = || syn::Error::new_spanned(e, format!("{what} must be a number literal (`1`, `-0.5`)"));
    let Some(SignedLit { negative, lit }) = signed_lit(e) else { return Err(bad()) };
    let x: f64 = match lit {
        Lit::Int(i) => i.base10_parse()?,
        Lit::Float(f) => f.base10_parse()?,
        _ => return Err(bad()),
    };
    if !x.is_finite() {
        return Err(syn::Error::new_spanned(e, format!("{what} must be a finite number")));
    }
    Ok(if negative { -x } else { x })
}

/// A string literal.
pub fn string(e: &Expr, what: &str) -> syn::Result<LitStr> {
    match peel(e) {
        Expr::Lit(ExprLit { lit: Lit::Str(s), .. }) => Ok(s.clone()),
        _ => Err(syn::Error::new_spanned(e, format!("{what} must be a string literal (`\"...\"`)"))),
    }
}

/// A signal or type name: not empty, no whitespace.
pub fn check_name(s: &LitStr, what: &str) -> syn::Result<String> {
    let v = s.value();
    if v.is_empty() || v.chars().any(char::is_whitespace) {
        return Err(syn::Error::new_spanned(s, format!("{what} must be non-empty and without spaces")));
    }
    Ok(v)
}

/// An expression evaluating to the `String` of the `///` doc comments in
/// `attrs`: lines joined with '\n' (one leading space stripped from each) and
/// trimmed. `#[doc = include_str!(...)]` and the like are kept and trimmed at
/// run time.
pub fn doc(attrs: &[Attribute]) -> TokenStream {
    enum Piece {
        Text(String),
        Expr(Box<Expr>),
    }
    let mut pieces: Vec<Piece> = Vec::new();
    for attr in attrs {
        let Meta::NameValue(nv) = &attr.meta else { continue };
        if !nv.path.is_ident("doc") {
            continue;
        }
        match peel(&nv.value) {
            Expr::Lit(ExprLit { lit: Lit::Str(s), .. }) => {
                let text = s.value();
                let lines: Vec<&str> = text.lines().map(|l| l.strip_prefix(' ').unwrap_or(l).trim_end()).collect();
                pieces.push(Piece::Text(lines.join("\n")));
            }
            other => pieces.push(Piece::Expr(Box::new(other.clone()))),
        }
    }
    if pieces.iter().all(|p| matches!(p, Piece::Text(_))) {
        let texts: Vec<&str> =
            pieces.iter().filter_map(|p| if let Piece::Text(t) = p { Some(t.as_str()) } else { None }).collect();
        let text = texts.join("\n");
        let text = text.trim();
        if text.is_empty() {
            return quote!(::std::string::String::new());
        }
        return quote!(::std::string::String::from(#text));
    }
    let mut parts = Vec::new();
    for (i, p) in pieces.iter().enumerate() {
        if i > 0 {
            parts.push(quote!("\n"));
        }
        parts.push(match p {
            Piece::Text(t) => quote!(#t),
            Piece::Expr(e) => quote!(#e),
        });
    }
    quote!(::std::string::String::from(::core::primitive::str::trim(::core::concat!(#(#parts),*))))
}

/// `T` for a type written `Option<T>` (the last path segment `Option` with
/// one type argument), else `None`.
pub fn option_inner(ty: &Type) -> Option<&Type> {
    let Type::Path(tp) = peel_type(ty) else { return None };
    if tp.qself.is_some() {
        return None;
    }
    let last = tp.path.segments.last()?;
    if last.ident != "Option" {
        return None;
    }
    let syn::PathArguments::AngleBracketed(args) = &last.arguments else { return None };
    if args.args.len() != 1 {
        return None;
    }
    match args.args.first()? {
        syn::GenericArgument::Type(t) => Some(t),
        _ => None,
    }
}

/// Strips invisible groups and parentheses around a type.
pub fn peel_type(mut ty: &Type) -> &Type {
    loop {
        match ty {
            Type::Group(g) => ty = &g.elem,
            Type::Paren(p) => ty = &p.elem,
            _ => return ty,
        }
    }
}

/// The bare name of a type written as a single identifier (`f64`,
/// `String`), else `None`.
pub fn simple_type_name(ty: &Type) -> Option<String> {
    let Type::Path(tp) = peel_type(ty) else { return None };
    if tp.qself.is_some() {
        return None;
    }
    let last = tp.path.segments.last()?;
    if !last.arguments.is_none() {
        return None;
    }
    Some(last.ident.to_string())
}

/// `RunAway` → `run_away`, `HTTPServer` → `http_server`,
/// `Vec3Filter` → `vec3_filter`, `Sonar2D` → `sonar2d`.
pub fn snake_case(name: &str) -> String {
    let chars: Vec<char> = name.chars().collect();
    let mut out = String::with_capacity(name.len() + 4);
    for (i, &c) in chars.iter().enumerate() {
        if c.is_uppercase() {
            let prev = i.checked_sub(1).and_then(|j| chars.get(j)).copied();
            let next_lower = chars.get(i + 1).is_some_and(|n| n.is_lowercase());
            let boundary = match prev {
                None | Some('_') => false,
                Some(p) if p.is_lowercase() => true,
                Some(p) if p.is_uppercase() || p.is_numeric() => next_lower,
                Some(_) => false,
            };
            if boundary {
                out.push('_');
            }
            out.extend(c.to_lowercase());
        } else {
            out.push(c);
        }
    }
    out
}

/// The named fields of the struct a derive is applied to, or an error
/// saying what `derive` needs (`what` names the fields' role).
pub fn named_fields<'a>(input: &'a syn::DeriveInput, derive: &str, what: &str) -> syn::Result<&'a syn::FieldsNamed> {
    match &input.data {
        syn::Data::Struct(s) => match &s.fields {
            syn::Fields::Named(named) => Ok(named),
            other => Err(syn::Error::new_spanned(
                other,
                format!("#[derive({derive})] needs a struct with named fields ({what})"),
            )),
        },
        syn::Data::Enum(e) => Err(syn::Error::new_spanned(
            e.enum_token,
            format!("#[derive({derive})] needs a struct with named fields, not an enum"),
        )),
        syn::Data::Union(u) => Err(syn::Error::new_spanned(
            u.union_token,
            format!("#[derive({derive})] needs a struct with named fields, not a union"),
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn snake_case_splits_words_and_acronyms() {
        assert_eq!(snake_case("RunAway"), "run_away");
        assert_eq!(snake_case("Runaway"), "runaway");
        assert_eq!(snake_case("HTTPServer"), "http_server");
        assert_eq!(snake_case("Vec3Filter"), "vec3_filter");
        assert_eq!(snake_case("Sonar2D"), "sonar2d");
        assert_eq!(snake_case("Already_Snake"), "already_snake");
        assert_eq!(snake_case("A"), "a");
    }

    #[test]
    fn option_types_are_recognised_by_their_last_segment() {
        let t: Type = syn::parse_quote!(::std::option::Option<f64>);
        assert!(option_inner(&t).is_some());
        let t: Type = syn::parse_quote!(Option<Arc<[f32]>>);
        assert!(option_inner(&t).is_some());
        let t: Type = syn::parse_quote!(Vec<f64>);
        assert!(option_inner(&t).is_none());
        let t: Type = syn::parse_quote!(Option);
        assert!(option_inner(&t).is_none());
    }

    #[test]
    fn numbers_may_be_negative_ints_or_floats() {
        let e: Expr = syn::parse_quote!(-1.5);
        assert_eq!(number(&e, "min").ok(), Some(-1.5));
        let e: Expr = syn::parse_quote!(3);
        assert_eq!(number(&e, "min").ok(), Some(3.0));
        let e: Expr = syn::parse_quote!("3");
        assert!(number(&e, "min").is_err());
    }

    #[test]
    fn unknown_keys_suggest_the_closest() {
        assert_eq!(closest("singal", &["signal"]), Some("signal"));
        assert_eq!(closest("frobnicate", &["signal"]), None);
    }
}
