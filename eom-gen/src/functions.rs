//! The table of generated functions.
//!
//! Every function eom generates is one row of [`TABLE`]: its name (in
//! scenes' `functions` lists, as the Rust method, as the key of
//! `eom-gen eval` and of `eom_sim::Model::evaluate`), its arguments, how
//! its program's outputs lay out its result, when it is generated, whether
//! the model trait has a method of its own for it, and what it can be
//! derived from when a scene leaves it out. The formulation
//! (`mech::formulate`) builds one program per row; emission, the
//! evaluator and the command line read the row and need nothing else.
//!
//! Adding a function is one row here plus its formulation (one arm in
//! `mech::formulate::program`).

use std::fmt;
use std::str::FromStr;

/// A generated function (in scene files by its variant name,
/// `MassMatrix`).
#[derive(
    Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, serde::Serialize, serde::Deserialize,
)]
pub enum Function {
    /// `q̇ = N(q) u`.
    Qdot,
    /// `u̇ = M⁻¹ (τ − b)`.
    ForwardDynamics,
    /// `M(q)`.
    MassMatrix,
    /// `b(q, u, t)` with `M u̇ = τ − b`.
    Bias,
    /// `τ = M u̇ + b`.
    InverseDynamics,
    /// Kinetic and potential energy.
    Energy,
    /// Angular and linear momentum.
    Momentum,
    /// The model's requested outputs.
    Outputs,
    /// Partial velocities `∂v/∂u` of the requested marker positions.
    MarkerJacobians,
    /// `Φ`, `Φ̇`, `γ`, `J` of the cut joints and the model's constraints.
    Constraints,
    /// Force and torque each cut joint applies to its child, from `λ`.
    CutJointReactions,
    /// The markers holding cable ends: positions, clamp normals and their
    /// Jacobians `∂/∂q`.
    Attachments,
    /// The unilateral contacts' gaps `g`, normal speeds `ġ = wᵀ u`, `γ`
    /// (`g̈ = wᵀ u̇ − γ`), their `e` and `μ`, and rows `w`.
    Contacts,
    /// The frames of the bodies cable nodes touch: positions, axes,
    /// velocities, their rates at `u̇ = 0` and their rows `∂/∂u`.
    ContactFrames,
    /// Joint impulses of a velocity jump (Wittenburg ch. 6).
    JointImpulses,
    /// The contacts' tangential speeds `v_t = W_t u`, `γ_t` and rows `W_t`
    /// (Coulomb friction).
    Friction,
    /// Partial derivatives of forward dynamics: `∂u̇/∂q` (in the tangent
    /// space), `∂u̇/∂u`, `∂u̇/∂τ`, `∂u̇/∂(inputs)`.
    ForwardDynamicsDerivatives,
    /// Partial derivatives of inverse dynamics: `∂τ/∂q` (in the tangent
    /// space), `∂τ/∂u`, `∂τ/∂u̇ = M`, `∂τ/∂(inputs)`.
    InverseDynamicsDerivatives,
}

/// An argument of a generated function, in this order when present.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Arg {
    /// Time `t`.
    T,
    /// Positions `q` (`NQ`).
    Q,
    /// Speeds `u` (`NU`).
    U,
    /// Speed rates `u̇` (`NU`).
    Udot,
    /// Extra generalised forces `τ` (`NU`).
    Tau,
}

impl Arg {
    /// The argument's name in generated code.
    pub fn name(self) -> &'static str {
        match self {
            Arg::T => "t",
            Arg::Q => "q",
            Arg::U => "u",
            Arg::Udot => "udot",
            Arg::Tau => "tau",
        }
    }
}

/// How the outputs of a function's program make up its flat result.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Layout {
    /// Output `k` is entry `k`.
    Vector,
    /// The lower triangle of a symmetric `NU × NU` matrix, row by row
    /// (entry `(i, j)`, `j ≤ i`, at `i(i+1)/2 + j`); the result is the full
    /// matrix by rows.
    LowerTriangle,
    /// For each equation `i`: `Φ_i`, `Φ̇_i`, `γ_i`; then `J` by rows. The
    /// result is `Φ`, `Φ̇`, `γ` (each `NC`), then `J` (`NC × NU`).
    Constraints,
}

