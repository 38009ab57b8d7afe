//! Linearisation about a state: the first-order system `y = (δq, u)`,
//! `ẏ ≈ A y + B w`, from the generated derivatives of forward dynamics
//! (`forward_dynamics_derivatives`, see [`crate::functions`]), and its
//! eigenvalues with natural frequencies and damping ratios.
//!
//! ```text
//! A = [[∂δq̇/∂δq, ∂δq̇/∂u],     B = [[0        ],
//!      [∂u̇/∂δq,  ∂u̇/∂u ]],         [∂u̇/∂w   ]]
//! ```
//!
//! `δq` is the displacement in the tangent space ([`tangent`]): the
//! coordinates themselves where `q̇ = u`, rotation vectors in body axes for
//! quaternions and body-axis displacements for a free joint's position.
//! Then `∂δq̇/∂u = I`, and `∂δq̇/∂δq` is zero but for quaternion joints
//! that move (`−½[ω]×`, and `−[v]×` from a free joint's rotation to its
//! position). `w` is the model's runtime inputs when it has any, else the
//! extra generalised forces `τ`, one per speed.
//!
//! Trees (rigid bodies, locked joints, flexible bodies) are linearised
//! about any state: `A`, `B` are the Jacobians there (at a state that is
//! not an equilibrium, the eigenvalues of `A` are those of the Jacobian,
//! chart terms included, not exponents of a motion). Holonomic loops with
//! `q̇ = u` about an equilibrium (`u = 0`, the constrained accelerations
//! zero) are linearised in minimal coordinates `δq = Z z`, `Z` an
//! orthonormal basis of the null space of the constraint Jacobian `J`
//! (Wittenburg 5.6): with `M u̇ = f(q, u) + τ + Jᵀλ` and the equilibrium's
//! multipliers `λ₀`,
//!
//! ```text
//! ZᵀMZ z̈ = Zᵀ (∂f/∂q + ∂(Jᵀλ₀)/∂q) Z z + Zᵀ ∂f/∂u Z ż + Zᵀ ∂τ/∂w w,
//! ```
//!
//! `∂f/∂q = M ∂u̇/∂q` from the generated derivatives evaluated at
//! `τ = Jᵀλ₀` (where the tree's `u̇` is the equilibrium's, zero), and the
//! constraint forces' geometric stiffness `∂(Jᵀλ₀)/∂q` by central
//! differences of the generated `J` (the one term not generated
//! symbolically). Redundant constraints are fine (the rank of `J` decides
//! the mobility). Every other constrained model — rolling contacts
//! (nonholonomic), loops with quaternions, loops about a steady motion —
//! goes through [`steady`]: independent coordinates and speeds about an
//! equilibrium or a steady motion with cyclic coordinates (the Whipple
//! bicycle, `models/whipple.ron`), and a state where the linearised flow
//! would leave the constraint manifold is refused. Models with cables are
//! refused: never a linearisation of the wrong system.

use crate::functions::Function;
use crate::interpret::{Point, run};
use crate::mech::Formulation;
use nalgebra::DMatrix;
use std::fmt;

mod outputs;
mod steady;
#[cfg(feature = "cables")]
pub mod structural;
mod tangent;

/// What `w` (the columns of `B`) is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum InputKind {
    /// The model's runtime inputs, in its order.
    Inputs,
    /// The extra generalised forces `τ`, one per speed.
    GeneralizedForces,
}

/// A linearisation about a state.
#[derive(Clone, Debug)]
pub struct Linearization {
    /// `A` (`N × N`: `2 NU` for a tree).
    pub a: DMatrix<f64>,
    /// `B` (`N × NW`).
    pub b: DMatrix<f64>,
    /// Names of the states, the rows of `A`: the displacements first (the
    /// coordinates where `q̇ = u`, else `d(speed)`; `z1…` for the minimal
    /// coordinates of loops), then the speeds.
    pub states: Vec<String>,
    /// How many of the states are displacements (the rest are speeds).
    pub positions: usize,
    /// Names of the columns of `B`.
    pub inputs: Vec<String>,
    /// What the columns of `B` are.
    pub input_kind: InputKind,
    /// For a constrained model, the map from the position states to all
    /// tangent displacements, `δq = Z z` (`NU × positions`): for loops an
    /// orthonormal basis of the null space of `J`, for [`steady`] the
    /// independent coordinates with the dependent ones following.
    pub basis: Option<DMatrix<f64>>,
    /// The names of the rows of `basis` (the tangent displacements).
    pub basis_rows: Vec<String>,
    /// Cyclic coordinates left out of a steady motion's linearisation
    /// (each with a zero eigenvalue).
    pub cyclic: Vec<String>,
    /// The states in the full tangent state `(δq, u)`: `y_full = T y`
    /// (`2 NU × N`; the identity for a tree).
    pub state_basis: DMatrix<f64>,
    /// The model's outputs, the rows of `C` and `D`.
    pub outputs: Vec<String>,
    /// `C` (`outputs × N`): `δh = C y + D w` (empty without outputs).
    pub c: DMatrix<f64>,
    /// `D` (`outputs × NW`).
    pub d: DMatrix<f64>,
}

