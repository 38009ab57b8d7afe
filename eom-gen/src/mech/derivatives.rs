//! Partial derivatives of forward dynamics, by differentiating the
//! expressions of the form forward dynamics was generated in (articulated
//! bodies or `LᵀDL`): `∂u̇/∂q`, `∂u̇/∂u`, `∂u̇/∂τ`, `∂u̇/∂(inputs)`.
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
//! The derivatives go through the same simplification, CSE and emission
//! as every other generated function (see [`crate::functions`] for the
//! layout of the result).

use crate::sym::{Context, Expr, LowerOptions, Program, Scalar};

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
    // N = ∂q̇/∂u, with its structural zeros (most entries).
    let n = cx.jacobian(qdot, u);
    let mut names: Vec<String> = Vec::new();
    let mut values: Vec<Expr<'cx>> = Vec::new();
    // ∂u̇/∂q in the tangent space.
    for (i, &ud) in udot.iter().enumerate() {
        let dq: Vec<Expr<'cx>> = q.iter().map(|&qk| cx.diff(ud, qk)).collect();
        for j in 0..u.len() {
            let mut sum = Expr::zero();
            for (k, d) in dq.iter().enumerate() {
                let nkj = n[k][j];
                if nkj.is_zero() || d.is_zero() {
                    continue;
                }
                sum = sum + *d * nkj;
            }
            names.push(format!("dq_{i}_{j}"));
            values.push(sum);
        }
    }
    for (prefix, vars) in [("du", u), ("dtau", tau), ("dinput", inputs)] {
        for (i, &ud) in udot.iter().enumerate() {
            for (j, &v) in vars.iter().enumerate() {
                names.push(format!("{prefix}_{i}_{j}"));
                values.push(cx.diff(ud, v));
            }
        }
    }
    let outs: Vec<(&str, Expr<'cx>)> = names.iter().map(String::as_str).zip(values).collect();
    cx.lower(&outs, opts)
}
