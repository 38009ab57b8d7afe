//! Partial derivatives of forward dynamics, `∂u̇/∂q`, `∂u̇/∂u`,
//! `∂u̇/∂τ`, `∂u̇/∂(inputs)`, three ways (the formulation keeps the one
//! with fewer counted operations, [`DerivativeForm`]):
//!
//! - [`forward_dynamics_derivatives`]: differentiate the expressions of
//!   the form forward dynamics was generated in (articulated bodies or
//!   `LᵀDL`);
//! - [`forward_dynamics_derivatives_rnea`]: differentiate inverse dynamics
//!   (recursive Newton–Euler) instead, as Carpentier and Mansard (2018) do:
//!   from `ID(q, u, FD(q, u, τ)) = τ`,
//!   `∂u̇/∂x = −M⁻¹ ∂ID/∂x |_{u̇ = FD}` for `x = q, u, inputs`, with
//!   `M⁻¹ = ∂u̇/∂τ` (forward dynamics is linear in `τ`);
//! - [`forward_dynamics_derivatives_recursive`]: the same `−M⁻¹ ∂ID/∂x`
//!   with `∂ID/∂(q, u)` of the Newton–Euler forces built by the recursion of
//!   Carpentier and Mansard over the tree ([`super::rnea_derivatives`]),
//!   and only the force elements' terms differentiated as expressions
//!   (`∂ID/∂u` of Newton–Euler may also be differentiated instead, where
//!   that counts fewer operations: the formulation tries both); the
//!   recursion in world axes ([`DerivativeForm::Recursive`]) or in body
//!   axes with the pairs of columns in common axes
//!   ([`DerivativeForm::RecursiveBodyAxes`]) or along the tree's paths
//!   ([`DerivativeForm::RecursivePaths`]), three candidates.
//!
//! Coordinates are differentiated in the tangent space: column `j` of
//! `∂u̇/∂q` is the derivative along `δq = N(q) e_j`, where `q̇ = N(q) u`,
//!
//! ```text
//! (∂u̇/∂q)_ij = Σ_k ∂u̇_i/∂q_k · N_kj ,    N = ∂q̇/∂u .
//! ```
//!
//! Where `q̇ = u` (`N = I`, exact ones and zeros) this is the plain partial
//! derivative and builds nothing more. For a unit quaternion `N` is
//! `½ q ⊗ (0, ·)` (the joint's angular velocity is in body axes,
//! `mech::joint::quaternion_rate`), so the columns are the derivatives with
//! respect to a rotation vector `δθ` in body axes, `q ⊕ δθ = q ⊗ (1, δθ/2)`
//! to first order; a free joint's translation columns are along body axes
//! (`ṗ = R v`). This is Pinocchio's local convention for its derivatives
//! (Carpentier and Mansard 2018): `NU` columns, not `NQ`, and independent
//! of how the expressions extend off the unit sphere (every column of `N`
//! is tangent to it).
//!
//! [`inverse_dynamics_derivatives`] differentiates inverse dynamics
//! (Newton–Euler) the same way: `∂τ/∂q` (tangent space), `∂τ/∂u`,
//! `∂τ/∂u̇ = M`, `∂τ/∂(inputs)`.
//!
//! The derivatives go through the same simplification, CSE and emission
//! as every other generated function (see [`crate::functions`] for the
//! layout of the result). In the `−M⁻¹ ∂ID/∂x` forms with at least
//! [`PRODUCTS_FROM_NU`] speeds the program computes `M⁻¹` and the
//! gradients `∂ID/∂x` only, and the multiplication `−M⁻¹ [∂ID/∂q ∂ID/∂u
//! ∂ID/∂(inputs)]` is a dense [`Product`] after it: loops along the rows
//! of the gradients, which the compiler runs in SIMD lanes, where
//! straight-line sums ran one operation at a time.

use crate::sym::{Context, Expr, LowerOptions, Product, Program, Scalar};
use std::fmt;

/// How the derivatives of forward dynamics are computed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DerivativeForm {
    /// Differentiating forward dynamics as generated.
    ForwardDynamics,
    /// `−M⁻¹ ∂ID/∂x` at `u̇ = FD`: differentiating recursive Newton–Euler.
    InverseDynamics,
    /// `−M⁻¹ ∂ID/∂x` at `u̇ = FD`, `∂ID/∂x` by the recursion of Carpentier
    /// and Mansard (rigid trees of joints with constant subspaces), in
    /// world axes.
    Recursive,
    /// The same recursion in body axes, where inertias are constant and
    /// subspace columns unit axes ([`super::rnea_derivatives::Axes::Body`]).
    RecursiveBodyAxes,
    /// The recursion in body axes with the pairs along the tree's paths
    /// ([`super::rnea_derivatives::Axes::Paths`]).
    RecursivePaths,
}

