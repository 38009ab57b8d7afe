//! Long chains as loops: forward dynamics, the mass matrix, inverse
//! dynamics and the bias of a serial chain as loops over its bodies, each
//! iteration one generated *body step*, so that the emitted code stops
//! growing with the number of links when links repeat.
//!
//! A recursive algorithm is a sequence of passes over the bodies (root to
//! tip or tip to root). Here each pass is cut at the bodies: body `i`'s
//! part of the pass is a small [`Program`] (a step) whose inputs are
//!
//! - the value the pass carries from body to body (`c_k`: the parent's
//!   velocity, the child's articulated inertia, …), a symbol per entry;
//! - what earlier passes stored for this body (`s<p>_<k>`: its pose, its
//!   velocity-product acceleration, …), a symbol per entry that is not a
//!   constant for this body (an exact zero of a rotation about `z` stays a
//!   zero: the step is specialised to the body);
//! - the body's own coordinate, speed and force or acceleration (`q0`,
//!   `u0`, `tau0` or `ud0`).
//!
//! Its outputs are the carried value for the next body, then what this
//! pass stores for the body. The body's constants (joint axis, frames,
//! inertia) are inlined, so bodies of one structure have *equal* step
//! programs: the steps are deduplicated ([`Pass::steps`], the class of each
//! body in [`Pass::class`]), and a chain of identical links needs a handful
//! of steps whatever its length. The first body of a pass reads the pass's
//! initial value as constants (ground at rest, gravity as the base
//! acceleration, no child beyond the tip), so it gets a step of its own.
//!
//! Passes, as the straight-line algorithms in `kinematics.rs`, `aba.rs`,
//! `rnea.rs` and `crba.rs` (same expressions, so same results up to
//! rounding):
//!
//! - forward dynamics (Featherstone §7.3): root to tip, velocities →
//!   stores `X` (pose), `c` (velocity product), `p⁰` (bias force); tip to
//!   root, articulated inertia and bias → stores `U`, `D⁻¹`, `u`; root to
//!   tip, accelerations → stores `u̇`;
//! - inverse dynamics and bias (§5.3; bias at `u̇ = 0`): root to tip,
//!   velocity and acceleration → stores `X`, the net force `f`; tip to
//!   root, the transmitted force → stores `τ`;
//! - mass matrix (§6.2): `X` per body; tip to root, composite inertia →
//!   stores `F = I_c S`, `M_ii`; then for every body up its ancestors
//!   `F ← Xᵀ F`, `M_ij = S_jᵀ F` (the step of the pair `j + 1 → j`).
//!
//! Which models: [`ChainLoops::build`] offers loops for a serial chain
//! of two or more rigid bodies (body `i` hangs from body `i − 1`) on joints with one
//! coordinate and one speed (revolute, prismatic, screw), free (not locked
//! or prescribed), without force elements besides gravity, inputs or
//! tunable parameters. Whether the emitter uses them is [`ChainLoops::pays`].

// Index loops over the bodies read like the passes they cut.
#![allow(clippy::needless_range_loop)]

use super::env::NumericEnv;
use super::error::MechError;
use super::spatial::{Force, Inertia6, Motion, Pose, RigidInertia};
use super::tree::{Coords, TreeBody, TreeModel};
use crate::functions::{Function, FunctionSet};
use crate::sym::{Context, Expr, LowerOptions, Mat3, Program, Scalar, SymKind, Symbol, Vec3};
use crate::system::System;
use std::collections::BTreeMap;
use std::ops::{Add, Sub};

/// Straight-line programs shorter than this many operations stay
/// straight: they fit the 64 KiB L1 instruction cache (≈ 9–10 bytes of
/// machine code per operation, BENCHMARKS.md "Long chains as loops").
pub const LOOP_MIN_OPS: usize = 6000;

/// The order in which a pass visits the bodies.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Order {
    /// Root to tip.
    Forward,
    /// Tip to root.
    Backward,
    /// For every body `i`, up its ancestors `j = i, …, 1`, the step of
    /// body `j` taking the carried value from `j` to its parent (the mass
    /// matrix's columns); the carry starts from the first `carry` entries of
    /// what pass [`Pass::seed`] stored for body `i`.
    Ancestors,
}

