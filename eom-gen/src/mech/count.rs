//! Operation counts of the recursive algorithms run generically: the same
//! code the generator specialises, run on a scalar that counts every
//! arithmetic operation and never reports an exact zero or one. This is
//! what the textbook algorithms cost as written (dense 3×3 rotations,
//! spatial vectors, no structural zeros), the baseline against which the
//! generated programs' counts show what symbolic specialisation saves.

use super::applied::Applied;
use super::env::{Env, NumericEnv};
use super::error::MechError;
use super::kinematics::{Evaluator, State};
use super::tree::TreeModel;
use crate::sym::Scalar;
use crate::system::System;
use std::cell::Cell;
use std::ops::{Add, Div, Mul, Neg, Sub};

thread_local! {
    static COUNTS: Cell<Counts> = const { Cell::new(Counts::ZERO) };
}

/// Operations performed, by kind.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Counts {
    /// Additions and subtractions.
    pub add: u64,
    /// Multiplications.
    pub mul: u64,
    /// Divisions.
    pub div: u64,
    /// Negations.
    pub neg: u64,
    /// Square roots, trigonometric and other elementary functions.
    pub func: u64,
}

impl Counts {
    const ZERO: Counts = Counts {
        add: 0,
        mul: 0,
        div: 0,
        neg: 0,
        func: 0,
    };

    /// All operations, each counted once (as `OpCount::total` counts the
    /// generated programs).
    pub fn total(&self) -> u64 {
        self.add + self.mul + self.div + self.neg + self.func
    }
}

fn bump(f: impl FnOnce(&mut Counts)) {
    COUNTS.with(|c| {
        let mut v = c.get();
        f(&mut v);
        c.set(v);
    });
}

/// An `f64` that counts the operations done on it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Counted(pub f64);

// Counting is the point: the operator bumps a counter besides computing.
#[allow(clippy::suspicious_arithmetic_impl)]
impl Add for Counted {
    type Output = Counted;
    fn add(self, o: Counted) -> Counted {
        bump(|c| c.add += 1);
        Counted(self.0 + o.0)
    }
}

// Counting is the point: the operator bumps a counter besides computing.
#[allow(clippy::suspicious_arithmetic_impl)]
impl Sub for Counted {
    type Output = Counted;
    fn sub(self, o: Counted) -> Counted {
        bump(|c| c.add += 1);
        Counted(self.0 - o.0)
    }
}

// Counting is the point: the operator bumps a counter besides computing.
#[allow(clippy::suspicious_arithmetic_impl)]
impl Mul for Counted {
    type Output = Counted;
    fn mul(self, o: Counted) -> Counted {
        bump(|c| c.mul += 1);
        Counted(self.0 * o.0)
    }
}

// Counting is the point: the operator bumps a counter besides computing.
#[allow(clippy::suspicious_arithmetic_impl)]
impl Div for Counted {
    type Output = Counted;
    fn div(self, o: Counted) -> Counted {
        bump(|c| c.div += 1);
        Counted(self.0 / o.0)
    }
}

// Counting is the point: the operator bumps a counter besides computing.
#[allow(clippy::suspicious_arithmetic_impl)]
impl Neg for Counted {
    type Output = Counted;
    fn neg(self) -> Counted {
        bump(|c| c.neg += 1);
        Counted(-self.0)
    }
}

impl Counted {
    fn func(self, f: impl FnOnce(f64) -> f64) -> Counted {
        bump(|c| c.func += 1);
        Counted(f(self.0))
    }
}

impl Scalar for Counted {
    fn from_f64(x: f64) -> Self {
        Counted(x)
    }
    fn from_ratio(p: i32, q: i32) -> Self {
        Counted(p as f64 / q as f64)
    }
    fn sin(self) -> Self {
        self.func(f64::sin)
    }
    fn cos(self) -> Self {
        self.func(f64::cos)
    }
    fn sin_cos(self) -> (Self, Self) {
        bump(|c| c.func += 1);
        (Counted(self.0.sin()), Counted(self.0.cos()))
    }
    fn tan(self) -> Self {
        self.func(f64::tan)
    }
    fn atan2(self, x: Self) -> Self {
        self.func(|y| y.atan2(x.0))
    }
    fn sqrt(self) -> Self {
        self.func(f64::sqrt)
    }
    fn exp(self) -> Self {
        self.func(f64::exp)
    }
    fn ln(self) -> Self {
        self.func(f64::ln)
    }
    fn abs(self) -> Self {
        self.func(f64::abs)
    }
    fn powi(self, n: i32) -> Self {
        self.func(|x| x.powi(n))
    }
    fn select(cond: Self, a: Self, b: Self) -> Self {
        bump(|c| c.func += 1);
        if cond.0 > 0.0 { a } else { b }
    }
    fn is_zero(&self) -> bool {
        false
    }
    fn is_one(&self) -> bool {
        false
    }
}