/// How `inverse_dynamics_derivatives` was generated: the formulation
/// counts every form that applies and keeps the cheapest.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum IdDerivativeForm {
    /// Differentiating recursive Newton–Euler as generated.
    Differentiated,
    /// `∂ID/∂(q, u)` by the recursion of Carpentier and Mansard in world
    /// axes, `∂ID/∂u̇ = M` from its composite inertias.
    Recursive,
    /// The same recursion in body axes.
    RecursiveBodyAxes,
    /// The recursion in body axes, the pairs along the tree's paths.
    RecursivePaths,
}

impl fmt::Display for IdDerivativeForm {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            IdDerivativeForm::Differentiated => "differentiated RNEA",
            IdDerivativeForm::Recursive => "RNEA derivatives by recursion",
            IdDerivativeForm::RecursiveBodyAxes => "RNEA derivatives by recursion in body axes",
            IdDerivativeForm::RecursivePaths => {
                "RNEA derivatives by recursion in body axes, pairs along the paths"
            }
        })
    }
}

impl fmt::Display for DerivativeForm {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            DerivativeForm::ForwardDynamics => "differentiated forward dynamics",
            DerivativeForm::InverseDynamics => "−M⁻¹ ∂ID/∂x (differentiated RNEA)",
            DerivativeForm::Recursive => "−M⁻¹ ∂ID/∂x (RNEA derivatives by recursion)",
            DerivativeForm::RecursiveBodyAxes => {
                "−M⁻¹ ∂ID/∂x (RNEA derivatives by recursion in body axes)"
            }
            DerivativeForm::RecursivePaths => {
                "−M⁻¹ ∂ID/∂x (RNEA derivatives by recursion in body axes, pairs along the paths)"
            }
        })
    }
}