/// When a function is generated.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum When {
    /// Always.
    Always,
    /// Unless a scene's `functions` list leaves it out.
    Requested,
    /// When the model requests outputs.
    HasOutputs,
    /// When the model requests marker positions.
    HasMarkerPositions,
    /// When the model has constraint equations.
    HasConstraints,
    /// When the model has cut joints.
    HasCutJoints,
    /// When cable ends are held at markers of rigid bodies.
    HasCableMounts,
    /// When the model has unilateral contacts.
    HasContacts,
    /// When a contact has Coulomb friction (`μ > 0`).
    HasFriction,
    /// When a cable node touches a plane or sphere on a body.
    HasCableFrames,
    /// Only when asked for by name (a scene's `functions` list, or a
    /// caller's request such as `eom-gen linearize`'s); never by default,
    /// so a model without such a request generates what it did before.
    Asked,
}

/// One row of the table.
#[derive(Clone, Copy, Debug)]
pub struct Entry {
    /// The function.
    pub function: Function,
    /// Its name.
    pub name: &'static str,
    /// One line on what it computes (the generated doc comment starts with it).
    pub doc: &'static str,
    /// Its arguments besides `&self`.
    pub args: &'static [Arg],
    /// Whether its result depends on the multipliers `λ` (read from the
    /// model's `multipliers` field in generated code).
    pub uses_multipliers: bool,
    /// How the program's outputs make up the result.
    pub layout: Layout,
    /// When it is generated.
    pub when: When,
    /// True if `eom_sim::Model` or `eom_sim::ConstrainedModel` has a method
    /// of its own for it (emitted with that signature); otherwise it is an
    /// inherent method `fn NAME(&self, args…, out: &mut [f64; LEN])`.
    pub in_trait: bool,
    /// When a scene leaves it out: the functions it is computed from
    /// (empty: it cannot be left out).
    pub derived_from: &'static [Function],
}

