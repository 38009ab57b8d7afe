//! The impulses of a redundant contact block (issue #26; Pfeiffer and
//! Glocker, *Multibody Dynamics with Unilateral Contacts*, ch. 7).
//!
//! A box landing flat on four corners has four normal and eight tangential
//! rows on six speeds: the block `G = W M⁻¹ Wᵀ` of a contact mode (which
//! rows are active, sticking, sliding) is singular. Its equations
//! `G z = −b` are consistent, the speeds after (`Δu = M⁻¹ Wᵀ z`) are
//! unique, but the impulses `z` are not: they form the affine set
//! `z₀ + N y`, `z₀` the minimum-norm solution, `N` an orthonormal basis of
//! the block's null space. The mode is feasible when SOME point of that set
//! satisfies the signs and the cones — per active row `Λ ≥ 0`, and with
//! sticking friction `‖Λ_t‖ ≤ μ Λ`. Of the feasible impulses we report the
//! one of minimum norm (a choice: the physics does not fix it; it spreads
//! the load evenly over symmetric contacts), the projection of the origin
//! onto the intersection of the affine set and the cones. Where the set
//! is a line (a null space of dimension one) it is found in closed form
//! ([`on_a_line`]: each cone holds the line on an interval); otherwise by
//! a barrier method on the set's coordinates ([`interior`]: a small
//! second-order cone program, Boyd and Vandenberghe, *Convex
//! Optimization*, §11.3–11.4), whose first phase decides whether the
//! intersection is empty with a bound, not a stall rule. Dykstra's
//! alternating projections (Boyle and Dykstra 1986), which this replaced,
//! stay as the tests' independent reference.

use crate::constrained::{DMatrix, DVector};

/// The cones are widened by this much, relative to `max |z0|` (`x ≥ −σ`,
/// `‖v‖ ≤ μ x + σ`): a set that touches a cone's boundary (a corner with
/// no load, a row on the edge of sticking) is feasible, as it is.
const SLACK: f64 = 1e-12;

/// The impulses are sought within `R = 10⁶` times `max |z0|` of `z0`
/// (a ball in the set's coordinates, part of the barrier): a feasible
/// point only farther away would be a load a million times the one the
/// equations need, and is not sought.
const RADIUS: f64 = 1e6;

/// Newton steps per centring before it stops where it is.
const NEWTON_STEPS: usize = 100;

/// The barrier's weight grows by this factor between centrings.
const GROWTH: f64 = 16.0;

/// The unknowns of one active contact row in the block: its normal
/// impulse's position and, if it sticks, its two tangential ones' and `μ`.
pub(super) struct Cone {
    pub normal: usize,
    pub tangential: Option<([usize; 2], f64)>,
}

/// Projects `z` onto the cones (`with_friction`) or only the signs
/// (`Λ ≥ 0`, tangential impulses free) of `cones`, in place.
pub(super) fn project_cones(z: &mut DVector<f64>, cones: &[Cone], with_friction: bool) {
    for c in cones {
        let x = z[c.normal];
        match c.tangential {
            Some(([a, b], mu)) if with_friction => {
                // The second-order cone K = {‖v‖ ≤ μ x}; its polar is
                // {μ ‖v‖ ≤ −x}; between them onto the ray (1, μ v/‖v‖).
                let nv = z[a].hypot(z[b]);
                if nv <= mu * x {
                    continue;
                }
                if mu * nv <= -x {
                    z[c.normal] = 0.0;
                    z[a] = 0.0;
                    z[b] = 0.0;
                    continue;
                }
                let s = (x + mu * nv) / (1.0 + mu * mu);
                z[c.normal] = s;
                z[a] *= mu * s / nv;
                z[b] *= mu * s / nv;
            }
            _ => z[c.normal] = x.max(0.0),
        }
    }
}

/// Whether `z` satisfies the signs (and the cones: `with_friction`) of
/// `cones` up to the runtime's tolerances (`Λ ≥ −10⁻¹⁰ max |z|`,
/// `‖Λ_t‖ ≤ μ Λ (1 + 10⁻⁹)`).
fn inside(z: &DVector<f64>, cones: &[Cone], with_friction: bool) -> bool {
    let big = z.amax();
    cones.iter().all(|c| {
        let x = z[c.normal];
        x >= -1e-10 * big
            && match c.tangential {
                Some(([a, b], mu)) if with_friction => z[a].hypot(z[b]) <= mu * x * (1.0 + 1e-9),
                _ => true,
            }
    })
}