/// The fourth scalar argument of a step.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Own {
    /// The body's extra generalised force `τ_i`.
    Tau,
    /// The body's speed rate `u̇_i`.
    Udot,
}

/// One pass over the bodies.
#[derive(Clone, Debug, PartialEq)]
pub struct Pass {
    /// The order.
    pub order: Order,
    /// The distinct steps.
    pub steps: Vec<Program>,
    /// The step of each body (for [`Order::Ancestors`] of each body `j ≥ 1`;
    /// entry 0 unused).
    pub class: Vec<usize>,
    /// Length of the carried value.
    pub carry: usize,
    /// Its value before the first body.
    pub init: Vec<f64>,
    /// The earlier passes whose stores this pass reads (`s<p>_<k>`).
    pub reads: Vec<usize>,
    /// Values stored per body.
    pub store: usize,
    /// The pass that seeds an [`Order::Ancestors`] pass.
    pub seed: usize,
    /// Reads the body's coordinate, speed, and which fourth scalar.
    pub own: (bool, bool, Option<Own>),
}

impl Pass {
    /// Operations of one call: the steps of every body (every pair for
    /// [`Order::Ancestors`]).
    pub fn ops(&self) -> usize {
        let op = |k: usize| self.steps[k].op_count().total();
        match self.order {
            Order::Forward | Order::Backward => self.class.iter().map(|&k| op(k)).sum(),
            Order::Ancestors => (1..self.class.len())
                .map(|j| op(self.class[j]) * (self.class.len() - j))
                .sum(),
        }
    }

    /// Operations in the distinct steps (what the code size follows).
    pub fn code_ops(&self) -> usize {
        self.steps.iter().map(|p| p.op_count().total()).sum()
    }
}

/// One function as loops.
#[derive(Clone, Debug, PartialEq)]
pub struct Loop {
    /// Its passes, in order.
    pub passes: Vec<Pass>,
}

impl Loop {
    /// Operations of one call.
    pub fn ops(&self) -> usize {
        self.passes.iter().map(Pass::ops).sum()
    }
    /// Operations in the distinct steps.
    pub fn code_ops(&self) -> usize {
        self.passes.iter().map(Pass::code_ops).sum()
    }
    /// Distinct steps.
    pub fn steps(&self) -> usize {
        self.passes.iter().map(|p| p.steps.len()).sum()
    }
}

/// The loops of one chain, by function.
#[derive(Clone, Debug, PartialEq)]
pub struct ChainLoops {
    /// Number of bodies (and speeds).
    pub n: usize,
    /// Forward dynamics, mass matrix, bias and inverse dynamics, as asked.
    pub loops: BTreeMap<Function, Loop>,
}

/// The functions that can be loops.
pub const LOOPED: [Function; 4] = [
    Function::ForwardDynamics,
    Function::MassMatrix,
    Function::Bias,
    Function::InverseDynamics,
];

impl ChainLoops {
    /// The loops of `sys` for the functions of `request` that can be
    /// loops, or `None` if `sys` is not a chain this module handles (see
    /// the module documentation).
    pub fn build(sys: &System, request: FunctionSet) -> Result<Option<ChainLoops>, MechError> {
        let qualifies = sys.parameters.iter().all(|p| !p.tunable)
            && sys.inputs.is_empty()
            && sys.forces.is_empty()
            && sys.bodies.iter().all(|b| b.flexible.is_none());
        if !qualifies || !LOOPED.iter().any(|&f| request.contains(f)) {
            return Ok(None);
        }
        let cx = Context::new();
        let env = LoopEnv(NumericEnv::defaults(sys));
        let tree = TreeModel::new(sys, &env)?;
        let n = tree.bodies.len();
        let chain = n > 1
            && tree.nq == n
            && tree.nu == n
            && tree.bodies.iter().enumerate().all(|(i, b)| {
                b.parent == i.checked_sub(1)
                    && b.flex.is_none()
                    && b.node.is_none()
                    && b.kind.nq() == 1
                    && b.kind.nu() == 1
                    && matches!(b.coords, Coords::Free { q, u } if q == i && u == i)
            });
        if !chain {
            return Ok(None);
        }
        let b = Builder {
            cx: &cx,
            tree: &tree,
        };
        let mut loops = BTreeMap::new();
        for f in LOOPED.into_iter().filter(|&f| request.contains(f)) {
            let l = match f {
                Function::ForwardDynamics => b.forward_dynamics(),
                Function::MassMatrix => b.mass_matrix(),
                Function::Bias => b.inverse_dynamics(false),
                _ => b.inverse_dynamics(true),
            };
            loops.insert(f, l);
        }
        Ok(Some(ChainLoops { n, loops }))
    }

