//! How the constraints are kept: [`Method`] and its default settings.

/// How constraints are kept (see the module docs); projection by default.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum Method {
    /// Multipliers with Baumgarte stabilisation `γ − 2α Φ̇ − β² Φ`.
    Baumgarte {
        /// `α`, s⁻¹.
        alpha: f64,
        /// `β`, s⁻¹.
        beta: f64,
    },
    /// Multipliers, then projection of `q` and `u` after every step.
    #[default]
    Projection,
    /// Multipliers, then the dependent coordinates and speeds recomputed
    /// from the independent ones after every step.
    Partitioning,
    /// The index-3 DAE in `(q, u, λ)`.
    Index3,
    /// Augmented Lagrangian (Bayo and Ledesma 1996; García de Jalón and
    /// Bayo 1994): every constrained solve — the accelerations at each
    /// right-hand side and the mass-orthogonal projections of `q` and `u`
    /// after every step — minimises `½ xᵀMx − fᵀx` subject to `J x = r` by
    /// iterating `(M + αJᵀJ) x_{k+1} = f + Jᵀ(λ_k + α r)`,
    /// `λ_{k+1} = λ_k + α (r − J x_{k+1})` from `λ_0 = 0`. The leading
    /// matrix stays positive definite when `J` is singular or redundant.
    AugmentedLagrangian {
        /// `α` relative to `max diag M / max diag JᵀJ` (dimensionless).
        penalty: f64,
        /// Most iterations per solve (it stops earlier once `J x = r`
        /// holds to round-off).
        iterations: usize,
    },
}

impl Method {
    /// Baumgarte with `α = β = 10 s⁻¹`, the default of `eom-gen simulate`.
    pub const BAUMGARTE: Method = Method::Baumgarte {
        alpha: 10.0,
        beta: 10.0,
    };

    /// The augmented Lagrangian with `α = 1e5` (relative) and at most 20
    /// iterations per solve, the default of `--constraints
    /// augmented-lagrangian`.
    pub const AUGMENTED_LAGRANGIAN: Method = Method::AugmentedLagrangian {
        penalty: 1e5,
        iterations: 20,
    };
}
