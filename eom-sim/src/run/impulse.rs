//! The impulse and force problems of contacts (Wittenburg ch. 6; Pfeiffer
//! and Glocker): the linear complementarity problem of the normal rows
//! ([`lcp`]), the generalised Newton law of an impact with Coulomb
//! friction ([`impact`]), and the mode search behind both ([`Problem`]:
//! which rows press, stick or slide, regular or redundant blocks). The
//! runtime that locates events and holds sustained contacts is
//! [`super::contact`].

use super::contact::{MAX_LCP, Rows};
use super::redundant::{Cone, min_norm_feasible};
use super::soccp;
use crate::constrained::{DMatrix, DVector};

/// The sustained forces of the rows `set` at rest, with friction (both
/// runtimes' force problem between events): each row sticks while the
/// force it needs fits its cone, else slides — along its sliding speed, or
/// from rest the way it would accelerate without friction, or against the
/// tangential force that left the cone (a sticking row whose `‖λ_t‖`
/// comes within `margin(k)` of `μ λ`). `slides` holds the rows' modes in
/// and out; `b`, `bt` are the normal and tangential rows' free
/// accelerations. `None`: no modes give forces.
#[allow(clippy::too_many_arguments)]
pub(crate) fn resting_forces(
    m: &DMatrix<f64>,
    j: Option<&DMatrix<f64>>,
    r: &Rows,
    set: &[usize],
    slides: &mut [Option<Slide>],
    b: &DVector<f64>,
    bt: &[[f64; 2]],
    margin: &dyn Fn(usize) -> f64,
) -> Option<Solved> {
    let mut forces = None;
    for _ in 0..(2 + 2 * set.len()) {
        let Some(sol) = (Problem {
            m,
            j,
            r,
            set,
            slide: slides,
            b: b.clone(),
            bt: bt.to_vec(),
            held: false,
        })
        .solve() else {
            // Sticking has no solution (a row whose tangential row is
            // nearly a multiple of its normal one): those rows slide,
            // along their sliding speed, or from rest the way they
            // would accelerate without friction.
            let mut changed = false;
            for (k, &i) in set.iter().enumerate() {
                let v = if norm2(r.vt[i]) > 0.0 { r.vt[i] } else { bt[k] };
                let nv = norm2(v);
                if slides[k] == Some(Slide::Stick) && nv > 0.0 {
                    slides[k] = Some(Slide::Slip([v[0] / nv, v[1] / nv]));
                    changed = true;
                }
            }
            if changed {
                continue;
            }
            return None;
        };
        let mut changed = false;
        for k in 0..set.len() {
            let (ln, lt) = (sol.ln[k], sol.lt[k]);
            let l = norm2(lt);
            if slides[k] == Some(Slide::Stick)
                && ln > 0.0
                && l > 0.0
                && l >= r.mu[set[k]] * ln * (1.0 - margin(k))
            {
                slides[k] = Some(Slide::Slip([-lt[0] / l, -lt[1] / l]));
                changed = true;
            }
        }
        forces = Some(sol);
        if !changed {
            break;
        }
    }
    forces
}

/// Solves the linear complementarity problem `ξ = A x + b`, `x ≥ 0`,
/// `ξ ≥ 0`, `xᵀ ξ = 0` exactly by enumerating the active sets, smallest
/// first (at most [`MAX_LCP`] unknowns). For the impact and contact
/// problems `A = W M⁻¹ Wᵀ` is symmetric positive semi-definite, and a
/// solution exists whenever the problem is feasible; `None` if none is
/// found (or too many unknowns).
pub fn lcp(a: &DMatrix<f64>, b: &DVector<f64>) -> Option<DVector<f64>> {
    let n = b.len();
    if n == 0 {
        return Some(DVector::zeros(0));
    }
    if n > MAX_LCP || a.nrows() != n || a.ncols() != n {
        return None;
    }
    let scale = b.amax().max(f64::MIN_POSITIVE);
    let mut masks: Vec<u32> = (0..1u32 << n).collect();
    masks.sort_by_key(|m| (m.count_ones(), *m));
    for mask in masks {
        let idx: Vec<usize> = (0..n).filter(|i| mask >> i & 1 == 1).collect();
        let mut x = DVector::zeros(n);
        if !idx.is_empty() {
            let k = idx.len();
            let sub = DMatrix::from_fn(k, k, |i, j| a[(idx[i], idx[j])]);
            let rhs = DVector::from_fn(k, |i, _| -b[idx[i]]);
            let Some(sol) = sub.lu().solve(&rhs) else {
                continue;
            };
            let big = sol.amax();
            if sol.iter().any(|v| !v.is_finite() || *v < -1e-10 * big) {
                continue;
            }
            // A singular block solved by round-off: check the equations.
            let check = DMatrix::from_fn(k, k, |i, j| a[(idx[i], idx[j])]) * &sol - &rhs;
            if check.amax() > 1e-9 * scale {
                continue;
            }
            for (i, &r) in idx.iter().enumerate() {
                x[r] = sol[i].max(0.0);
            }
        }
        let xi = a * &x + b;
        if (0..n).all(|i| mask >> i & 1 == 1 || xi[i] >= -1e-10 * scale) {
            return Some(x);
        }
    }
    None
}