/// Why a model cannot be linearised here.
#[derive(Clone, Debug, PartialEq)]
pub enum LinearizeError {
    /// A model with loops about a state that is not an equilibrium.
    NotEquilibrium {
        /// The model.
        model: String,
        /// `max |u|` at the state.
        speed: f64,
        /// `max |u̇|` of the constrained accelerations at the state.
        acceleration: f64,
    },
    /// A constrained model about a state that is neither an equilibrium
    /// nor a steady motion with cyclic coordinates: the linearised flow
    /// leaves the constraint manifold's tangent space.
    NotSteady {
        /// The model.
        model: String,
        /// `max |u|` at the state.
        speed: f64,
        /// `max |u̇|` of the constrained accelerations at the state.
        acceleration: f64,
        /// How far the flow leaves the tangent space (relative).
        leak: f64,
    },
    /// A model with cables at a state that is not a static equilibrium.
    NotStatic {
        /// The model.
        model: String,
        /// `max |ẏ|` at the state.
        speed: f64,
        /// `max |ÿ|` there.
        acceleration: f64,
    },
    /// A model with loops at a state that does not close them.
    NotAssembled {
        /// The model.
        model: String,
        /// `max |Φ|`.
        residual: f64,
    },
    /// Unilateral contacts closed at the state: `(row, gap)`.
    ClosedContacts {
        /// The model.
        model: String,
        /// The closed gap rows and their gaps.
        rows: Vec<(String, f64)>,
    },
    /// The model has cables.
    Cables {
        /// The model.
        model: String,
    },
    /// The formulation lacks the derivatives (not asked for).
    NoDerivatives,
    /// A state of the wrong size.
    Size {
        /// `q` or `u`.
        what: &'static str,
        /// How many were given.
        got: usize,
        /// How many the model has.
        want: usize,
    },
    /// `A` or `B` holds a NaN or infinity (a singular mass matrix at the
    /// state, or a state outside the model's domain).
    NotFinite,
}

impl fmt::Display for LinearizeError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            LinearizeError::NotEquilibrium {
                model,
                speed,
                acceleration,
            } => write!(
                f,
                "`{model}` has loops and the state is not an equilibrium (max |u| = {speed:.3e}, max |u̇| = {acceleration:.3e}): loops are linearised about equilibria only (give `--q` at one and `--u` zeros)"
            ),
            LinearizeError::NotSteady {
                model,
                speed,
                acceleration,
                leak,
            } => write!(
                f,
                "`{model}`: the state is neither an equilibrium nor a steady motion (max |u| = {speed:.3e}, max |u̇| = {acceleration:.3e}; the linearised flow leaves the constraint manifold by {leak:.1e} relative): a constrained model is linearised about an equilibrium (`--u` zeros) or a steady motion whose moving coordinates are cyclic, nothing depending on them (a wheel's angle on a revolute joint, as in models/whipple.ron; not a spin carried in a free joint's quaternion, whose body-axis speeds are periodic)"
            ),
            LinearizeError::NotStatic {
                model,
                speed,
                acceleration,
            } => write!(
                f,
                "`{model}` is not at rest in a static equilibrium (max |ẏ| = {speed:.3e}, max |ÿ| = {acceleration:.3e}): a model with cables is linearised about its static equilibrium"
            ),
            LinearizeError::NotAssembled { model, residual } => write!(
                f,
                "`{model}`: the state does not satisfy the constraints (max |Φ|, |Φ̇| = {residual:.3e}); give `--q` and `--u` that satisfy them"
            ),
            LinearizeError::ClosedContacts { model, rows } => write!(
                f,
                "`{model}`: unilateral contact(s) closed at this state ({}): a sustained contact's constraint is not part of the linearisation, not implemented; linearise where every contact is open (gap > 0)",
                rows.iter()
                    .map(|(r, g)| format!("`{r}` gap {g:.3e}"))
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
            LinearizeError::Cables { model } => write!(
                f,
                "`{model}` has cables: linearisation supports trees of rigid and flexible bodies without cables"
            ),
            LinearizeError::NoDerivatives => {
                f.write_str("the formulation has no `forward_dynamics_derivatives` (ask for them)")
            }
            LinearizeError::Size { what, got, want } => {
                write!(f, "`{what}` has {got} value(s), the model has {want}")
            }
            LinearizeError::NotFinite => f.write_str(
                "A or B is not finite at this state (is the mass matrix singular there?)",
            ),
        }
    }
}