/// The impulse of minimum norm in `{z0 + N y} ∩ K` (`null` = `N`, with
/// orthonormal columns; `z0` the minimum-norm solution, orthogonal to
/// them), `K` the cones of `cones` (`with_friction`) or their signs:
/// `(z_K, z_A)`, the point in `K` (the impulses to report) and its
/// projection on the affine set (the one whose speeds to take), within
/// `10⁻¹²` of each other relative to `z0`; `None` if the intersection is
/// empty (even with the cones widened by [`SLACK`]). A one-dimensional
/// null space (the commonest: a box on four corners, one of them free of
/// friction's rows) is solved in closed form by [`on_a_line`]; a wider one
/// by the barrier method of [`interior`].
pub(super) fn min_norm_feasible(
    z0: &DVector<f64>,
    null: &DMatrix<f64>,
    cones: &[Cone],
    with_friction: bool,
) -> Option<(DVector<f64>, DVector<f64>)> {
    if inside(z0, cones, with_friction) {
        let mut z = z0.clone();
        for c in cones {
            z[c.normal] = z[c.normal].max(0.0);
        }
        return Some((z, z0.clone()));
    }
    if null.ncols() == 1 {
        on_a_line(z0, null, cones, with_friction)
    } else {
        interior(z0, null, cones, with_friction)
    }
}

/// `t` with `lo ≤ t ≤ hi` for the points `z0 + t n` of a line that lie
/// in one cone (`normal` row `x`, tangential rows `v`, friction `mu`) or
/// its sign (`mu = None`), each widened by `slack` (`x ≥ −slack`,
/// `‖v‖ ≤ μ x + slack`): the intersection of a line with a convex set is
/// an interval. `None` if it is empty.
fn interval(x: [f64; 2], v: [[f64; 2]; 2], mu: Option<f64>, slack: f64) -> Option<[f64; 2]> {
    // x0 + t xn ≥ −slack.
    let half_line = |x0: f64, xn: f64| -> Option<[f64; 2]> {
        if xn == 0.0 {
            (x0 >= 0.0).then_some([f64::NEG_INFINITY, f64::INFINITY])
        } else if xn > 0.0 {
            Some([-x0 / xn, f64::INFINITY])
        } else {
            Some([f64::NEG_INFINITY, -x0 / xn])
        }
    };
    let Some(mu) = mu else {
        return half_line(x[0] + slack, x[1]);
    };
    // ‖v0 + t vn‖ ≤ μ (x0 + t xn) + slack, i.e. in the cone shifted to
    // the apex −slack/μ: y = x + slack/μ ≥ 0 and q(t) = μ² y² − ‖v‖² ≥ 0.
    let y = [x[0] + slack / mu, x[1]];
    let on = half_line(y[0], y[1])?;
    let (m2, [v0, vn]) = (mu * mu, v);
    let a = m2 * y[1] * y[1] - vn[0] * vn[0] - vn[1] * vn[1];
    let b = 2.0 * (m2 * y[0] * y[1] - v0[0] * vn[0] - v0[1] * vn[1]);
    let c = m2 * y[0] * y[0] - v0[0] * v0[0] - v0[1] * v0[1];
    let big = m2 * y[1] * y[1] + vn[0] * vn[0] + vn[1] * vn[1];
    // Where q ≥ 0 the line is in the cone or in its mirror (y < 0); the
    // cone's part is the piece on `on`'s side (q > 0 never changes sides:
    // y = 0 makes q = −‖v‖² ≤ 0).
    let quad = if a.abs() <= 1e-14 * big {
        // q linear: a half-line (or all or nothing).
        if b == 0.0 {
            if c < 0.0 {
                return None;
            }
            [f64::NEG_INFINITY, f64::INFINITY]
        } else if b > 0.0 {
            [-c / b, f64::INFINITY]
        } else {
            [f64::NEG_INFINITY, -c / b]
        }
    } else {
        let disc = b * b - 4.0 * a * c;
        if disc < 0.0 {
            // q keeps the sign of a: everywhere inside (a > 0), or nowhere.
            if a < 0.0 {
                return None;
            }
            [f64::NEG_INFINITY, f64::INFINITY]
        } else {
            let h = -0.5 * (b + b.signum() * disc.sqrt());
            let (r1, r2) = if h == 0.0 { (0.0, 0.0) } else { (h / a, c / h) };
            let (r1, r2) = (r1.min(r2), r1.max(r2));
            if a < 0.0 {
                [r1, r2]
            } else if y[1] > 0.0 {
                // a > 0 needs μ² y_n² > ‖v_n‖², so y_n ≠ 0: the cone is
                // the piece where y grows, the upper one ...
                [r2, f64::INFINITY]
            } else {
                // ... or, y falling, the lower one.
                [f64::NEG_INFINITY, r1]
            }
        }
    };
    let (lo, hi) = (on[0].max(quad[0]), on[1].min(quad[1]));
    (lo <= hi).then_some([lo, hi])
}