/// Every generated function, in emission order.
pub const TABLE: &[Entry] = &[
    Entry {
        function: Function::Qdot,
        name: "qdot",
        doc: "`q̇ = N(q) u`",
        args: &[Arg::Q, Arg::U],
        uses_multipliers: false,
        layout: Layout::Vector,
        when: When::Always,
        in_trait: true,
        derived_from: &[],
    },
    Entry {
        function: Function::ForwardDynamics,
        name: "forward_dynamics",
        doc: "forward dynamics `u̇ = M⁻¹ (τ − b)`",
        args: &[Arg::T, Arg::Q, Arg::U, Arg::Tau],
        uses_multipliers: false,
        layout: Layout::Vector,
        when: When::Requested,
        in_trait: true,
        derived_from: &[],
    },
    Entry {
        function: Function::MassMatrix,
        name: "mass_matrix",
        doc: "mass matrix `M(q)`, by rows",
        args: &[Arg::T, Arg::Q],
        uses_multipliers: false,
        layout: Layout::LowerTriangle,
        when: When::Requested,
        in_trait: true,
        derived_from: &[Function::InverseDynamics],
    },
    Entry {
        function: Function::Bias,
        name: "bias",
        doc: "bias `b(q, u, t)` of `M u̇ = τ − b`",
        args: &[Arg::T, Arg::Q, Arg::U],
        uses_multipliers: false,
        layout: Layout::Vector,
        when: When::Requested,
        in_trait: true,
        derived_from: &[Function::InverseDynamics],
    },
    Entry {
        function: Function::InverseDynamics,
        name: "inverse_dynamics",
        doc: "inverse dynamics `τ = M u̇ + b`",
        args: &[Arg::T, Arg::Q, Arg::U, Arg::Udot],
        uses_multipliers: false,
        layout: Layout::Vector,
        when: When::Requested,
        in_trait: true,
        derived_from: &[Function::MassMatrix, Function::Bias],
    },
    Entry {
        function: Function::Energy,
        name: "energy",
        doc: "kinetic and potential energy",
        args: &[Arg::T, Arg::Q, Arg::U],
        uses_multipliers: false,
        layout: Layout::Vector,
        when: When::Requested,
        in_trait: true,
        derived_from: &[],
    },
    Entry {
        function: Function::Momentum,
        name: "momentum",
        doc: "angular momentum about the world origin, then linear momentum, world axes",
        args: &[Arg::T, Arg::Q, Arg::U],
        uses_multipliers: false,
        layout: Layout::Vector,
        when: When::Requested,
        in_trait: true,
        derived_from: &[],
    },
    Entry {
        function: Function::Outputs,
        name: "outputs",
        doc: "the model's requested outputs (marker positions and velocities in world axes, joint reactions in the child joint frame)",
        args: &[Arg::T, Arg::Q, Arg::U, Arg::Udot],
        uses_multipliers: true,
        layout: Layout::Vector,
        when: When::HasOutputs,
        in_trait: true,
        derived_from: &[],
    },
    Entry {
        function: Function::MarkerJacobians,
        name: "marker_jacobians",
        doc: "partial velocities `∂v/∂u_k` of the requested marker positions (world axes): marker by marker, axis by axis, speed by speed",
        args: &[Arg::T, Arg::Q],
        uses_multipliers: false,
        layout: Layout::Vector,
        when: When::HasMarkerPositions,
        in_trait: false,
        derived_from: &[],
    },
    Entry {
        function: Function::Constraints,
        name: "constraints",
        doc: "constraint equations: `Φ`, `Φ̇ = J u + Φ_t`, `γ` (`J u̇ = γ`) and `J`",
        args: &[Arg::T, Arg::Q, Arg::U],
        uses_multipliers: false,
        layout: Layout::Constraints,
        when: When::HasConstraints,
        in_trait: true,
        derived_from: &[],
    },
    Entry {
        function: Function::CutJointReactions,
        name: "cut_joint_reactions",
        doc: "force and torque each cut joint applies to its child body, in the parent joint frame's axes, from the multipliers `λ`: six numbers per cut joint",
        args: &[Arg::T, Arg::Q],
        uses_multipliers: true,
        layout: Layout::Vector,
        when: When::HasCutJoints,
        in_trait: false,
        derived_from: &[],
    },
    Entry {
        function: Function::Attachments,
        name: "attachments",
        doc: "the markers holding cable ends (issue #18), mount by mount: world position, and for a clamped end the unit normals `n1`, `n2` of the clamp's axis (world axes); each value followed by its partial derivatives `∂/∂q_k`",
        args: &[Arg::T, Arg::Q],
        uses_multipliers: false,
        layout: Layout::Vector,
        when: When::HasCableMounts,
        in_trait: false,
        derived_from: &[],
    },
    Entry {
        function: Function::Contacts,
        name: "contacts",
        doc: "the unilateral contacts (issue #26), `NK` gap rows in the order of the model's contacts (a joint limit's lower row before its upper): the gaps `g` (`NK`, m or rad, open when positive), the normal speeds `ġ = wᵀ u` (`NK`), `γ` with `g̈ = wᵀ u̇ − γ` (`NK`), Newton's restitution coefficient `e` and Coulomb's `μ` of each row (`NK` each), then the rows `w = ∂ġ/∂u` (`NK × NU`, row by row)",
        args: &[Arg::T, Arg::Q, Arg::U],
        uses_multipliers: false,
        layout: Layout::Vector,
        when: When::HasContacts,
        in_trait: false,
        derived_from: &[],
    },
    Entry {
        function: Function::ContactFrames,
        name: "contact_frames",
        doc: "the frames of the bodies cable nodes touch (issue #26), frame by frame (a plane's point or a sphere's centre on its body): the point's world position `p` (3, m), the body's axes in the world by rows (9), the point's velocity `ṗ` (3, m/s) and the body's angular velocity `ω` (3, rad/s), then their rates at `u̇ = 0` (`p̈ − J_p u̇`, `ω̇ − J_ω u̇`, 6), then the rows `J_p = ∂ṗ/∂u` (3 × `NU`) and `J_ω = ∂ω/∂u` (3 × `NU`), row by row; all in world axes",
        args: &[Arg::T, Arg::Q, Arg::U],
        uses_multipliers: false,
        layout: Layout::Vector,
        when: When::HasCableFrames,
        in_trait: false,
        derived_from: &[],
    },
    Entry {
        function: Function::JointImpulses,
        name: "joint_impulses",
        doc: "the impulses the tree joints transmit in a velocity jump `Δu` (passed as `udot`) caused by contact impulses `Λ` (Wittenburg ch. 6), in the child joint frame's axes at its origin, force then torque (N s, N m s), six per tree joint: first the part `Σ ΔH` of the momentum change of the bodies the joint carries, then per contact row the part per unit `Λ_k` (`−` its load, zero for joint limits, which act inside their joint), and for a model with friction then per contact row the parts per unit tangential impulse along `t1` and along `t2` (blocks `NK` times two, as in `friction`); a joint's impulse is the first block plus the impulses times the row blocks",
        args: &[Arg::T, Arg::Q, Arg::U, Arg::Udot],
        uses_multipliers: false,
        layout: Layout::Vector,
        when: When::HasContacts,
        in_trait: false,
        derived_from: &[],
    },
    Entry {
        function: Function::Friction,
        name: "friction",
        doc: "the tangential rows of the contacts with Coulomb friction (issue #26), per gap row of `contacts` (`NK`, zero for rows without friction): the tangential speeds `v_t1 = t1·v_c`, `v_t2 = t2·v_c` of the touching material point `c` (`NK` each, m/s), `γ_t1`, `γ_t2` with `v̇_t = W_t u̇ − γ_t` (`NK` each), then the rows `W_t1 = ∂v_t1/∂u` and `W_t2 = ∂v_t2/∂u` (`NK × NU` each, row by row); `t1` is the world axis least aligned with the plane's normal `n` projected onto the plane, `t2 = n × t1`",
        args: &[Arg::T, Arg::Q, Arg::U],
        uses_multipliers: false,
        layout: Layout::Vector,
        when: When::HasFriction,
        in_trait: false,
        derived_from: &[],
    },
    Entry {
        function: Function::ForwardDynamicsDerivatives,
        name: "forward_dynamics_derivatives",
        doc: "partial derivatives of forward dynamics `u̇ = M⁻¹ (τ − b)` of the tree (constraint forces not included), row-major blocks one after the other: `∂u̇/∂q` (`NU × NU`: column `j` is the derivative along `δq = N(q) e_j`, the direction `q̇ = N(q) u` moves for speed `j`, so the tangent space; for quaternions a rotation vector in body axes, for a free joint's position a displacement along body axes, as Pinocchio's; equal to `∂u̇/∂q` where `q̇ = u`), `∂u̇/∂u` (`NU × NU`), `∂u̇/∂τ = M⁻¹` (`NU × NU`), then `∂u̇/∂(inputs)` (`NU × NI`, inputs in the model's order); entry `(i, j)` of block `k` at `k·NU² + i·NU + j`, of the inputs' block at `3·NU² + i·NI + j`",
        args: &[Arg::T, Arg::Q, Arg::U, Arg::Tau],
        uses_multipliers: false,
        layout: Layout::Vector,
        when: When::Asked,
        in_trait: false,
        derived_from: &[],
    },
    Entry {
        function: Function::InverseDynamicsDerivatives,
        name: "inverse_dynamics_derivatives",
        doc: "partial derivatives of inverse dynamics `τ = M u̇ + b` of the tree, row-major blocks one after the other: `∂τ/∂q` (`NU × NU`, in the tangent space as `forward_dynamics_derivatives`'), `∂τ/∂u` (`NU × NU`), `∂τ/∂u̇ = M` (`NU × NU`), then `∂τ/∂(inputs)` (`NU × NI`); entry `(i, j)` of block `k` at `k·NU² + i·NU + j`, of the inputs' block at `3·NU² + i·NI + j`",
        args: &[Arg::T, Arg::Q, Arg::U, Arg::Udot],
        uses_multipliers: false,
        layout: Layout::Vector,
        when: When::Asked,
        in_trait: false,
        derived_from: &[],
    },
];