/// `M⁻¹ R` with the loop constraints `J Δu = 0` held: the first `n_u`
/// rows of `[[M, Jᵀ], [J, 0]]⁻¹ [R; 0]` (least squares on redundant
/// constraints).
pub(crate) fn effective_inverse(
    m: &DMatrix<f64>,
    j: Option<&DMatrix<f64>>,
    r: &DMatrix<f64>,
) -> Option<DMatrix<f64>> {
    let x = match j.filter(|j| j.nrows() > 0) {
        None => m.clone().cholesky().map(|c| c.solve(r))?,
        Some(j) => {
            let zero = DMatrix::zeros(j.nrows(), r.ncols());
            bordered(m, j, r, &zero)?
        }
    };
    x.iter().all(|v| v.is_finite()).then_some(x)
}

/// The first `n_u` rows of `[[M, Jᵀ], [J, 0]]⁻¹ [R; C]` (least squares on
/// redundant constraints).
fn bordered(
    m: &DMatrix<f64>,
    j: &DMatrix<f64>,
    r: &DMatrix<f64>,
    c: &DMatrix<f64>,
) -> Option<DMatrix<f64>> {
    let (nu, nc) = (m.nrows(), j.nrows());
    let mut k = DMatrix::zeros(nu + nc, nu + nc);
    k.view_mut((0, 0), (nu, nu)).copy_from(m);
    k.view_mut((nu, 0), (nc, nu)).copy_from(j);
    k.view_mut((0, nu), (nu, nc)).copy_from(&j.transpose());
    let mut rhs = DMatrix::zeros(nu + nc, r.ncols());
    rhs.view_mut((0, 0), (nu, r.ncols())).copy_from(r);
    rhs.view_mut((nu, 0), (nc, r.ncols())).copy_from(c);
    let eps = 1e-12 * k.amax().max(f64::MIN_POSITIVE);
    let x = k.svd(true, true).solve(&rhs, eps).ok()?;
    Some(x.rows(0, nu).into_owned())
}

/// The speed change `Δu` that brings speeds whose constraint rates are
/// `d = J u + Φ_t` onto the constraints (`J (u + Δu) + Φ_t = 0`) with the
/// least kinetic energy, `M Δu = Jᵀ ν`: the projection of the speeds an
/// index-3 integrator leaves off its velocity constraints (the vector
/// runtime's, with cables).
#[cfg(feature = "cables")]
pub(crate) fn onto_constraints(
    m: &DMatrix<f64>,
    j: &DMatrix<f64>,
    d: &DVector<f64>,
) -> Option<DVector<f64>> {
    if j.nrows() == 0 || d.len() != j.nrows() {
        return None;
    }
    let r = DMatrix::zeros(m.nrows(), 1);
    let c = DMatrix::from_fn(d.len(), 1, |i, _| -d[i]);
    let x = bordered(m, j, &r, &c)?;
    x.iter()
        .all(|v| v.is_finite())
        .then(|| DVector::from_fn(m.nrows(), |i, _| x[(i, 0)]))
}

/// How a contact with Coulomb friction moves along its plane.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Slide {
    /// `v_t = 0`, held by a tangential force (impulse) `λ_t` inside the
    /// cone `‖λ_t‖ ≤ μ λ`.
    Stick,
    /// Sliding along the unit direction `s` of `v_t` (at the start of a
    /// slide from rest: the direction it starts to slide in): friction
    /// `λ_t = −μ λ s`.
    Slip([f64; 2]),
}

/// A contact problem on the rows `set` (Pfeiffer and Glocker): normal
/// unknowns `Λ ≥ 0` with `ξ = W Δ + b ≥ 0`, complementary (or all held,
/// `ξ = 0` with `Λ` of either sign); per row with friction, by its
/// [`Slide`] (`None`: frictionless here), `Stick`: tangential unknowns
/// `Λ_t` with `ξ_t = W_t Δ + b_t = 0`, or `Slip(s)`: `Λ_t = −μ Λ s`; and
/// `Δ = M⁻¹ (Wᵀ Λ + W_tᵀ Λ_t)`, the loop constraints held (`j`). For an
/// impact `Δ` is the jump of the speeds and `b` the speeds it is measured
/// from; for sustained contact `Δ` is the accelerations' part from the
/// contact forces and `b` the free accelerations' `g̈`.
pub(crate) struct Problem<'a> {
    pub(crate) m: &'a DMatrix<f64>,
    pub(crate) j: Option<&'a DMatrix<f64>>,
    pub(crate) r: &'a Rows,
    pub(crate) set: &'a [usize],
    pub(crate) slide: &'a [Option<Slide>],
    pub(crate) b: DVector<f64>,
    pub(crate) bt: Vec<[f64; 2]>,
    pub(crate) held: bool,
}

