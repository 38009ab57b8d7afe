//! `#[multibody(model = "models/x.ron")] pub struct X;` — eom-gen at compile
//! time. The path is relative to the crate's `Cargo.toml` directory
//! (`CARGO_MANIFEST_DIR`); the model file is tracked (an edit rebuilds) and
//! model errors become compile errors carrying the model's own
//! `file:line:col` diagnostics. The expansion implements `eom_sim::Model`
//! and `eom_sim::OdeSystem` on the struct, so the crate depends on `eom-sim`.
//! The file goes through eom-gen's one loader (`eom_gen::model::check_in`):
//! a `.urdf` file is converted first (URDF errors carry the URDF's
//! `file:line:col`), a scene (`.scene.ron`) is applied to its model
//! (relative to the scene), and both files are tracked.

use proc_macro::TokenStream;
use proc_macro2::TokenStream as Tokens;
use quote::quote;
use syn::parse::{Parse, ParseStream};
use syn::{Ident, ItemStruct, LitStr, Token};

/// `model = "path"`.
struct Args {
    path: LitStr,
}

impl Parse for Args {
    fn parse(input: ParseStream<'_>) -> syn::Result<Self> {
        let key: Ident = input.parse()?;
        if key != "model" {
            return Err(syn::Error::new(
                key.span(),
                format!("unknown argument `{key}`; expected `model = \"models/x.ron\"`"),
            ));
        }
        input.parse::<Token![=]>()?;
        let path: LitStr = input.parse()?;
        if !input.is_empty() {
            return Err(input.error("expected only `model = \"models/x.ron\"`"));
        }
        Ok(Args { path })
    }
}

/// Generates the equations of motion of a model file onto the struct.
#[proc_macro_attribute]
pub fn multibody(attr: TokenStream, item: TokenStream) -> TokenStream {
    let item = syn::parse_macro_input!(item as ItemStruct);
    match expand(attr.into(), &item) {
        Ok(tokens) => tokens.into(),
        // Keep the struct so that one mistake gives one error.
        Err(e) => {
            let err = e.to_compile_error();
            quote!(#err #item).into()
        }
    }
}

fn expand(attr: Tokens, item: &ItemStruct) -> syn::Result<Tokens> {
    let args: Args = syn::parse2(attr).map_err(|e| {
        syn::Error::new(
            e.span(),
            format!("{e}\n  = help: write `#[multibody(model = \"models/x.ron\")]`"),
        )
    })?;
    let rel = args.path.value();
    let dir = std::env::var("CARGO_MANIFEST_DIR").unwrap_or_default();
    let full = std::path::Path::new(&dir).join(&rel);
    let text = std::fs::read_to_string(&full).map_err(|e| {
        syn::Error::new_spanned(&args.path, format!("cannot read model `{rel}`: {e}\n  = help: the path is relative to the directory of the crate's Cargo.toml"))
    })?;
    // `eom_gen::model::check_in` tells a model, a scene and a URDF apart.
    let src = eom_gen::Source::new(rel.clone(), text);
    let root = std::path::Path::new(&dir);
    let invalid = |e: &dyn std::fmt::Display| {
        syn::Error::new_spanned(&args.path, format!("model `{rel}` is invalid:\n{e}"))
    };
    let checked = eom_gen::model::check_in(&src, root).map_err(|e| invalid(&e))?;
    let tokens = eom_gen::generate_tokens_checked(&checked, &item.ident.to_string())
        .map_err(|e| invalid(&e))?;
    let tracked = full.display().to_string();
    // A scene's model is tracked too.
    let model = checked.scene.as_ref().map(|s| {
        let path = root.join(&s.model_path).display().to_string();
        quote!(
            const _: &[u8] = include_bytes!(#path);
        )
    });
    Ok(quote! {
        #tokens
        const _: &[u8] = include_bytes!(#tracked);
        #model
    })
}