    /// The loop of `f`, if any.
    pub fn get(&self, f: Function) -> Option<&Loop> {
        self.loops.get(&f)
    }

    /// Whether emitting `f` as loops pays, given its straight-line
    /// operation count: the straight-line code outgrows the instruction
    /// cache (at least [`LOOP_MIN_OPS`] operations), the loops' code is at
    /// most a quarter of it, and the loops do at most 1.5 times its
    /// operations per call. Measured in BENCHMARKS.md ("Long chains as
    /// loops").
    pub fn pays(&self, f: Function, straight_ops: usize) -> bool {
        self.get(f).is_some_and(|l| {
            straight_ops >= LOOP_MIN_OPS
                && 4 * l.code_ops() <= straight_ops
                && 2 * l.ops() <= 3 * straight_ops
        })
    }
}

/// Parameters as numbers (tunable ones are refused before).
struct LoopEnv(NumericEnv);

impl<'cx> super::env::Env<Expr<'cx>> for LoopEnv {
    fn param(&self, name: &str) -> Option<Expr<'cx>> {
        self.0.param(name).map(Expr::from_f64)
    }
    fn is_tunable(&self, _name: &str) -> bool {
        false
    }
}

/// Builds the steps of one chain.
struct Builder<'a, 'cx> {
    cx: &'cx Context,
    tree: &'a TreeModel<Expr<'cx>>,
}

/// A body's joint quantities: pose in the parent, motion subspace column,
/// joint bias `S̊ u`, joint velocity `S u`.
struct Joint<'cx> {
    x: Pose<Expr<'cx>>,
    s: Motion<Expr<'cx>>,
    c: Motion<Expr<'cx>>,
    vj: Motion<Expr<'cx>>,
}

fn pose_values<S: Scalar>(x: &Pose<S>) -> Vec<S> {
    let mut out: Vec<S> = x.e.0.iter().flatten().copied().collect();
    out.extend(x.r.0);
    out
}

fn motion_values<S: Scalar>(m: &Motion<S>) -> Vec<S> {
    m.w.0.iter().chain(&m.v.0).copied().collect()
}

fn force_values<S: Scalar>(f: &Force<S>) -> Vec<S> {
    f.n.0.iter().chain(&f.f.0).copied().collect()
}

fn motion_from<S: Scalar>(v: &[S]) -> Motion<S> {
    Motion {
        w: Vec3([v[0], v[1], v[2]]),
        v: Vec3([v[3], v[4], v[5]]),
    }
}

fn force_from<S: Scalar>(v: &[S]) -> Force<S> {
    Force {
        n: Vec3([v[0], v[1], v[2]]),
        f: Vec3([v[3], v[4], v[5]]),
    }
}

fn pose_from<S: Scalar>(v: &[S]) -> Pose<S> {
    Pose {
        e: Mat3([[v[0], v[1], v[2]], [v[3], v[4], v[5]], [v[6], v[7], v[8]]]),
        r: Vec3([v[9], v[10], v[11]]),
    }
}

/// Upper triangle of a symmetric 3×3 matrix (6 values) and back.
const SYM: [(usize, usize); 6] = [(0, 0), (0, 1), (0, 2), (1, 1), (1, 2), (2, 2)];

fn sym_values<S: Scalar>(m: &Mat3<S>) -> Vec<S> {
    SYM.iter().map(|&(i, j)| m.0[i][j]).collect()
}

fn sym_from<S: Scalar>(v: &[S]) -> Mat3<S> {
    Mat3([[v[0], v[1], v[2]], [v[1], v[3], v[4]], [v[2], v[4], v[5]]])
}