/// [`min_norm_feasible`] on a line `z0 + t n` (`null` one unit column
/// `n ⊥ z0`), exactly: each cone holds the line on an interval of `t`
/// ([`interval`]), and of their intersection the `t` of least `|t|`
/// gives the least `‖z‖² = ‖z0‖² + t²`. The cones are widened by
/// `10⁻¹²` of `z0`, the tolerance [`dykstra`] closes its gap to, so a
/// line that touches a cone's boundary (a corner with no load, a row on
/// the edge of sticking) is found feasible as it is by the projections;
/// the point found is then projected onto the cones themselves.
fn on_a_line(
    z0: &DVector<f64>,
    null: &DMatrix<f64>,
    cones: &[Cone],
    with_friction: bool,
) -> Option<(DVector<f64>, DVector<f64>)> {
    let n = null.column(0);
    let slack = SLACK * z0.amax().max(f64::MIN_POSITIVE);
    let (mut lo, mut hi) = (f64::NEG_INFINITY, f64::INFINITY);
    for c in cones {
        let x = [z0[c.normal], n[c.normal]];
        let [l, h] = match c.tangential {
            Some(([p, q], mu)) if with_friction => {
                interval(x, [[z0[p], z0[q]], [n[p], n[q]]], Some(mu), slack)?
            }
            _ => interval(x, [[0.0; 2]; 2], None, slack)?,
        };
        (lo, hi) = (lo.max(l), hi.min(h));
        if lo > hi || lo.is_nan() || hi.is_nan() {
            return None;
        }
    }
    let t = 0f64.clamp(lo, hi);
    let mut zk = z0 + n * t;
    project_cones(&mut zk, cones, with_friction);
    if !zk.iter().all(|v| v.is_finite()) {
        return None;
    }
    let za = z0 + n * (n.dot(&(&zk - z0)));
    Some((zk, za))
}

/// One cone's rows as affine functions of the coordinates `y` of the
/// affine set (`z = z0 + N y`, in units of `max |z0|`): the normal impulse
/// `x0 + gx·y` and, with friction, the tangential pair `v0 + gv y` and `μ`.
struct Rows {
    x0: f64,
    gx: DVector<f64>,
    friction: Option<([f64; 2], [DVector<f64>; 2], f64)>,
}

/// The logarithmic barrier of the cones widened by [`SLACK`] (`−ln h` of
/// a sign's margin `h = x + σ`, `−ln(w² − ‖v‖²)` of a cone's, `w = μ x +
/// σ`, `w > 0`) and of the ball `‖y‖ < R` ([`RADIUS`]) at `p`, `None`
/// outside its domain; with `derivatives`, its gradient and Hessian are
/// added to them. In phase one the last coordinate of `p` is a margin `s`
/// added to every `h` and `w`.
fn barrier(
    rows: &[Rows],
    p: &DVector<f64>,
    phase_one: bool,
    mut derivatives: Option<(&mut DVector<f64>, &mut DMatrix<f64>)>,
) -> Option<f64> {
    let dim = p.len();
    let d = dim - usize::from(phase_one);
    let y = p.rows(0, d);
    let s = if phase_one { p[d] } else { 0.0 };
    // The ball `‖y‖ < R`: `−ln(R² − ‖y‖²)`, curvature in every direction
    // (phase one is otherwise flat along directions that move every margin
    // alike, and unbounded along those that open them all).
    let ball = RADIUS * RADIUS - y.norm_squared();
    if ball.is_nan() || ball <= 0.0 {
        return None;
    }
    let mut value = -ball.ln();
    if let Some((grad, hess)) = derivatives.as_mut() {
        for i in 0..d {
            grad[i] += 2.0 * y[i] / ball;
            hess[(i, i)] += 2.0 / ball;
            for j in 0..d {
                hess[(i, j)] += 4.0 * y[i] * y[j] / (ball * ball);
            }
        }
    }
    for r in rows {
        let x = r.x0 + r.gx.dot(&y);
        match &r.friction {
            None => {
                let h = x + SLACK + s;
                if h.is_nan() || h <= 0.0 {
                    return None;
                }
                value -= h.ln();
                if let Some((grad, hess)) = derivatives.as_mut() {
                    // ∇h = a (its last component 1 in phase one).
                    let a = |i: usize| if i < d { r.gx[i] } else { 1.0 };
                    for i in 0..dim {
                        grad[i] -= a(i) / h;
                        for j in 0..dim {
                            hess[(i, j)] += a(i) * a(j) / (h * h);
                        }
                    }
                }
            }
            Some((v0, gv, mu)) => {
                let w = mu * x + SLACK + s;
                let v = [v0[0] + gv[0].dot(&y), v0[1] + gv[1].dot(&y)];
                let q = w * w - v[0] * v[0] - v[1] * v[1];
                if w.is_nan() || q.is_nan() || w <= 0.0 || q <= 0.0 {
                    return None;
                }
                value -= q.ln();
                if let Some((grad, hess)) = derivatives.as_mut() {
                    // ∇w = a, ∇v_k = b_k; ∇q = 2 w a − 2 Σ v_k b_k;
                    // ∇²(−ln q) = ∇q ∇qᵀ / q² − ∇²q / q, ∇²q = 2 a aᵀ − 2 Σ b bᵀ.
                    let a = |i: usize| if i < d { mu * r.gx[i] } else { 1.0 };
                    let b = |k: usize, i: usize| if i < d { gv[k][i] } else { 0.0 };
                    let dq = |i: usize| 2.0 * (w * a(i) - v[0] * b(0, i) - v[1] * b(1, i));
                    for i in 0..dim {
                        grad[i] -= dq(i) / q;
                        for j in 0..dim {
                            hess[(i, j)] += dq(i) * dq(j) / (q * q)
                                - 2.0 * (a(i) * a(j) - b(0, i) * b(0, j) - b(1, i) * b(1, j)) / q;
                        }
                    }
                }
            }
        }
    }
    Some(value)
}

