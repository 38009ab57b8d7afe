//! Emission of long chains as loops ([`crate::mech::looped`]): each
//! distinct body step becomes an associated function of the model type
//! (`forward_dynamics_p1_s0`, through the one lowering of `lower.rs`), each
//! pass a `for` loop over the bodies that calls the step of each body's
//! class (a table `FORWARD_DYNAMICS_P1: [u16; N]`). A step reads and
//! writes the carried value in place (`c: &mut [f64; K]`) and returns what
//! it stores for its body; a pass storing several values per body fills
//! `[[f64; K]; N]` on the stack with `core::array::from_fn` in pass order
//! (no zeroing first: slot `k` is body `k` root to tip, body `N − 1 − k`
//! tip to root, [`store_index`]), a pass storing one value writes it into
//! the function's output. The code does not grow with the number of bodies
//! once the bodies repeat; nothing allocates, every index is below its
//! array's length by construction. The sines and cosines of the
//! coordinates are computed for every body before the loops, in one
//! vectorised pass where the build has 256-bit vectors
//! ([`with_sin_cos_given`]).

use super::lower::{Arg, Style, lower};
use crate::functions::Function;
use crate::mech::looped::{ChainLoops, Loop, Order, Own, Pass};
use crate::sym::{Op, Operand, Program, SymKind, Symbol};
use proc_macro2::{Literal, TokenStream};
use quote::{format_ident, quote};

/// Whether to emit long chains as loops.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum LoopChoice {
    /// Where the formulation offers loops and they pay
    /// (`ChainLoops::pays`).
    #[default]
    Auto,
    /// Wherever the model is a chain the loops handle (for tests and
    /// measurements).
    Always,
    /// Never: straight-line code throughout.
    Never,
}

/// A looped function: the trait method and the items it uses.
pub(crate) struct Looped {
    /// The method.
    pub method: TokenStream,
    /// Step functions and class tables (associated items).
    pub items: TokenStream,
}

const STORE_ARGS: [&str; 4] = ["s0", "s1", "s2", "s3"];

/// The names of the sine and cosine of a body's coordinate where a step
/// reads them instead of computing them.
const SIN_COS_ARGS: [&str; 2] = ["q_sin", "q_cos"];

/// A step's program with `sin q` and `cos q` read from two inputs
/// ([`SIN_COS_ARGS`]) instead of computed by it, so that the loop's
/// caller computes them for every body in one vectorised pass before the
/// loop (`sin_cos_lanes` where the build has 256-bit vectors, as the
/// straight-line functions do) rather than one call of the C library's
/// per body; `None` if the step takes no sine or cosine of its coordinate.
/// Same values otherwise: the operations on them are unchanged.
fn with_sin_cos_given(p: &Program) -> Option<Program> {
    if !reads_sin_cos(p) {
        return None;
    }
    let iq = coordinate(p)?;
    let of_q = |x: Operand| x == Operand::Var(iq);
    // The inputs with the two new ones, kept sorted by kind then name; `q`
    // itself only if something else still reads it (a step whose only
    // use of `q` was its sine and cosine takes it as `_q`).
    let reads_q = p.instrs.iter().any(|i| {
        !matches!(i.op, Op::Sin(x) | Op::Cos(x) | Op::SinCos(x) if of_q(x))
            && i.op.operands().any(of_q)
    }) || p.outputs.iter().any(|&(_, o)| of_q(o));
    let mut inputs: Vec<Symbol> = p
        .inputs
        .iter()
        .enumerate()
        .filter(|&(i, _)| reads_q || i as u32 != iq)
        .map(|(_, s)| s.clone())
        .collect();
    for name in SIN_COS_ARGS {
        inputs.push(Symbol {
            kind: SymKind::Input,
            name: name.to_string(),
        });
    }
    inputs.sort_by(|a, b| (a.kind, &a.name).cmp(&(b.kind, &b.name)));
    let at = |sym: &Symbol| inputs.iter().position(|x| x == sym).map(|i| i as u32);
    // Old input index → new (`q`'s, if dropped, is never read again).
    let remap: Vec<u32> = p.inputs.iter().map(|s| at(s).unwrap_or(u32::MAX)).collect();
    let given_input = |name: &str| {
        at(&Symbol {
            kind: SymKind::Input,
            name: name.to_string(),
        })
        .map(Operand::Var)
    };
    let sin_cos = [given_input(SIN_COS_ARGS[0])?, given_input(SIN_COS_ARGS[1])?];
    // Temporaries that were the sine or cosine of `q`, now those inputs.
    let mut given: std::collections::HashMap<u32, Operand> = std::collections::HashMap::new();
    let mut instrs = Vec::with_capacity(p.instrs.len());
    for ins in &p.instrs {
        let op = ins.op.map(|o| match o {
            Operand::Var(i) => Operand::Var(remap[i as usize]),
            Operand::Tmp(t) => given.get(&t).copied().unwrap_or(o),
            c => c,
        });
        match ins.op {
            Op::SinCos(x) if of_q(x) => {
                given.insert(ins.dst, sin_cos[0]);
                given.insert(ins.dst + 1, sin_cos[1]);
            }
            Op::Sin(x) if of_q(x) => {
                given.insert(ins.dst, sin_cos[0]);
            }
            Op::Cos(x) if of_q(x) => {
                given.insert(ins.dst, sin_cos[1]);
            }
            _ => instrs.push(crate::sym::Instr { dst: ins.dst, op }),
        }
    }
    let outputs = p
        .outputs
        .iter()
        .map(|(name, o)| {
            let o = match *o {
                Operand::Var(i) => Operand::Var(remap[i as usize]),
                Operand::Tmp(t) => given.get(&t).copied().unwrap_or(*o),
                c => c,
            };
            (name.clone(), o)
        })
        .collect();
    Some(Program {
        inputs,
        instrs,
        outputs,
        n_tmps: p.n_tmps,
        products: p.products.clone(),
    })
}