/// A solved [`Problem`], per element of its `set`.
pub(crate) struct Solved {
    pub du: DVector<f64>,
    pub ln: DVector<f64>,
    pub lt: Vec<[f64; 2]>,
    /// `ξ_t = W_t Δ + b_t` (for an impact, the tangential speeds after).
    pub xi_t: Vec<[f64; 2]>,
    /// `ξ = W Δ + b` (for an impact, `ġ⁺ + e ġ⁻`).
    pub xi: Vec<f64>,
}

impl Problem<'_> {
    pub(crate) fn solve(&self) -> Option<Solved> {
        let set = self.set;
        let (n, nu) = (set.len(), self.m.nrows());
        if n == 0 {
            return Some(Solved {
                du: DVector::zeros(nu),
                ln: DVector::zeros(0),
                lt: Vec::new(),
                xi_t: Vec::new(),
                xi: Vec::new(),
            });
        }
        if n > MAX_LCP {
            return None;
        }
        // Unknowns: the normal impulses, then two per sticking row.
        let stick: Vec<usize> = (0..n)
            .filter(|&k| self.slide[k] == Some(Slide::Stick))
            .collect();
        let (x, g, b) = self.block(&stick)?;
        let cols = b.len();
        let scale = b.amax().max(g.amax() * f64::EPSILON).max(f64::MIN_POSITIVE);
        let mut masks: Vec<u32> = if self.held {
            vec![(1u32 << n) - 1]
        } else {
            (0..1u32 << n).collect()
        };
        masks.sort_by_key(|m| (m.count_ones(), *m));
        // Widened modes of singular blocks found infeasible (several masks
        // widen to the same one).
        let mut refused = Vec::new();
        for mask in masks {
            let on = |k: usize| mask >> k & 1 == 1;
            let idx = self.unknowns(mask, &stick);
            let mut z = DVector::zeros(cols);
            if !idx.is_empty() {
                let sub = DMatrix::from_fn(idx.len(), idx.len(), |a, c| g[(idx[a], idx[c])]);
                let rhs = DVector::from_fn(idx.len(), |a, _| -b[idx[a]]);
                let eps = 1e-13 * sub.amax().max(f64::MIN_POSITIVE);
                let svd = sub.clone().svd(true, true);
                let Ok(sol) = svd.solve(&rhs, eps) else {
                    continue;
                };
                if sol.iter().any(|v| !v.is_finite()) || (&sub * &sol - &rhs).amax() > 1e-9 * scale
                {
                    continue;
                }
                if !self.held && svd.singular_values.iter().any(|&s| s <= eps) {
                    // Redundant rows: the speeds are unique, the impulses a
                    // set, feasible if some point of it is.
                    for (a, &c) in idx.iter().enumerate() {
                        z[c] = sol[a];
                    }
                    match self.redundant(&g, &b, &x, mask, &stick, &z, scale, false, &mut refused) {
                        Some(found) => return Some(found),
                        None => continue,
                    }
                }
                let big = sol.amax();
                if !self.held && (0..idx.len()).any(|a| idx[a] < n && sol[a] < -1e-10 * big) {
                    continue;
                }
                for (a, &c) in idx.iter().enumerate() {
                    z[c] = if !self.held && c < n {
                        sol[a].max(0.0)
                    } else {
                        sol[a]
                    };
                }
            }
            let xi = &g * &z + &b;
            if !self.held && (0..n).any(|k| !on(k) && xi[k] < -1e-10 * scale) {
                continue;
            }
            // Rows left closed without impulse: if with them the block is
            // singular, the impulses are a set (see `redundant`).
            if !self.held
                && let Some(found) =
                    self.redundant(&g, &b, &x, mask, &stick, &z, scale, true, &mut refused)
            {
                return Some(found);
            }
            return Some(self.finish(&x, &stick, &z, &z));
        }
        None
    }

    /// The block of the unknowns — the normal impulses, then two per
    /// sticking row of `stick` (the others slide by their [`Slide`]) —
    /// `(X, G, b)`: the speeds (accelerations) `Δ = X z` and
    /// `ξ = G z + b`, normal rows then the sticking rows' tangential ones.
    fn block(&self, stick: &[usize]) -> Option<(DMatrix<f64>, DMatrix<f64>, DVector<f64>)> {
        let (r, set) = (self.r, self.set);
        let (n, nu) = (set.len(), self.m.nrows());
        let cols = n + 2 * stick.len();
        let mut d = DMatrix::zeros(nu, cols);
        let mut rows_b = DMatrix::zeros(cols, nu);
        let mut b = DVector::zeros(cols);
        for (k, &i) in set.iter().enumerate() {
            for c in 0..nu {
                let mut col = r.w[(i, c)];
                if let Some(Slide::Slip(s)) = self.slide[k] {
                    col -= r.mu[i] * (s[0] * r.wt[(2 * i, c)] + s[1] * r.wt[(2 * i + 1, c)]);
                }
                d[(c, k)] = col;
                rows_b[(k, c)] = r.w[(i, c)];
            }
            b[k] = self.b[k];
        }
        for (p, &k) in stick.iter().enumerate() {
            let i = set[k];
            for a in 0..2 {
                let col = n + 2 * p + a;
                for c in 0..nu {
                    d[(c, col)] = r.wt[(2 * i + a, c)];
                    rows_b[(col, c)] = r.wt[(2 * i + a, c)];
                }
                b[col] = self.bt[k][a];
            }
        }
        let x = effective_inverse(self.m, self.j, &d)?;
        let g = &rows_b * &x;
        Some((x, g, b))
    }

    /// The unknowns of the active rows `mask`: their normal impulses, then
    /// the tangential ones of those that stick (`stick`, as in `solve`).
    fn unknowns(&self, mask: u32, stick: &[usize]) -> Vec<usize> {
        let n = self.set.len();
        let on = |k: usize| mask >> k & 1 == 1;
        let mut idx: Vec<usize> = (0..n).filter(|&k| on(k)).collect();
        for (p, &k) in stick.iter().enumerate() {
            if on(k) {
                idx.extend([n + 2 * p, n + 2 * p + 1]);
            }
        }
        idx
    }

    /// The mode `mask` of a singular block `g` (`ξ = g z + b`), `z0` its
    /// minimum-norm solution (zero off the mask): feasible if some impulse
    /// with the same speeds fits the signs and the cones (see
    /// `redundant`). The mask is first widened to every row that `z0`
    /// leaves closed (`ξ = 0`, and for a sticking row `ξ_t = 0`): a box
    /// that lands flat is solved by three of its corners, the fourth one
    /// closing with no impulse, and the impulses of all four are the set
    /// to choose from. Of it the impulse of minimum norm fitting the cones
    /// (failing that, the signs only: the caller then slides the rows
    /// outside their cones) is returned, with the speeds of its projection
    /// on the equations. With `widening` (a regular block's solution `z0`)
    /// `None` unless the widened block is singular: the regular solution
    /// stands.
    #[allow(clippy::too_many_arguments)]
    fn redundant(
        &self,
        g: &DMatrix<f64>,
        b: &DVector<f64>,
        x: &DMatrix<f64>,
        mask: u32,
        stick: &[usize],
        z0: &DVector<f64>,
        scale: f64,
        widening: bool,
        refused: &mut Vec<u32>,
    ) -> Option<Solved> {
        let n = self.set.len();
        let tol = 1e-10 * scale;
        let xi = g * z0 + b;
        if (0..n).any(|k| mask >> k & 1 == 0 && xi[k] < -tol) {
            return None;
        }
        let mut wide = mask;
        for k in 0..n {
            let closed = match stick.iter().position(|&s| s == k) {
                Some(p) => [k, n + 2 * p, n + 2 * p + 1]
                    .iter()
                    .all(|&c| xi[c].abs() <= tol),
                None => xi[k].abs() <= tol,
            };
            if closed {
                wide |= 1 << k;
            }
        }
        if (widening && wide == mask) || refused.contains(&wide) {
            return None;
        }
        let idx = self.unknowns(wide, stick);
        let sub = DMatrix::from_fn(idx.len(), idx.len(), |a, c| g[(idx[a], idx[c])]);
        let rhs = DVector::from_fn(idx.len(), |a, _| -b[idx[a]]);
        let eps = 1e-13 * sub.amax().max(f64::MIN_POSITIVE);
        let svd = sub.clone().svd(true, true);
        let sol = svd.solve(&rhs, eps).ok()?;
        if sol.iter().any(|v| !v.is_finite()) || (&sub * &sol - &rhs).amax() > 1e-9 * scale {
            return None;
        }
        let v_t = svd.v_t.as_ref()?;
        let free: Vec<usize> = (0..idx.len())
            .filter(|&i| svd.singular_values[i] <= eps)
            .collect();
        if widening && free.is_empty() {
            return None;
        }
        let null = DMatrix::from_fn(idx.len(), free.len(), |a, c| v_t[(free[c], a)]);
        let cones: Vec<Cone> = (0..n)
            .filter(|&k| wide >> k & 1 == 1)
            .map(|k| {
                let at = |c: usize| idx.iter().position(|&i| i == c);
                Cone {
                    normal: at(k).unwrap_or(0),
                    tangential: stick.iter().position(|&s| s == k).and_then(|p| {
                        Some(([at(n + 2 * p)?, at(n + 2 * p + 1)?], self.r.mu[self.set[k]]))
                    }),
                }
            })
            .collect();
        let Some((in_k, in_a)) = min_norm_feasible(&sol, &null, &cones, true)
            .or_else(|| min_norm_feasible(&sol, &null, &cones, false))
        else {
            refused.push(wide);
            return None;
        };
        let (mut zk, mut za) = (DVector::zeros(b.len()), DVector::zeros(b.len()));
        for (a, &c) in idx.iter().enumerate() {
            zk[c] = in_k[a];
            za[c] = in_a[a];
        }
        // The speeds after of the rows left open (unique unless sliding
        // rows make the speeds depend on the choice).
        let xi = g * &za + b;
        if (0..n).any(|k| wide >> k & 1 == 0 && xi[k] < -tol) {
            return None;
        }
        Some(self.finish(x, stick, &zk, &za))
    }

    /// The solution of the impulses (forces) `z` — normal, then tangential
    /// of the sticking rows `stick` — with the speeds (accelerations) of
    /// `z_speeds` (`Δ = x z_speeds`; the same as `z` but for a redundant
    /// block, see `redundant`).
    fn finish(
        &self,
        x: &DMatrix<f64>,
        stick: &[usize],
        z: &DVector<f64>,
        z_speeds: &DVector<f64>,
    ) -> Solved {
        let (r, set, n) = (self.r, self.set, self.set.len());
        let du = x * z_speeds;
        let ln = DVector::from_fn(n, |k, _| z[k]);
        let mut lt = vec![[0.0; 2]; n];
        for (k, slide) in self.slide.iter().enumerate() {
            if let Some(Slide::Slip(s)) = slide {
                let l = r.mu[set[k]] * ln[k];
                lt[k] = [-l * s[0], -l * s[1]];
            }
        }
        for (p, &k) in stick.iter().enumerate() {
            lt[k] = [z[n + 2 * p], z[n + 2 * p + 1]];
        }
        let xi_t = (0..n)
            .map(|k| {
                let i = set[k];
                [0, 1].map(|a| r.tangential_dot(i, a, &du) + self.bt[k][a])
            })
            .collect();
        let xi = (0..n)
            .map(|k| (0..du.len()).map(|c| r.w[(set[k], c)] * du[c]).sum::<f64>() + self.b[k])
            .collect();
        Solved {
            du,
            ln,
            lt,
            xi_t,
            xi,
        }
    }
}