/// The Newton step `−H⁻¹ g` (Cholesky; `H` shifted by a multiple of the
/// identity, growing, where it is only semi-definite: a direction along
/// which the barrier is flat).
fn newton_step(mut h: DMatrix<f64>, g: &DVector<f64>) -> Option<DVector<f64>> {
    let mut shift = 1e-14 * h.diagonal().amax().max(f64::MIN_POSITIVE);
    for _ in 0..20 {
        if let Some(ch) = h.clone().cholesky() {
            let step = -ch.solve(g);
            return step.iter().all(|v| v.is_finite()).then_some(step);
        }
        for i in 0..h.nrows() {
            h[(i, i)] += shift;
        }
        shift *= 100.0;
    }
    None
}

/// Centres `p` on the central path at weight `t`: Newton's method with a
/// backtracking line search on `t f + barrier`, `f` the margin `s` (phase
/// one, which stops as soon as `s < 0`) or `‖y‖²` (phase two). `None` if
/// `p` leaves the domain (it never does: every step is checked) or a
/// Hessian cannot be factored.
fn centre(rows: &[Rows], p: &mut DVector<f64>, t: f64, phase_one: bool) -> Option<()> {
    let dim = p.len();
    // t f + barrier: value only, or with its gradient and Hessian.
    let value = |p: &DVector<f64>| -> Option<f64> {
        let f = if phase_one {
            p[dim - 1]
        } else {
            p.norm_squared()
        };
        Some(t * f + barrier(rows, p, phase_one, None)?)
    };
    for _ in 0..NEWTON_STEPS {
        let (mut g, mut h) = (DVector::zeros(dim), DMatrix::zeros(dim, dim));
        let b = barrier(rows, p, phase_one, Some((&mut g, &mut h)))?;
        let current = if phase_one {
            g[dim - 1] += t;
            t * p[dim - 1] + b
        } else {
            g.axpy(2.0 * t, p, 1.0);
            for i in 0..dim {
                h[(i, i)] += 2.0 * t;
            }
            t * p.norm_squared() + b
        };
        let step = newton_step(h, &g)?;
        // The Newton decrement λ² = −gᵀ Δ: half of it estimates how far
        // the value is above the centre's.
        let decrement = -g.dot(&step);
        if decrement <= 1e-12 {
            return Some(());
        }
        // Backtracking from the full step: the value must fall by a
        // quarter of what the step promises. Where rounding hides that (a
        // decrement below the value's last digits), the point is as
        // centred as it gets.
        if decrement <= 1e-15 * current.abs() {
            return Some(());
        }
        let mut alpha = 1.0;
        let mut next = loop {
            let trial = &*p + &step * alpha;
            if value(&trial).is_some_and(|v| v <= current - 0.25 * alpha * decrement) {
                break Some(trial);
            }
            alpha *= 0.5;
            if alpha < 1e-12 {
                break None;
            }
        };
        // Phase one is done at any `s < 0`; the step may run far along a
        // direction in which the cones are unbounded: stop on its segment
        // where `s = −½` (inside, as the set with margins is convex).
        if let Some(n) = next.as_mut()
            && phase_one
            && n[dim - 1] < -0.5
        {
            let (s0, s1) = (p[dim - 1], n[dim - 1]);
            let at = (s0 + 0.5) / (s0 - s1);
            *n = &*p + (&*n - &*p) * at;
        }
        match next {
            Some(n) => *p = n,
            None => return Some(()),
        }
        if phase_one && p[dim - 1] < 0.0 {
            return Some(());
        }
    }
    Some(())
}