/// The input index of a step's coordinate, if it reads one.
fn coordinate(p: &Program) -> Option<u32> {
    let i = p
        .inputs
        .iter()
        .position(|s| matches!(s.kind, SymKind::Coord(_)))?;
    Some(i as u32)
}

/// True if the step `p` takes the sine or cosine of its coordinate (what
/// [`with_sin_cos_given`] rewrites).
fn reads_sin_cos(p: &Program) -> bool {
    coordinate(p).is_some_and(|iq| {
        let of_q = |x: Operand| x == Operand::Var(iq);
        p.instrs
            .iter()
            .any(|i| matches!(i.op, Op::Sin(x) | Op::Cos(x) | Op::SinCos(x) if of_q(x)))
    })
}

/// True if some step of `pass` reads the sine and cosine of its
/// coordinate ([`with_sin_cos_given`]).
fn pass_takes_sin_cos(pass: &Pass) -> bool {
    pass.own.0 && pass.steps.iter().any(reads_sin_cos)
}

/// The step function of one pass's class `k`.
fn step_fn(fname: &str, p: usize, k: usize, l: &Loop, fma: bool) -> TokenStream {
    let pass = &l.passes[p];
    let given = with_sin_cos_given(&pass.steps[k]);
    let prog = given.as_ref().unwrap_or(&pass.steps[k]);
    let input = |s: &Symbol| -> TokenStream {
        if s.kind == SymKind::Input && SIN_COS_ARGS.contains(&s.name.as_str()) {
            let n = format_ident!("{}", s.name);
            return quote!(#n);
        }
        match s.kind {
            SymKind::Coord(_) => quote!(q),
            SymKind::Speed(_) => quote!(u),
            SymKind::Tau(_) => quote!(tau),
            SymKind::SpeedRate(_) => quote!(udot),
            _ => {
                let idx = |r: &str| r.parse::<usize>().ok();
                if let Some(i) = s.name.strip_prefix("c_").and_then(idx) {
                    let i = Literal::usize_unsuffixed(i);
                    return quote!(c[#i]);
                }
                let mut parts = s.name.trim_start_matches('s').splitn(2, '_');
                match (parts.next().and_then(idx), parts.next().and_then(idx)) {
                    (Some(r), Some(i)) if r < STORE_ARGS.len() => {
                        let (a, i) = (
                            format_ident!("{}", STORE_ARGS[r]),
                            Literal::usize_unsuffixed(i),
                        );
                        quote!(#a[#i])
                    }
                    _ => {
                        let msg = format!("eom-gen: step input `{}` has no argument", s.name);
                        quote!(::core::compile_error!(#msg))
                    }
                }
            }
        }
    };
    let style = Style {
        input: &input,
        fma,
        lanes: None,
        sin_cos_together: true,
        methods: false,
    };
    let args = step_args(l, pass);
    let name = format!("{fname}_p{p}_s{k}");
    let l = lower(&style, prog, &name, &args);
    // The carried value is read and written in place (`c`, always named:
    // the step writes it even where its body reads none of it, the first
    // body of a pass); the stores are the return value, so the caller writes
    // them where they go without zeroing an output array first.
    let params = args.iter().zip(&l.used).map(|(a, &used)| {
        let n = if used || a.name == "c" {
            format_ident!("{}", a.name)
        } else {
            format_ident!("_{}", a.name)
        };
        let ty = &a.ty;
        quote!(#n: #ty)
    });
    let body = &l.body;
    let (nc, ns) = (pass.carry, pass.store);
    let carry_out = &l.outputs[..nc];
    let store_out = &l.outputs[nc..];
    let write_carry = if nc > 0 {
        quote!(*c = [#(#carry_out),*];)
    } else {
        TokenStream::new()
    };
    let (ret, value) = if ns == 1 {
        (quote!(f64), quote!(#(#store_out)*))
    } else {
        let nsl = Literal::usize_unsuffixed(ns);
        (quote!([f64; #nsl]), quote!([#(#store_out),*]))
    };
    let ident = format_ident!("{name}");
    let doc = format!(
        " Body step {k} of pass {p} of `{fname}` ({} operations; see `eom_gen::mech::looped`).",
        prog.op_count().total()
    );
    // The stores are read before the carried value is written (an output
    // may be the carried value passed through); a step that carries
    // nothing returns them directly.
    let tail = if nc > 0 {
        quote! {
            let value = #value;
            #write_carry
            value
        }
    } else {
        value
    };
    quote! {
        #[doc = #doc]
        #[allow(clippy::too_many_arguments)]
        fn #ident(#(#params),*) -> #ret {
            #body
            #tail
        }
    }
}

/// The arguments of a pass's steps, in order (outputs follow).
fn step_args(l: &Loop, pass: &Pass) -> Vec<Arg<'static>> {
    let mut args = Vec::new();
    if pass.carry > 0 {
        let n = Literal::usize_unsuffixed(pass.carry);
        args.push(Arg {
            name: "c",
            ty: quote!(&mut [f64; #n]),
            carries: Box::new(|s: &Symbol| s.name.starts_with("c_")),
        });
    }
    for &r in &pass.reads {
        let name = STORE_ARGS[r.min(STORE_ARGS.len() - 1)];
        let prefix = format!("s{r}_");
        let len = Literal::usize_unsuffixed(l.passes.get(r).map_or(0, |q| q.store));
        args.push(Arg {
            name,
            ty: quote!(&[f64; #len]),
            carries: Box::new(move |s: &Symbol| s.name.starts_with(&prefix)),
        });
    }
    let scalar = |name: &'static str, f: fn(&SymKind) -> bool| Arg {
        name,
        ty: quote!(f64),
        carries: Box::new(move |s: &Symbol| f(&s.kind)),
    };
    if pass.own.0 {
        args.push(scalar("q", |k| matches!(k, SymKind::Coord(_))));
    }
    if pass_takes_sin_cos(pass) {
        for name in SIN_COS_ARGS {
            args.push(Arg {
                name,
                ty: quote!(f64),
                carries: Box::new(move |s: &Symbol| s.kind == SymKind::Input && s.name == name),
            });
        }
    }
    if pass.own.1 {
        args.push(scalar("u", |k| matches!(k, SymKind::Speed(_))));
    }
    match pass.own.2 {
        Some(Own::Tau) => args.push(scalar("tau", |k| matches!(k, SymKind::Tau(_)))),
        Some(Own::Udot) => args.push(scalar("udot", |k| matches!(k, SymKind::SpeedRate(_)))),
        None => {}
    }
    args
}

/// Where pass `r` stored body `i`'s values: slot `i` if it went root to
/// tip, `N − 1 − i` if tip to root (its slots are filled in pass order).
fn store_index(l: &Loop, r: usize, i: &TokenStream, n: usize) -> TokenStream {
    match l.passes.get(r).map(|p| p.order) {
        Some(Order::Backward) => {
            let last = Literal::usize_unsuffixed(n - 1);
            quote!(#last - #i)
        }
        _ => i.clone(),
    }
}

/// The loop of `fname` (`f`) on a chain of `n` bodies. A pass that stores
/// one value per body (the last of forward dynamics, inverse dynamics and
/// the bias) writes it straight into `out[i]`.
fn emit_loop(
    fname: &str,
    l: &Loop,
    n: usize,
    fma: bool,
    out: &TokenStream,
) -> (TokenStream, TokenStream) {
    let nl = Literal::usize_unsuffixed(n);
    let mut items = TokenStream::new();
    let mut body = TokenStream::new();
    // Every body's `sin q`, `cos q` at once, where a pass's steps read them:
    // in one vectorised pass where the build has 256-bit vectors, else by
    // the C library one at a time (as the straight-line functions).
    if l.passes.iter().any(pass_takes_sin_cos) {
        body.extend(quote! {
            let (q_sin, q_cos) = if cfg!(target_feature = "avx2") {
                ::eom_sim::__private::sin_cos_lanes(*q)
            } else {
                ::eom_sim::__private::sin_cos_each(*q, #nl)
            };
        });
    }
    for (p, pass) in l.passes.iter().enumerate() {
        for k in 0..pass.steps.len() {
            items.extend(step_fn(fname, p, k, l, fma));
        }
        let table = format_ident!("{}_P{p}", fname.to_uppercase());
        let classes = pass
            .class
            .iter()
            .map(|&k| Literal::u16_unsuffixed(k as u16));
        if pass.steps.len() > 1 {
            let doc = format!(" The body step of each body in pass {p} of `{fname}`.");
            items.extend(quote! {
                #[doc = #doc]
                const #table: [u16; #nl] = [#(#classes),*];
            });
        }
        let idx = |order: Order| match order {
            Order::Ancestors => quote!(j),
            _ => quote!(i),
        };
        let i = idx(pass.order);
        let mut call_args = Vec::new();
        if pass.carry > 0 {
            call_args.push(quote!(&mut c));
        }
        for &r in &pass.reads {
            let st = format_ident!("st{r}");
            let at = store_index(l, r, &i, n);
            call_args.push(quote!(&#st[#at]));
        }
        if pass.own.0 {
            call_args.push(quote!(q[#i]));
        }
        if pass_takes_sin_cos(pass) {
            call_args.push(quote!(q_sin[#i]));
            call_args.push(quote!(q_cos[#i]));
        }
        if pass.own.1 {
            call_args.push(quote!(u[#i]));
        }
        match pass.own.2 {
            Some(Own::Tau) => call_args.push(quote!(tau[#i])),
            Some(Own::Udot) => call_args.push(quote!(udot[#i])),
            None => {}
        }
        let st = format_ident!("st{p}");
        let call_of = |k: usize| {
            let f = format_ident!("{fname}_p{p}_s{k}");
            quote!(Self::#f(#(#call_args),*))
        };
        let value = if pass.steps.len() == 1 {
            call_of(0)
        } else {
            let last = pass.steps.len() - 1;
            let arms = (0..last).map(|k| {
                let kl = Literal::u16_unsuffixed(k as u16);
                let c = call_of(k);
                quote!(#kl => #c,)
            });
            let c = call_of(last);
            quote! {
                match Self::#table[#i] {
                    #(#arms)*
                    _ => #c,
                }
            }
        };
        let single = pass.store == 1;
        let dispatch = match pass.order {
            Order::Ancestors => quote! {
                let mij = #value;
                m[i][j - 1] = mij;
                m[j - 1][i] = mij;
            },
            _ if single => quote!(#out[i] = #value;),
            // Filled in pass order by `core::array::from_fn` (below).
            _ => value.clone(),
        };
        let ncl = Literal::usize_unsuffixed(pass.carry);
        let init = pass.init.iter().map(|&x| super::float(x));
        let c_decl = if pass.carry > 0 && pass.order != Order::Ancestors {
            if pass.init.iter().all(|&x| x == 0.0) {
                quote!(let mut c = [0.0f64; #ncl];)
            } else {
                quote!(let mut c: [f64; #ncl] = [#(#init),*];)
            }
        } else {
            TokenStream::new()
        };
        let nsl = Literal::usize_unsuffixed(pass.store);
        body.extend(match pass.order {
            Order::Forward | Order::Backward => {
                let range = if pass.order == Order::Forward {
                    quote!(0..#nl)
                } else {
                    quote!((0..#nl).rev())
                };
                if single {
                    quote! {
                        #c_decl
                        for i in #range {
                            #dispatch
                        }
                    }
                } else {
                    // The stores of every body, written once each in pass
                    // order (no zeroing first): slot `k` holds body `k`
                    // going root to tip, body `N − 1 − k` going tip to root
                    // (`store_index`).
                    let body_of = if pass.order == Order::Forward {
                        quote!(k)
                    } else {
                        quote!(#nl - 1 - k)
                    };
                    quote! {
                        #c_decl
                        let #st: [[f64; #nsl]; #nl] = ::core::array::from_fn(|k| {
                            let i = #body_of;
                            #dispatch
                        });
                    }
                }
            }
            Order::Ancestors => {
                let seed = format_ident!("st{}", pass.seed);
                let at = store_index(l, pass.seed, &quote!(i), n);
                let seeds = (0..pass.carry).map(|k| {
                    let k = Literal::usize_unsuffixed(k);
                    quote!(s[#k])
                });
                let diag = Literal::usize_unsuffixed(pass.carry);
                quote! {
                    for i in 0..#nl {
                        let s = &#seed[#at];
                        let mut c: [f64; #ncl] = [#(#seeds),*];
                        m[i][i] = s[#diag];
                        for j in (1..=i).rev() {
                            #dispatch
                        }
                    }
                }
            }
        });
    }
    (body, items)
}

/// The looped functions of `f`'s chain that `choice` selects, with the
/// straight-line operation count of each.
pub(crate) fn looped(
    loops: &ChainLoops,
    straight: &[(Function, usize)],
    choice: LoopChoice,
    fma: bool,
) -> Vec<(Function, Looped)> {
    let mut out = Vec::new();
    for &(f, ops) in straight {
        let Some(l) = loops.get(f) else { continue };
        let take = match choice {
            LoopChoice::Never => false,
            LoopChoice::Always => true,
            LoopChoice::Auto => loops.pays(f, ops),
        };
        if !take {
            continue;
        }
        let n = loops.n;
        let nl = Literal::usize_unsuffixed(n);
        let fname = f.name();
        let target = match f {
            Function::ForwardDynamics => quote!(udot),
            Function::Bias => quote!(b),
            Function::InverseDynamics => quote!(tau),
            _ => quote!(m),
        };
        let (body, items) = emit_loop(fname, l, n, fma, &target);
        let doc = format!(
            " {} as loops over the {n} bodies of the chain ({} operations per call in {} body steps of {} operations; straight-line: {ops}; see `eom_gen::mech::looped`).",
            match f {
                Function::ForwardDynamics =>
                    "Forward dynamics by the articulated-body algorithm, `u̇ = M⁻¹ (τ − b)`,",
                Function::MassMatrix => "The mass matrix by composite rigid bodies",
                Function::Bias => "The bias `b = ID(q, u, 0)` by recursive Newton–Euler",
                _ => "Inverse dynamics by recursive Newton–Euler, `τ = M u̇ + b`,",
            },
            l.ops(),
            l.steps(),
            l.code_ops()
        );
        let method = match f {
            Function::ForwardDynamics => quote! {
                #[doc = #doc]
                #[allow(clippy::needless_range_loop)]
                fn forward_dynamics(&self, _t: f64, q: &[f64; #nl], u: &[f64; #nl], tau: &[f64; #nl], udot: &mut [f64; #nl]) {
                    #body
                }
            },
            Function::MassMatrix => quote! {
                #[doc = #doc]
                #[allow(clippy::needless_range_loop)]
                fn mass_matrix(&self, _t: f64, q: &[f64; #nl], m: &mut [[f64; #nl]; #nl]) {
                    #body
                }
            },
            Function::Bias => quote! {
                #[doc = #doc]
                #[allow(clippy::needless_range_loop)]
                fn bias(&self, _t: f64, q: &[f64; #nl], u: &[f64; #nl], b: &mut [f64; #nl]) {
                    #body
                }
            },
            _ => quote! {
                #[doc = #doc]
                #[allow(clippy::needless_range_loop)]
                fn inverse_dynamics(&self, _t: f64, q: &[f64; #nl], u: &[f64; #nl], udot: &[f64; #nl], tau: &mut [f64; #nl]) {
                    #body
                }
            },
        };
        out.push((f, Looped { method, items }));
    }
    out
}

/// The steps with their sine and cosine given are the steps: evaluated
/// with `(q_sin, q_cos)` set to the C library's `sin_cos(q)`, every step
/// of every pass of the 50-link spatial chain and of a chain of unequal
/// links (prismatic joints among them) gives its outputs bit for bit, and
/// the passes that read them are the ones whose steps take a sine.
#[cfg(test)]
mod tests {
    use super::{SIN_COS_ARGS, pass_takes_sin_cos, with_sin_cos_given};
    use crate::functions::{Function, FunctionSet};
    use crate::mech::looped::ChainLoops;
    use crate::model::{Source, check};
    use crate::sym::{Op, Program, SymKind};
    use crate::testkit::Rng;

    /// A step's input values: the angle `q`, its sine and cosine by the C
    /// library, and for every other input a value drawn once per symbol
    /// name (so both programs get the same).
    fn inputs(p: &Program, q: f64, seed: u64) -> Vec<f64> {
        let (sn, cs) = q.sin_cos();
        p.inputs
            .iter()
            .map(|s| match s.kind {
                SymKind::Coord(_) => q,
                SymKind::Input if s.name == SIN_COS_ARGS[0] => sn,
                SymKind::Input if s.name == SIN_COS_ARGS[1] => cs,
                _ => {
                    let h = s
                        .name
                        .bytes()
                        .fold(seed, |h, c| h.wrapping_mul(0x100_0000_01b3) ^ u64::from(c));
                    Rng(h | 1).uniform()
                }
            })
            .collect()
    }

    fn check_chain(text: String) {
        let sys = check(&Source::new("chain", text))
            .unwrap_or_else(|r| panic!("{r}"))
            .system;
        let loops = ChainLoops::build(&sys, FunctionSet::all_requested())
            .expect("builds")
            .expect("a chain");
        let mut rewritten = 0;
        for f in [
            Function::ForwardDynamics,
            Function::MassMatrix,
            Function::Bias,
            Function::InverseDynamics,
        ] {
            let Some(l) = loops.get(f) else { continue };
            for pass in &l.passes {
                let takes_sine = pass.steps.iter().any(|p| {
                    p.instrs
                        .iter()
                        .any(|i| matches!(i.op, Op::Sin(_) | Op::Cos(_) | Op::SinCos(_)))
                });
                assert_eq!(pass_takes_sin_cos(pass), pass.own.0 && takes_sine);
                for p in &pass.steps {
                    let Some(g) = with_sin_cos_given(p) else {
                        continue;
                    };
                    rewritten += 1;
                    assert!(
                        !g.instrs
                            .iter()
                            .any(|i| matches!(i.op, Op::Sin(_) | Op::Cos(_) | Op::SinCos(_)))
                    );
                    for seed in 0..20u64 {
                        let q = -7.0 + 0.7 * seed as f64;
                        let want = p.eval(&inputs(p, q, seed));
                        let got = g.eval(&inputs(&g, q, seed));
                        assert_eq!(want.len(), got.len());
                        for (w, x) in want.iter().zip(&got) {
                            assert_eq!(w.to_bits(), x.to_bits(), "{f:?} at q = {q}");
                        }
                    }
                }
            }
        }
        assert!(rewritten > 0, "some step takes a sine");
    }

    #[test]
    fn steps_with_the_sine_and_cosine_given_are_the_steps() {
        check_chain(crate::model::builder::n_link_chain(50, true).to_ron());
        check_chain(crate::model::builder::n_link_chain(12, false).to_ron());
    }
}
