//! Batched emission: every generated function of the table also over
//! `W` lanes (`::eom_sim::Lanes<W>`, `W` states per call), from the same
//! lowered programs as the single-state methods (one lowering, `lower`,
//! with `Style::lanes`). Per function an associated function
//! `NAME_lanes::<W>(m: &[Self; W], args…, out: &mut [Lanes<W>; LEN])`
//! whose result is the flat layout of `eom_sim::Model::evaluate`; then
//! `eom_sim::Batched` (the dispatch by name) and `eom_sim::OdeLanes` (the
//! first-order system `y = (q, u)`) for the model.
//!
//! Lane `l` reads its tunable parameters, inputs and multipliers from
//! `m[l]`; time and every array argument are lanes. Nothing allocates or
//! panics: indices are constants into fixed-size arrays, and the lane
//! functions (`sin_cos` included, `eom_lanes::sincos`, with two tests a
//! vector) are lane-wise code that LLVM vectorises.

use super::lower::{Arg, Style, lower};
use super::{Binding, list};
use crate::functions::{Arg as FnArg, Function, Layout, TABLE};
use crate::mech::Formulation;
use crate::sym::{SymKind, Symbol};
use crate::system::System;
use proc_macro2::{Ident, Literal, TokenStream};
use quote::{format_ident, quote};