/// `‖v‖` of a tangential pair.
pub(crate) fn norm2(v: [f64; 2]) -> f64 {
    v[0].hypot(v[1])
}

/// The impact on the closed rows `set` (the generalised Newton law,
/// `ξ = ġ⁺ + e ġ⁻`, `b = (1 + e) ġ⁻`) with Coulomb friction on the
/// tangential speeds after it (Newton–Coulomb: a row sticks, `v_t⁺ = 0`,
/// if its impulse fits the cone `‖Λ_t‖ ≤ μ Λ`, else it slides with
/// `Λ_t = −μ Λ s`, `s` the direction of `v_t⁺`): the sliding directions
/// found by fixed-point iteration from all rows sticking (a row that
/// cannot stick, its tangential row a multiple of its normal one, slides
/// from the direction of its sliding speed before, then of the one after
/// it). With `held`
/// (contacts coming to rest, `e = 0` on every row) sliding rows take no
/// tangential impulse. Where that iteration finds no answer (an impact,
/// not `held`), the impact is solved as the second-order-cone
/// complementarity problem it is ([`cone_impact`]); `None` if that finds
/// none either that satisfies every Newton–Coulomb condition.
pub(crate) fn impact(
    m: &DMatrix<f64>,
    j: Option<&DMatrix<f64>>,
    r: &Rows,
    set: &[usize],
    e: &dyn Fn(usize) -> f64,
    held: bool,
    slides: &[Option<Slide>],
) -> Option<Solved> {
    iterate_directions(m, j, r, set, e, held, slides).or_else(|| {
        if held {
            None
        } else {
            cone_impact(m, j, r, set, e, slides)
        }
    })
}