/// [`min_norm_feasible`] for a null space of any width, by a barrier
/// method on the coordinates `y` of the affine set, in units of
/// `max |z0|`, with the cones widened by [`SLACK`] (Boyd and
/// Vandenberghe §11.3–11.4):
///
/// - **Phase one** minimises a margin `s` added to every cone's (`x + σ +
///   s ≥ 0`, `‖v‖ ≤ μ x + σ + s`) from `y = 0` and an `s` that makes it
///   strictly feasible. A point with `s < 0` is strictly inside the widened
///   cones: the intersection is not empty. On the central path at weight
///   `t` the least margin is at least `s − ν/t` (`ν` the barrier's
///   parameter: 1 per sign, 2 per cone, 1 for the ball), so once that is
///   positive the
///   widened intersection is empty — a bound, where the projections had a
///   rule of thumb (a gap that stopped shrinking). Undecided at
///   `t = 10¹⁶` (the widened set touches the origin's margin to rounding)
///   counts as empty.
/// - **Phase two** minimises `‖y‖²` (`‖z‖² = ‖z0‖² + ‖y‖²`, `z0 ⊥ N`) from
///   there, until `ν/t ≤ 10⁻¹⁴`: the value is then within that of the
///   least, the point on the central path within `O(1/t)` of it.
///
/// The point found is in the widened cones; it is projected onto the
/// cones themselves, and then onto the affine set, as [`on_a_line`] does.
fn interior(
    z0: &DVector<f64>,
    null: &DMatrix<f64>,
    cones: &[Cone],
    with_friction: bool,
) -> Option<(DVector<f64>, DVector<f64>)> {
    let scale = z0.amax().max(f64::MIN_POSITIVE);
    // The directions of the set the cones see: the span of their rows'
    // gradients. Along the others no margin changes (phase one would be
    // flat there) and the least ‖y‖ has no component.
    let seen: Vec<usize> = cones
        .iter()
        .flat_map(|c| match c.tangential {
            Some(([a, b], _)) if with_friction => vec![c.normal, a, b],
            _ => vec![c.normal],
        })
        .collect();
    if seen.is_empty() || null.ncols() == 0 {
        // Nothing to move, or nothing to fit: z0 alone, and it is not
        // inside (checked first).
        return None;
    }
    let grads = DMatrix::from_fn(seen.len(), null.ncols(), |r, k| null[(seen[r], k)]);
    let svd = grads.svd(false, true);
    let v_t = svd.v_t.as_ref()?;
    let cut = 1e-12 * svd.singular_values.amax();
    let basis: Vec<usize> = (0..svd.singular_values.len())
        .filter(|&i| svd.singular_values[i] > cut)
        .collect();
    if basis.is_empty() {
        // No cone sees the set: z0 is the only candidate, and it is not
        // inside (checked first).
        return None;
    }
    // `N B`: the set's directions the cones see, orthonormal.
    let b = DMatrix::from_fn(null.ncols(), basis.len(), |k, c| v_t[(basis[c], k)]);
    let seen_null = null * b;
    let d = seen_null.ncols();
    let rows: Vec<Rows> = cones
        .iter()
        .map(|c| {
            let at = |k: usize| (z0[k] / scale, seen_null.row(k).transpose());
            let (x0, gx) = at(c.normal);
            let friction = match c.tangential {
                Some(([a, b], mu)) if with_friction => {
                    let ((va, ga), (vb, gb)) = (at(a), at(b));
                    Some(([va, vb], [ga, gb], mu))
                }
                _ => None,
            };
            Rows { x0, gx, friction }
        })
        .collect();
    let nu: f64 = 1.0
        + rows
            .iter()
            .map(|r| if r.friction.is_some() { 2.0 } else { 1.0 })
            .sum::<f64>();
    // Phase one from y = 0 with a margin that makes every cone strict.
    let violation = rows
        .iter()
        .map(|r| match &r.friction {
            None => -(r.x0 + SLACK),
            Some((v0, _, mu)) => v0[0].hypot(v0[1]) - (mu * r.x0 + SLACK),
        })
        .fold(0.0, f64::max);
    let mut p = DVector::zeros(d + 1);
    p[d] = violation + 1.0;
    let mut t = 1.0;
    loop {
        centre(&rows, &mut p, t, true)?;
        if p[d] < 0.0 {
            break;
        }
        if p[d] - nu / t > 0.0 || t > 1e16 {
            return None;
        }
        t *= GROWTH;
    }
    // Phase two: the least ‖y‖² in the widened cones.
    let mut y = p.rows(0, d).into_owned();
    let mut t = 1.0;
    while nu / t > 1e-14 {
        centre(&rows, &mut y, t, false)?;
        t *= GROWTH;
    }
    let mut zk = z0 + &seen_null * (y * scale);
    project_cones(&mut zk, cones, with_friction);
    if !zk.iter().all(|v| v.is_finite()) {
        return None;
    }
    let za = z0 + null * (null.transpose() * (&zk - z0));
    Some((zk, za))
}

