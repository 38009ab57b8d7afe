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
        // Keep the struct, and the `Default` the expansion would have
        // given it, so that one mistake gives one error (not a cascade of
        // "no function `default`" where the user's code makes one; the
        // fallback thiserror uses too).
        Err(e) => {
            let err = e.to_compile_error();
            let fallback = fallback_default(&item);
            quote!(#err #item #fallback).into()
        }
    }
}

/// `impl Default` for the struct of a failed expansion, unless the
/// struct derives its own; it is never called (the crate does not build).
fn fallback_default(item: &ItemStruct) -> Tokens {
    let derives_default = item.attrs.iter().any(|a| {
        a.path().is_ident("derive")
            && a.parse_args_with(
                syn::punctuated::Punctuated::<syn::Path, Token![,]>::parse_terminated,
            )
            .is_ok_and(|paths| {
                paths
                    .iter()
                    .any(|p| p.segments.last().is_some_and(|s| s.ident == "Default"))
            })
    });
    if derives_default {
        return Tokens::new();
    }
    let name = &item.ident;
    let (impl_generics, ty_generics, where_clause) = item.generics.split_for_impl();
    quote! {
        impl #impl_generics ::core::default::Default for #name #ty_generics #where_clause {
            fn default() -> Self {
                ::core::unreachable!("#[multibody] failed; see the error above")
            }
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
    // The expansion names `::eom_sim`; without that dependency rustc's
    // "could not find `eom_sim`" would say nothing of what to add.
    let manifest = std::path::Path::new(&dir).join("Cargo.toml");
    if let Ok(text) = std::fs::read_to_string(&manifest)
        && !depends_on_eom_sim(&text)
    {
        return Err(syn::Error::new_spanned(
            &args.path,
            format!(
                "the code #[multibody] generates uses the `eom-sim` runtime, which `{}` does not depend on\n  = help: add `eom-sim = {{ git = \"…\" }}` (or `{{ path = \"…/eom-sim\" }}`) under [dependencies]; README \"Use eom in your own crate\" has the lines",
                manifest.display()
            ),
        ));
    }
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

/// Whether a `Cargo.toml` text declares the `eom-sim` crate as a
/// dependency of any kind: a key `eom-sim` (or `eom_sim`) in a table, a
/// dotted `eom-sim.workspace = true`, or a `[dependencies.eom-sim]` table.
/// A renamed dependency (`package = "eom-sim"`) counts too, though the
/// generated `::eom_sim` paths then need the name `eom_sim`.
fn depends_on_eom_sim(manifest: &str) -> bool {
    manifest.lines().any(|line| {
        let line = line.split('#').next().unwrap_or("").trim();
        let key = |k: &str| {
            let k = k.trim().trim_matches('"');
            k == "eom-sim" || k == "eom_sim"
        };
        if let Some(header) = line.strip_prefix('[').and_then(|l| l.strip_suffix(']')) {
            return header.split('.').any(key);
        }
        match line.split_once('=') {
            Some((k, v)) => {
                k.split('.').next().is_some_and(key)
                    || v.replace(' ', "").contains("package=\"eom-sim\"")
            }
            None => false,
        }
    })
}

#[cfg(test)]
mod tests {
    use super::depends_on_eom_sim;

    #[test]
    fn the_eom_sim_dependency_is_found_in_every_spelling() {
        for yes in [
            "[dependencies]\neom-sim = { path = \"../eom-sim\" }\n",
            "[dependencies]\neom_sim = \"0.1\"\n",
            "[dependencies]\neom-sim.workspace = true\n",
            "[dependencies.eom-sim]\npath = \"x\"\n",
            "[dependencies]\nsim = { package = \"eom-sim\", path = \"x\" }\n",
            "[target.'cfg(unix)'.dependencies]\n\"eom-sim\" = \"0.1\"\n",
        ] {
            assert!(depends_on_eom_sim(yes), "{yes}");
        }
        for no in [
            "[dependencies]\neom-macros = { path = \"../eom-macros\" }\n",
            "[package]\nname = \"x\"\n# eom-sim = \"0.1\"\n",
            "[dependencies]\neom-simulator = \"1\"\n",
        ] {
            assert!(!depends_on_eom_sim(no), "{no}");
        }
    }
}
