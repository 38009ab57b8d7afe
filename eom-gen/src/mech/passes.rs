//! Where forward dynamics' operations go: the articulated-body algorithm of
//! a rigid tree (Featherstone §7.3, Table 7.1) lowered pass by pass. Each
//! pass's outputs are lowered together with every earlier pass's, so a
//! pass is charged only the operations it adds (common subexpressions go
//! to the first pass that needs them). [`derivative_part_counts`] does the
//! same for the parts of `−M⁻¹ ∂ID/∂x`.

use super::applied::Applied;
use super::formulate::{FormulateError, SymEnv};
use super::kinematics::{Evaluator, State};
use super::spatial::{Force, Inertia6, Motion};
use super::tree::Coords;
use crate::sym::{Context, Expr, Id, LowerOptions, OpCount, Scalar};
use crate::system::System;
use rustc_hash::FxHashSet;
use std::ops::{Add, Sub};

/// The passes, in order, with the operations each adds.
pub type PassCounts = Vec<(&'static str, OpCount)>;

fn motion_parts<'a>(m: &Motion<Expr<'a>>, out: &mut Vec<Expr<'a>>) {
    out.extend(m.w.0.iter().chain(&m.v.0).copied());
}

fn force_parts<'a>(f: &Force<Expr<'a>>, out: &mut Vec<Expr<'a>>) {
    out.extend(f.n.0.iter().chain(&f.f.0).copied());
}

fn inertia_parts<'a>(ia: &Inertia6<Expr<'a>>, out: &mut Vec<Expr<'a>>) {
    for m in [&ia.a, &ia.b, &ia.c] {
        out.extend(m.0.iter().flatten().copied());
    }
}

/// Operations added by each pass of the articulated-body algorithm on a
/// rigid tree of one-speed-or-more free joints: poses, velocities, velocity
/// products and bias forces, articulated inertias, articulated bias forces,
/// and the forward pass (`u̇`). `None` for trees the breakdown does not
/// cover (flexible bodies, nodes, locked or prescribed joints).
pub fn aba_pass_counts(sys: &System) -> Result<Option<PassCounts>, FormulateError> {
    part_counts(sys, false)
}