impl std::error::Error for LinearizeError {}

/// Linearises the model of `f` about `x` (its `q`, `u`, `t`, inputs and
/// parameters; `x.tau` is the operating point of `τ`, zero if empty).
/// `f` must hold `forward_dynamics_derivatives`.
pub fn linearize(f: &Formulation, x: &Point<'_>) -> Result<Linearization, LinearizeError> {
    closed_contacts(f, x)?;
    let mut lin = states(f, x)?;
    if let Some((c, d)) = outputs::linearize(f, x, &lin.state_basis, lin.input_kind)? {
        lin.outputs = f.output_names.clone();
        lin.c = c;
        lin.d = d;
    }
    Ok(lin)
}

/// Unilateral contacts (#26) take part in the motion only where they are
/// closed: a state with every contact open is linearised without them (a
/// small motion keeps them open), one with a contact closed is refused —
/// the sustained contact's constraint is not part of the linearisation.
fn closed_contacts(f: &Formulation, x: &Point<'_>) -> Result<(), LinearizeError> {
    let rows = &f.contact_rows;
    if rows.is_empty() {
        return Ok(());
    }
    let c = crate::interpret::evaluate_function(f, Function::Contacts, x)
        .ok_or(LinearizeError::NotFinite)?;
    let closed: Vec<(String, f64)> = rows
        .iter()
        .zip(&c)
        .filter(|(_, g)| g.is_nan() || **g <= eom_sim::run::GAP_TOL)
        .map(|(name, g)| (name.clone(), *g))
        .collect();
    if closed.is_empty() {
        Ok(())
    } else {
        Err(LinearizeError::ClosedContacts {
            model: x.sys.name.clone(),
            rows: closed,
        })
    }
}

/// `A`, `B` (and the basis) without the outputs.
fn states(f: &Formulation, x: &Point<'_>) -> Result<Linearization, LinearizeError> {
    let sys = x.sys;
    let (nq, nu) = (sys.nq(), sys.nu());
    if !sys.cables.is_empty() {
        return Err(LinearizeError::Cables {
            model: sys.name.clone(),
        });
    }
    for (what, got, want) in [("q", x.q.len(), nq), ("u", x.u.len(), nu)] {
        if got != want {
            return Err(LinearizeError::Size { what, got, want });
        }
    }
    let tangent = nq != nu || !sys.quaternion_indices().is_empty();
    if !f.constraint_names.is_empty() {
        let holonomic_at_rest =
            f.n_holonomic == f.constraint_names.len() && !tangent && x.u.iter().all(|&v| v == 0.0);
        return if holonomic_at_rest {
            loops(f, x)
        } else {
            steady::linearize(f, x)
        };
    }
    let Blocks {
        dq,
        du,
        dw,
        input_kind,
    } = derivative_blocks(f, x)?;
    let (n, nw) = (2 * nu, dw.ncols());
    let chart = tangent::Chart::new(sys);
    let mut a = DMatrix::<f64>::zeros(n, n);
    a.view_mut((0, 0), (nu, nu))
        .copy_from(&chart.kinematics(x.u));
    a.view_mut((0, nu), (nu, nu))
        .copy_from(&DMatrix::identity(nu, nu));
    a.view_mut((nu, 0), (nu, nu)).copy_from(&dq);
    a.view_mut((nu, nu), (nu, nu)).copy_from(&du);
    let mut b = DMatrix::<f64>::zeros(n, nw);
    b.view_mut((nu, 0), (nu, nw)).copy_from(&dw);
    if a.iter().chain(b.iter()).any(|v| !v.is_finite()) {
        return Err(LinearizeError::NotFinite);
    }
    let speeds = sys.speed_names();
    let positions = chart.names(sys);
    let inputs = match input_kind {
        InputKind::Inputs => sys.inputs.clone(),
        InputKind::GeneralizedForces => speeds.iter().map(|s| format!("tau({s})")).collect(),
    };
    Ok(Linearization {
        a,
        b,
        states: positions
            .into_iter()
            .chain(speeds.into_iter().map(String::from))
            .collect(),
        positions: nu,
        inputs,
        input_kind,
        basis: None,
        basis_rows: Vec::new(),
        cyclic: Vec::new(),
        state_basis: DMatrix::identity(n, n),
        outputs: Vec::new(),
        c: DMatrix::zeros(0, n),
        d: DMatrix::zeros(0, nw),
    })
}