/// The batched functions, `eom_sim::Batched` and `eom_sim::OdeLanes` of
/// the model struct `ty`.
pub(super) fn emit(
    sys: &System,
    f: &Formulation,
    ty: &Ident,
    b: &Binding<'_>,
    fma: bool,
) -> TokenStream {
    let idx = Literal::usize_unsuffixed;
    let (nq, nu) = (sys.nq(), sys.nu());
    let (nq_l, nu_l) = (idx(nq), idx(nu));
    let lt = quote!(::eom_sim::Lanes);
    // Per-model values gathered from the lanes' models; the rest as in
    // the single-state functions.
    let input = |s: &Symbol| -> TokenStream {
        match s.kind {
            SymKind::Time => quote!(t),
            SymKind::Param | SymKind::Input | SymKind::Multiplier(_) => {
                let one = b.input(s);
                // `self.params.x` → `m[l].params.x`.
                let per_lane: TokenStream = one
                    .into_iter()
                    .map(|tt| match &tt {
                        proc_macro2::TokenTree::Ident(i) if i == "self" => quote!(m[l]),
                        _ => tt.into(),
                    })
                    .collect();
                quote!(#lt::<W>::from_fn(|l| #per_lane))
            }
            _ => b.input(s),
        }
    };
    let style = Style {
        input: &input,
        fma,
        lanes: Some(lt.clone()),
        sin_cos_together: false,
        methods: true,
    };
    let arg_m = || Arg {
        name: "m",
        ty: quote!(&[Self; W]),
        carries: Box::new(|s: &Symbol| {
            matches!(
                s.kind,
                SymKind::Param | SymKind::Input | SymKind::Multiplier(_)
            )
        }),
    };
    let arg = |a: &FnArg| -> Arg<'static> {
        let (n, ty) = match a {
            FnArg::T => ("t", quote!(#lt<W>)),
            FnArg::Q => ("q", quote!(&[#lt<W>; #nq_l])),
            FnArg::U => ("u", quote!(&[#lt<W>; #nu_l])),
            FnArg::Udot => ("udot", quote!(&[#lt<W>; #nu_l])),
            FnArg::Tau => ("tau", quote!(&[#lt<W>; #nu_l])),
        };
        let a = *a;
        Arg {
            name: n,
            ty,
            carries: Box::new(move |s: &Symbol| match a {
                FnArg::T => s.kind == SymKind::Time,
                FnArg::Q => matches!(s.kind, SymKind::Coord(_)),
                FnArg::U => matches!(s.kind, SymKind::Speed(_)),
                FnArg::Udot => matches!(s.kind, SymKind::SpeedRate(_)),
                FnArg::Tau => matches!(s.kind, SymKind::Tau(_)),
            }),
        }
    };
    let mut fns = TokenStream::new();
    let mut parts = TokenStream::new();
    let mut batched: Vec<(&crate::functions::Entry, usize)> = Vec::new();
    for e in TABLE {
        let Some(p) = f.program(e.function) else {
            continue;
        };
        let mut args = vec![arg_m()];
        args.extend(e.args.iter().map(arg));
        let name = format!("{}_lanes", e.name);
        let l = lower(&style, p, &name, &args);
        parts.extend(l.parts.clone());
        let len = f.result_len(e.function, nu);
        batched.push((e, len));
        let mut assign = TokenStream::new();
        match e.layout {
            Layout::Vector => {
                for (k, v) in l.outputs.iter().enumerate() {
                    let k = idx(k);
                    assign.extend(quote!(out[#k] = #v;));
                }
            }
            Layout::LowerTriangle => {
                let mut k = 0;
                for i in 0..nu {
                    for j in 0..=i {
                        let (a, v) = (idx(i * nu + j), &l.outputs[k]);
                        assign.extend(quote!(out[#a] = #v;));
                        if i != j {
                            let c = idx(j * nu + i);
                            assign.extend(quote!(out[#c] = out[#a];));
                        }
                        k += 1;
                    }
                }
            }
            Layout::Constraints => {
                let nc = f.constraint_names.len();
                for (k, v) in l.outputs.iter().enumerate() {
                    // Φ_i, Φ̇_i, γ_i per equation → Φ, Φ̇, γ; then J.
                    let a = if k < 3 * nc { (k % 3) * nc + k / 3 } else { k };
                    let a = idx(a);
                    assign.extend(quote!(out[#a] = #v;));
                }
            }
        }
        let params = l.params(&args);
        let body = &l.body;
        let n = format_ident!("{name}");
        let out = if len == 0 {
            format_ident!("_out")
        } else {
            format_ident!("out")
        };
        let len_l = idx(len);
        let args_doc = e
            .args
            .iter()
            .map(|a| format!("`{}`", a.name()))
            .collect::<Vec<_>>()
            .join(", ");
        let doc = format!(
            " `{}` of `W` states at once, one per lane ({} operations per state): {}. Arguments {args_doc} as `{}`'s, each number a `Lanes<W>` (entry `k`, lane `l`: entry `k` of state `l`); lane `l` reads parameters, inputs and multipliers from `m[l]`; `out` ({len} entries per lane) laid out as `Model::evaluate(\"{}\")`'s result.",
            e.name,
            p.op_count().total(),
            e.doc,
            e.name,
            e.name,
        );
        let products = super::lower::products(&style, p, &quote!(#out));
        fns.extend(quote! {
            #[doc = #doc]
            pub fn #n<const W: usize>(#params, #out: &mut [#lt<W>; #len_l]) {
                #body
                #assign
                #products
            }
        });
    }
    let nc = f.constraint_names.len();
    let arms = batched.iter().map(|(e, len)| {
        let name = e.name;
        let n = format_ident!("{}_lanes", e.name);
        let len_l = idx(*len);
        let fetch = e.args.iter().map(|a| match a {
            FnArg::T => quote!(let t = at.t;),
            FnArg::Q => quote!(let Some(q) = ::eom_sim::batch::__private::arg_lanes::<#nq_l, W>(at.q, false) else { return false };),
            FnArg::U => quote!(let Some(u) = ::eom_sim::batch::__private::arg_lanes::<#nu_l, W>(at.u, false) else { return false };),
            FnArg::Udot => quote!(let Some(udot) = ::eom_sim::batch::__private::arg_lanes::<#nu_l, W>(at.udot, true) else { return false };),
            FnArg::Tau => quote!(let Some(tau) = ::eom_sim::batch::__private::arg_lanes::<#nu_l, W>(at.tau, true) else { return false };),
        });
        let call_args = e.args.iter().map(|a| match a {
            FnArg::T => quote!(t),
            other => {
                let i = format_ident!("{}", other.name());
                quote!(&#i)
            }
        });
        let this = if e.uses_multipliers && nc > 0 {
            let nc_l = idx(nc);
            quote! {
                let Some(lambda) = ::eom_sim::batch::__private::arg_lanes::<#nc_l, W>(at.lambda, true) else { return false };
                let mut with_lambda = *models;
                for (l, m) in with_lambda.iter_mut().enumerate() {
                    m.multipliers = ::eom_sim::batch::__private::lane(&lambda, l);
                }
                let this = &with_lambda;
            }
        } else {
            quote!(let this = models;)
        };
        quote! {
            #name => {
                #(#fetch)*
                let Ok(out) = <&mut [#lt<W>; #len_l]>::try_from(out) else { return false };
                #this
                Self::#n(this, #(#call_args,)* out);
                true
            }
        }
    });
    let offered = list(&batched.iter().map(|(e, _)| e.name).collect::<Vec<_>>());
    let batched_doc = format!(" The batched functions by name: {offered}.");
    let ode = f.program(Function::ForwardDynamics).map(|_| {
        let ny_l = idx(nq + nu);
        let q_split = (0..nq).map(|k| {
            let k = idx(k);
            quote!(y[#k])
        });
        let u_split = (0..nu).map(|k| {
            let k = idx(nq + k);
            quote!(y[#k])
        });
        let dy_q = (0..nq).map(|k| {
            let kl = idx(k);
            quote!(dy[#kl] = qdot[#kl];)
        });
        let dy_u = (0..nu).map(|k| {
            let (kl, yl) = (idx(k), idx(nq + k));
            quote!(dy[#yl] = udot[#kl];)
        });
        let quats = sys.quaternion_indices();
        let project = if quats.is_empty() {
            quote! {
                fn project_lanes<const W: usize>(_models: &[Self; W], _y: &mut [#lt<W>; #ny_l]) -> bool {
                    false
                }
            }
        } else {
            let norms = quats.iter().map(|&a| {
                let i: Vec<Literal> = (a..a + 4).map(idx).collect();
                let (i0, i1, i2, i3) = (&i[0], &i[1], &i[2], &i[3]);
                quote! {
                    for l in 0..W {
                        let n = f64::sqrt(y[#i0].0[l] * y[#i0].0[l] + y[#i1].0[l] * y[#i1].0[l] + y[#i2].0[l] * y[#i2].0[l] + y[#i3].0[l] * y[#i3].0[l]);
                        if n > 0.0 && n.is_finite() {
                            y[#i0].0[l] /= n; y[#i1].0[l] /= n; y[#i2].0[l] /= n; y[#i3].0[l] /= n;
                        }
                    }
                }
            });
            quote! {
                fn project_lanes<const W: usize>(_models: &[Self; W], y: &mut [#lt<W>; #ny_l]) -> bool {
                    #(#norms)*
                    true
                }
            }
        };
        let doc = format!(
            " The first-order system `y = (q, u)` of `{}` ({} states) with `τ = 0`, `W` states per call.",
            sys.name,
            nq + nu
        );
        quote! {
            #[doc = #doc]
            impl ::eom_sim::OdeLanes<#ny_l> for #ty {
                fn rhs_lanes<const W: usize>(
                    models: &[Self; W],
                    t: #lt<W>,
                    y: &[#lt<W>; #ny_l],
                    dy: &mut [#lt<W>; #ny_l],
                ) {
                    let q: [#lt<W>; #nq_l] = [#(#q_split),*];
                    let u: [#lt<W>; #nu_l] = [#(#u_split),*];
                    let mut qdot = [#lt::<W>::splat(0.0); #nq_l];
                    let mut udot = [#lt::<W>::splat(0.0); #nu_l];
                    Self::qdot_lanes(models, &q, &u, &mut qdot);
                    Self::forward_dynamics_lanes(models, t, &q, &u, &[#lt::<W>::splat(0.0); #nu_l], &mut udot);
                    #(#dy_q)*
                    #(#dy_u)*
                }
                #project
            }
        }
    });
    let parts_doc = if parts.is_empty() {
        TokenStream::new()
    } else {
        quote! {
            /// Parts of the long batched functions (see `eom_gen::emit`).
            impl #ty {
                #parts
            }
        }
    };
    quote! {
        /// The generated functions over lanes: `W` states per call (see
        /// `eom_sim::batch`).
        impl #ty {
            #fns
        }

        #parts_doc

        #[doc = #batched_doc]
        impl ::eom_sim::Batched for #ty {
            fn evaluate_lanes<const W: usize>(
                models: &[Self; W],
                name: &str,
                at: &::eom_sim::PointLanes<'_, W>,
                out: &mut [#lt<W>],
            ) -> bool {
                match name {
                    #(#arms)*
                    _ => false,
                }
            }
        }

        #ode
    }
}