/// [`aba_pass_counts`], or with `derivatives` [`derivative_part_counts`].
fn part_counts(sys: &System, derivatives: bool) -> Result<Option<PassCounts>, FormulateError> {
    let cx = Context::new();
    let env = SymEnv::new(&cx, sys)?;
    let tree = super::tree::TreeModel::new(sys, &env)?;
    let applied = Applied::new(sys, &tree, &env)?;
    let ev = Evaluator::new(&tree, &applied, &env);
    if tree
        .bodies
        .iter()
        .any(|b| b.flex.is_some() || b.node.is_some() || !matches!(b.coords, Coords::Free { .. }))
    {
        return Ok(None);
    }
    let q: Vec<Expr> = (0..tree.nq).map(|i| cx.q(i as u32)).collect();
    let u: Vec<Expr> = (0..tree.nu).map(|i| cx.u(i as u32)).collect();
    let inputs: Vec<Expr> = sys
        .inputs
        .iter()
        .map(|n| cx.input(n))
        .collect::<Result<_, _>>()
        .map_err(|error| FormulateError::Sym { error, span: None })?;
    let st = State {
        q: &q,
        u: &u,
        t: cx.t(),
        inputs: &inputs,
    };
    let k = ev.kinematics(&st)?;
    let (fext, _) = ev.point_forces(&k);
    let (generalized, _) = ev.generalized_forces(&st)?;
    let tau: Vec<Expr> = (0..tree.nu)
        .map(|i| generalized[i] + cx.tau(i as u32))
        .collect();
    if derivatives {
        // u̇, then M⁻¹ = ∂u̇/∂τ, then Newton–Euler's ∂τ/∂(q, u) at u̇ by
        // the recursion along the paths.
        let udot = ev.aba(&k, &tau, &fext);
        let taus: Vec<Expr> = (0..tree.nu).map(|i| cx.tau(i as u32)).collect();
        let minv: Vec<Expr> = cx.jacobian(&udot, &taus).into_iter().flatten().collect();
        let Some(rd) = ev.rnea_derivatives(&k, &udot, super::rnea_derivatives::Axes::Paths) else {
            return Ok(None);
        };
        let grads: Vec<Expr> = rd.dq.into_iter().chain(rd.du).flatten().collect();
        return Ok(Some(cumulative(
            &cx,
            vec![
                ("forward dynamics u̇ (articulated bodies)", udot),
                ("M⁻¹ = ∂u̇/∂τ", minv),
                (
                    "∂ID/∂q, ∂ID/∂u at u̇ (recursion, pairs along the paths)",
                    grads,
                ),
            ],
        )));
    }
    let n = tree.bodies.len();
    let mut stages: Vec<(&'static str, Vec<Expr>)> = Vec::new();
    let mut out = Vec::new();
    for x in &k.x {
        out.extend(x.e.0.iter().flatten().copied());
        out.extend(x.r.0.iter().copied());
    }
    stages.push(("poses X_i (rotations, offsets)", out));
    let mut out = Vec::new();
    for v in &k.v {
        motion_parts(v, &mut out);
    }
    stages.push(("velocities v_i", out));
    let cv: Vec<Motion<Expr>> = (0..n)
        .map(|i| k.c[i].add(k.v[i].cross_motion(k.vj[i])))
        .collect();
    let mut pa: Vec<Force<Expr>> = (0..n)
        .map(|i| {
            let inertia = &k.inertia[i];
            k.v[i].cross_force(inertia.mul_motion(k.v[i])).sub(fext[i])
        })
        .collect();
    let mut out = Vec::new();
    for i in 0..n {
        motion_parts(&cv[i], &mut out);
        force_parts(&pa[i], &mut out);
    }
    stages.push(("velocity products c_i, bias forces p_i", out));
    // Backward pass, inertias and forces apart.
    let mut ia: Vec<Inertia6<Expr>> = k.inertia.iter().map(Inertia6::from_rigid).collect();
    let mut uu: Vec<Vec<Force<Expr>>> = vec![Vec::new(); n];
    let mut dinv: Vec<Vec<Vec<Expr>>> = vec![Vec::new(); n];
    let mut small_u: Vec<Vec<Expr>> = vec![Vec::new(); n];
    let mut inner_all = Vec::new();
    let mut pa_all = Vec::new();
    for i in (0..n).rev() {
        let body = &tree.bodies[i];
        let s = &k.s[i];
        let Coords::Free { u: ui0, .. } = body.coords else {
            return Ok(None);
        };
        let ucols: Vec<Force<Expr>> = s.iter().map(|col| ia[i].mul_motion(*col)).collect();
        let d: Vec<Vec<Expr>> = s
            .iter()
            .map(|sr| ucols.iter().map(|uc| sr.dot(*uc)).collect())
            .collect();
        let di = super::dense::invert_spd(d);
        let ui: Vec<Expr> = s
            .iter()
            .enumerate()
            .map(|(r, col)| tau[ui0 + r] - col.dot(pa[i]))
            .collect();
        let mut inner = ia[i];
        for r in 0..s.len() {
            for c in 0..s.len() {
                inner = inner.sub_outer(&ucols[r], &ucols[c], di[r][c]);
            }
        }
        let mut p = pa[i].add(inner.mul_motion(cv[i]));
        for r in 0..s.len() {
            let w = (0..s.len()).fold(Expr::zero(), |acc, c| acc + di[r][c] * ui[c]);
            p = p.add(ucols[r].scale(w));
        }
        inertia_parts(&inner, &mut inner_all);
        inner_all.extend(di.iter().flatten().copied());
        for uc in &ucols {
            force_parts(uc, &mut inner_all);
        }
        force_parts(&p, &mut pa_all);
        pa_all.extend(ui.iter().copied());
        if let Some(par) = body.parent {
            let moved = inner.to_parent(&k.x[i]);
            ia[par] = ia[par].add(moved);
            inertia_parts(&moved, &mut inner_all);
            pa[par] = pa[par].add(k.x[i].force_to_parent(p));
        }
        uu[i] = ucols;
        dinv[i] = di;
        small_u[i] = ui;
    }
    stages.push(("articulated inertias I^A_i, U_i, D_i⁻¹", inner_all));
    stages.push(("articulated bias forces p^A_i, u_i", pa_all));
    let udot = ev.aba(&k, &tau, &fext);
    // Only what u̇ needs is charged (the root's articulated inertia, for
    // one, is computed by the pass but never used).
    let needed: FxHashSet<Id> = {
        let roots: Vec<Id> = udot.iter().map(|&e| cx.id(e)).collect();
        cx.arena()
            .reachable(&roots, |_| false)
            .into_iter()
            .collect()
    };
    for (_, outs) in &mut stages {
        outs.retain(|&e| needed.contains(&cx.id(e)));
    }
    stages.push(("forward pass: a_i, u̇", udot));
    Ok(Some(cumulative(&cx, stages)))
}

/// Operations added by each part of `forward_dynamics_derivatives` by
/// `−M⁻¹ ∂ID/∂x` on a rigid tree ([`aba_pass_counts`]'s trees): `u̇`,
/// `M⁻¹` and the recursion's `∂ID/∂(q, u)` (the dense product after them
/// and the force elements' terms not counted). `None` for trees the
/// breakdown or the recursion does not cover.
pub fn derivative_part_counts(sys: &System) -> Result<Option<PassCounts>, FormulateError> {
    part_counts(sys, true)
}

/// Each stage's outputs lowered with every earlier stage's: the operations
/// each adds.
fn cumulative<'a>(cx: &'a Context, stages: Vec<(&'static str, Vec<Expr<'a>>)>) -> PassCounts {
    let mut so_far: Vec<Expr> = Vec::new();
    let mut last = OpCount::default();
    let mut counts = Vec::new();
    for (name, outs) in stages {
        so_far.extend(outs);
        let names: Vec<String> = (0..so_far.len()).map(|i| format!("o{i}")).collect();
        let pairs: Vec<(&str, Expr)> = names
            .iter()
            .map(String::as_str)
            .zip(so_far.iter().copied())
            .collect();
        let c = cx.lower(&pairs, LowerOptions::default()).op_count();
        counts.push((name, minus(c, last)));
        last = c;
    }
    counts
}

fn minus(a: OpCount, b: OpCount) -> OpCount {
    let d = |x: usize, y: usize| x.saturating_sub(y);
    OpCount {
        adds: d(a.adds, b.adds),
        muls: d(a.muls, b.muls),
        divs: d(a.divs, b.divs),
        negs: d(a.negs, b.negs),
        sqrts: d(a.sqrts, b.sqrts),
        trig: d(a.trig, b.trig),
        other: d(a.other, b.other),
    }
}
