//! Emission: [`Program`]s → Rust tokens (`quote`) → formatted source
//! (`prettyplease`).
//!
//! Per model the output holds a parameter struct (tunable parameters with
//! their defaults), the model struct (parameters and runtime inputs), an
//! implementation of `eom_sim::Model` and one of `eom_sim::OdeSystem` on the
//! state `y = (q, u)`. Every function is straight-line: one `let` per
//! instruction, constants inlined as unsuffixed literals (or `std` float
//! constants where they match one exactly), `sin_cos` for paired trig
//! (the inputs' together in one vectorised call where the build has
//! 256-bit vectors, `eom_sim::__private::sin_cos_lanes`), and
//! array indices that are compile-time constants into fixed-size arrays,
//! so nothing can panic or allocate. Functions a scene leaves out (mass
//! matrix, bias, inverse dynamics; see `model::scene::Function`) are
//! short loops over the generated ones on fixed-size arrays instead.
//! Output is byte-identical for identical input.

use crate::functions::{Arg as FnArg, Function, Layout, TABLE};
use crate::mech::Formulation;
use crate::sym::{SymKind, Symbol};
use lower::{Arg, Schedule, Style, lower};

mod batch;
mod loops;
pub(crate) mod lower;
mod names;
use crate::system::{Motion, System};
pub use loops::LoopChoice;
pub use lower::{BLOCK_LIMIT, DERIVATIVES_ONE_PART_LIMIT, ONE_PART_LIMIT, PART_LIMIT};
pub use names::{field_names, is_keyword, type_name};
use proc_macro2::{Ident, Literal, Span, TokenStream};
use quote::{format_ident, quote};

/// The generator's version, written into every generated file.
pub const VERSION: &str = env!("CARGO_PKG_VERSION");

/// How a program's inputs and outputs map to Rust.
struct Binding<'a> {
    sys: &'a System,
    /// Name of the `u̇` argument (`udot` in inverse dynamics).
    speed_rate: &'a str,
    /// Field of each tunable parameter in the parameter struct.
    fields: std::collections::HashMap<&'a str, Ident>,
}

/// Emission options.
#[derive(Clone, Debug, Default)]
pub struct EmitOptions {
    /// Name of the model struct (default: the model name in CamelCase).
    pub type_name: Option<String>,
    /// Emit `f64::mul_add(a, b, c)` for `a·b + c` where the product is used
    /// only there: one rounding and a shorter dependency chain. Worth it
    /// only when compiling with FMA (`-C target-feature=+fma` or a
    /// `target-cpu` that has it); otherwise `mul_add` is a libm call.
    pub fma: bool,
    /// Emit forward dynamics, the mass matrix, the bias and inverse
    /// dynamics of long chains as loops over body steps
    /// (`eom_gen::mech::looped`): where they pay (default), always (where
    /// the model is such a chain) or never.
    pub loops: LoopChoice,
    /// Also emit every generated function over lanes, `W` states per call
    /// (`NAME_lanes::<W>`, `eom_sim::Batched`, `eom_sim::OdeLanes`; see
    /// `emit::batch`). Off by default: it doubles the source a model
    /// compiles from.
    pub lanes: bool,
}