impl Function {
    /// Its row of [`TABLE`].
    pub fn entry(self) -> &'static Entry {
        TABLE
            .iter()
            .find(|e| e.function == self)
            .unwrap_or(&TABLE[0])
    }

    /// Its name.
    pub fn name(self) -> &'static str {
        self.entry().name
    }

    /// The functions a scene may name in its `functions` list: those
    /// generated unless left out, and those generated only when asked for.
    pub fn selectable() -> impl Iterator<Item = Function> {
        TABLE
            .iter()
            .filter(|e| matches!(e.when, When::Requested | When::Asked))
            .map(|e| e.function)
    }
}

impl fmt::Display for Function {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Function {
    type Err = ();
    fn from_str(s: &str) -> Result<Self, ()> {
        TABLE
            .iter()
            .find(|e| e.name == s)
            .map(|e| e.function)
            .ok_or(())
    }
}

/// A set of functions (a scene's request, what a formulation holds).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct FunctionSet(u32);

impl FunctionSet {
    /// Every function generated unless a scene leaves it out: what a
    /// model without a scene gets (not those generated only when asked
    /// for, [`When::Asked`]).
    pub fn all_requested() -> Self {
        TABLE
            .iter()
            .filter(|e| e.when == When::Requested)
            .map(|e| e.function)
            .collect()
    }