/// `∂u̇/∂q`, `∂u̇/∂u`, `∂u̇/∂w` and what `w` is.
struct Blocks {
    dq: DMatrix<f64>,
    du: DMatrix<f64>,
    dw: DMatrix<f64>,
    input_kind: InputKind,
}

/// The derivative blocks at `x`, with `w` the inputs if the model has any,
/// else `τ`.
fn derivative_blocks(f: &Formulation, x: &Point<'_>) -> Result<Blocks, LinearizeError> {
    let (nu, ni) = (x.sys.nu(), x.sys.inputs.len());
    let p = f
        .program(Function::ForwardDynamicsDerivatives)
        .ok_or(LinearizeError::NoDerivatives)?;
    let flat = run(p, x);
    if flat.len() != 3 * nu * nu + nu * ni {
        return Err(LinearizeError::NoDerivatives);
    }
    let block = |k: usize| DMatrix::from_row_slice(nu, nu, &flat[k * nu * nu..(k + 1) * nu * nu]);
    let (w, kind) = if ni > 0 {
        (
            DMatrix::from_row_slice(nu, ni, &flat[3 * nu * nu..]),
            InputKind::Inputs,
        )
    } else {
        (block(2), InputKind::GeneralizedForces)
    };
    Ok(Blocks {
        dq: block(0),
        du: block(1),
        dw: w,
        input_kind: kind,
    })
}

/// `M` and the forces `τ − b` at `x` (`τ` zero where `x.tau` is short).
fn mass_and_force(
    f: &Formulation,
    x: &Point<'_>,
) -> Option<(DMatrix<f64>, nalgebra::DVector<f64>)> {
    use crate::interpret::evaluate_function;
    let nu = x.sys.nu();
    let m = DMatrix::from_row_slice(nu, nu, &evaluate_function(f, Function::MassMatrix, x)?);
    let b = evaluate_function(f, Function::Bias, x)?;
    let force = nalgebra::DVector::from_iterator(
        nu,
        (0..nu).map(|k| x.tau.get(k).copied().unwrap_or(0.0) - b[k]),
    );
    Some((m, force))
}

/// The fourth-order central difference of `g` at `0` with step `h`,
/// `(−g(2h) + 8g(h) − 8g(−h) + g(−2h)) / 12h`: truncation `h⁴`, so steps
/// near 1e-3 leave errors near 1e-12 of the derivative's scale.
fn central(
    h: f64,
    g: impl Fn(f64) -> Option<nalgebra::DVector<f64>>,
) -> Result<nalgebra::DVector<f64>, LinearizeError> {
    let at = |s: f64| g(s).ok_or(LinearizeError::NotFinite);
    let (p2, p1, m1, m2) = (at(2.0 * h)?, at(h)?, at(-h)?, at(-2.0 * h)?);
    Ok((p1 - m1) * (8.0 / (12.0 * h)) - (p2 - m2) * (1.0 / (12.0 * h)))
}

