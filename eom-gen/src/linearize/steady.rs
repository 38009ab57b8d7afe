//! Linearisation of a constrained model about an equilibrium or a steady
//! motion, in independent coordinates and speeds: rolling contacts
//! (nonholonomic), holonomic loops with quaternion coordinates, and loops
//! about states that move.
//!
//! The state is `y = (δq, u)` in the chart of [`super::tangent`]; the
//! constrained dynamics `M u̇ = −b + τ + Jᵀλ`, `J u̇ = γ` (all constraint
//! rows, holonomic first) are differentiated about the state `y*` with its
//! accelerations `u̇*` and multipliers `λ*`:
//!
//! ```text
//! [M  −Jᵀ] [δu̇]   [M ∂u̇ₜ/∂δq + ∂(Jᵀλ*)/∂δq] δq + M ∂u̇ₜ/∂u δu + M ∂u̇ₜ/∂w δw
//! [J   0 ] [δλ] = [∂(γ − J u̇*)/∂δq] δq + ∂γ/∂u δu
//! ```
//!
//! with `u̇ₜ` the tree's forward dynamics at `τ + Jᵀλ*` (generated
//! symbolically, `forward_dynamics_derivatives`) and the constraint terms
//! by fourth-order central differences of the generated `J`, `γ` and
//! `Φ̇ = J u + Φ_t`. The motion stays on the manifold `Φ = 0`, `Φ̇ = 0`,
//! whose tangent space at `y*` is
//!
//! ```text
//! J_h δq = 0,      ∂Φ̇/∂δq δq + J δu = 0        (J_h the holonomic rows).
//! ```
//!
//! **Cyclic coordinates** (a steady motion's position along the road, its
//! heading, a wheel's angle) are those on which nothing depends: no
//! constraint, no acceleration, and no rate but other cyclic coordinates'.
//! They are dropped; each took a zero eigenvalue with it.
//!
//! **Independent coordinates and speeds** (coordinate partitioning,
//! Wehage and Haug 1982; Wittenburg 5.6 takes the null space of `J`
//! instead): a column-pivoted QR of `J_h` (of `J`) picks the dependent
//! coordinates (speeds) where the constraints are best conditioned; the
//! others are the states. `A` and `B` are the rates of the independent
//! ones, the dependent ones following from the tangent conditions.
//!
//! This is the linearisation of the flow on the manifold only where the
//! flow maps the tangent space into itself: at an equilibrium, or a steady
//! motion whose moving coordinates are cyclic. Elsewhere the linearised
//! flow leaves the tangent space, and the state is refused
//! ([`LinearizeError::NotSteady`]) rather than linearised wrongly.

use super::tangent::Chart;
use super::{
    Blocks, InputKind, Linearization, LinearizeError, central, derivative_blocks, mass_and_force,
};
use crate::functions::Function;
use crate::interpret::{Point, evaluate_function};
use crate::mech::Formulation;
use nalgebra::{DMatrix, DVector};

/// The constraint functions at a state: `Φ` (zero in nonholonomic rows),
/// `Φ̇ = J u + Φ_t`, `γ` and `J`.
struct Parts {
    phi: DVector<f64>,
    phidot: DVector<f64>,
    gamma: DVector<f64>,
    j: DMatrix<f64>,
}

fn parts(f: &Formulation, x: &Point<'_>) -> Option<Parts> {
    let nu = x.sys.nu();
    let nc = f.constraint_names.len();
    let c = evaluate_function(f, Function::Constraints, x)?;
    if c.len() != 3 * nc + nc * nu || c.iter().any(|v| !v.is_finite()) {
        return None;
    }
    Some(Parts {
        phi: DVector::from_column_slice(&c[..nc]),
        phidot: DVector::from_column_slice(&c[nc..2 * nc]),
        gamma: DVector::from_column_slice(&c[2 * nc..3 * nc]),
        j: DMatrix::from_row_slice(nc, nu, &c[3 * nc..]),
    })
}

/// Step of the central differences (m, rad, or the coordinate's unit):
/// truncation `h⁴` and rounding `ε/h` both near 1e-12.
const STEP: f64 = 1e-3;