    /// This set with `f` added.
    pub fn with(mut self, f: Function) -> Self {
        self.insert(f);
        self
    }

    /// True if `f` is in the set.
    pub fn contains(self, f: Function) -> bool {
        self.0 & (1 << f as u32) != 0
    }

    /// Adds `f`.
    pub fn insert(&mut self, f: Function) {
        self.0 |= 1 << f as u32;
    }

    /// The functions in table order.
    pub fn iter(self) -> impl Iterator<Item = Function> {
        TABLE
            .iter()
            .map(|e| e.function)
            .filter(move |f| self.contains(*f))
    }

    /// This request completed so that every selectable function is either
    /// generated or derivable: those that cannot be derived are added, and
    /// for each function left out, the functions it is derived from.
    pub fn derivable(self) -> FunctionSet {
        let mut out = self;
        for e in TABLE.iter().filter(|e| e.when == When::Requested) {
            if e.derived_from.is_empty() {
                out.insert(e.function);
            }
        }
        for e in TABLE.iter().filter(|e| e.when == When::Requested) {
            if !out.contains(e.function) && !e.derived_from.iter().all(|d| out.contains(*d)) {
                // Derive from its sources, generating the first missing
                // one (`M` and `b` from inverse dynamics).
                if let Some(d) = e.derived_from.iter().find(|d| !out.contains(**d)) {
                    out.insert(*d);
                }
            }
        }
        // Inverse dynamics left out needs both `M` and `b`.
        for e in TABLE.iter().filter(|e| e.when == When::Requested) {
            if !out.contains(e.function) && !e.derived_from.iter().all(|d| out.contains(*d)) {
                out.insert(e.function);
            }
        }
        out
    }
}

impl FromIterator<Function> for FunctionSet {
    fn from_iter<I: IntoIterator<Item = Function>>(iter: I) -> Self {
        let mut s = FunctionSet::default();
        for f in iter {
            s.insert(f);
        }
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The rules of the old request: forward dynamics, energy and momentum
    /// always; inverse dynamics unless both `M` and `b` are generated.
    #[test]
    fn derivable_completes_a_request() {
        let set = |fs: &[Function]| fs.iter().copied().collect::<FunctionSet>();
        use Function::*;
        let only_m_b = set(&[MassMatrix, Bias]).derivable();
        assert!(!only_m_b.contains(InverseDynamics));
        assert!(only_m_b.contains(ForwardDynamics) && only_m_b.contains(Energy));
        let only_m = set(&[MassMatrix]).derivable();
        assert!(only_m.contains(InverseDynamics) && !only_m.contains(Bias));
        let none = FunctionSet::default().derivable();
        assert!(none.contains(InverseDynamics) && !none.contains(MassMatrix));
        assert_eq!(
            FunctionSet::all_requested().derivable(),
            FunctionSet::all_requested()
        );
        for e in TABLE {
            assert_eq!(e.name.parse::<Function>(), Ok(e.function));
            assert_eq!(e.function.entry().name, e.name);
        }
    }

    /// Derivatives are generated only when asked for: not by default (so
    /// the committed generated code of every model stays as it was), kept
    /// when asked, and they bring forward dynamics with them.
    #[test]
    fn derivatives_only_when_asked() {
        use Function::*;
        assert!(!FunctionSet::all_requested().contains(ForwardDynamicsDerivatives));
        assert!(Function::selectable().any(|f| f == ForwardDynamicsDerivatives));
        let asked = [ForwardDynamicsDerivatives]
            .into_iter()
            .collect::<FunctionSet>()
            .derivable();
        assert!(asked.contains(ForwardDynamicsDerivatives) && asked.contains(ForwardDynamics));
    }
}