/// An orthonormal basis of the null space of `j` (`n × f`), from the
/// eigenvectors of `jᵀj` whose eigenvalues are below `1e-12` of the
/// largest (at least 1): deterministic signs (largest entry positive) and
/// order (by the index of that entry). All of `ℝⁿ` for a `j` without rows.
fn null_space(j: &DMatrix<f64>) -> DMatrix<f64> {
    let n = j.ncols();
    let eig = nalgebra::SymmetricEigen::new(j.transpose() * j);
    let largest = eig.eigenvalues.amax().max(1.0);
    let mut columns: Vec<nalgebra::DVector<f64>> = (0..n)
        .filter(|&k| eig.eigenvalues[k] <= 1e-12 * largest)
        .map(|k| {
            let mut v = eig.eigenvectors.column(k).into_owned();
            let imax = v.iamax();
            if v[imax] < 0.0 {
                v.neg_mut();
            }
            v
        })
        .collect();
    columns.sort_by_key(|v| v.iamax());
    if columns.is_empty() {
        DMatrix::zeros(n, 0)
    } else {
        DMatrix::from_columns(&columns)
    }
}

/// `Φ` and `J` (holonomic rows) at `q`.
fn constraint_values(f: &Formulation, x: &Point<'_>) -> Option<(Vec<f64>, DMatrix<f64>)> {
    let nu = x.sys.nu();
    let nc = f.constraint_names.len();
    let c = crate::interpret::evaluate_function(f, Function::Constraints, x)?;
    if c.len() != 3 * nc + nc * nu {
        return None;
    }
    Some((
        c[..nc].to_vec(),
        DMatrix::from_row_slice(nc, nu, &c[3 * nc..]),
    ))
}

/// Holonomic loops about an equilibrium, in minimal coordinates (see the
/// module documentation).
fn loops(f: &Formulation, x: &Point<'_>) -> Result<Linearization, LinearizeError> {
    let sys = x.sys;
    let nu = sys.nu();
    let model = sys.name.clone();
    let not_finite = |m: &DMatrix<f64>| m.iter().any(|v| !v.is_finite());
    let (phi, j) = constraint_values(f, x).ok_or(LinearizeError::NotFinite)?;
    let residual = phi.iter().fold(0.0f64, |s, p| s.max(p.abs()));
    // (NaN is not assembled either.)
    if residual.is_nan() || residual > 1e-8 {
        return Err(LinearizeError::NotAssembled { model, residual });
    }
    let (m, force) = mass_and_force(f, x).ok_or(LinearizeError::NotFinite)?;
    let gamma = nalgebra::DVector::zeros(j.nrows());
    if not_finite(&m) || not_finite(&j) {
        return Err(LinearizeError::NotFinite);
    }
    // The equilibrium: u = 0 and the constrained accelerations zero
    // (relative to what gravity and the force elements alone would give).
    let (udot, lambda, _) = eom_sim::constrained::accelerations(&m, &force, &j, &gamma)
        .ok_or(LinearizeError::NotFinite)?;
    let speed = x.u.iter().fold(0.0f64, |s, v| s.max(v.abs()));
    let acceleration = udot.amax();
    let free = m
        .clone()
        .cholesky()
        .map_or(f64::INFINITY, |c| c.solve(&force).amax());
    if speed != 0.0 || acceleration.is_nan() || acceleration > 1e-8 * free.max(1.0) {
        return Err(LinearizeError::NotEquilibrium {
            model,
            speed,
            acceleration,
        });
    }
    // Derivatives of the tree at τ = Jᵀλ₀ (the tree's u̇ is then zero).
    let tau0 = j.transpose() * &lambda;
    let tau0 = tau0.as_slice().to_vec();
    let at = Point {
        tau: &tau0,
        ..x.clone()
    };
    let Blocks {
        dq,
        du,
        dw,
        input_kind,
    } = derivative_blocks(f, &at)?;
    // Geometric stiffness of the constraint forces, ∂(J(q)ᵀλ₀)/∂q, by
    // central differences of the generated J.
    let mut h = DMatrix::<f64>::zeros(nu, nu);
    for k in 0..nu {
        let step = 1e-6 * x.q[k].abs().max(1.0);
        let jt_lambda = |s: f64| -> Option<nalgebra::DVector<f64>> {
            let mut q = x.q.to_vec();
            q[k] += s;
            let (_, jk) = constraint_values(f, &Point { q: &q, ..x.clone() })?;
            Some(jk.transpose() * &lambda)
        };
        let (plus, minus) = (
            jt_lambda(step).ok_or(LinearizeError::NotFinite)?,
            jt_lambda(-step).ok_or(LinearizeError::NotFinite)?,
        );
        h.set_column(k, &((plus - minus) / (2.0 * step)));
    }
    let z = null_space(&j);
    let dof = z.ncols();
    let mr = z.transpose() * &m * &z;
    let Some(mr_inv) = mr.clone().try_inverse() else {
        return Err(LinearizeError::NotFinite);
    };
    let stiffness = mr_inv.clone() * z.transpose() * (&m * &dq + &h) * &z;
    let damping = mr_inv.clone() * z.transpose() * &m * &du * &z;
    let input = mr_inv * z.transpose() * &m * &dw;
    let n = 2 * dof;
    let mut a = DMatrix::<f64>::zeros(n, n);
    let mut bm = DMatrix::<f64>::zeros(n, input.ncols());
    for i in 0..dof {
        a[(i, dof + i)] = 1.0;
        for k in 0..dof {
            a[(dof + i, k)] = stiffness[(i, k)];
            a[(dof + i, dof + k)] = damping[(i, k)];
        }
        for k in 0..input.ncols() {
            bm[(dof + i, k)] = input[(i, k)];
        }
    }
    if not_finite(&a) || not_finite(&bm) {
        return Err(LinearizeError::NotFinite);
    }
    let speeds = sys.speed_names();
    let inputs = match input_kind {
        InputKind::Inputs => sys.inputs.clone(),
        InputKind::GeneralizedForces => speeds.iter().map(|s| format!("tau({s})")).collect(),
    };
    let states = (1..=dof)
        .map(|k| format!("z{k}"))
        .chain((1..=dof).map(|k| format!("z{k}_dot")))
        .collect();
    Ok(Linearization {
        a,
        b: bm,
        states,
        positions: dof,
        inputs,
        input_kind,
        state_basis: {
            let mut t = DMatrix::<f64>::zeros(2 * nu, 2 * dof);
            t.view_mut((0, 0), (nu, dof)).copy_from(&z);
            t.view_mut((nu, dof), (nu, dof)).copy_from(&z);
            t
        },
        outputs: Vec::new(),
        c: DMatrix::zeros(0, n),
        d: DMatrix::zeros(0, input.ncols()),
        basis: Some(z),
        basis_rows: sys
            .coordinate_names()
            .into_iter()
            .map(String::from)
            .collect(),
        cyclic: Vec::new(),
    })
}