/// The impact of [`impact`] on the rows `set` as a second-order-cone
/// complementarity problem on the Delassus operator of all their normal
/// and tangential rows (rows with friction per `slides`, the others
/// frictionless), solved by [`soccp::solve`] and accepted only if its
/// Newton–Coulomb conditions hold ([`soccp::check`]).
pub(crate) fn cone_impact(
    m: &DMatrix<f64>,
    j: Option<&DMatrix<f64>>,
    r: &Rows,
    set: &[usize],
    e: &dyn Fn(usize) -> f64,
    slides: &[Option<Slide>],
) -> Option<Solved> {
    let n = set.len();
    if n == 0 || n > MAX_LCP || slides.len() != n {
        return None;
    }
    let slide: Vec<Option<Slide>> = slides.iter().map(|s| s.map(|_| Slide::Stick)).collect();
    let p = Problem {
        m,
        j,
        r,
        set,
        slide: &slide,
        b: DVector::from_fn(n, |k, _| (1.0 + e(set[k])) * r.gdot[set[k]]),
        bt: set.iter().map(|&i| r.vt[i]).collect(),
        held: false,
    };
    let stick: Vec<usize> = (0..n).filter(|&k| slide[k].is_some()).collect();
    let (x, g, b) = p.block(&stick)?;
    let cones: Vec<Cone> = (0..n)
        .map(|k| Cone {
            normal: k,
            tangential: stick
                .iter()
                .position(|&s| s == k)
                .map(|q| ([n + 2 * q, n + 2 * q + 1], r.mu[set[k]])),
        })
        .collect();
    let z = soccp::solve(&g, &b, &cones, &[])?;
    soccp::check(&g, &b, &cones, &z).ok()?;
    Some(p.finish(&x, &stick, &z, &z))
}