/// Articulated inertia as 21 values (`A` and `C` symmetric).
fn inertia6_values<S: Scalar>(i: &Inertia6<S>) -> Vec<S> {
    let mut out = sym_values(&i.a);
    out.extend(i.b.0.iter().flatten().copied());
    out.extend(sym_values(&i.c));
    out
}

fn inertia6_from<S: Scalar>(v: &[S]) -> Inertia6<S> {
    Inertia6 {
        a: sym_from(&v[0..6]),
        b: Mat3([
            [v[6], v[7], v[8]],
            [v[9], v[10], v[11]],
            [v[12], v[13], v[14]],
        ]),
        c: sym_from(&v[15..21]),
    }
}

/// Rigid (composite) inertia as 10 values.
fn rigid_values<S: Scalar>(r: &RigidInertia<S>) -> Vec<S> {
    let mut out = vec![r.m];
    out.extend(r.h.0);
    out.extend(sym_values(&r.i));
    out
}

fn rigid_from<S: Scalar>(v: &[S]) -> RigidInertia<S> {
    RigidInertia {
        m: v[0],
        h: Vec3([v[1], v[2], v[3]]),
        i: sym_from(&v[4..10]),
    }
}

/// The steps of one pass as they are built, deduplicated.
struct PassBuilder {
    pass: Pass,
}

impl PassBuilder {
    fn new(order: Order, carry: usize, init: Vec<f64>, reads: Vec<usize>, store: usize) -> Self {
        PassBuilder {
            pass: Pass {
                order,
                steps: Vec::new(),
                class: Vec::new(),
                carry,
                init,
                reads,
                store,
                seed: 0,
                own: (false, false, None),
            },
        }
    }

    /// Adds the step of the next body (in body order, not pass order).
    fn push(&mut self, p: Program) {
        for s in &p.inputs {
            match s.kind {
                SymKind::Coord(_) => self.pass.own.0 = true,
                SymKind::Speed(_) => self.pass.own.1 = true,
                SymKind::Tau(_) => self.pass.own.2 = Some(Own::Tau),
                SymKind::SpeedRate(_) => self.pass.own.2 = Some(Own::Udot),
                _ => {}
            }
        }
        let k = match self.pass.steps.iter().position(|s| *s == p) {
            Some(k) => k,
            None => {
                self.pass.steps.push(p);
                self.pass.steps.len() - 1
            }
        };
        self.pass.class.push(k);
    }
}