/// One eigenvalue `λ = re + i·im` of `A`, with `ω_n = |λ|` and, for
/// `ω_n > 0`, the damping ratio `ζ = −re/ω_n` (`λ = −ζω_n ± iω_n√(1−ζ²)`
/// for an oscillatory pair).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Eigenvalue {
    /// Real part, 1/s.
    pub re: f64,
    /// Imaginary part, rad/s.
    pub im: f64,
    /// Natural frequency `|λ|`, rad/s.
    pub natural_frequency: f64,
    /// Damping ratio `−re/|λ|` (NaN for `λ = 0`).
    pub damping_ratio: f64,
}

/// The eigenvalues of a real square matrix (complex in general: the real
/// Schur form), sorted by natural frequency, then imaginary part; `None`
/// if the Schur iteration does not converge or the matrix is not finite.
pub fn eigenvalues(a: &DMatrix<f64>) -> Option<Vec<Eigenvalue>> {
    if a.nrows() != a.ncols() || a.iter().any(|v| !v.is_finite()) {
        return None;
    }
    if a.is_empty() {
        return Some(Vec::new());
    }
    let schur = nalgebra::linalg::Schur::try_new(a.clone(), f64::EPSILON, 10_000)?;
    let mut out: Vec<Eigenvalue> = schur
        .complex_eigenvalues()
        .iter()
        .map(|l| {
            let w = l.re.hypot(l.im);
            Eigenvalue {
                re: l.re,
                im: l.im,
                natural_frequency: w,
                damping_ratio: if w > 0.0 { -l.re / w } else { f64::NAN },
            }
        })
        .collect();
    out.sort_by(|x, y| {
        x.natural_frequency
            .total_cmp(&y.natural_frequency)
            .then(x.im.total_cmp(&y.im))
    });
    Some(out)
}

