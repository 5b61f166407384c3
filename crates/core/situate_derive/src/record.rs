//! `#[derive(Record)]`.

use proc_macro2::TokenStream;
use quote::{quote, quote_spanned};
use syn::ext::IdentExt;
use syn::spanned::Spanned;
use syn::DeriveInput;

use crate::util;

pub fn expand(input: &DeriveInput) -> syn::Result<TokenStream> {
    let fields = util::named_fields(input, "Record", "the record's fields")?;
    let core = quote!(::situate::__core);
    let ident = &input.ident;

    // A generic record needs every field type to be a signal value.
    let mut generics = input.generics.clone();
    if generics.type_params().next().is_some() {
        let where_clause = generics.make_where_clause();
        for f in &fields.named {
            let ty = &f.ty;
            where_clause.predicates.push(syn::parse_quote!(#ty: #core::SignalValue));
        }
    }
    let (impl_generics, ty_generics, where_clause) = generics.split_for_impl();

    let [value, record, name_at, value_at] = ["value", "record", "name", "field"].map(util::local);
    let mut types = Vec::new();
    let mut reads = Vec::new();
    let mut writes = Vec::new();
    let mut names = Vec::new();
    let mut fills = Vec::new();
    for (i, f) in fields.named.iter().enumerate() {
        let Some(field) = &f.ident else { continue };
        let name = field.unraw().to_string();
        let ty = &f.ty;
        let signal_type = quote_spanned!(ty.span()=> <#ty as #core::SignalValue>::signal_type());
        let from = quote_spanned!(ty.span()=> <#ty as #core::SignalValue>::from_value);
        let into = quote_spanned!(ty.span()=> <#ty as #core::SignalValue>::into_value);
        types.push(quote!((#name, #signal_type)));
        // Fields normally arrive in declaration order: try the expected
        // position first, then search by name.
        reads.push(quote! {
            #field: #from(
                match #record.fields.get(#i) {
                    ::core::option::Option::Some((#name_at, #value_at)) if &**#name_at == #name => #value_at,
                    _ => #record.get(#name)?,
                }
            )?
        });
        writes.push(quote!(#into(self.#field)));
        fills.push(quote!(#core::fill_field(self.#field, &mut #record[#i].1);));
        names.push(name);
    }

    let binding = if reads.is_empty() { quote!(_) } else { quote!(#record) };
    Ok(quote! {
        #[automatically_derived]
        impl #impl_generics #core::SignalValue for #ident #ty_generics #where_clause {
            fn signal_type() -> #core::SignalType {
                #core::record_type(::std::vec![#(#types),*])
            }

            fn from_value(#value: &#core::Value) -> ::core::option::Option<Self> {
                match #value {
                    #core::Value::Record(#binding) => ::core::option::Option::Some(Self {
                        #(#reads),*
                    }),
                    _ => ::core::option::Option::None,
                }
            }

            fn into_value(self) -> #core::Value {
                static NAMES: ::std::sync::OnceLock<::std::boxed::Box<[::std::sync::Arc<str>]>> =
                    ::std::sync::OnceLock::new();
                let names = #core::record_names(&NAMES, &[#(#names),*]);
                #core::record_of(names, [#(#writes),*])
            }

            /// Written in place into a spare record of this type that nobody
            /// else holds (no allocation), else made anew.
            fn into_output(self, output: &mut ::core::option::Option<#core::Value>) {
                if let ::core::option::Option::Some(#record) = #core::record_fields_to_fill(output, &[#(#names),*]) {
                    let _ = &#record;
                    #(#fills)*
                    return;
                }
                if let ::core::option::Option::Some(spare) = output.take() {
                    #core::value::recycle(spare);
                }
                *output = ::core::option::Option::Some(self.into_value());
            }
        }
    })
}