/// Dykstra's stall rule: every this many projections the gap between the
/// sets must have shrunk by 1 % (away from zero), else they were declared
/// apart.
#[cfg(test)]
const STALL_EVERY: usize = 100;

/// Dykstra's alternating projections from the origin onto the affine set
/// and the cones, as [`min_norm_feasible`] used them for the wider null
/// spaces before [`interior`]: `None` when the gap is not closed within
/// `max_iter` projections or, with `stall_rule`, when it stalls (see
/// [`STALL_EVERY`]). The tests' independent reference, and their record
/// of what the stall rule got wrong.
#[cfg(test)]
fn dykstra(
    z0: &DVector<f64>,
    null: &DMatrix<f64>,
    cones: &[Cone],
    with_friction: bool,
    max_iter: usize,
    stall_rule: bool,
) -> Option<(DVector<f64>, DVector<f64>)> {
    let affine = |z: &DVector<f64>| z0 + null * (null.transpose() * (z - z0));
    let tol = SLACK * z0.amax().max(f64::MIN_POSITIVE);
    // Dykstra from the origin: y = P_A(x), x' = P_K(y + q), q' = y + q − x'.
    let mut x = DVector::zeros(z0.len());
    let mut q = DVector::zeros(z0.len());
    let mut last = f64::INFINITY;
    for it in 1..=max_iter {
        let y = affine(&x);
        let mut next = &y + &q;
        project_cones(&mut next, cones, with_friction);
        q += &y - &next;
        let (gap, moved) = ((&next - &y).amax(), (&next - &x).amax());
        x = next;
        if !x.iter().all(|v| v.is_finite()) {
            return None;
        }
        if gap <= tol && moved <= tol {
            let y = affine(&x);
            return Some((x, y));
        }
        if stall_rule && it % STALL_EVERY == 0 {
            if gap > 1e3 * tol && gap >= 0.99 * last {
                return None;
            }
            last = gap;
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two equal rows `z₁ + z₂ = 2` (a load on two redundant supports):
    /// the minimum-norm impulses `(1, 1)` are feasible and kept. One row
    /// `z₁ − z₂ = 4`: its minimum-norm solution `(2, −2)` is not, the
    /// feasible one of minimum norm is `(4, 0)`; with `z₁ + z₂ = 0` held
    /// too, none is.
    #[test]
    fn two_redundant_supports_share_the_load() {
        let s = std::f64::consts::FRAC_1_SQRT_2;
        let null = DMatrix::from_column_slice(2, 1, &[s, -s]);
        let cones = [
            Cone {
                normal: 0,
                tangential: None,
            },
            Cone {
                normal: 1,
                tangential: None,
            },
        ];
        let z0 = DVector::from_vec(vec![1.0, 1.0]);
        let (z, _) = min_norm_feasible(&z0, &null, &cones, true).expect("feasible");
        assert_eq!(z.as_slice(), &[1.0, 1.0]);
        let null = DMatrix::from_column_slice(2, 1, &[s, s]);
        let z0 = DVector::from_vec(vec![2.0, -2.0]);
        let (z, y) = min_norm_feasible(&z0, &null, &cones, true).expect("feasible");
        assert!((z[0] - 4.0).abs() < 1e-10 && z[1].abs() < 1e-10, "{z}");
        assert!((y[0] - y[1] - 4.0).abs() < 1e-12, "{y}");
        let null = DMatrix::zeros(2, 0);
        assert!(min_norm_feasible(&z0, &null, &cones, true).is_none());
    }

    /// A sticking row `(Λ, Λ_t)` with `Λ_t = 1` fixed and `Λ` free: the
    /// cone `|Λ_t| ≤ μ Λ` with `μ = 0.5` needs `Λ ≥ 2`.
    #[test]
    fn the_cone_sets_the_least_normal_impulse() {
        let null = DMatrix::from_column_slice(3, 1, &[1.0, 0.0, 0.0]);
        let z0 = DVector::from_vec(vec![0.0, 1.0, 0.0]);
        let cones = [Cone {
            normal: 0,
            tangential: Some(([1, 2], 0.5)),
        }];
        let (z, _) = min_norm_feasible(&z0, &null, &cones, true).expect("feasible");
        assert!(
            (z[0] - 2.0).abs() < 1e-10 && (z[1] - 1.0).abs() < 1e-10,
            "{z}"
        );
        // Without friction's cone only Λ ≥ 0: z0 itself.
        let (z, _) = min_norm_feasible(&z0, &null, &cones, false).expect("feasible");
        assert_eq!(z.as_slice(), z0.as_slice());
    }

    /// The closed form on a line against Dykstra's projections, on random
    /// lines through three cones (two with friction's rows). Every point
    /// the line finds is in the cones, on the line, and the least: a point
    /// a millionth nearer `z0` is outside. Where both find a point it is
    /// the same; the line never misses a point the projections find. The
    /// projections miss some (they stall on lines at a small angle to a
    /// cone's face, and are then declared empty): counted, and printed.
    /// A small linear congruential generator keeps the cases fixed.
    #[test]
    fn the_line_agrees_with_the_projections() {
        let mut seed = 0x2545_f491_4f6c_dd1d_u64;
        let mut next = move || {
            seed = seed
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            (seed >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
        };
        let (mut both, mut neither, mut missed) = (0, 0, 0);
        for case in 0..400 {
            let mu = [0.2 + 1.8 * next().abs(), 0.2 + 1.8 * next().abs()];
            let cones = [
                Cone {
                    normal: 0,
                    tangential: Some(([1, 2], mu[0])),
                },
                Cone {
                    normal: 3,
                    tangential: Some(([4, 5], mu[1])),
                },
                Cone {
                    normal: 6,
                    tangential: None,
                },
            ];
            let n = DVector::from_fn(7, |_, _| next()).normalize();
            let z = DVector::from_fn(7, |_, _| next());
            let z0 = &z - &n * n.dot(&z);
            let null = DMatrix::from_column_slice(7, 1, n.as_slice());
            for with_friction in [true, false] {
                let what = format!("case {case} (friction {with_friction})");
                let line = on_a_line(&z0, &null, &cones, with_friction);
                if let Some((zl, al)) = &line {
                    let t = n.dot(&(zl - &z0));
                    assert!(inside(zl, &cones, with_friction), "{what}: {zl}");
                    assert!((zl - al).amax() < 1e-10, "{what}: {zl} vs {al}");
                    assert!((al - (&z0 + &n * t)).amax() < 1e-12, "{what}: {al}");
                    if t.abs() > 1e-9 {
                        let nearer = &z0 + &n * (t * (1.0 - 1e-6));
                        assert!(!inside(&nearer, &cones, with_friction), "{what}: t = {t}");
                    }
                }
                match (
                    &line,
                    dykstra(&z0, &null, &cones, with_friction, 20_000, true),
                ) {
                    (Some((zl, _)), Some((zp, _))) => {
                        both += 1;
                        assert!(
                            (zl - &zp).amax() < 1e-6 * zp.amax(),
                            "{what}: line {zl}, projections {zp}"
                        );
                    }
                    (None, None) => neither += 1,
                    (Some(_), None) => missed += 1,
                    (None, Some((zp, _))) => panic!("{what}: the line missed {zp}"),
                }
            }
        }
        eprintln!("{both} found by both, {neither} by neither, {missed} by the line only");
        assert!(both > 50 && neither > 50, "{both} / {neither}");
    }

    /// The small linear congruential generator of the random cases (fixed
    /// seeds keep them the same run to run): numbers in `[−1, 1)`.
    fn uniform(mut seed: u64) -> impl FnMut() -> f64 {
        move || {
            seed = seed
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            (seed >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
        }
    }

    /// Three friction cones on nine unknowns, random coefficients.
    fn three_cones(next: &mut impl FnMut() -> f64) -> [Cone; 3] {
        [0, 3, 6].map(|k| Cone {
            normal: k,
            tangential: Some(([k + 1, k + 2], 0.2 + 1.8 * next().abs())),
        })
    }

    /// What every point `interior` returns must be: in the cones, on the
    /// affine set (`za`, within `10⁻¹⁰` of `zk`), and the least (`y`
    /// shrunk by a millionth toward `z0` leaves the cones).
    fn check_least(
        what: &str,
        (zk, za): &(DVector<f64>, DVector<f64>),
        z0: &DVector<f64>,
        null: &DMatrix<f64>,
        cones: &[Cone],
        with_friction: bool,
    ) {
        let y = null.transpose() * (za - z0);
        assert!(inside(zk, cones, with_friction), "{what}: {zk}");
        assert!((zk - za).amax() < 1e-10 * z0.amax(), "{what}: {zk} vs {za}");
        assert!(
            (za - (z0 + null * &y)).amax() < 1e-12 * z0.amax(),
            "{what}: {za}"
        );
        if y.norm() > 1e-6 * z0.amax() {
            let nearer = z0 + null * (&y * (1.0 - 1e-6));
            assert!(!inside(&nearer, cones, with_friction), "{what}: y = {y}");
        }
    }

    /// The barrier method on lines, against the closed form: the same
    /// verdict on every line and the same point where there is one.
    #[test]
    fn the_barrier_agrees_with_the_line() {
        let mut next = uniform(0x9e37_79b9_7f4a_7c15);
        let (mut found, mut empty) = (0, 0);
        for case in 0..300 {
            let cones = three_cones(&mut next);
            let n = DVector::from_fn(9, |_, _| next()).normalize();
            let z = DVector::from_fn(9, |_, _| next());
            let z0 = &z - &n * n.dot(&z);
            let null = DMatrix::from_column_slice(9, 1, n.as_slice());
            for with_friction in [true, false] {
                let what = format!("case {case} (friction {with_friction})");
                let line = on_a_line(&z0, &null, &cones, with_friction);
                match (&line, interior(&z0, &null, &cones, with_friction)) {
                    (Some((zl, _)), Some(zb)) => {
                        found += 1;
                        check_least(&what, &zb, &z0, &null, &cones, with_friction);
                        assert!(
                            (zl - &zb.0).amax() < 1e-7 * z0.amax(),
                            "{what}: line {zl}, barrier {}",
                            zb.0
                        );
                    }
                    (None, None) => empty += 1,
                    (l, b) => panic!("{what}: line {l:?}, barrier {b:?}"),
                }
            }
        }
        eprintln!("{found} lines meet the cones, {empty} do not");
        assert!(found > 50 && empty > 50, "{found} / {empty}");
    }

    /// Null spaces of two to four dimensions through three friction cones,
    /// against Dykstra's projections run without the stall rule (10 000
    /// projections): where the projections close the gap, the barrier
    /// method finds the same point; it never declares such a set empty;
    /// every point it returns is in the cones, on the set and the least.
    /// The stall rule's verdicts (which the solver used before) are
    /// counted beside: each feasible set it declared empty would have had
    /// its sticking contacts made to slide.
    #[test]
    fn wider_null_spaces_against_the_projections() {
        let mut next = uniform(0x2545_f491_4f6c_dd1d);
        let (mut both, mut barrier_only, mut neither, mut stalled) = (0, 0, 0, 0);
        for case in 0..36 {
            let cones = three_cones(&mut next);
            let d = 2 + case % 3;
            let raw = DMatrix::from_fn(9, d, |_, _| next());
            let null = raw.qr().q();
            let z = DVector::from_fn(9, |_, _| next());
            let z0 = &z - &null * (null.transpose() * &z);
            for with_friction in [true, false] {
                let what = format!("case {case}, {d} dimensions (friction {with_friction})");
                let barrier = interior(&z0, &null, &cones, with_friction);
                if let Some(zb) = &barrier {
                    check_least(&what, zb, &z0, &null, &cones, with_friction);
                }
                let long = dykstra(&z0, &null, &cones, with_friction, 10_000, false);
                match (&barrier, &long) {
                    (Some((zb, _)), Some((zp, _))) => {
                        both += 1;
                        assert!(
                            (zb - zp).amax() < 1e-6 * z0.amax(),
                            "{what}: barrier {zb}, projections {zp}"
                        );
                        if dykstra(&z0, &null, &cones, with_friction, 10_000, true).is_none() {
                            stalled += 1;
                        }
                    }
                    (Some(_), None) => barrier_only += 1,
                    (None, None) => neither += 1,
                    (None, Some((zp, _))) => panic!("{what}: the barrier missed {zp}"),
                }
            }
        }
        eprintln!(
            "{both} found by both ({stalled} of them declared empty by the stall rule), \
             {barrier_only} by the barrier only, {neither} by neither"
        );
        assert!(both > 10 && neither > 10, "{both} / {neither}");
    }
}