/// The mode shape of eigenvalue `l` of `a`: the eigenvector's first
/// `positions` entries (the displacements of `y = (δq, u)`), mapped by
/// `basis` when given (`δq = Z z`), scaled so that the entry of largest
/// modulus is `1`; by inverse iteration on `A − μI` in complex arithmetic
/// (`μ` a hair away from `l`, so the solve is regular). `None` if it does
/// not converge to a finite vector, or if the mode moves the speeds only.
pub fn mode_shape(
    a: &DMatrix<f64>,
    l: &Eigenvalue,
    positions: usize,
    basis: Option<&DMatrix<f64>>,
) -> Option<Vec<nalgebra::Complex<f64>>> {
    use nalgebra::Complex;
    let n = a.nrows();
    if n == 0 || positions == 0 || positions > n {
        return None;
    }
    let scale = a.amax().max(1.0);
    let mu = Complex::new(l.re + 1e-10 * scale, l.im + 1e-10 * scale);
    let shifted = a.map(|x| Complex::new(x, 0.0)) - DMatrix::<Complex<f64>>::identity(n, n) * mu;
    let lu = shifted.lu();
    // A start with every component (deterministic), then two iterations.
    let mut v = nalgebra::DVector::<Complex<f64>>::from_fn(n, |i, _| {
        Complex::new(1.0 + 0.1 * i as f64, 0.05 * i as f64)
    });
    for _ in 0..3 {
        v = lu.solve(&v)?;
        let norm = v.norm();
        if !norm.is_finite() || norm <= 0.0 {
            return None;
        }
        v /= Complex::new(norm, 0.0);
    }
    let head: Vec<Complex<f64>> = v.iter().take(positions).copied().collect();
    // A mode of the speeds alone (a conserved speed's zero eigenvalue)
    // displaces nothing: no shape, rather than normalised round-off.
    if head.iter().map(|c| c.norm_sqr()).sum::<f64>().sqrt() < 1e-8 {
        return None;
    }
    let shape: Vec<Complex<f64>> = match basis {
        Some(z) if z.ncols() == positions => (0..z.nrows())
            .map(|r| {
                (0..positions)
                    .map(|c| head[c] * z[(r, c)])
                    .fold(Complex::new(0.0, 0.0), |s, x| s + x)
            })
            .collect(),
        _ => head,
    };
    let big = shape
        .iter()
        .copied()
        .max_by(|x, y| x.norm().total_cmp(&y.norm()))?;
    let size = big.norm();
    if size.is_nan() || size <= 0.0 {
        return None;
    }
    let out: Vec<Complex<f64>> = shape.iter().map(|x| x / big).collect();
    out.iter()
        .all(|x| x.re.is_finite() && x.im.is_finite())
        .then_some(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A damped oscillator `ẍ = −ω₀² x − 2ζω₀ ẋ` (`ω₀ = 3`, `ζ = 0.1`):
    /// `λ = −ζω₀ ± iω₀√(1−ζ²)`, `|λ| = ω₀`, damping ratio `ζ`; a rotation
    /// generator has `±i`; a diagonal matrix its diagonal, sorted by
    /// magnitude.
    #[test]
    fn eigenvalues_of_known_matrices() {
        let (w, z) = (3.0f64, 0.1f64);
        let a = DMatrix::from_row_slice(2, 2, &[0.0, 1.0, -w * w, -2.0 * z * w]);
        let e = eigenvalues(&a).expect("converges");
        assert_eq!(e.len(), 2);
        for (k, sign) in [(0, -1.0), (1, 1.0)] {
            let l = e[k];
            assert!((l.re + z * w).abs() < 1e-12, "re {}", l.re);
            assert!(
                (l.im - sign * w * (1.0 - z * z).sqrt()).abs() < 1e-12,
                "im {}",
                l.im
            );
            assert!((l.natural_frequency - w).abs() < 1e-12);
            assert!((l.damping_ratio - z).abs() < 1e-12);
        }
        let r = DMatrix::from_row_slice(2, 2, &[0.0, -1.0, 1.0, 0.0]);
        let e = eigenvalues(&r).expect("converges");
        assert!(
            e.iter()
                .all(|l| l.re.abs() < 1e-15 && (l.im.abs() - 1.0).abs() < 1e-15)
        );
        let d = DMatrix::from_row_slice(2, 2, &[-4.0, 0.0, 0.0, 2.0]);
        let e = eigenvalues(&d).expect("converges");
        assert_eq!((e[0].re, e[1].re), (2.0, -4.0));
        assert!(eigenvalues(&DMatrix::from_row_slice(1, 1, &[f64::NAN])).is_none());
        assert_eq!(eigenvalues(&DMatrix::zeros(0, 0)), Some(Vec::new()));
    }
}
