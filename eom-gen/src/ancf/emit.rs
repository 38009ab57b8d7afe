//! Emission of an element type's kernels as one
//! `eom_elements::ElementKernel` implementation: straight-line Rust,
//! one `let` per instruction, fixed-size arrays with constant indices (no
//! allocation, no panic), formatted by `prettyplease`. The force and
//! Jacobian kernels are generic in a lane count `W` (`Lanes<W>` values:
//! `W` elements evaluated by the same code at once, which the compiler
//! turns into SIMD instructions; the scalar entry points of the trait are
//! `W = 1`).

use super::{Kernels, LOAD_NAMES};
use crate::emit::VERSION;
use crate::emit::lower::{Arg, Style, lower};
use crate::sym::{Program, SymKind, Symbol};
use proc_macro2::{Literal, TokenStream};
use quote::{format_ident, quote};

/// How each symbol kind is read in the generated functions.
fn input(k: &Kernels, s: &Symbol) -> TokenStream {
    let idx = |i: usize| Literal::usize_unsuffixed(i);
    match s.kind {
        SymKind::Coord(i) => {
            let i = idx(i as usize);
            quote!(q[#i])
        }
        SymKind::CoordRate(i) => {
            let i = idx(i as usize);
            quote!(qd[#i])
        }
        SymKind::Param => match k.def.params.iter().position(|(n, _)| *n == s.name) {
            Some(i) => {
                let i = idx(i);
                quote!(p[#i])
            }
            None => quote!(::core::compile_error!("eom-gen: unknown element parameter")),
        },
        SymKind::Input => match LOAD_NAMES.iter().position(|n| *n == s.name) {
            Some(i) => {
                let i = idx(i);
                quote!(w[#i])
            }
            None => quote!(::core::compile_error!("eom-gen: unknown element input")),
        },
        _ => quote!(::core::compile_error!(
            "eom-gen: unexpected symbol in an element kernel"
        )),
    }
}

/// Instructions per function: longer straight-line functions overflow
/// rustc's stack when it writes debug information (one nested scope per
/// `let`).
pub use crate::emit::lower::PART_LIMIT;

/// An argument of a kernel function: name, type, which symbols it carries.
struct KArg {
    name: &'static str,
    ty: TokenStream,
    carries: fn(&SymKind) -> bool,
}

/// A kernel function's body and its helper parts (free functions).
struct Body {
    stmts: TokenStream,
    parts: TokenStream,
    used: Vec<bool>,
}

/// The statements of `p` (the one lowering of `crate::emit::lower`), then
/// `targets[i] = output i`. Programs longer than [`PART_LIMIT`] become
/// consecutive `#[inline(never)]` free functions; a temporary read in a
/// later part or written to an output goes through a scratch array `s` on
/// the caller's stack.
///
/// With `lanes`, every value is a `Lanes<W>` (`W` elements at once, one per
/// lane, the same straight-line code) and the parts are generic in `W`.
fn body(
    k: &Kernels,
    p: &Program,
    fname: &str,
    args: &[KArg],
    targets: &[TokenStream],
    lanes: bool,
) -> Body {
    let read = |s: &Symbol| input(k, s);
    let style = Style {
        input: &read,
        fma: false,
        lanes: lanes.then(|| quote!(Lanes)),
        sin_cos_together: false,
        methods: false,
    };
    let args: Vec<Arg<'_>> = args
        .iter()
        .map(|a| {
            let carries = a.carries;
            Arg {
                name: a.name,
                ty: a.ty.clone(),
                carries: Box::new(move |s: &Symbol| carries(&s.kind)),
            }
        })
        .collect();
    let l = lower(&style, p, fname, &args);
    let mut stmts = l.body;
    for (v, t) in l.outputs.iter().zip(targets) {
        stmts.extend(quote!(#t = #v;));
    }
    Body {
        stmts,
        parts: l.parts,
        used: l.used,
    }
}

fn arg(name: &str, used: bool) -> proc_macro2::Ident {
    if used {
        format_ident!("{name}")
    } else {
        format_ident!("_{name}")
    }
}

/// One line of markdown per op count.
pub fn op_line(name: &str, p: &Program) -> String {
    format!("`{name}`: {}", p.op_count())
}

/// The formatted source of `elements/src/<module>.rs`.
pub fn emit(k: &Kernels) -> String {
    let def = &k.def;
    let n = def.n();
    let np = def.params.len();
    let nl = Literal::usize_unsuffixed(n);
    let npl = Literal::usize_unsuffixed(np);
    let ty = format_ident!("{}", def.name);
    let name = def.name;
    let node_coords = Literal::usize_unsuffixed(def.node_coords);
    let dim = Literal::usize_unsuffixed(def.dim);
    let pnames = def.params.iter().map(|(p, _)| *p);
    let idx = |i: usize| Literal::usize_unsuffixed(i);

    let vec_targets = |arr: &str| -> Vec<TokenStream> {
        let a = format_ident!("{arr}");
        (0..n)
            .map(|i| {
                let i = idx(i);
                quote!(#a[#i])
            })
            .collect()
    };
    let mat_targets = |arr: &str| -> Vec<TokenStream> {
        let a = format_ident!("{arr}");
        (0..n * n)
            .map(|ij| {
                let (i, j) = (idx(ij / n), idx(ij % n));
                quote!(#a[#i][#j])
            })
            .collect()
    };
    let is_q = |s: &SymKind| matches!(s, SymKind::Coord(_));
    let is_qd = |s: &SymKind| matches!(s, SymKind::CoordRate(_));
    let is_p = |s: &SymKind| matches!(s, SymKind::Param);
    let is_w = |s: &SymKind| matches!(s, SymKind::Input);

    let vec_ty = quote!(&[f64; #nl]);
    let p_ty = quote!(&[f64; #npl]);
    let lvec_ty = quote!(&[Lanes<W>; #nl]);
    let lp_ty = quote!(&[Lanes<W>; #npl]);
    let qa = |ty: &TokenStream| KArg {
        name: "q",
        ty: ty.clone(),
        carries: is_q,
    };
    let qda = |ty: &TokenStream| KArg {
        name: "qd",
        ty: ty.clone(),
        carries: is_qd,
    };
    let pa = |ty: &TokenStream| KArg {
        name: "p",
        ty: ty.clone(),
        carries: is_p,
    };

    let fargs = [qa(&lvec_ty), qda(&lvec_ty), pa(&lp_ty)];
    let fb = body(
        k,
        &k.forces,
        "forces_lanes",
        &fargs,
        &vec_targets("f"),
        true,
    );
    let (fq, fqd, fp) = (
        arg("q", fb.used[0]),
        arg("qd", fb.used[1]),
        arg("p", fb.used[2]),
    );
    let mut jt = mat_targets("k");
    jt.extend(mat_targets("d"));
    let jb = body(k, &k.jacobians, "jacobians_lanes", &fargs, &jt, true);
    let (jq, jqd, jp) = (
        arg("q", jb.used[0]),
        arg("qd", jb.used[1]),
        arg("p", jb.used[2]),
    );
    let eargs = [qa(&lvec_ty), pa(&lp_ty)];
    let efb = body(
        k,
        &k.elastic_forces,
        "elastic_forces_lanes",
        &eargs,
        &vec_targets("f"),
        true,
    );
    let (efq, efp) = (arg("q", efb.used[0]), arg("p", efb.used[1]));
    let ekb = body(
        k,
        &k.elastic_stiffness,
        "elastic_stiffness_lanes",
        &eargs,
        &mat_targets("k"),
        true,
    );
    let (ekq, ekp) = (arg("q", ekb.used[0]), arg("p", ekb.used[1]));
    let margs = [pa(&p_ty)];
    let mb = body(k, &k.mass, "mass", &margs, &mat_targets("m"), false);
    let mp = arg("p", mb.used[0]);
    let largs = [
        pa(&p_ty),
        KArg {
            name: "w",
            ty: quote!(&[f64; 3]),
            carries: is_w,
        },
    ];
    let lb = body(k, &k.load, "uniform_load", &largs, &vec_targets("f"), false);
    let (lp, lw) = (arg("p", lb.used[0]), arg("w", lb.used[1]));
    let _ = &vec_ty;
    let parts = [
        &fb.parts, &jb.parts, &efb.parts, &ekb.parts, &mb.parts, &lb.parts,
    ];
    let (fb, jb, efb, ekb, mb, lb) = (
        &fb.stmts, &jb.stmts, &efb.stmts, &ekb.stmts, &mb.stmts, &lb.stmts,
    );
    let damping = if k.damping_params.is_empty() {
        quote!(None)
    } else {
        let d = k
            .damping_params
            .iter()
            .map(|&i| Literal::usize_unsuffixed(i));
        quote!(Some(&[#(#d),*]))
    };

    let layout = {
        let node = |a: usize| {
            def.node_layout
                .iter()
                .enumerate()
                .map(|(i, s)| format!("`q[{}]` = `{s}`", a * def.node_coords + i))
                .collect::<Vec<_>>()
                .join(", ")
        };
        format!(
            " Node 1 (at `x = 0`): {}.\n\n Node 2 (at `x = L`): {}.",
            node(0),
            node(1)
        )
    };
    let params_doc = def
        .params
        .iter()
        .enumerate()
        .map(|(i, (p, m))| format!(" - `p[{i}]` = `{p}`: {m}"))
        .collect::<Vec<_>>()
        .join("\n");
    let counts = [
        ("internal_forces", &k.forces),
        ("internal_jacobians", &k.jacobians),
        ("elastic_forces", &k.elastic_forces),
        ("elastic_stiffness", &k.elastic_stiffness),
        ("mass", &k.mass),
        ("uniform_load", &k.load),
    ]
    .map(|(n, p)| format!(" - {}", op_line(n, p)))
    .join("\n");
    let doc = format!(
        " {}\n\n # Coordinates ({n}, `{}` per node; positions and gradients in the inertial frame)\n\n{layout}\n\n # Parameters\n\n{params_doc}\n\n # Integration\n\n {}\n\n # Operations per call\n\n{counts}",
        def.summary, def.node_coords, def.integration
    );
    let module_doc = format!(
        "//! Element `{name}`: kernels generated by eom-gen {VERSION} (`eom-gen/src/ancf/`) — do not edit.\n//! Regenerate with `cargo run -p eom-gen --example regenerate`.\n\n"
    );
    let tokens = quote! {
        use super::{ElementKernel, Lanes, one_lane};

        #[doc = #doc]
        #[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
        pub struct #ty;

        impl ElementKernel<#nl, #npl> for #ty {
            const NAME: &'static str = #name;
            const NODE_COORDS: usize = #node_coords;
            const DIM: usize = #dim;
            const PARAMS: [&'static str; #npl] = [#(#pnames),*];
            const DAMPING_PARAMS: Option<&'static [usize]> = #damping;

            fn internal_forces(q: &[f64; #nl], qd: &[f64; #nl], p: &[f64; #npl], f: &mut [f64; #nl]) {
                let mut out = [Lanes([0.0]); #nl];
                Self::forces_lanes(&one_lane(q), &one_lane(qd), &one_lane(p), &mut out);
                *f = out.map(|x| x.0[0]);
            }

            fn internal_jacobians(
                q: &[f64; #nl],
                qd: &[f64; #nl],
                p: &[f64; #npl],
                k: &mut [[f64; #nl]; #nl],
                d: &mut [[f64; #nl]; #nl],
            ) {
                let mut kl = [[Lanes([0.0]); #nl]; #nl];
                let mut dl = [[Lanes([0.0]); #nl]; #nl];
                Self::jacobians_lanes(&one_lane(q), &one_lane(qd), &one_lane(p), &mut kl, &mut dl);
                *k = kl.map(|r| r.map(|x| x.0[0]));
                *d = dl.map(|r| r.map(|x| x.0[0]));
            }

            fn forces_lanes<const W: usize>(
                #fq: &[Lanes<W>; #nl],
                #fqd: &[Lanes<W>; #nl],
                #fp: &[Lanes<W>; #npl],
                f: &mut [Lanes<W>; #nl],
            ) {
                #fb
            }

            fn jacobians_lanes<const W: usize>(
                #jq: &[Lanes<W>; #nl],
                #jqd: &[Lanes<W>; #nl],
                #jp: &[Lanes<W>; #npl],
                k: &mut [[Lanes<W>; #nl]; #nl],
                d: &mut [[Lanes<W>; #nl]; #nl],
            ) {
                #jb
            }

            fn elastic_forces_lanes<const W: usize>(
                #efq: &[Lanes<W>; #nl],
                #efp: &[Lanes<W>; #npl],
                f: &mut [Lanes<W>; #nl],
            ) {
                #efb
            }

            fn elastic_stiffness_lanes<const W: usize>(
                #ekq: &[Lanes<W>; #nl],
                #ekp: &[Lanes<W>; #npl],
                k: &mut [[Lanes<W>; #nl]; #nl],
            ) {
                #ekb
            }

            fn mass(#mp: &[f64; #npl], m: &mut [[f64; #nl]; #nl]) {
                #mb
            }

            fn uniform_load(#lp: &[f64; #npl], #lw: &[f64; 3], f: &mut [f64; #nl]) {
                #lb
            }
        }

        #(#parts)*
    };
    let text = match syn::parse2::<syn::File>(tokens.clone()) {
        Ok(file) => prettyplease::unparse(&file),
        Err(e) => format!("// eom-gen: formatting failed ({e}); raw tokens follow\n{tokens}\n"),
    };
    module_doc + &text
}
