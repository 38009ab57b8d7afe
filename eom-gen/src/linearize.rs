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
//! `δq` is the displacement in the tangent space (`q = q₀ ⊕ δq`, to first
//! order `q₀ + N(q₀) δq` with `q̇ = N(q) u`): the coordinates themselves
//! where `q̇ = u`, rotation vectors in body axes for quaternions. Then
//! `∂δq̇/∂u = I`, and `∂δq̇/∂δq = 0` where `q̇ = u` and for quaternion
//! joints at rest; a model with quaternions is refused about a state where
//! it moves (that block would need the derivative of the chart, not done).
//! `w` is the model's runtime inputs when it has any, else the extra
//! generalised forces `τ`, one per speed.
//!
//! Supported: trees (rigid bodies, locked joints, flexible bodies) without
//! constraint equations. Closed loops and nonholonomic constraints need
//! minimal coordinates (the null space of the constraint Jacobian,
//! Wittenburg 5.6) and are refused, as are models with cables: never a
//! linearisation of the wrong system.

use crate::functions::Function;
use crate::interpret::{Point, run};
use crate::mech::Formulation;
use nalgebra::DMatrix;
use std::fmt;

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
    /// `A` (`2 NU × 2 NU`).
    pub a: DMatrix<f64>,
    /// `B` (`2 NU × NW`).
    pub b: DMatrix<f64>,
    /// Names of the displacements `δq` (the coordinates where `q̇ = u`,
    /// else `d(speed)` per speed), then of the speeds: the rows of `A`.
    pub states: Vec<String>,
    /// Names of the columns of `B`.
    pub inputs: Vec<String>,
    /// What the columns of `B` are.
    pub input_kind: InputKind,
}

/// Why a model cannot be linearised here.
#[derive(Clone, Debug, PartialEq)]
pub enum LinearizeError {
    /// The model has constraint equations (cut joints, constraints).
    Constraints {
        /// The model.
        model: String,
        /// The equations' names.
        equations: Vec<String>,
    },
    /// The model has cables.
    Cables {
        /// The model.
        model: String,
    },
    /// Quaternion coordinates about a state where they move.
    MovingQuaternions {
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
            LinearizeError::Constraints { model, equations } => write!(
                f,
                "`{model}` has {} constraint equation(s) ({}): linearisation supports trees without constraint equations (rigid and flexible bodies, locked joints); closed loops and rolling contacts need minimal coordinates, not implemented yet",
                equations.len(),
                equations
                    .iter()
                    .map(|e| format!("`{e}`"))
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
            LinearizeError::Cables { model } => write!(
                f,
                "`{model}` has cables: linearisation supports trees of rigid and flexible bodies without cables"
            ),
            LinearizeError::MovingQuaternions { model } => write!(
                f,
                "`{model}` has quaternion coordinates and the state moves (some speed is not zero): its linearisation in the tangent space needs the derivative of the chart there, not implemented; linearise about a state at rest (`--u` all zeros)"
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
    let sys = x.sys;
    let (nq, nu, ni) = (sys.nq(), sys.nu(), sys.inputs.len());
    if !sys.cables.is_empty() {
        return Err(LinearizeError::Cables {
            model: sys.name.clone(),
        });
    }
    if !f.constraint_names.is_empty() {
        return Err(LinearizeError::Constraints {
            model: sys.name.clone(),
            equations: f.constraint_names.clone(),
        });
    }
    for (what, got, want) in [("q", x.q.len(), nq), ("u", x.u.len(), nu)] {
        if got != want {
            return Err(LinearizeError::Size { what, got, want });
        }
    }
    let tangent = nq != nu || !sys.quaternion_indices().is_empty();
    if tangent && x.u.iter().any(|&v| v != 0.0) {
        return Err(LinearizeError::MovingQuaternions {
            model: sys.name.clone(),
        });
    }
    let p = f
        .program(Function::ForwardDynamicsDerivatives)
        .ok_or(LinearizeError::NoDerivatives)?;
    let flat = run(p, x);
    if flat.len() != 3 * nu * nu + nu * ni {
        return Err(LinearizeError::NoDerivatives);
    }
    let block = |k: usize, i: usize, j: usize| flat[k * nu * nu + i * nu + j];
    let n = 2 * nu;
    let mut a = DMatrix::<f64>::zeros(n, n);
    for i in 0..nu {
        a[(i, nu + i)] = 1.0;
        for j in 0..nu {
            a[(nu + i, j)] = block(0, i, j);
            a[(nu + i, nu + j)] = block(1, i, j);
        }
    }
    let (input_kind, nw) = if ni > 0 {
        (InputKind::Inputs, ni)
    } else {
        (InputKind::GeneralizedForces, nu)
    };
    let mut b = DMatrix::<f64>::zeros(n, nw);
    for i in 0..nu {
        for j in 0..nw {
            b[(nu + i, j)] = match input_kind {
                InputKind::Inputs => flat[3 * nu * nu + i * ni + j],
                InputKind::GeneralizedForces => block(2, i, j),
            };
        }
    }
    if a.iter().chain(b.iter()).any(|v| !v.is_finite()) {
        return Err(LinearizeError::NotFinite);
    }
    let speeds = sys.speed_names();
    let positions: Vec<String> = if tangent {
        speeds.iter().map(|s| format!("d({s})")).collect()
    } else {
        sys.coordinate_names()
            .into_iter()
            .map(String::from)
            .collect()
    };
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
        inputs,
        input_kind,
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
