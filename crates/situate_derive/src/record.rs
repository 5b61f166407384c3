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
        writes.push(quote!((#name, #into(self.#field))));
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
                #core::record_value(::std::vec![#(#writes),*])
            }
        }
    })
}