/// Column-pivoted QR of `a`'s columns `cols`: the numerical rank and the
/// columns in pivot order (the first `rank` are the best-conditioned).
fn pivot_columns(a: &DMatrix<f64>, cols: &[usize]) -> (usize, Vec<usize>) {
    if a.nrows() == 0 || cols.is_empty() {
        return (0, cols.to_vec());
    }
    let sub = DMatrix::from_fn(a.nrows(), cols.len(), |i, k| a[(i, cols[k])]);
    let qr = sub.col_piv_qr();
    let r = qr.r();
    let diag: Vec<f64> = (0..r.nrows().min(r.ncols()))
        .map(|i| r[(i, i)].abs())
        .collect();
    let largest = diag.first().copied().unwrap_or(0.0);
    let rank = diag.iter().filter(|&&d| d > 1e-10 * largest).count();
    // The permutation applied to the identity gives the pivot order.
    let mut order = DMatrix::<f64>::from_fn(1, cols.len(), |_, k| k as f64);
    qr.p().permute_columns(&mut order);
    let pivots = (0..cols.len())
        .map(|k| cols[order[(0, k)] as usize])
        .collect();
    (rank, pivots)
}

/// Linearises a constrained model about `x` (see the module
/// documentation).
pub(super) fn linearize(f: &Formulation, x: &Point<'_>) -> Result<Linearization, LinearizeError> {
    let sys = x.sys;
    let model = sys.name.clone();
    let (nu, nc, nh) = (sys.nu(), f.constraint_names.len(), f.n_holonomic);
    let chart = Chart::new(sys);
    let not_finite = |m: &DMatrix<f64>| m.iter().any(|v| !v.is_finite());

    // The state: assembled, its accelerations and multipliers.
    let p0 = parts(f, x).ok_or(LinearizeError::NotFinite)?;
    let speed_scale = x.u.iter().fold(1.0f64, |s, v| s.max(v.abs()));
    let residual = p0
        .phi
        .rows(0, nh)
        .amax()
        .max(p0.phidot.amax() / speed_scale);
    if residual.is_nan() || residual > 1e-8 {
        return Err(LinearizeError::NotAssembled { model, residual });
    }
    let (m, force) = mass_and_force(f, x).ok_or(LinearizeError::NotFinite)?;
    let tau = DVector::from_iterator(nu, (0..nu).map(|k| x.tau.get(k).copied().unwrap_or(0.0)));
    if not_finite(&m) || not_finite(&p0.j) {
        return Err(LinearizeError::NotFinite);
    }
    let (udot, lambda, _) = eom_sim::constrained::accelerations(&m, &force, &p0.j, &p0.gamma)
        .ok_or(LinearizeError::NotFinite)?;

    // The tree's derivatives at τ + Jᵀλ* (its u̇ is then u̇*).
    let tau_eff = (tau + p0.j.transpose() * &lambda).as_slice().to_vec();
    let Blocks {
        dq,
        du,
        dw,
        input_kind,
    } = derivative_blocks(
        f,
        &Point {
            tau: &tau_eff,
            ..x.clone()
        },
    )?;

    // The constraint terms by central differences along the chart.
    let mut h = DMatrix::<f64>::zeros(nu, nu); // ∂(Jᵀλ*)/∂δq
    let mut gq = DMatrix::<f64>::zeros(nc, nu); // ∂(γ − J u̇*)/∂δq
    let mut kq = DMatrix::<f64>::zeros(nc, nu); // ∂Φ̇/∂δq
    let mut gu = DMatrix::<f64>::zeros(nc, nu); // ∂γ/∂u
    for k in 0..nu {
        let column = central(STEP, |s| {
            let q = chart.displaced(x.q, k, s);
            let p = parts(f, &Point { q: &q, ..x.clone() })?;
            let mut v = DVector::zeros(nu + 2 * nc);
            v.rows_mut(0, nu).copy_from(&(p.j.transpose() * &lambda));
            v.rows_mut(nu, nc).copy_from(&(&p.gamma - &p.j * &udot));
            v.rows_mut(nu + nc, nc).copy_from(&p.phidot);
            Some(v)
        })?;
        h.set_column(k, &column.rows(0, nu));
        gq.set_column(k, &column.rows(nu, nc));
        kq.set_column(k, &column.rows(nu + nc, nc));
        let step = STEP * x.u[k].abs().max(1.0);
        let column = central(step, |s| {
            let mut u = x.u.to_vec();
            u[k] += s;
            Some(parts(f, &Point { u: &u, ..x.clone() })?.gamma)
        })?;
        gu.set_column(k, &column);
    }

    // δu̇ (and δλ) of every δq, δu and δw: one KKT solve.
    let nw = dw.ncols();
    let mut kkt = DMatrix::<f64>::zeros(nu + nc, nu + nc);
    kkt.view_mut((0, 0), (nu, nu)).copy_from(&m);
    kkt.view_mut((0, nu), (nu, nc))
        .copy_from(&(-p0.j.transpose()));
    kkt.view_mut((nu, 0), (nc, nu)).copy_from(&p0.j);
    let mut rhs = DMatrix::<f64>::zeros(nu + nc, 2 * nu + nw);
    rhs.view_mut((0, 0), (nu, nu)).copy_from(&(&m * &dq + &h));
    rhs.view_mut((nu, 0), (nc, nu)).copy_from(&gq);
    rhs.view_mut((0, nu), (nu, nu)).copy_from(&(&m * &du));
    rhs.view_mut((nu, nu), (nc, nu)).copy_from(&gu);
    rhs.view_mut((0, 2 * nu), (nu, nw)).copy_from(&(&m * &dw));
    if not_finite(&kkt) || not_finite(&rhs) {
        return Err(LinearizeError::NotFinite);
    }
    let svd = kkt.svd(true, true);
    let cut = 1e-12 * svd.singular_values.max();
    let rates = svd
        .solve(&rhs, cut)
        .map_err(|_| LinearizeError::NotFinite)?;

    // The full first-order system y = (δq, u): ẏ = F y + G w.
    let mut full = DMatrix::<f64>::zeros(2 * nu, 2 * nu);
    full.view_mut((0, 0), (nu, nu))
        .copy_from(&chart.kinematics(x.u));
    full.view_mut((0, nu), (nu, nu))
        .copy_from(&DMatrix::identity(nu, nu));
    full.view_mut((nu, 0), (nu, 2 * nu))
        .copy_from(&rates.view((0, 0), (nu, 2 * nu)));
    let mut input = DMatrix::<f64>::zeros(2 * nu, nw);
    input
        .view_mut((nu, 0), (nu, nw))
        .copy_from(&rates.view((0, 2 * nu), (nu, nw)));
    // The tangent conditions: C y = 0.
    let mut tangent = DMatrix::<f64>::zeros(nh + nc, 2 * nu);
    tangent
        .view_mut((0, 0), (nh, nu))
        .copy_from(&p0.j.rows(0, nh));
    tangent.view_mut((nh, 0), (nc, nu)).copy_from(&kq);
    tangent.view_mut((nh, nu), (nc, nu)).copy_from(&p0.j);
    if not_finite(&full) || not_finite(&input) || not_finite(&tangent) {
        return Err(LinearizeError::NotFinite);
    }

    // Cyclic coordinates: no constraint, no acceleration depends on them,
    // and only cyclic coordinates' rates do.
    let zero_tol = 1e-8 * full.amax().max(tangent.amax()).max(1.0);
    let mut cyclic: Vec<bool> = (0..nu)
        .map(|k| {
            tangent.column(k).amax() <= zero_tol && full.view((nu, k), (nu, 1)).amax() <= zero_tol
        })
        .collect();
    loop {
        let before = cyclic.clone();
        for k in 0..nu {
            if cyclic[k] && (0..nu).any(|i| !cyclic[i] && full[(i, k)].abs() > zero_tol) {
                cyclic[k] = false;
            }
        }
        if cyclic == before {
            break;
        }
    }
    let kept: Vec<usize> = (0..nu).filter(|&k| !cyclic[k]).collect();

    // Independent coordinates (of the kept) and speeds.
    let jh = p0.j.rows(0, nh).into_owned();
    let (rank_h, pivots_q) = pivot_columns(&jh, &kept);
    let (dep_q, mut ind_q) = (pivots_q[..rank_h].to_vec(), pivots_q[rank_h..].to_vec());
    ind_q.sort_unstable();
    let all: Vec<usize> = (0..nu).collect();
    let (rank_u, pivots_u) = pivot_columns(&p0.j, &all);
    let (dep_u, mut ind_u) = (pivots_u[..rank_u].to_vec(), pivots_u[rank_u..].to_vec());
    ind_u.sort_unstable();
    let (nz, ns) = (ind_q.len(), ind_u.len());

    // The basis T of the tangent space over y = (δq, u): δq = Z z (cyclic
    // coordinates zero), u = Y s − W z.
    let solve_dependent = |a: &DMatrix<f64>, dep: &[usize], rhs: &DMatrix<f64>| {
        let ad = DMatrix::from_fn(a.nrows(), dep.len(), |i, k| a[(i, dep[k])]);
        let svd = ad.svd(true, true);
        let cut = 1e-12 * svd.singular_values.max().max(1e-300);
        svd.solve(rhs, cut)
    };
    let mut z = DMatrix::<f64>::zeros(nu, nz);
    for (c, &i) in ind_q.iter().enumerate() {
        z[(i, c)] = 1.0;
    }
    if !dep_q.is_empty() {
        let rhs = -(&jh * &z);
        let d = solve_dependent(&jh, &dep_q, &rhs).map_err(|_| LinearizeError::NotFinite)?;
        for (r, &i) in dep_q.iter().enumerate() {
            z.set_row(i, &d.row(r));
        }
    }
    let mut y = DMatrix::<f64>::zeros(nu, ns);
    for (c, &i) in ind_u.iter().enumerate() {
        y[(i, c)] = 1.0;
    }
    let mut w = DMatrix::<f64>::zeros(nu, nz);
    if !dep_u.is_empty() {
        let rhs = -(&p0.j * &y);
        let d = solve_dependent(&p0.j, &dep_u, &rhs).map_err(|_| LinearizeError::NotFinite)?;
        for (r, &i) in dep_u.iter().enumerate() {
            y.set_row(i, &d.row(r));
        }
        let rhs = -(&kq * &z);
        let d = solve_dependent(&p0.j, &dep_u, &rhs).map_err(|_| LinearizeError::NotFinite)?;
        for (r, &i) in dep_u.iter().enumerate() {
            w.set_row(i, &d.row(r));
        }
    }
    let mut basis = DMatrix::<f64>::zeros(2 * nu, nz + ns);
    basis.view_mut((0, 0), (nu, nz)).copy_from(&z);
    basis.view_mut((nu, 0), (nu, nz)).copy_from(&w);
    basis.view_mut((nu, nz), (nu, ns)).copy_from(&y);

    // Invariance: the linearised flow keeps the tangent space.
    let flow = &full * &basis;
    let leak = (&tangent * &flow).amax();
    let scale = tangent.amax().max(1e-300) * flow.amax().max(1e-300);
    if leak.is_nan() || leak > 1e-6 * scale {
        let speed = x.u.iter().fold(0.0f64, |s, v| s.max(v.abs()));
        return Err(LinearizeError::NotSteady {
            model,
            speed,
            acceleration: udot.amax(),
            leak: leak / scale,
        });
    }

    // The rates of the independent coordinates and speeds.
    let rows: Vec<usize> = ind_q
        .iter()
        .copied()
        .chain(ind_u.iter().map(|&i| nu + i))
        .collect();
    let a = DMatrix::from_fn(nz + ns, nz + ns, |r, c| flow[(rows[r], c)]);
    let bm = DMatrix::from_fn(nz + ns, nw, |r, c| input[(rows[r], c)]);
    if not_finite(&a) || not_finite(&bm) {
        return Err(LinearizeError::NotFinite);
    }
    let tangent_names = chart.names(sys);
    let speeds = sys.speed_names();
    let inputs = match input_kind {
        InputKind::Inputs => sys.inputs.clone(),
        InputKind::GeneralizedForces => speeds.iter().map(|s| format!("tau({s})")).collect(),
    };
    Ok(Linearization {
        a,
        b: bm,
        states: ind_q
            .iter()
            .map(|&i| tangent_names[i].clone())
            .chain(ind_u.iter().map(|&i| speeds[i].to_string()))
            .collect(),
        positions: nz,
        inputs,
        input_kind,
        outputs: Vec::new(),
        c: DMatrix::zeros(0, nz + ns),
        d: DMatrix::zeros(0, nw),
        state_basis: basis,
        basis: Some(z),
        basis_rows: tangent_names.clone(),
        cyclic: (0..nu)
            .filter(|&k| cyclic[k])
            .map(|k| tangent_names[k].clone())
            .collect(),
    })
}