struct CountedEnv(NumericEnv);

impl Env<Counted> for CountedEnv {
    fn param(&self, name: &str) -> Option<Counted> {
        Env::<f64>::param(&self.0, name).map(Counted)
    }
    fn is_tunable(&self, name: &str) -> bool {
        Env::<f64>::is_tunable(&self.0, name)
    }
}

/// Counted cost of one call of each algorithm, kinematics included (as in
/// the generated functions).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct AlgorithmCounts {
    /// Forward dynamics by the articulated-body algorithm.
    pub aba: Counts,
    /// Inverse dynamics by recursive Newton–Euler.
    pub rnea: Counts,
    /// The mass matrix by composite rigid bodies (kinematics of positions
    /// only).
    pub crba: Counts,
}

fn measure<T>(f: impl FnOnce() -> Result<T, MechError>) -> Result<Counts, MechError> {
    COUNTS.with(|c| c.set(Counts::ZERO));
    f()?;
    Ok(COUNTS.with(Cell::get))
}

/// Runs ABA, RNEA and CRBA on `sys` at its initial state with counting
/// scalars.
pub fn textbook_counts(sys: &System) -> Result<AlgorithmCounts, MechError> {
    let env = CountedEnv(NumericEnv::defaults(sys));
    let tree = TreeModel::new(sys, &env)?;
    let applied = Applied::new(sys, &tree, &env)?;
    let ev = Evaluator::new(&tree, &applied, &env);
    let wrap = |v: Vec<f64>| v.into_iter().map(Counted).collect::<Vec<_>>();
    let (q, u) = (wrap(sys.q0()), wrap(sys.u0()));
    let zero = vec![Counted(0.0); tree.nu];
    let st = State {
        q: &q,
        u: &u,
        t: Counted(0.0),
        inputs: &[],
    };
    let still = State { u: &zero, ..st };
    let aba = measure(|| {
        let k = ev.kinematics(&st)?;
        let (fext, _) = ev.point_forces(&k);
        let (generalized, _) = ev.generalized_forces(&st)?;
        Ok(ev.aba(&k, &generalized, &fext))
    })?;
    let rnea = measure(|| {
        let k = ev.kinematics(&st)?;
        let (fext, _) = ev.point_forces(&k);
        let (generalized, _) = ev.generalized_forces(&st)?;
        let (tau, _) = ev.rnea(&k, &zero, &fext);
        Ok((tau, generalized))
    })?;
    let crba = measure(|| {
        let k = ev.kinematics(&still)?;
        Ok(ev.crba(&k))
    })?;
    Ok(AlgorithmCounts { aba, rnea, crba })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts_every_operation() {
        COUNTS.with(|c| c.set(Counts::ZERO));
        let (a, b) = (Counted(2.0), Counted(3.0));
        let r = (a * b + a - b / a).sqrt().sin_cos().0 * -a;
        assert!((r.0 - -2.0 * (6.5f64).sqrt().sin()).abs() < 1e-15);
        let c = COUNTS.with(Cell::get);
        assert_eq!(
            c,
            Counts {
                add: 2,
                mul: 2,
                div: 1,
                neg: 1,
                func: 2
            }
        );
        assert_eq!(c.total(), 8);
    }

    #[test]
    fn textbook_counts_grow_linearly_for_aba_and_rnea() {
        let count = |n: usize| {
            let spec = crate::model::builder::n_link_chain(n, true);
            let src = crate::model::Source::new("chain.ron", spec.to_ron());
            let sys = crate::model::check(&src)
                .unwrap_or_else(|r| panic!("{r}"))
                .system;
            textbook_counts(&sys).expect("counts")
        };
        let (a, b, c) = (count(10), count(20), count(40));
        // Equal increments per 10 and per 20 links: linear.
        let per = |x: Counts, y: Counts, n: u64| (y.total() - x.total()) / n;
        assert_eq!(per(a.aba, b.aba, 10), per(b.aba, c.aba, 20));
        assert_eq!(per(a.rnea, b.rnea, 10), per(b.rnea, c.rnea, 20));
        // CRBA is quadratic: the second difference is positive.
        assert!(c.crba.total() - b.crba.total() > 2 * (b.crba.total() - a.crba.total()));
    }
}