impl<'cx> Builder<'_, 'cx> {
    fn body(&self, i: usize) -> &TreeBody<Expr<'cx>> {
        &self.tree.bodies[i]
    }

    /// The carried value: symbols `c_k`, or `init` for the pass's first body.
    fn carry(&self, n: usize, init: Option<&[f64]>) -> Vec<Expr<'cx>> {
        match init {
            Some(v) => v.iter().map(|&x| Expr::from_f64(x)).collect(),
            None => (0..n).map(|k| self.input(&format!("c_{k}"))).collect(),
        }
    }

    fn input(&self, name: &str) -> Expr<'cx> {
        // The names are fixed and free (`c_0`, `s1_4`): never refused.
        self.cx.input(name).unwrap_or(Expr::zero())
    }

    /// What pass `p` stored for a body, as its step reads it: the
    /// constants of `values` (that body's expressions) stay constants.
    fn stored(&self, p: usize, values: &[Expr<'cx>]) -> Vec<Expr<'cx>> {
        values
            .iter()
            .enumerate()
            .map(|(k, e)| match e.as_num() {
                Some(_) => *e,
                None => self.input(&format!("s{p}_{k}")),
            })
            .collect()
    }

    fn lower(&self, carry: &[Expr<'cx>], store: &[Expr<'cx>]) -> Program {
        let names: Vec<String> = (0..carry.len())
            .map(|k| format!("co{k}"))
            .chain((0..store.len()).map(|k| format!("so{k}")))
            .collect();
        let outs: Vec<(&str, Expr<'cx>)> = names
            .iter()
            .map(String::as_str)
            .zip(carry.iter().chain(store).copied())
            .collect();
        self.cx.lower(&outs, LowerOptions::default())
    }

    /// Joint quantities of body `i` at its coordinate `q0` and speed `u0`,
    /// as `Evaluator::kinematics` writes them.
    fn joint(&self, i: usize) -> Joint<'cx> {
        let b = self.body(i);
        let (q, u) = ([self.cx.q(0)], [self.cx.u(0)]);
        let fc = b.frame_child;
        let x = b
            .frame_parent
            .then(&b.kind.transform(&q))
            .then(&fc.inverse());
        let s: Vec<Motion<Expr>> = b
            .kind
            .subspace(&q)
            .into_iter()
            .map(|m| fc.motion_to_parent(m))
            .collect();
        let c = fc.motion_to_parent(b.kind.bias(&q, &u));
        let vj = s
            .iter()
            .zip(&u)
            .fold(Motion::zero(), |acc, (col, &uk)| acc.add(col.scale(uk)));
        Joint { x, s: s[0], c, vj }
    }

    fn base_acceleration(&self) -> Vec<f64> {
        let g = self
            .tree
            .gravity
            .0
            .map(|e| e.as_num().map_or(0.0, |n| n.to_f64()));
        vec![0.0, 0.0, 0.0, -g[0], -g[1], -g[2]]
    }

    /// Forward dynamics by the articulated-body algorithm, three passes.
    fn forward_dynamics(&self) -> Loop {
        let n = self.tree.bodies.len();
        // Pass 0, root to tip: v; stores X (12), c + v × v_J (6), p⁰ (6).
        let mut p0 = PassBuilder::new(Order::Forward, 6, vec![0.0; 6], vec![], 24);
        let mut stored0 = Vec::with_capacity(n);
        for i in 0..n {
            let j = self.joint(i);
            let vp = motion_from(&self.carry(6, (i == 0).then_some(&[0.0; 6][..])));
            let v = j.x.motion_to_child(vp).add(j.vj);
            let inertia = self.body(i).inertia;
            let cv = j.c.add(v.cross_motion(j.vj));
            let pa = v.cross_force(inertia.mul_motion(v)).sub(Force::zero());
            let mut store = pose_values(&j.x);
            store.extend(motion_values(&cv));
            store.extend(force_values(&pa));
            p0.push(self.lower(&motion_values(&v), &store));
            stored0.push(store);
        }
        // Pass 1, tip to root: articulated inertia and bias of the child
        // (in this body's coordinates); stores U (6), D⁻¹, u.
        let mut p1 = PassBuilder::new(Order::Backward, 27, vec![0.0; 27], vec![0], 8);
        let mut stored1 = Vec::with_capacity(n);
        for i in 0..n {
            let j = self.joint(i);
            let s0 = self.stored(0, &stored0[i]);
            let (x, cv, pa0) = (
                pose_from(&s0[0..12]),
                motion_from(&s0[12..18]),
                force_from(&s0[18..24]),
            );
            let carry = self.carry(27, (i + 1 == n).then_some(&[0.0; 27][..]));
            let ia = Inertia6::from_rigid(&self.body(i).inertia).add(inertia6_from(&carry[0..21]));
            let pa = pa0.add(force_from(&carry[21..27]));
            let ucol = ia.mul_motion(j.s);
            let d = j.s.dot(ucol);
            let di = Expr::one() / d;
            let ui = self.cx.tau(0) - j.s.dot(pa);
            let inner = ia.sub_outer(&ucol, &ucol, di);
            let p = pa
                .add(inner.mul_motion(cv))
                .add(ucol.scale(Expr::zero() + di * ui));
            let mut out = inertia6_values(&inner.to_parent(&x));
            out.extend(force_values(&x.force_to_parent(p)));
            let mut store = force_values(&ucol);
            store.extend([di, ui]);
            p1.push(self.lower(&out, &store));
            stored1.push(store);
        }
        // Pass 2, root to tip: accelerations; stores u̇.
        let base = self.base_acceleration();
        let mut p2 = PassBuilder::new(Order::Forward, 6, base.clone(), vec![0, 1], 1);
        for i in 0..n {
            let j = self.joint(i);
            let s0 = self.stored(0, &stored0[i]);
            let s1 = self.stored(1, &stored1[i]);
            let (x, cv) = (pose_from(&s0[0..12]), motion_from(&s0[12..18]));
            let (ucol, di, ui) = (force_from(&s1[0..6]), s1[6], s1[7]);
            let ap = motion_from(&self.carry(6, (i == 0).then_some(&base[..])));
            let mut ai = x.motion_to_child(ap).add(cv);
            let rhs = ui - ai.dot(ucol);
            let xdd = Expr::zero() + di * rhs;
            ai = ai.add(j.s.scale(xdd));
            p2.push(self.lower(&motion_values(&ai), &[xdd]));
        }
        Loop {
            passes: vec![p0.pass, p1.pass, p2.pass],
        }
    }

    /// Inverse dynamics (`with_udot`) or the bias (at `u̇ = 0`) by
    /// recursive Newton–Euler, two passes.
    fn inverse_dynamics(&self, with_udot: bool) -> Loop {
        let n = self.tree.bodies.len();
        let base = self.base_acceleration();
        let mut init = vec![0.0; 6];
        init.extend(&base);
        // Pass 0, root to tip: (v, a); stores X (12), f (6).
        let mut p0 = PassBuilder::new(Order::Forward, 12, init.clone(), vec![], 18);
        let mut stored0 = Vec::with_capacity(n);
        for i in 0..n {
            let j = self.joint(i);
            let carry = self.carry(12, (i == 0).then_some(&init[..]));
            let (vp, ap) = (motion_from(&carry[0..6]), motion_from(&carry[6..12]));
            let v = j.x.motion_to_child(vp).add(j.vj);
            let ud = if with_udot {
                self.cx.ud(0)
            } else {
                Expr::zero()
            };
            let a =
                j.x.motion_to_child(ap)
                    .add(j.c)
                    .add(v.cross_motion(j.vj))
                    .add(j.s.scale(ud));
            let inertia = self.body(i).inertia;
            let f = inertia
                .mul_motion(a)
                .add(v.cross_force(inertia.mul_motion(v)))
                .sub(Force::zero());
            let mut carry_out = motion_values(&v);
            carry_out.extend(motion_values(&a));
            let mut store = pose_values(&j.x);
            store.extend(force_values(&f));
            p0.push(self.lower(&carry_out, &store));
            stored0.push(store);
        }
        // Pass 1, tip to root: the force the child transmits; stores τ.
        let mut p1 = PassBuilder::new(Order::Backward, 6, vec![0.0; 6], vec![0], 1);
        for i in 0..n {
            let j = self.joint(i);
            let s0 = self.stored(0, &stored0[i]);
            let x = pose_from(&s0[0..12]);
            let carry = self.carry(6, (i + 1 == n).then_some(&[0.0; 6][..]));
            let f = force_from(&s0[12..18]).add(force_from(&carry));
            let tau = j.s.dot(f);
            p1.push(self.lower(&force_values(&x.force_to_parent(f)), &[tau]));
        }
        Loop {
            passes: vec![p0.pass, p1.pass],
        }
    }

    /// The mass matrix by composite rigid bodies: poses, composite
    /// inertias, then the columns up the ancestors.
    fn mass_matrix(&self) -> Loop {
        let n = self.tree.bodies.len();
        // Pass 0: X (12).
        let mut p0 = PassBuilder::new(Order::Forward, 0, vec![], vec![], 12);
        let mut stored0 = Vec::with_capacity(n);
        for i in 0..n {
            let store = pose_values(&self.joint(i).x);
            p0.push(self.lower(&[], &store));
            stored0.push(store);
        }
        // Pass 1, tip to root: composite inertia of the child (this body's
        // coordinates); stores F = I_c S (6) and M_ii.
        let mut p1 = PassBuilder::new(Order::Backward, 10, vec![0.0; 10], vec![0], 7);
        for i in 0..n {
            let j = self.joint(i);
            let s0 = self.stored(0, &stored0[i]);
            let x = pose_from(&s0[0..12]);
            let carry = self.carry(10, (i + 1 == n).then_some(&[0.0; 10][..]));
            let ic = self.body(i).inertia.add(rigid_from(&carry));
            let f = ic.mul_motion(j.s);
            let mut store = force_values(&f);
            store.push(j.s.dot(f));
            p1.push(self.lower(&rigid_values(&ic.to_parent(&x)), &store));
        }
        // Pass 2: for each column, F ← Xⱼᵀ F and M_i,j−1 = S_{j−1}ᵀ F.
        let mut p2 = PassBuilder::new(Order::Ancestors, 6, vec![], vec![0], 1);
        p2.pass.seed = 1;
        let pair = |jb: usize| {
            let s0 = self.stored(0, &stored0[jb]);
            let x = pose_from(&s0[0..12]);
            let f = x.force_to_parent(force_from(&self.carry(6, None)));
            let m = self.joint(jb - 1).s.dot(f);
            self.lower(&force_values(&f), &[m])
        };
        // Body 0 has no parent: its entry (body 1's step) is never run.
        p2.push(pair(1));
        for jb in 1..n {
            p2.push(pair(jb));
        }
        Loop {
            passes: vec![p0.pass, p1.pass, p2.pass],
        }
    }
}

/// The value of a step input at a body.
fn input_value(s: &Symbol, carry: &[f64], stores: &[&[f64]], own: [f64; 3]) -> f64 {
    match s.kind {
        SymKind::Coord(_) => own[0],
        SymKind::Speed(_) => own[1],
        SymKind::Tau(_) | SymKind::SpeedRate(_) => own[2],
        _ => {
            let idx = |rest: &str| rest.parse::<usize>().ok();
            if let Some(k) = s.name.strip_prefix("c_").and_then(idx) {
                return carry.get(k).copied().unwrap_or(f64::NAN);
            }
            let mut parts = s.name.trim_start_matches('s').splitn(2, '_');
            match (parts.next().and_then(idx), parts.next().and_then(idx)) {
                (Some(p), Some(k)) => stores
                    .get(p)
                    .and_then(|st| st.get(k))
                    .copied()
                    .unwrap_or(f64::NAN),
                _ => f64::NAN,
            }
        }
    }
}

impl Loop {
    /// Runs the loops on `f64`, as the emitted code does: `q`, `u` and the
    /// fourth argument `w` (`τ` or `u̇`) per body; returns every pass's
    /// stores (per body, in body order). The numeric twin of the emitted
    /// loops, for tests.
    pub fn run(&self, q: &[f64], u: &[f64], w: &[f64]) -> Vec<Vec<Vec<f64>>> {
        let n = q.len();
        let mut stores: Vec<Vec<Vec<f64>>> = Vec::new();
        for pass in &self.passes {
            let mut out = vec![Vec::new(); n];
            let own = |i: usize| {
                [
                    q.get(i).copied().unwrap_or(f64::NAN),
                    u.get(i).copied().unwrap_or(f64::NAN),
                    w.get(i).copied().unwrap_or(0.0),
                ]
            };
            let step = |k: usize, carry: &[f64], i: usize, stores: &[Vec<Vec<f64>>]| {
                let st: Vec<&[f64]> = stores.iter().map(|s| s[i].as_slice()).collect();
                let p = &pass.steps[pass.class[k]];
                let ins: Vec<f64> = p
                    .inputs
                    .iter()
                    .map(|s| input_value(s, carry, &st, own(i)))
                    .collect();
                p.eval(&ins)
            };
            match pass.order {
                Order::Forward | Order::Backward => {
                    let mut carry = pass.init.clone();
                    let order: Vec<usize> = if pass.order == Order::Forward {
                        (0..n).collect()
                    } else {
                        (0..n).rev().collect()
                    };
                    for i in order {
                        let r = step(i, &carry, i, &stores);
                        carry = r[..pass.carry].to_vec();
                        out[i] = r[pass.carry..].to_vec();
                    }
                }
                Order::Ancestors => {
                    // out[i] holds M_i,j for j < i, in order j = 0, …, i − 1.
                    for i in 0..n {
                        let mut carry = stores[pass.seed][i][..pass.carry].to_vec();
                        let mut row = vec![0.0; i];
                        for jb in (1..=i).rev() {
                            let r = step(jb, &carry, jb, &stores);
                            carry = r[..pass.carry].to_vec();
                            row[jb - 1] = r[pass.carry];
                        }
                        out[i] = row;
                    }
                }
            }
            stores.push(out);
        }
        stores
    }
}
