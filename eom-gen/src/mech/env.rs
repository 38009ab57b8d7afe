//! What names in model expressions stand for: an [`Env`] says whether a
//! parameter is a number (the `f64` reference numerics, [`NumericEnv`]) or
//! a symbol (generation, tunable parameters).

use crate::system::System;

/// What names in model expressions stand for.
pub trait Env<S> {
    /// The value or symbol of parameter `name` (`None` if unknown).
    fn param(&self, name: &str) -> Option<S>;
    /// True if the parameter is tunable (kept symbolic when generating).
    fn is_tunable(&self, name: &str) -> bool;
}

/// Parameters as numbers: defaults, optionally overridden.
#[derive(Clone, Debug, Default)]
pub struct NumericEnv {
    values: Vec<(String, f64)>,
    tunable: Vec<String>,
}

impl NumericEnv {
    /// Every parameter of `sys` at its default (derived parameters are
    /// recomputed from the others, in file order).
    pub fn defaults(sys: &System) -> Self {
        Self::with(sys, &[])
    }

    /// Defaults with some tunable parameters set to other values.
    pub fn with(sys: &System, overrides: &[(&str, f64)]) -> Self {
        let mut env = NumericEnv::default();
        for p in &sys.parameters {
            let given = overrides
                .iter()
                .find(|(n, _)| *n == p.name)
                .map(|(_, v)| *v);
            let value = given.unwrap_or_else(|| {
                p.value
                    .expr
                    .eval(&|n: &str| env.param(n))
                    .unwrap_or(p.value.value)
            });
            env.values.push((p.name.clone(), value));
            if p.tunable {
                env.tunable.push(p.name.clone());
            }
        }
        env
    }
}

impl Env<f64> for NumericEnv {
    fn param(&self, name: &str) -> Option<f64> {
        self.values
            .iter()
            .rev()
            .find(|(n, _)| n == name)
            .map(|(_, v)| *v)
    }
    fn is_tunable(&self, name: &str) -> bool {
        self.tunable.iter().any(|n| n == name)
    }
}