/// The fixed-point iteration of the sliding directions of [`impact`].
fn iterate_directions(
    m: &DMatrix<f64>,
    j: Option<&DMatrix<f64>>,
    r: &Rows,
    set: &[usize],
    e: &dyn Fn(usize) -> f64,
    held: bool,
    slides: &[Option<Slide>],
) -> Option<Solved> {
    let b = DVector::from_fn(set.len(), |k, _| (1.0 + e(set[k])) * r.gdot[set[k]]);
    let bt: Vec<[f64; 2]> = set.iter().map(|&i| r.vt[i]).collect();
    let mut slide: Vec<Option<Slide>> = slides.to_vec();
    if held {
        for s in slide.iter_mut() {
            if matches!(s, Some(Slide::Slip(_))) {
                *s = None;
            }
        }
    }
    let mut refused_stick = vec![false; set.len()];
    // Past `plain` iterations the sliding directions are relaxed: turning
    // the body, friction can make the plain iteration `s ← v̂_t⁺(s)` swing
    // between two directions for ever (a box landing on one corner while
    // moving sideways); `s ← (s + ω (v̂_t⁺ − s))/‖…‖`, ω = ½ then ⅕, has
    // the same fixed point.
    let plain = 8 + 8 * set.len();
    for it in 0..plain + 400 {
        let p = Problem {
            m,
            j,
            r,
            set,
            slide: &slide,
            b: b.clone(),
            bt: bt.clone(),
            held,
        };
        let Some(sol) = p.solve() else {
            // Leaving without sliding has no solution (a row whose
            // tangential row is a multiple of its normal one: `v_t⁺ = 0`
            // would stop `ġ⁺ = −e ġ⁻` too): those rows slide, starting
            // from the direction of their sliding speed before.
            let mut changed = false;
            for k in 0..set.len() {
                let v = r.vt[set[k]];
                let nv = norm2(v);
                if slide[k] == Some(Slide::Stick) && !refused_stick[k] && nv > 0.0 {
                    slide[k] = Some(Slide::Slip([v[0] / nv, v[1] / nv]));
                    refused_stick[k] = true;
                    changed = true;
                }
            }
            if changed && !held {
                continue;
            }
            return None;
        };
        if held {
            return Some(sol);
        }
        let mut changed = false;
        let closed = 1e-10 * b.amax().max(f64::MIN_POSITIVE);
        // (also the least sliding speed such a row is slid with)
        for k in 0..set.len() {
            let mu = r.mu[set[k]];
            let ln = sol.ln[k];
            match slide[k] {
                // Closed without impulse but moving along the plane (a
                // fourth corner of a box landing flat, its load taken by
                // the other three): it slides, with the others, so that
                // the impulses of all of them are the set to choose from.
                Some(Slide::Stick)
                    if ln == 0.0 && sol.xi[k].abs() <= closed && norm2(sol.xi_t[k]) > closed =>
                {
                    let (v, nv) = (sol.xi_t[k], norm2(sol.xi_t[k]));
                    slide[k] = Some(Slide::Slip([v[0] / nv, v[1] / nv]));
                    changed = true;
                }
                Some(Slide::Stick) if norm2(sol.lt[k]) > mu * ln * (1.0 + 1e-9) + 1e-300 => {
                    let l = norm2(sol.lt[k]);
                    slide[k] = Some(Slide::Slip([-sol.lt[k][0] / l, -sol.lt[k][1] / l]));
                    refused_stick[k] = true;
                    changed = true;
                }
                Some(Slide::Slip(s)) => {
                    let v = sol.xi_t[k];
                    let nv = norm2(v);
                    if nv == 0.0 || v[0] * s[0] + v[1] * s[1] <= 0.0 && !refused_stick[k] {
                        if !refused_stick[k] {
                            slide[k] = Some(Slide::Stick);
                            changed = true;
                        }
                    } else {
                        let t = [v[0] / nv, v[1] / nv];
                        if (t[0] - s[0]).abs() + (t[1] - s[1]).abs() > 1e-12 {
                            slide[k] = Some(Slide::Slip(relax(s, t, it, plain)));
                            changed = true;
                        }
                    }
                }
                _ => {}
            }
        }
        if !changed {
            return Some(sol);
        }
    }
    None
}