/// `∂f/∂q` in the tangent space, by rows: `(∂f_i/∂q) N` with
/// `N = ∂q̇/∂u` (its structural zeros, most entries, skipped), so that
/// column `j` is the derivative along `N e_j` (for quaternions a
/// body-axis rotation vector).
fn tangent_jacobian<'cx>(
    cx: &'cx Context,
    f: &[Expr<'cx>],
    qdot: &[Expr<'cx>],
    q: &[Expr<'cx>],
    u: &[Expr<'cx>],
) -> Vec<Vec<Expr<'cx>>> {
    let n = cx.jacobian(qdot, u);
    f.iter()
        .map(|&fi| {
            let d: Vec<Expr<'cx>> = q.iter().map(|&qk| cx.diff(fi, qk)).collect();
            (0..u.len())
                .map(|j| {
                    let mut sum = Expr::zero();
                    for (k, dk) in d.iter().enumerate() {
                        let nkj = n[k][j];
                        if nkj.is_zero() || dk.is_zero() {
                            continue;
                        }
                        sum = sum + *dk * nkj;
                    }
                    sum
                })
                .collect()
        })
        .collect()
}

/// The outputs in the layout of `forward_dynamics_derivatives`.
fn lower_blocks<'cx>(
    cx: &'cx Context,
    blocks: [(&str, Vec<Vec<Expr<'cx>>>); 4],
    opts: LowerOptions,
) -> Program {
    let mut names: Vec<String> = Vec::new();
    let mut values: Vec<Expr<'cx>> = Vec::new();
    for (prefix, rows) in blocks {
        for (i, row) in rows.into_iter().enumerate() {
            for (j, v) in row.into_iter().enumerate() {
                names.push(format!("{prefix}_{i}_{j}"));
                values.push(v);
            }
        }
    }
    let outs: Vec<(&str, Expr<'cx>)> = names.iter().map(String::as_str).zip(values).collect();
    cx.lower(&outs, opts)
}

/// The program of `forward_dynamics_derivatives` for forward dynamics
/// `udot` (`NU` expressions), kinematics `qdot` (`NQ`, linear in `u`),
/// coordinates `q`, speeds `u`, extra forces `tau` and the runtime
/// `inputs`: outputs `dq_i_j`, `du_i_j`, `dtau_i_j` (each `NU × NU`, by
/// rows), then `dinput_i_j` (`NU × NI`, by rows).
#[allow(clippy::too_many_arguments)]
pub fn forward_dynamics_derivatives<'cx>(
    cx: &'cx Context,
    udot: &[Expr<'cx>],
    qdot: &[Expr<'cx>],
    q: &[Expr<'cx>],
    u: &[Expr<'cx>],
    tau: &[Expr<'cx>],
    inputs: &[Expr<'cx>],
    opts: LowerOptions,
) -> Program {
    let dq = tangent_jacobian(cx, udot, qdot, q, u);
    lower_blocks(
        cx,
        [
            ("dq", dq),
            ("du", cx.jacobian(udot, u)),
            ("dtau", cx.jacobian(udot, tau)),
            ("dinput", cx.jacobian(udot, inputs)),
        ],
        opts,
    )
}

/// The same program by differentiating inverse dynamics: `inverse` is
/// `ID(q, u, u̇)` (`NU` expressions in the speed-rate symbols `ud`,
/// generalised forces of the model's force elements subtracted, so that
/// `ID(q, u, FD(q, u, τ)) = τ`), `udot` forward dynamics. `∂ID/∂x` is
/// built with `u̇` a symbol, then `u̇ = FD` is substituted and the result
/// multiplied by `−M⁻¹`, `M⁻¹ = ∂FD/∂τ`.
#[allow(clippy::too_many_arguments)]
pub fn forward_dynamics_derivatives_rnea<'cx>(
    cx: &'cx Context,
    udot: &[Expr<'cx>],
    inverse: &[Expr<'cx>],
    ud: &[Expr<'cx>],
    qdot: &[Expr<'cx>],
    q: &[Expr<'cx>],
    u: &[Expr<'cx>],
    tau: &[Expr<'cx>],
    inputs: &[Expr<'cx>],
    opts: LowerOptions,
) -> Program {
    let minv = cx.jacobian(udot, tau);
    // ∂ID/∂x with u̇ symbolic, by rows; then u̇ = FD substituted.
    let gq = tangent_jacobian(cx, inverse, qdot, q, u);
    let gu = cx.jacobian(inverse, u);
    let gi = cx.jacobian(inverse, inputs);
    let rates: Vec<(crate::sym::SymId, crate::sym::Id)> = ud
        .iter()
        .zip(udot)
        .filter_map(|(&s, &f)| Some((cx.sym_id(s)?, cx.id(f))))
        .collect();
    let at_fd = |rows: Vec<Vec<Expr<'cx>>>| -> Vec<Vec<Expr<'cx>>> {
        let ids: Vec<crate::sym::Id> = rows.iter().flatten().map(|&e| cx.id(e)).collect();
        let new = cx.arena_mut().substitute(&ids, |s| {
            rates.iter().find(|(r, _)| *r == s).map(|(_, f)| *f)
        });
        let cols = rows.first().map_or(0, Vec::len);
        new.chunks(cols.max(1))
            .take(rows.len())
            .map(|c| c.iter().map(|&id| cx.expr(id)).collect())
            .collect()
    };
    let (gq, gu) = (at_fd(gq), at_fd(gu));
    let gi = if inputs.is_empty() {
        vec![Vec::new(); u.len()]
    } else {
        at_fd(gi)
    };
    lower_solved(cx, &minv, [gq, gu, gi], opts)
}

/// The outputs `−M⁻¹ ∂ID/∂q`, `−M⁻¹ ∂ID/∂u`, `M⁻¹`, `−M⁻¹ ∂ID/∂(inputs)`
/// for the gradients `[gq, gu, gi]` (`NU` rows each, the columns of `gi`
/// the inputs): the layout of `forward_dynamics_derivatives`.
fn lower_solved<'cx>(
    cx: &'cx Context,
    minv: &[Vec<Expr<'cx>>],
    [gq, gu, gi]: [Vec<Vec<Expr<'cx>>>; 3],
    opts: LowerOptions,
) -> Program {
    let (nu, ni) = (minv.len(), gi.first().map_or(0, Vec::len));
    // Terms of the straight-line sums (structural zeros skipped) against
    // the dense product's, which run `PRODUCT_LANES` to an instruction.
    let sparse_terms: usize = [&gq, &gu, &gi]
        .iter()
        .map(|g| {
            let cols = g.first().map_or(0, Vec::len);
            (0..cols)
                .map(|j| {
                    minv.iter()
                        .map(|mrow| {
                            mrow.iter()
                                .zip(g.iter())
                                .filter(|(m, gk)| !m.is_zero() && !gk[j].is_zero())
                                .count()
                        })
                        .sum::<usize>()
                })
                .sum::<usize>()
        })
        .sum();
    let dense_terms = nu * nu * (2 * nu + ni);
    if nu < PRODUCTS_FROM_NU || dense_terms > PRODUCT_LANES * sparse_terms {
        return lower_blocks(
            cx,
            [
                ("dq", minus_solve(minv, gq, nu)),
                ("du", minus_solve(minv, gu, nu)),
                ("dtau", minv.to_vec()),
                ("dinput", minus_solve(minv, gi, ni)),
            ],
            opts,
        );
    }
    // The gradients in the outputs' places, `−M⁻¹ G` as products after the
    // instructions (in SIMD lanes in generated code).
    let mut p = lower_blocks(
        cx,
        [
            ("dq", gq),
            ("du", gu),
            ("dtau", minv.to_vec()),
            ("dinput", gi),
        ],
        opts,
    );
    p.products = vec![Product {
        a: 2 * nu * nu,
        n: nu,
        blocks: [(0, nu), (nu * nu, nu), (3 * nu * nu, ni)]
            .into_iter()
            .filter(|&(_, cols)| cols > 0)
            .collect(),
    }];
    p
}

/// From this many speeds on, `−M⁻¹ G` is left to a dense [`Product`]
/// after the program (loops along rows, SIMD lanes in generated code)
/// rather than expanded into straight-line sums with their structural
/// zeros skipped, unless the dense product has more than
/// [`PRODUCT_LANES`] times the sums' terms (a branched tree's `M⁻¹` with
/// its zero blocks: the Stewart platform's spanning tree, 21 speeds).
/// Measured (BENCHMARKS.md, "`−M⁻¹ ∂ID/∂x` as a dense product"): panda (9
/// speeds) 19 % fewer instructions and 12 % less time, arm7 (7) 8 % fewer
/// instructions in the same time, the spatial 10-link chain 22 % fewer
/// instructions and faster. At six speeds (BENCHMARKS.md, "ur5's
/// derivatives and the instruction cache"): ur5's function 37 KB → 33 KB
/// of machine code, which then mostly runs from the AMD EPYC host's 32 KiB
/// instruction cache, 628 → 380 ns (session 49's Intel host, with twice
/// the cache, gave the same time either way). Below six, the spatial
/// 5-link chain was slower with it (a five-wide row is a four-lane vector
/// and a remainder).
pub const PRODUCTS_FROM_NU: usize = 6;

/// The SIMD lanes a dense product is assumed to run in (four doubles to a
/// 256-bit instruction).
pub const PRODUCT_LANES: usize = 4;

/// `−M⁻¹ G` for `G` with `cols` columns (structural zeros skipped).
fn minus_solve<'cx>(
    minv: &[Vec<Expr<'cx>>],
    g: Vec<Vec<Expr<'cx>>>,
    cols: usize,
) -> Vec<Vec<Expr<'cx>>> {
    minv.iter()
        .map(|mrow| {
            (0..cols)
                .map(|j| {
                    let mut sum = Expr::zero();
                    for (gk, &m) in g.iter().zip(mrow) {
                        let x = gk[j];
                        if m.is_zero() || x.is_zero() {
                            continue;
                        }
                        sum = sum + m * x;
                    }
                    -sum
                })
                .collect()
        })
        .collect()
}

/// The same program with `∂ID/∂q` (tangent space) and `∂ID/∂u` of the
/// Newton–Euler forces given, `gq` and `gu` (`NU × NU` by rows, at
/// `u̇ = FD`, by [`crate::mech::Evaluator::rnea_derivatives`]), `minv` the
/// inverse mass matrix (`∂FD/∂τ`, or from the `LᵀDL` factors of `M`,
/// [`crate::mech::ltdl::ltdl_inverse`]), and `loads` the rest of inverse
/// dynamics (`−Jᵀ f_ext − Q`, force elements and inputs, no `u̇`),
/// differentiated here as expressions.
#[allow(clippy::too_many_arguments)]
pub fn forward_dynamics_derivatives_recursive<'cx>(
    cx: &'cx Context,
    minv: &[Vec<Expr<'cx>>],
    (gq, gu): (Vec<Vec<Expr<'cx>>>, Vec<Vec<Expr<'cx>>>),
    loads: &[Expr<'cx>],
    qdot: &[Expr<'cx>],
    q: &[Expr<'cx>],
    u: &[Expr<'cx>],
    inputs: &[Expr<'cx>],
    opts: LowerOptions,
) -> Program {
    let blocks = with_loads(cx, (gq, gu), loads, qdot, q, u, inputs);
    lower_solved(cx, minv, blocks, opts)
}

/// `∂ID/∂q` (tangent space), `∂ID/∂u` and `∂ID/∂(inputs)`: the Newton–Euler
/// forces' `gq` and `gu` plus the derivatives of `loads` (the rest of
/// inverse dynamics, no `u̇`), differentiated here as expressions.
fn with_loads<'cx>(
    cx: &'cx Context,
    (gq, gu): (Vec<Vec<Expr<'cx>>>, Vec<Vec<Expr<'cx>>>),
    loads: &[Expr<'cx>],
    qdot: &[Expr<'cx>],
    q: &[Expr<'cx>],
    u: &[Expr<'cx>],
    inputs: &[Expr<'cx>],
) -> [Vec<Vec<Expr<'cx>>>; 3] {
    if loads.iter().all(|l| l.is_zero()) {
        [gq, gu, vec![vec![Expr::zero(); inputs.len()]; u.len()]]
    } else {
        [
            add(gq, tangent_jacobian(cx, loads, qdot, q, u)),
            add(gu, cx.jacobian(loads, u)),
            cx.jacobian(loads, inputs),
        ]
    }
}

/// `a + b`, matrices by rows.
fn add<'cx>(a: Vec<Vec<Expr<'cx>>>, b: Vec<Vec<Expr<'cx>>>) -> Vec<Vec<Expr<'cx>>> {
    a.into_iter()
        .zip(b)
        .map(|(ra, rb)| ra.into_iter().zip(rb).map(|(x, y)| x + y).collect())
        .collect()
}

/// The program of `inverse_dynamics_derivatives` for inverse dynamics
/// `inverse` (`NU` expressions in the speed-rate symbols `ud`): outputs
/// `dq_i_j` (tangent space), `du_i_j`, `dud_i_j` (each `NU × NU`, by
/// rows), then `dinput_i_j` (`NU × NI`).
#[allow(clippy::too_many_arguments)]
pub fn inverse_dynamics_derivatives<'cx>(
    cx: &'cx Context,
    inverse: &[Expr<'cx>],
    ud: &[Expr<'cx>],
    qdot: &[Expr<'cx>],
    q: &[Expr<'cx>],
    u: &[Expr<'cx>],
    inputs: &[Expr<'cx>],
    opts: LowerOptions,
) -> Program {
    let dq = tangent_jacobian(cx, inverse, qdot, q, u);
    lower_blocks(
        cx,
        [
            ("dq", dq),
            ("du", cx.jacobian(inverse, u)),
            ("dud", cx.jacobian(inverse, ud)),
            ("dinput", cx.jacobian(inverse, inputs)),
        ],
        opts,
    )
}

/// The program of `inverse_dynamics_derivatives` (layout of
/// [`inverse_dynamics_derivatives`]) from the recursion's `∂ID/∂q`
/// (tangent space), `∂ID/∂u` and `M = ∂ID/∂u̇` of the Newton–Euler forces
/// at symbolic `u̇` ([`crate::mech::Evaluator::rnea_derivatives`]), and
/// `loads`, the rest of inverse dynamics (`−Jᵀ f_ext − Q`: force elements
/// and inputs, no `u̇`), differentiated here as expressions.
#[allow(clippy::too_many_arguments)]
pub fn inverse_dynamics_derivatives_recursive<'cx>(
    cx: &'cx Context,
    rd: super::rnea_derivatives::RneaDerivatives<Expr<'cx>>,
    loads: &[Expr<'cx>],
    qdot: &[Expr<'cx>],
    q: &[Expr<'cx>],
    u: &[Expr<'cx>],
    inputs: &[Expr<'cx>],
    opts: LowerOptions,
) -> Program {
    let [gq, gu, gi] = with_loads(cx, (rd.dq, rd.du), loads, qdot, q, u, inputs);
    lower_blocks(
        cx,
        [("dq", gq), ("du", gu), ("dud", rd.m), ("dinput", gi)],
        opts,
    )
}