impl Binding<'_> {
    fn input(&self, s: &Symbol) -> TokenStream {
        let idx = |i: u32| Literal::usize_unsuffixed(i as usize);
        match s.kind {
            SymKind::Coord(i) => {
                let i = idx(i);
                quote!(q[#i])
            }
            SymKind::Speed(i) => {
                let i = idx(i);
                quote!(u[#i])
            }
            SymKind::SpeedRate(i) => {
                let i = idx(i);
                let name = Ident::new(self.speed_rate, Span::call_site());
                quote!(#name[#i])
            }
            SymKind::CoordRate(i) => {
                let i = idx(i);
                quote!(qdot[#i])
            }
            SymKind::Time => quote!(t),
            SymKind::Param => {
                let name = self
                    .fields
                    .get(s.name.as_str())
                    .cloned()
                    .unwrap_or_else(|| names::ident(&names::field_names([s.name.as_str()])[0]));
                quote!(self.params.#name)
            }
            // Formulation declares only the model's inputs as inputs; any
            // other would be a generator bug, and fails to compile loudly.
            SymKind::Input => match self.sys.inputs.iter().position(|n| *n == s.name) {
                Some(k) => {
                    let k = Literal::usize_unsuffixed(k);
                    quote!(self.inputs[#k])
                }
                None => {
                    let msg = format!("eom-gen: `{}` is not an input of the model", s.name);
                    quote!(::core::compile_error!(#msg))
                }
            },
            SymKind::Multiplier(i) => {
                let i = idx(i);
                quote!(self.multipliers[#i])
            }
            SymKind::Tau(i) => {
                let i = idx(i);
                quote!(tau[#i])
            }
        }
    }
}

/// A float literal (unsuffixed), a `std` constant it equals exactly, or a
/// negated one.
pub(crate) fn float(x: f64) -> TokenStream {
    use std::f64::consts as c;
    // Formulation refuses programs with such constants
    // (`FormulateError::NotFinite`), but emission never panics:
    // `proc_macro2` refuses non-finite literals.
    if x.is_nan() {
        return quote!(::core::f64::NAN);
    } else if x.is_infinite() {
        return if x > 0.0 {
            quote!(::core::f64::INFINITY)
        } else {
            quote!((-::core::f64::INFINITY))
        };
    }
    let named: [(f64, &str); 18] = [
        (c::PI, "PI"),
        (c::TAU, "TAU"),
        (c::FRAC_PI_2, "FRAC_PI_2"),
        (c::FRAC_PI_3, "FRAC_PI_3"),
        (c::FRAC_PI_4, "FRAC_PI_4"),
        (c::FRAC_PI_6, "FRAC_PI_6"),
        (c::FRAC_PI_8, "FRAC_PI_8"),
        (c::FRAC_1_PI, "FRAC_1_PI"),
        (c::FRAC_2_PI, "FRAC_2_PI"),
        (c::FRAC_2_SQRT_PI, "FRAC_2_SQRT_PI"),
        (c::SQRT_2, "SQRT_2"),
        (c::FRAC_1_SQRT_2, "FRAC_1_SQRT_2"),
        (c::E, "E"),
        (c::LOG2_E, "LOG2_E"),
        (c::LOG10_E, "LOG10_E"),
        (c::LN_2, "LN_2"),
        (c::LN_10, "LN_10"),
        (c::LOG2_10, "LOG2_10"),
    ];
    let magnitude = x.abs();
    let body = match named.iter().find(|(v, _)| *v == magnitude) {
        Some((_, name)) => {
            let name = format_ident!("{name}");
            quote!(::core::f64::consts::#name)
        }
        None => {
            let lit = Literal::f64_unsuffixed(magnitude);
            quote!(#lit)
        }
    };
    if x.is_sign_negative() && x != 0.0 {
        quote!(-#body)
    } else {
        body
    }
}

/// [`float`] in operand position: negative values in parentheses.
pub(crate) fn float_operand(x: f64) -> TokenStream {
    let f = float(x);
    if x.is_sign_negative() && x != 0.0 {
        quote!((#f))
    } else {
        f
    }
}

fn tmp(i: u32) -> Ident {
    format_ident!("x{i}")
}

/// The model struct's name for the model name `name`: `Name` from
/// `snake_name`, always a valid non-keyword identifier (see
/// [`type_name`]).
pub fn camel(name: &str) -> String {
    type_name(name)
}

/// A 64-bit FNV-1a hash, for the content hash in the header.
pub fn fnv1a(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |h, &b| {
        (h ^ u64::from(b)).wrapping_mul(0x0000_0100_0000_01b3)
    })
}

fn list(names: &[&str]) -> String {
    names
        .iter()
        .map(|n| format!("`{n}`"))
        .collect::<Vec<_>>()
        .join(", ")
}

/// Emits the formatted Rust source of one model; `source_text` is the
/// model file's text, hashed into the doc comment with the generator
/// version.
pub fn emit(sys: &System, f: &Formulation, source_text: &str) -> String {
    emit_with(sys, f, source_text, &EmitOptions::default())
}

/// [`emit`] with options.
pub fn emit_with(sys: &System, f: &Formulation, source_text: &str, opts: &EmitOptions) -> String {
    let tokens = emit_tokens(sys, f, source_text, opts);
    match syn::parse2::<syn::File>(tokens.clone()) {
        Ok(file) => prettyplease::unparse(&file),
        // Unreachable for well-formed programs; keep the raw tokens visible.
        Err(e) => format!("// eom-gen: formatting failed ({e}); raw tokens follow\n{tokens}\n"),
    }
}

/// The tokens of [`emit`], unformatted; `type_name` replaces the model
/// struct's name (`#[multibody]` uses the annotated struct's).
pub fn emit_tokens(
    sys: &System,
    f: &Formulation,
    source_text: &str,
    opts: &EmitOptions,
) -> TokenStream {
    let type_name = opts.type_name.as_deref();
    let name = &sys.name;
    let base = type_name.map_or_else(|| camel(name), str::to_string);
    // `type_name` comes from the user's struct (`#[multibody]`); anything
    // else from the model name, made an identifier.
    let base = if syn::parse_str::<syn::Ident>(&base).is_ok() {
        base
    } else {
        names::type_name(&base)
    };
    let ty = format_ident!("{base}");
    let params_ty = format_ident!("{base}Params");
    let (nq, nu, ni) = (sys.nq(), sys.nu(), sys.inputs.len());
    let (nq_l, nu_l, ni_l, ny_l) = (
        Literal::usize_unsuffixed(nq),
        Literal::usize_unsuffixed(nu),
        Literal::usize_unsuffixed(ni),
        Literal::usize_unsuffixed(nq + nu),
    );
    let hash = format!(
        "{:016x}",
        fnv1a(format!("{VERSION}\n{source_text}").as_bytes())
    );
    let coords = sys.coordinate_names();
    let speeds = sys.speed_names();
    let inputs: Vec<&str> = sys.inputs.iter().map(String::as_str).collect();
    let quats: Vec<usize> = sys.quaternion_indices();
    let quats_l = quats.iter().map(|&k| Literal::usize_unsuffixed(k));
    let q0 = sys.q0().into_iter().map(float);
    let u0 = sys.u0().into_iter().map(float);
    let tunable: Vec<_> = sys.parameters.iter().filter(|p| p.tunable).collect();
    let field_idents: Vec<Ident> = names::field_names(tunable.iter().map(|p| p.name.as_str()))
        .iter()
        .map(|n| names::ident(n))
        .collect();
    let fields: std::collections::HashMap<&str, Ident> = tunable
        .iter()
        .zip(&field_idents)
        .map(|(p, i)| (p.name.as_str(), i.clone()))
        .collect();
    let param_fields = tunable.iter().zip(&field_idents).map(|(p, n)| {
        let doc = match &p.doc {
            Some(text) => format!(" `{}` (default {}): {text}", p.name, p.value.value),
            None => format!(" `{}` (default {}).", p.name, p.value.value),
        };
        quote!(#[doc = #doc] pub #n: f64,)
    });
    let param_defaults = tunable.iter().zip(&field_idents).map(|(p, n)| {
        let v = float(p.value.value);
        quote!(#n: #v,)
    });
    let locked: Vec<&str> = sys
        .joints
        .iter()
        .filter(|j| j.motion == Motion::Locked)
        .map(|j| j.name.as_str())
        .collect();
    let prescribed: Vec<&str> = sys
        .joints
        .iter()
        .filter(|j| matches!(j.motion, Motion::Prescribed(_)))
        .map(|j| j.name.as_str())
        .collect();

    let b = Binding {
        sys,
        speed_rate: "udot",
        fields,
    };
    let input = |s: &Symbol| b.input(s);
    let style = Style {
        input: &input,
        fma: opts.fma,
        lanes: None,
        sin_cos_together: true,
        methods: true,
    };
    let q_doc = format!("`q` = ({})", list(&coords));
    let u_doc = format!("`u` = ({})", list(&speeds));
    let arg_t = || Arg {
        name: "t",
        ty: quote!(f64),
        carries: Box::new(|s: &Symbol| s.kind == SymKind::Time),
    };
    let arg_q = || Arg {
        name: "q",
        ty: quote!(&[f64; #nq_l]),
        carries: Box::new(|s: &Symbol| matches!(s.kind, SymKind::Coord(_))),
    };
    let arg_u = || Arg {
        name: "u",
        ty: quote!(&[f64; #nu_l]),
        carries: Box::new(|s: &Symbol| matches!(s.kind, SymKind::Speed(_))),
    };
    let arg_tau = || Arg {
        name: "tau",
        ty: quote!(&[f64; #nu_l]),
        carries: Box::new(|s: &Symbol| matches!(s.kind, SymKind::Tau(_))),
    };
    let arg_udot = || Arg {
        name: "udot",
        ty: quote!(&[f64; #nu_l]),
        carries: Box::new(|s: &Symbol| matches!(s.kind, SymKind::SpeedRate(_))),
    };
    let mut parts = TokenStream::new();
    let idx = Literal::usize_unsuffixed;
    // An output array of length zero (a model without coordinates) is
    // never written: its name gets a `_` prefix.
    let out_arg = |name: &str, len: usize| {
        if len == 0 {
            format_ident!("_{name}")
        } else {
            format_ident!("{name}")
        }
    };
    let (qdot_out, udot_out, m_out, b_out, tau_out) = (
        out_arg("qdot", nq),
        out_arg("udot", nu),
        out_arg("m", nu),
        out_arg("b", nu),
        out_arg("tau", nu),
    );
    // Assignments `out[k] = value;` for the outputs of a lowered program.
    let assign_all = |out: &str, values: &[TokenStream]| -> TokenStream {
        let out = format_ident!("{out}");
        let items = values.iter().enumerate().map(|(k, v)| {
            let k = idx(k);
            quote!(#out[#k] = #v;)
        });
        quote!(#(#items)*)
    };

    // Long chains as loops, where chosen: these functions are not lowered
    // straight.
    let chain_loops = match opts.loops {
        LoopChoice::Never => None,
        LoopChoice::Auto => f.loops.clone(),
        LoopChoice::Always => f.loops.clone().or_else(|| {
            crate::mech::looped::ChainLoops::build(sys, f.functions().collect())
                .ok()
                .flatten()
        }),
    };
    let straight_ops: Vec<(Function, usize)> = crate::mech::looped::LOOPED
        .iter()
        .filter_map(|&g| f.program(g).map(|p| (g, p.op_count().total())))
        .collect();
    let mut looped: std::collections::BTreeMap<Function, loops::Looped> = chain_loops
        .as_ref()
        .map(|cl| loops::looped(cl, &straight_ops, opts.loops, opts.fma))
        .unwrap_or_default()
        .into_iter()
        .collect();
    let mut loop_items = TokenStream::new();
    let mut take_loop = |g: Function| {
        looped.remove(&g).map(|l| {
            loop_items.extend(l.items);
            l.method
        })
    };
    let fd_loop = take_loop(Function::ForwardDynamics);
    let mm_loop = take_loop(Function::MassMatrix);
    let bias_loop = take_loop(Function::Bias);
    let id_loop = take_loop(Function::InverseDynamics);

    // q̇ = N(q) u
    let args = [arg_q(), arg_u()];
    let Some(qdot_program) = f.program(Function::Qdot) else {
        return quote!(::core::compile_error!("eom-gen: the formulation has no q̇ program"););
    };
    let dest = lower::Dest::flat(&qdot_out, nq);
    let l = lower::lower_into(
        &style,
        qdot_program,
        "qdot",
        &args,
        lower::PART_LIMIT,
        &dest,
        Schedule::Late,
    );
    parts.extend(l.parts.clone());
    let (params, body, assign) = (l.params(&args), &l.body, &l.assign);
    let qdot_fn = quote! {
        fn qdot(&self, #params, #qdot_out: &mut [f64; #nq_l]) {
            #body
            #assign
        }
    };

    let fd_straight = f
        .program(Function::ForwardDynamics)
        .filter(|_| fd_loop.is_none());
    let fd_fn = fd_straight.map(|p| {
        let args = [arg_t(), arg_q(), arg_u(), arg_tau()];
        let dest = lower::Dest::flat(&udot_out, nu);
        let limit = lower::part_limit(&style, p, ONE_PART_LIMIT);
        let l = lower::lower_into(
            &style,
            p,
            "forward_dynamics",
            &args,
            limit,
            &dest,
            Schedule::Late,
        );
        parts.extend(l.parts.clone());
        let (params, body, assign) = (l.params(&args), &l.body, &l.assign);
        let doc = format!(
            " Forward dynamics by the {} ({} operations): `u̇ = M⁻¹ (τ − b)`.",
            f.fd_form,
            p.op_count().total()
        );
        quote! {
            #[doc = #doc]
            fn forward_dynamics(&self, #params, #udot_out: &mut [f64; #nu_l]) {
                #body
                #assign
            }
        }
    });
    let fd_fn = fd_loop.or(fd_fn);
    let mm_straight = f
        .program(Function::MassMatrix)
        .filter(|_| mm_loop.is_none());
    let mm_fn = mm_straight.map(|p| {
        let args = [arg_t(), arg_q()];
        // Output `k` is entry `(i, j)` of the lower triangle by rows,
        // stored to both triangles.
        let lower_triangle: Vec<(usize, usize)> =
            (0..nu).flat_map(|i| (0..=i).map(move |j| (i, j))).collect();
        let store = move |k: usize, v: &TokenStream| {
            let (i, j) = lower_triangle[k];
            let (il, jl) = (idx(i), idx(j));
            if i == j {
                quote!(m[#il][#jl] = #v;)
            } else {
                quote!(m[#il][#jl] = #v; m[#jl][#il] = m[#il][#jl];)
            }
        };
        let dest = lower::Dest {
            name: m_out.clone(),
            ty: quote!(&mut [[f64; #nu_l]; #nu_l]),
            assign: Box::new(store),
        };
        let l = lower::lower_into(
            &style,
            p,
            "mass_matrix",
            &args,
            lower::PART_LIMIT,
            &dest,
            Schedule::Late,
        );
        parts.extend(l.parts.clone());
        let (params, body, assign) = (l.params(&args), &l.body, &l.assign);
        quote! {
            fn mass_matrix(&self, #params, #m_out: &mut [[f64; #nu_l]; #nu_l]) {
                #body
                #assign
            }
        }
    });
    let mm_fn = mm_loop.or(mm_fn);
    let bias_straight = f.program(Function::Bias).filter(|_| bias_loop.is_none());
    let bias_fn = bias_straight.map(|p| {
        let args = [arg_t(), arg_q(), arg_u()];
        let dest = lower::Dest::flat(&b_out, nu);
        let l = lower::lower_into(
            &style,
            p,
            "bias",
            &args,
            lower::PART_LIMIT,
            &dest,
            Schedule::Late,
        );
        parts.extend(l.parts.clone());
        let (params, body, assign) = (l.params(&args), &l.body, &l.assign);
        quote! {
            fn bias(&self, #params, #b_out: &mut [f64; #nu_l]) {
                #body
                #assign
            }
        }
    });
    let bias_fn = bias_loop.or(bias_fn);
    let id_straight = f
        .program(Function::InverseDynamics)
        .filter(|_| id_loop.is_none());
    let id_fn = id_straight.map(|p| {
        let args = [arg_t(), arg_q(), arg_u(), arg_udot()];
        let dest = lower::Dest::flat(&tau_out, nu);
        let limit = lower::part_limit(&style, p, ONE_PART_LIMIT);
        let l = lower::lower_into(
            &style,
            p,
            "inverse_dynamics",
            &args,
            limit,
            &dest,
            Schedule::Late,
        );
        parts.extend(l.parts.clone());
        let (params, body, assign) = (l.params(&args), &l.body, &l.assign);
        quote! {
            fn inverse_dynamics(&self, #params, #tau_out: &mut [f64; #nu_l]) {
                #body
                #assign
            }
        }
    });
    let id_fn = id_loop.or(id_fn);
    // Functions the scene leaves out, computed from the generated ones
    // (formulate guarantees inverse dynamics, or both M and b).
    let mm_fn = mm_fn.unwrap_or_else(|| {
        let doc = format!(
            " Mass matrix, derived (not generated symbolically: the scene leaves it out): column `i` is `ID(q, 0, e_i) − ID(q, 0, 0)` ({} inverse-dynamics calls at zero speed), then symmetrised.",
            nu + 1
        );
        quote! {
            #[doc = #doc]
            #[allow(clippy::needless_range_loop, clippy::reversed_empty_ranges)]
            fn mass_matrix(&self, t: f64, q: &[f64; #nq_l], m: &mut [[f64; #nu_l]; #nu_l]) {
                let zero = [0.0; #nu_l];
                let mut tau0 = [0.0; #nu_l];
                self.inverse_dynamics(t, q, &zero, &zero, &mut tau0);
                let mut e = [0.0; #nu_l];
                let mut column = [0.0; #nu_l];
                for i in 0..#nu_l {
                    e[i] = 1.0;
                    self.inverse_dynamics(t, q, &zero, &e, &mut column);
                    e[i] = 0.0;
                    for r in 0..#nu_l {
                        m[r][i] = column[r] - tau0[r];
                    }
                }
                for i in 0..#nu_l {
                    for j in 0..i {
                        let s = 0.5 * (m[i][j] + m[j][i]);
                        m[i][j] = s;
                        m[j][i] = s;
                    }
                }
            }
        }
    });
    let bias_fn = bias_fn.unwrap_or_else(|| {
        quote! {
            /// Bias, derived (not generated symbolically: the scene leaves it
            /// out): inverse dynamics at zero acceleration, `b = ID(q, u, 0)`.
            fn bias(&self, t: f64, q: &[f64; #nq_l], u: &[f64; #nu_l], b: &mut [f64; #nu_l]) {
                self.inverse_dynamics(t, q, u, &[0.0; #nu_l], b);
            }
        }
    });
    let id_fn = id_fn.unwrap_or_else(|| {
        quote! {
            /// Inverse dynamics, derived (not generated symbolically: the
            /// scene leaves it out): `τ = M(q) u̇ + b(q, u, t)`.
            fn inverse_dynamics(&self, t: f64, q: &[f64; #nq_l], u: &[f64; #nu_l], udot: &[f64; #nu_l], tau: &mut [f64; #nu_l]) {
                let mut m = [[0.0; #nu_l]; #nu_l];
                self.mass_matrix(t, q, &mut m);
                self.bias(t, q, u, tau);
                for (tau_i, row) in tau.iter_mut().zip(&m) {
                    *tau_i += row.iter().zip(udot).map(|(a, b)| a * b).sum::<f64>();
                }
            }
        }
    });
    let energy_fn = f.program(Function::Energy).map(|p| {
        let args = [arg_t(), arg_q(), arg_u()];
        let l = lower(&style, p, "energy", &args);
        parts.extend(l.parts.clone());
        let (params, body, o) = (l.params(&args), &l.body, &l.outputs);
        let (k0, k1) = (&o[0], &o[1]);
        quote! {
            fn energy(&self, #params) -> [f64; 2] {
                #body
                [#k0, #k1]
            }
        }
    });
    let momentum_fn = f.program(Function::Momentum).map(|p| {
        let args = [arg_t(), arg_q(), arg_u()];
        let l = lower(&style, p, "momentum", &args);
        parts.extend(l.parts.clone());
        let (params, body, o) = (l.params(&args), &l.body, &l.outputs);
        quote! {
            fn momentum(&self, #params) -> [f64; 6] {
                #body
                [#(#o),*]
            }
        }
    });
    let output_names: Vec<String> = f.output_names.clone();
    let nout_l = idx(output_names.len());
    let outputs_fn = match f.program(Function::Outputs) {
        Some(p) => {
            let args = [arg_t(), arg_q(), arg_u(), arg_udot()];
            let l = lower(&style, p, "outputs", &args);
            parts.extend(l.parts.clone());
            let (params, body, assign) = (l.params(&args), &l.body, assign_all("out", &l.outputs));
            quote! {
                fn outputs(&self, #params, out: &mut [f64; #nout_l]) {
                    #body
                    #assign
                }
            }
        }
        None => quote! {
            fn outputs(&self, _t: f64, _q: &[f64; #nq_l], _u: &[f64; #nu_l], _udot: &[f64; #nu_l], _out: &mut [f64; 0]) {}
        },
    };
    let constrained_impl = f.program(Function::Constraints).map(|p| {
        let args = [arg_t(), arg_q(), arg_u()];
        let l = lower(&style, p, "constraints", &args);
        parts.extend(l.parts.clone());
        let params = l.params(&args);
        let body = &l.body;
        let nc = f.constraint_names.len();
        let mut assign = TokenStream::new();
        // Layout::Constraints: Φ_i, Φ̇_i, γ_i per equation, then J by rows.
        for (k, v) in l.outputs.iter().enumerate() {
            let target = if k < 3 * nc {
                let array = format_ident!("{}", ["phi", "phidot", "gamma"][k % 3]);
                let i = idx(k / 3);
                quote!(#array[#i])
            } else {
                let j = idx(k - 3 * nc);
                quote!(jacobian[#j])
            };
            assign.extend(quote!(#target = #v;));
        }
        let (nc_l, nh_l, ncj_l) = (idx(nc), idx(f.n_holonomic), idx(nc * nu));
        let names = f.constraint_names.iter();
        let doc = format!(
            " {nc} constraint equation(s), the first {} holonomic: {}. `J` is by rows ({nc} × {nu}).",
            f.n_holonomic,
            list(&f.constraint_names.iter().map(String::as_str).collect::<Vec<_>>())
        );
        quote! {
            #[doc = #doc]
            impl ::eom_sim::ConstrainedModel for #ty {
                const NC: usize = #nc_l;
                const NHOLONOMIC: usize = #nh_l;
                const CONSTRAINT_NAMES: &'static [&'static str] = &[#(#names),*];
                type Constraints = [f64; #nc_l];
                type ConstraintJacobian = [f64; #ncj_l];
                fn set_multipliers(&mut self, lambda: &[f64; #nc_l]) {
                    self.multipliers = *lambda;
                }
                fn constraints(
                    &self,
                    #params,
                    phi: &mut [f64; #nc_l],
                    phidot: &mut [f64; #nc_l],
                    gamma: &mut [f64; #nc_l],
                    jacobian: &mut [f64; #ncj_l],
                ) {
                    #body
                    #assign
                }
            }
        }
    });
    // A model without constraint equations is a constrained one with none,
    // so that one runner serves every model.
    let constrained_impl = constrained_impl.unwrap_or_else(|| {
        quote! {
            /// No constraint equations.
            impl ::eom_sim::ConstrainedModel for #ty {
                const NC: usize = 0;
                const NHOLONOMIC: usize = 0;
                const CONSTRAINT_NAMES: &'static [&'static str] = &[];
                type Constraints = [f64; 0];
                type ConstraintJacobian = [f64; 0];
                fn set_multipliers(&mut self, _lambda: &[f64; 0]) {}
                fn constraints(
                    &self,
                    _t: f64,
                    _q: &[f64; #nq_l],
                    _u: &[f64; #nu_l],
                    _phi: &mut [f64; 0],
                    _phidot: &mut [f64; 0],
                    _gamma: &mut [f64; 0],
                    _jacobian: &mut [f64; 0],
                ) {
                }
            }
        }
    });
    // The functions without a method of their own in the model trait, as
    // inherent methods (see `crate::functions::TABLE`).
    let mut inherent = TokenStream::new();
    for e in TABLE.iter().filter(|e| !e.in_trait) {
        let Some(p) = f.program(e.function) else {
            continue;
        };
        let args: Vec<Arg> = e
            .args
            .iter()
            .map(|a| match a {
                FnArg::T => arg_t(),
                FnArg::Q => arg_q(),
                FnArg::U => arg_u(),
                FnArg::Udot => arg_udot(),
                FnArg::Tau => arg_tau(),
            })
            .collect();
        let derivatives = matches!(
            e.function,
            Function::ForwardDynamicsDerivatives | Function::InverseDynamicsDerivatives
        );
        // Derivatives up to their own limit are one function, depth first.
        let (whole, schedule) = if derivatives {
            (DERIVATIVES_ONE_PART_LIMIT, Schedule::DepthFirst)
        } else {
            (0, Schedule::Late)
        };
        let limit = lower::part_limit(&style, p, whole);
        let out = out_arg("out", p.outputs.len());
        let len = idx(p.outputs.len());
        let dest = lower::Dest::flat(&out, p.outputs.len());
        let l = lower::lower_into(&style, p, e.name, &args, limit, &dest, schedule);
        parts.extend(l.parts.clone());
        let (params, body, assign) = (l.params(&args), &l.body, &l.assign);
        let n = format_ident!("{}", e.name);
        let labels = list(
            &f.labels(e.function)
                .iter()
                .map(String::as_str)
                .collect::<Vec<_>>(),
        );
        let doc = format!(
            " {}{} ({} operations){}.",
            e.doc[..1].to_uppercase(),
            &e.doc[1..],
            p.op_count().total(),
            if labels.is_empty() {
                String::new()
            } else {
                format!("; {labels}")
            }
        );
        let lambda_doc = if e.uses_multipliers {
            quote!(#[doc = " Reads the multipliers `λ` from the `multipliers` field."])
        } else {
            TokenStream::new()
        };
        let products = lower::products(&style, p, &quote!(#out));
        inherent.extend(quote! {
            #[doc = #doc]
            #lambda_doc
            pub fn #n(&self, #params, #out: &mut [f64; #len]) {
                #body
                #assign
                #products
            }
        });
    }
    let inherent_impl = if inherent.is_empty() {
        TokenStream::new()
    } else {
        quote! {
            /// Generated functions beyond the model trait's.
            impl #ty {
                #inherent
            }
        }
    };
    let (functions_const, evaluate_fn) = evaluate_dispatch(sys, f);
    let batched = if opts.lanes {
        batch::emit(sys, f, &ty, &b, opts.fma)
    } else {
        TokenStream::new()
    };
    let (multipliers_field, multipliers_default) = if f.constraint_names.is_empty() {
        (TokenStream::new(), TokenStream::new())
    } else {
        let nc_l = idx(f.constraint_names.len());
        (
            quote! {
                /// Constraint multipliers `λ` (`CONSTRAINT_NAMES` order) that
                /// `outputs` uses for joint reactions in closed loops; the
                /// constraint solvers' `accelerations` give them.
                pub multipliers: [f64; #nc_l],
            },
            quote!(multipliers: [0.0; #nc_l],),
        )
    };
    let output_names_l = output_names.iter();
    let loops_impl = if loop_items.is_empty() {
        TokenStream::new()
    } else {
        quote! {
            /// Body steps and class tables of the functions emitted as loops
            /// over the chain's bodies (see `eom_gen::mech::looped`).
            impl #ty {
                #loop_items
            }
        }
    };
    let parts_impl = if parts.is_empty() {
        TokenStream::new()
    } else {
        quote! {
            /// Parts of the long generated functions (see `eom_gen::emit`).
            impl #ty {
                #parts
            }
        }
    };

    let doc_top = format!(
        " Model `{name}`: {nq} coordinate(s), {nu} speed(s), {ni} input(s). Generated by eom-gen {VERSION}; model content hash {hash}."
    );
    let doc_layout = format!(
        " State layout: {q_doc}; {u_doc}; inputs ({}). Locked joints: {}. Prescribed joints: {}. Equations: `q̇ = N(q) u`, `M(q) u̇ = τ − b(q, u, t)`.",
        if inputs.is_empty() {
            "none".to_string()
        } else {
            list(&inputs)
        },
        if locked.is_empty() {
            "none".to_string()
        } else {
            list(&locked)
        },
        if prescribed.is_empty() {
            "none".to_string()
        } else {
            list(&prescribed)
        },
    );
    let ode_doc = format!(
        " The first-order system `y = (q, u)` of `{name}` ({} states) with `τ = 0`.",
        nq + nu
    );
    let params_doc = format!(" Tunable parameters of `{name}`, defaults from the model file.");
    let q_split = (0..nq).map(|k| {
        let kl = Literal::usize_unsuffixed(k);
        quote!(y[#kl])
    });
    let u_split = (0..nu).map(|k| {
        let yl = Literal::usize_unsuffixed(nq + k);
        quote!(y[#yl])
    });
    let dy_q = (0..nq).map(|k| {
        let kl = Literal::usize_unsuffixed(k);
        quote!(dy[#kl] = qdot[#kl];)
    });
    let dy_u = (0..nu).map(|k| {
        let (kl, yl) = (
            Literal::usize_unsuffixed(k),
            Literal::usize_unsuffixed(nq + k),
        );
        quote!(dy[#yl] = udot[#kl];)
    });
    let project_body = if quats.is_empty() {
        quote!(let _ = y; false)
    } else {
        let norms = quats.iter().map(|&a| {
            let idx: Vec<Literal> = (a..a + 4).map(Literal::usize_unsuffixed).collect();
            let (i0, i1, i2, i3) = (&idx[0], &idx[1], &idx[2], &idx[3]);
            quote! {
                let n = f64::sqrt(y[#i0] * y[#i0] + y[#i1] * y[#i1] + y[#i2] * y[#i2] + y[#i3] * y[#i3]);
                if n > 0.0 && n.is_finite() {
                    y[#i0] /= n; y[#i1] /= n; y[#i2] /= n; y[#i3] /= n;
                }
            }
        });
        quote!(#(#norms)* true)
    };
    let (y_in, dy_out) = (out_arg("y", nq + nu), out_arg("dy", nq + nu));
    let coords_l = coords.iter();
    let speeds_l = speeds.iter();
    let inputs_l = inputs.iter();
    let params_item = if tunable.is_empty() {
        quote! {
            #[doc = #params_doc]
            #[derive(Clone, Copy, Debug, Default, PartialEq)]
            pub struct #params_ty {}
        }
    } else {
        quote! {
            #[doc = #params_doc]
            #[derive(Clone, Copy, Debug, PartialEq)]
            pub struct #params_ty {
                #(#param_fields)*
            }

            impl Default for #params_ty {
                fn default() -> Self {
                    #params_ty { #(#param_defaults)* }
                }
            }
        }
    };
    quote! {
        #params_item

        #[doc = #doc_top]
        #[doc = ""]
        #[doc = #doc_layout]
        #[derive(Clone, Copy, Debug, PartialEq)]
        pub struct #ty {
            /// Tunable parameters.
            pub params: #params_ty,
            /// Runtime inputs (actuator commands), in `INPUT_NAMES` order.
            pub inputs: [f64; #ni_l],
            #multipliers_field
        }

        impl Default for #ty {
            fn default() -> Self {
                #ty { params: #params_ty::default(), inputs: [0.0; #ni_l], #multipliers_default }
            }
        }

        impl ::eom_sim::Model for #ty {
            const NAME: &'static str = #name;
            const NQ: usize = #nq_l;
            const NU: usize = #nu_l;
            const NINPUTS: usize = #ni_l;
            const COORDINATE_NAMES: &'static [&'static str] = &[#(#coords_l),*];
            const SPEED_NAMES: &'static [&'static str] = &[#(#speeds_l),*];
            const INPUT_NAMES: &'static [&'static str] = &[#(#inputs_l),*];
            const QUATERNIONS: &'static [usize] = &[#(#quats_l),*];
            const OUTPUT_NAMES: &'static [&'static str] = &[#(#output_names_l),*];
            type Q = [f64; #nq_l];
            type U = [f64; #nu_l];
            type Inputs = [f64; #ni_l];
            type Outputs = [f64; #nout_l];
            type MassMatrix = [[f64; #nu_l]; #nu_l];
            const MASS_ZERO: [[f64; #nu_l]; #nu_l] = [[0.0; #nu_l]; #nu_l];

            fn q0(&self) -> [f64; #nq_l] {
                [#(#q0),*]
            }
            fn u0(&self) -> [f64; #nu_l] {
                [#(#u0),*]
            }
            #qdot_fn
            #fd_fn
            #mm_fn
            #bias_fn
            #id_fn
            #energy_fn
            #momentum_fn
            #outputs_fn
            #functions_const
            #evaluate_fn
        }

        #constrained_impl

        #inherent_impl

        #parts_impl

        #loops_impl
        #batched

        #[doc = #ode_doc]
        impl ::eom_sim::OdeSystem<#ny_l> for #ty {
            fn rhs(&self, t: f64, #y_in: &[f64; #ny_l], #dy_out: &mut [f64; #ny_l]) {
                use ::eom_sim::Model as _;
                let q: [f64; #nq_l] = [#(#q_split),*];
                let u: [f64; #nu_l] = [#(#u_split),*];
                let mut qdot = [0.0; #nq_l];
                let mut udot = [0.0; #nu_l];
                self.qdot(&q, &u, &mut qdot);
                self.forward_dynamics(t, &q, &u, &[0.0; #nu_l], &mut udot);
                #(#dy_q)*
                #(#dy_u)*
            }
            fn project(&self, _t: f64, y: &mut [f64; #ny_l]) -> bool {
                #project_body
            }
        }
    }
}

/// Every function the model offers through `eom_sim::Model::evaluate`:
/// those generated and those derived from them, with their result lengths.
fn offered(sys: &System, f: &Formulation) -> Vec<(&'static crate::functions::Entry, usize)> {
    use crate::functions::When;
    let nu = sys.nu();
    TABLE
        .iter()
        .filter_map(|e| {
            let len = match f.program(e.function) {
                Some(_) => f.result_len(e.function, nu),
                // Derived from the generated ones (see `emit_tokens`).
                None if e.when == When::Requested => match e.layout {
                    Layout::LowerTriangle => nu * nu,
                    _ => nu,
                },
                None => return None,
            };
            Some((e, len))
        })
        .collect()
}

/// `const FUNCTIONS` and `fn evaluate` of the model trait, from the table.
fn evaluate_dispatch(sys: &System, f: &Formulation) -> (TokenStream, TokenStream) {
    let (nq, nu, nc) = (sys.nq(), sys.nu(), f.constraint_names.len());
    let idx = Literal::usize_unsuffixed;
    let (nq_l, nu_l) = (idx(nq), idx(nu));
    let offered = offered(sys, f);
    let infos = offered.iter().map(|(e, len)| {
        let (name, len, doc) = (e.name, idx(*len), e.doc);
        let labels = f.labels(e.function).iter();
        quote!(::eom_sim::FunctionInfo { name: #name, len: #len, doc: #doc, labels: &[#(#labels),*] })
    });
    let functions_const = quote! {
        const FUNCTIONS: &'static [::eom_sim::FunctionInfo] = &[#(#infos),*];
    };
    let arms = offered.iter().map(|(e, len)| {
        let name = e.name;
        let n = format_ident!("{}", e.name);
        let len_l = idx(*len);
        let fetch = e.args.iter().map(|a| match a {
            FnArg::T => quote!(let t = at.t;),
            FnArg::Q => quote!(let Some(q) = ::eom_sim::__private::arg::<#nq_l>(at.q, false) else { return false };),
            FnArg::U => quote!(let Some(u) = ::eom_sim::__private::arg::<#nu_l>(at.u, false) else { return false };),
            FnArg::Udot => quote!(let Some(udot) = ::eom_sim::__private::arg::<#nu_l>(at.udot, true) else { return false };),
            FnArg::Tau => quote!(let Some(tau) = ::eom_sim::__private::arg::<#nu_l>(at.tau, true) else { return false };),
        });
        let call_args: Vec<TokenStream> = e
            .args
            .iter()
            .map(|a| match a {
                FnArg::T => quote!(t),
                other => {
                    let i = format_ident!("{}", other.name());
                    quote!(&#i)
                }
            })
            .collect();
        let this = if e.uses_multipliers && nc > 0 {
            let nc_l = idx(nc);
            quote! {
                let Some(lambda) = ::eom_sim::__private::arg::<#nc_l>(at.lambda, true) else { return false };
                let mut with_lambda = *self;
                with_lambda.multipliers = lambda;
                let this = &with_lambda;
            }
        } else {
            quote!(let this = self;)
        };
        let call = match (e.function, e.in_trait) {
            (Function::MassMatrix, _) => quote! {
                let mut m = [[0.0; #nu_l]; #nu_l];
                ::eom_sim::Model::mass_matrix(this, #(#call_args),*, &mut m);
                for (o, v) in out.iter_mut().zip(m.iter().flatten()) {
                    *o = *v;
                }
            },
            (Function::Energy | Function::Momentum, _) => quote! {
                *out = ::eom_sim::Model::#n(this, #(#call_args),*);
            },
            (Function::Constraints, _) => {
                let nc_l = idx(nc);
                let ncj_l = idx(nc * nu);
                quote! {
                    let (mut phi, mut phidot, mut gamma, mut jacobian) =
                        ([0.0; #nc_l], [0.0; #nc_l], [0.0; #nc_l], [0.0; #ncj_l]);
                    ::eom_sim::ConstrainedModel::constraints(this, #(#call_args),*, &mut phi, &mut phidot, &mut gamma, &mut jacobian);
                    for (o, v) in out.iter_mut().zip(phi.iter().chain(&phidot).chain(&gamma).chain(&jacobian)) {
                        *o = *v;
                    }
                }
            }
            (_, true) => quote!(::eom_sim::Model::#n(this, #(#call_args),*, out);),
            (_, false) => quote!(this.#n(#(#call_args),*, out);),
        };
        quote! {
            #name => {
                #(#fetch)*
                let Ok(out) = <&mut [f64; #len_l]>::try_from(out) else { return false };
                #this
                #call
                true
            }
        }
    });
    let evaluate_fn = quote! {
        fn evaluate(&self, name: &str, at: &::eom_sim::Point<'_>, out: &mut [f64]) -> bool {
            match name {
                #(#arms)*
                _ => false,
            }
        }
    };
    (functions_const, evaluate_fn)
}

#[cfg(test)]
mod tests {
    /// `proc_macro2` panics on a non-finite literal; `float` writes the
    /// constants instead (see `tests/fuzz_findings.rs`).
    #[test]
    fn non_finite_floats_are_written_as_constants() {
        let text = |x: f64| super::float_operand(x).to_string().replace(' ', "");
        assert_eq!(text(f64::INFINITY), "::core::f64::INFINITY");
        assert_eq!(text(f64::NEG_INFINITY), "((-::core::f64::INFINITY))");
        assert_eq!(text(f64::NAN), "::core::f64::NAN");
        assert_eq!(text(-0.5), "(-0.5)");
    }
}