/// The sliding direction after `s` whose speed after points along `t`, at
/// iteration `it` of `impact`: `t` for the first `plain` ones, then moved
/// from `s` by ½ (the next 200) or ⅕ of the way (`t` if that cancels).
fn relax(s: [f64; 2], t: [f64; 2], it: usize, plain: usize) -> [f64; 2] {
    if it < plain {
        return t;
    }
    let w = if it < plain + 200 { 0.5 } else { 0.2 };
    let d = [s[0] + w * (t[0] - s[0]), s[1] + w * (t[1] - s[1])];
    let n = norm2(d);
    if n > 0.0 { [d[0] / n, d[1] / n] } else { t }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The rows of a ball of mass `m`, radius `r`, inertia `i` (`None`: a
    /// particle, speeds `v` only) touching the floor `z = 0` at `−r ẑ`,
    /// at the speeds `u` (`v`, then `ω`; world axes), `e` and `μ`: the
    /// touching point moves at `v + ω × (−r ẑ) = (vx − r ωy, vy + r ωx, vz)`.
    fn ball_rows(
        m: f64,
        r: f64,
        i: Option<f64>,
        u: &[f64],
        e: f64,
        mu: f64,
    ) -> (DMatrix<f64>, Rows) {
        let nu = u.len();
        let mut w = DMatrix::zeros(1, nu);
        w[(0, 2)] = 1.0;
        let mut wt = DMatrix::zeros(2, nu);
        wt[(0, 0)] = 1.0;
        wt[(1, 1)] = 1.0;
        let mut diag = vec![m; 3];
        if let Some(i) = i {
            wt[(0, 4)] = -r;
            wt[(1, 3)] = r;
            diag.extend([i; 3]);
        }
        let u = DVector::from_row_slice(u);
        let (gdot, vt) = (&w * &u, &wt * &u);
        let rows = Rows {
            g: vec![0.0],
            gdot: vec![gdot[0]],
            gamma: vec![0.0],
            e: vec![e],
            mu: vec![mu],
            w,
            vt: vec![[vt[0], vt[1]]],
            gamma_t: vec![[0.0; 2]],
            wt,
        };
        (DMatrix::from_diagonal(&DVector::from_vec(diag)), rows)
    }

    /// A particle and a solid sphere (`I = 2/5 m r²`) striking the floor
    /// obliquely at `v_n⁻ = −W`, sliding at `V` along `s = (0.6, −0.8)`,
    /// without spin (Newton–Coulomb): `Λ = m (1 + e) W` either way; the
    /// touching point's speed changes by `k Λ_t/m` (`k = 1` for the
    /// particle, `1 + m r²/I = 7/2` for the sphere), so it slides
    /// throughout, `Λ_t = −μ Λ s` and `v_t⁺ = (V − k μ (1 + e) W) s`, when
    /// `k μ (1 + e) W < V`, else sticks, `v_t⁺ = 0` with `Λ_t = −m V s/k`
    /// inside the cone; at `V = k μ (1 + e) W` it stops exactly on the
    /// cone. Both sides of the threshold and on it, through `impact` (the
    /// direction iteration, the SOCCP where that fails) and through
    /// `cone_impact` alone, which must agree with the closed forms.
    #[test]
    fn oblique_particle_and_sphere_slide_or_stick_by_newton_coulomb() {
        let (m, r, e, mu, big_w) = (1.5, 0.2, 0.5, 0.3, 2.0);
        let s = [0.6, -0.8];
        for (i, k) in [(None, 1.0), (Some(0.4 * m * r * r), 3.5)] {
            let edge = k * mu * (1.0 + e) * big_w;
            for big_v in [0.5 * edge, edge, 1.5 * edge] {
                let mut u = vec![big_v * s[0], big_v * s[1], -big_w];
                if i.is_some() {
                    u.extend([0.0; 3]);
                }
                let (mm, rows) = ball_rows(m, r, i, &u, e, mu);
                let ee = |_: usize| e;
                let slides = [Some(Slide::Stick)];
                let ln = m * (1.0 + e) * big_w;
                let slides_through = big_v > edge;
                let (lt, vt) = if slides_through {
                    (-mu * ln, big_v - edge)
                } else {
                    (-m * big_v / k, 0.0)
                };
                let what = format!("k = {k}, V = {big_v} (edge {edge})");
                let cone = cone_impact(&mm, None, &rows, &[0], &ee, &slides);
                let any = impact(&mm, None, &rows, &[0], &ee, false, &slides);
                for (how, sol) in [("cone_impact", cone), ("impact", any)] {
                    let sol = sol.unwrap_or_else(|| panic!("{what}, {how}: no solution"));
                    assert!(
                        (sol.ln[0] - ln).abs() < 1e-12 * ln,
                        "{what}, {how}: Λ = {}, want m (1 + e) W = {ln}",
                        sol.ln[0]
                    );
                    assert!(sol.xi[0].abs() < 1e-12, "{what}, {how}: ġ⁺ ≠ −e ġ⁻");
                    for (a, sa) in s.iter().enumerate() {
                        assert!(
                            (sol.lt[0][a] - lt * sa).abs() < 1e-12 * ln,
                            "{what}, {how}: Λ_t = {:?}, want {lt} s",
                            sol.lt[0]
                        );
                        assert!(
                            (sol.xi_t[0][a] - vt * sa).abs() < 1e-12,
                            "{what}, {how}: v_t⁺ = {:?}, want {vt} s",
                            sol.xi_t[0]
                        );
                    }
                }
            }
        }
    }

    /// The cost of one impact of `box4` (the bench's box landing flat on
    /// its four corners at 1 m/s along x, μ = 0.5, e = 0.5; it sticks) by
    /// the mode enumeration and by the SOCCP solver: microseconds per
    /// impact in this (debug) build, printed; both answers are the same
    /// speeds after.
    #[test]
    fn box4_impact_cost_by_enumeration_and_by_the_cone_solver() {
        let h = -0.06;
        let corners = [(0.2, 0.15), (-0.2, 0.15), (-0.2, -0.15), (0.2, -0.15)];
        let w: Vec<f64> = corners
            .iter()
            .flat_map(|&(x, y)| [0.0, 0.0, 1.0, y, -x, 0.0])
            .collect();
        let wt: Vec<f64> = corners
            .iter()
            .flat_map(|&(x, y)| [1.0, 0.0, 0.0, 0.0, h, -y, 0.0, 1.0, 0.0, -h, 0.0, x])
            .collect();
        let (w, wt) = (
            DMatrix::from_row_slice(4, 6, &w),
            DMatrix::from_row_slice(8, 6, &wt),
        );
        let u = DVector::from_row_slice(&[1.0, 0.0, -2.4, 0.0, 0.0, 0.0]);
        let (gdot, vt) = (&w * &u, &wt * &u);
        let m = DMatrix::from_diagonal(&DVector::from_vec(vec![2.0, 2.0, 2.0, 0.02, 0.03, 0.04]));
        let r = Rows {
            g: vec![0.0; 4],
            gdot: gdot.as_slice().to_vec(),
            gamma: vec![0.0; 4],
            e: vec![0.5; 4],
            mu: vec![0.5; 4],
            w,
            vt: (0..4).map(|k| [vt[2 * k], vt[2 * k + 1]]).collect(),
            gamma_t: vec![[0.0; 2]; 4],
            wt,
        };
        let (set, slides) = ([0, 1, 2, 3], [Some(Slide::Stick); 4]);
        let e = |i: usize| r.e[i];
        let reps = 20;
        let t0 = std::time::Instant::now();
        let mut old = None;
        for _ in 0..reps {
            old = iterate_directions(&m, None, &r, &set, &e, false, &slides);
        }
        let t_old = t0.elapsed().as_secs_f64() / f64::from(reps);
        let t0 = std::time::Instant::now();
        let mut new = None;
        for _ in 0..reps {
            new = cone_impact(&m, None, &r, &set, &e, &slides);
        }
        let t_new = t0.elapsed().as_secs_f64() / f64::from(reps);
        let (old, new) = (old.expect("enumeration"), new.expect("cone solver"));
        eprintln!(
            "box4 impact (debug build): enumeration {:.1} µs, SOCCP {:.1} µs",
            1e6 * t_old,
            1e6 * t_new
        );
        assert!(
            (&old.du - &new.du).amax() < 1e-9 * old.du.amax(),
            "Δu {} vs {}",
            old.du,
            new.du
        );
    }
}
