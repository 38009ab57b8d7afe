//! The recursive algorithms on `f64`: the reference numerics every
//! generated function is tested against, and the baseline that shows what
//! generation buys.

use super::applied::Applied;
use super::env::NumericEnv;
use super::error::MechError;
use super::kinematics::{Evaluator, State};
use super::ltdl::{ltdl, ltdl_solve};
use super::spatial::Force;
use super::tree::TreeModel;
use crate::system::System;

/// The first speed whose motion has no inertia: the first zero pivot
/// (at most `1e-12` times the largest diagonal entry, or not finite) of
/// `M = L D Lᵀ` without pivoting, i.e. the first column of `M` that is a
/// combination of the ones before it. `None` when `M` is positive definite.
pub fn singular_speed(m: &[Vec<f64>]) -> Option<usize> {
    let n = m.len();
    let scale = (0..n)
        .map(|i| m[i].get(i).copied().unwrap_or(f64::NAN).abs())
        .fold(0.0, f64::max);
    let tol = 1e-12 * scale;
    let mut l = vec![vec![0.0; n]; n];
    let mut d = vec![0.0; n];
    for j in 0..n {
        let dj = m[j][j] - (0..j).map(|k| l[j][k] * l[j][k] * d[k]).sum::<f64>();
        if dj.is_nan() || dj <= tol || !dj.is_finite() {
            return Some(j);
        }
        d[j] = dj;
        for i in j + 1..n {
            let s = m[i][j] - (0..j).map(|k| l[i][k] * l[j][k] * d[k]).sum::<f64>();
            l[i][j] = s / dj;
        }
    }
    None
}

/// Where the mass matrix is singular: the first speed (and its joint)
/// whose motion has no inertia at the initial state, and whether it has
/// none at other configurations either.
pub struct Singular {
    /// The speed: a zero pivot of `M = L D Lᵀ` at the initial state.
    pub speed: usize,
    /// The tree joint that speed belongs to.
    pub joint: usize,
    /// Singular at two generic configurations too (a motion without
    /// inertia, a massless leaf), not only at the initial state (two axes
    /// aligned there, icub's neck).
    pub everywhere: bool,
}

/// The mass matrix at the initial state, checked by its `L D Lᵀ` pivots
/// (see [`singular_speed`]). `None` when it is
/// positive definite or cannot be evaluated.
pub fn singular_joint(system: &System) -> Option<Singular> {
    let num = Numeric::new(system).ok()?;
    let u0 = vec![0.0; system.nu()];
    let inputs = vec![0.0; system.inputs.len()];
    // Some(None): positive definite; None: not evaluable.
    let at = |q: &[f64]| -> Option<Option<usize>> {
        let terms = num.terms(q, &u0, 0.0, &inputs).ok()?;
        Some(singular_speed(&terms.mass_matrix))
    };
    let q0 = system.q0();
    let k = at(&q0)??;
    let joint = system.graph.tree_joints().iter().copied().find(|&j| {
        let j = &system.joints[j];
        j.motion == crate::system::Motion::Free
            && (j.u_index..j.u_index + j.speed_names.len()).contains(&k)
    })?;
    // Two fixed, generic configurations near q0 (quaternions renormalised).
    let everywhere = (1..=2).all(|s| {
        let mut q: Vec<f64> = q0
            .iter()
            .enumerate()
            .map(|(i, x)| x + 0.4 * ((0.618_033_988_75 * (i * 7 + s * 13) as f64).fract() - 0.5))
            .collect();
        for w in system.quaternion_indices() {
            let n = q[w..w + 4].iter().map(|x| x * x).sum::<f64>().sqrt();
            q[w..w + 4].iter_mut().for_each(|x| *x /= n);
        }
        at(&q) != Some(None)
    });
    Some(Singular {
        speed: k,
        joint,
        everywhere,
    })
}

/// A system ready for numeric evaluation.
#[derive(Clone, Debug)]
pub struct Numeric {
    env: NumericEnv,
    tree: TreeModel<f64>,
    applied: Applied<f64>,
    cuts: Vec<super::constraints::CutJoint<f64>>,
    sys_constraints: Vec<crate::system::Constraint>,
    coordinate_names: Vec<String>,
}

/// The result of [`Numeric::assemble`]: the runtime's assembly.
pub use eom_sim::constrained::Assembly;

/// The rank of the constraint Jacobian and what it implies.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Mobility {
    /// Number of closure equations.
    pub equations: usize,
    /// Rank of `Φ_q N(q)` (numerical, relative tolerance 1e-8).
    pub rank: usize,
    /// Degrees of freedom: speeds minus rank.
    pub dof: usize,
}

/// Everything the equations of motion need at one state.
#[derive(Clone, Debug, PartialEq)]
pub struct Terms {
    /// Mass matrix `M(q)`, `nu × nu`.
    pub mass_matrix: Vec<Vec<f64>>,
    /// `b = C + g − Jᵀ f_ext − Q`, so that `M u̇ = τ − b`.
    pub bias: Vec<f64>,
}

impl Numeric {
    /// `sys` with every parameter at its default.
    pub fn new(sys: &System) -> Result<Self, MechError> {
        Self::with_env(sys, NumericEnv::defaults(sys))
    }

    /// `sys` with the given parameter values.
    pub fn with_env(sys: &System, env: NumericEnv) -> Result<Self, MechError> {
        let tree = TreeModel::new(sys, &env)?;
        let applied = Applied::new(sys, &tree, &env)?;
        let cuts = super::constraints::cut_joints(sys, &tree, &env)?;
        Ok(Numeric {
            env,
            tree,
            applied,
            cuts,
            sys_constraints: sys.constraints.clone(),
            coordinate_names: sys
                .coordinate_names()
                .into_iter()
                .map(String::from)
                .collect(),
        })
    }

    /// The tree.
    pub fn tree(&self) -> &TreeModel<f64> {
        &self.tree
    }

    fn eval(&self) -> Evaluator<'_, f64> {
        Evaluator::new(&self.tree, &self.applied, &self.env)
    }

    /// `M(q)` and `b(q, u, t)`.
    pub fn terms(&self, q: &[f64], u: &[f64], t: f64, inputs: &[f64]) -> Result<Terms, MechError> {
        let ev = self.eval();
        let st = State { q, u, t, inputs };
        let k = ev.kinematics(&st)?;
        let (fext, _) = ev.point_forces(&k);
        let (generalized, _) = ev.generalized_forces(&st)?;
        let zero = vec![0.0; self.tree.nu];
        let (c, _) = ev.rnea(&k, &zero, &fext);
        Ok(Terms {
            mass_matrix: ev.crba(&k),
            bias: c.iter().zip(&generalized).map(|(c, g)| c - g).collect(),
        })
    }

    /// Forward dynamics by the articulated-body algorithm: `u̇` with extra
    /// generalised forces `tau` (one per speed).
    pub fn forward_dynamics(
        &self,
        q: &[f64],
        u: &[f64],
        t: f64,
        tau: &[f64],
        inputs: &[f64],
    ) -> Result<Vec<f64>, MechError> {
        let ev = self.eval();
        let st = State { q, u, t, inputs };
        let k = ev.kinematics(&st)?;
        let (fext, _) = ev.point_forces(&k);
        let (generalized, _) = ev.generalized_forces(&st)?;
        let total: Vec<f64> = generalized.iter().zip(tau).map(|(g, t)| g + t).collect();
        Ok(ev.aba(&k, &total, &fext))
    }

    /// Forward dynamics by `M u̇ = τ − b` with the tree-sparse `LᵀDL`.
    pub fn forward_dynamics_ltdl(
        &self,
        q: &[f64],
        u: &[f64],
        t: f64,
        tau: &[f64],
        inputs: &[f64],
    ) -> Result<Vec<f64>, MechError> {
        let mut terms = self.terms(q, u, t, inputs)?;
        let lambda = self.eval().speed_parents();
        ltdl(&mut terms.mass_matrix, &lambda);
        let rhs: Vec<f64> = tau.iter().zip(&terms.bias).map(|(t, b)| t - b).collect();
        Ok(ltdl_solve(&terms.mass_matrix, &lambda, rhs))
    }

    /// Inverse dynamics: the extra generalised forces `τ = M u̇ + b` that
    /// produce the accelerations `ud`.
    pub fn inverse_dynamics(
        &self,
        q: &[f64],
        u: &[f64],
        ud: &[f64],
        t: f64,
        inputs: &[f64],
    ) -> Result<Vec<f64>, MechError> {
        let ev = self.eval();
        let st = State { q, u, t, inputs };
        let k = ev.kinematics(&st)?;
        let (fext, _) = ev.point_forces(&k);
        let (generalized, _) = ev.generalized_forces(&st)?;
        let (tau, _) = ev.rnea(&k, ud, &fext);
        Ok(tau.iter().zip(&generalized).map(|(t, g)| t - g).collect())
    }

    /// Kinetic and potential energy (gravity, point springs, joint springs).
    pub fn energy(&self, q: &[f64], u: &[f64], t: f64) -> Result<(f64, f64), MechError> {
        let ev = self.eval();
        let st = State {
            q,
            u,
            t,
            inputs: &[],
        };
        let k = ev.kinematics(&st)?;
        let (_, springs) = ev.point_forces(&k);
        let (_, joint_springs) = ev.generalized_forces(&st)?;
        Ok((
            ev.kinetic_energy(&k),
            ev.gravity_potential(&k) + springs + joint_springs,
        ))
    }

    /// Angular momentum about the world origin and linear momentum, world axes.
    pub fn momentum(&self, q: &[f64], u: &[f64], t: f64) -> Result<Force<f64>, MechError> {
        let ev = self.eval();
        let k = ev.kinematics(&State {
            q,
            u,
            t,
            inputs: &[],
        })?;
        Ok(ev.momentum(&k))
    }

    /// `q̇ = N(q) u`.
    pub fn qdot(&self, q: &[f64], u: &[f64]) -> Vec<f64> {
        self.eval().qdot(&State {
            q,
            u,
            t: 0.0,
            inputs: &[],
        })
    }

    /// The world pose of every tree body at `q`, `t` (tree order, as
    /// [`Numeric::scene`]): rotation (columns: body axes in world axes)
    /// and origin. What an animation sends per frame.
    pub fn world_poses(&self, q: &[f64], t: f64) -> Result<Vec<WorldPose>, MechError> {
        let u = vec![0.0; self.tree.nu];
        let k = self.eval().kinematics(&State {
            q,
            u: &u,
            t,
            inputs: &[],
        })?;
        Ok(k.world
            .iter()
            .map(|w| WorldPose {
                rotation: w.e.0,
                origin: w.r.0,
            })
            .collect())
    }

    /// What an animation draws of each tree body, in its own coordinates:
    /// its joint frame, the joint frames of its children, its centre of
    /// mass, its joint's axis, its markers and where loop-closing (cut)
    /// joints hold it; and the points of ground that cut joints hold.
    pub fn scene(&self, sys: &System) -> Result<Scene, MechError> {
        use super::joint::JointModel;
        let low = super::lower::Lowering::new(&self.env);
        let mut out = Vec::with_capacity(self.tree.bodies.len());
        for b in &self.tree.bodies {
            let info = &sys.bodies[b.body];
            let axis = match &b.kind {
                JointModel::Revolute(a)
                | JointModel::Prismatic(a)
                | JointModel::Cylindrical(a)
                | JointModel::Screw(a, _) => Some(b.frame_child.e.mul_vec(*a).0),
                _ => None,
            };
            let m = b.inertia.m;
            let com = if m > 0.0 {
                b.inertia.h.scale(1.0 / m).0
            } else {
                b.frame_child.r.0
            };
            let markers = info
                .markers
                .iter()
                .map(|mk| Ok((mk.name.clone(), low.frame(&mk.frame)?.r.0)))
                .collect::<Result<Vec<_>, MechError>>()?;
            out.push(SceneBody {
                name: info.name.clone(),
                joint: sys.joints[b.joint].name.clone(),
                parent: b.parent,
                joint_on_parent: b.frame_parent.r.0,
                joint_on_body: b.frame_child.r.0,
                axis,
                prismatic: matches!(b.kind, JointModel::Prismatic(_)),
                com,
                mass: m,
                markers,
                loop_joints: Vec::new(),
                geometry: info
                    .geometry
                    .iter()
                    .map(|g| placed(&low, g))
                    .collect::<Result<_, _>>()?,
            });
        }
        let mut ground = Vec::new();
        for c in &self.cuts {
            for (side, frame) in [(c.parent, &c.frame_parent), (c.child, &c.frame_child)] {
                match side.and_then(|i| out.get_mut(i)) {
                    Some(b) => b.loop_joints.push(frame.r.0),
                    None => ground.push(frame.r.0),
                }
            }
        }
        let ground_geometry = sys.bodies[0]
            .geometry
            .iter()
            .map(|g| placed(&low, g))
            .collect::<Result<_, _>>()?;
        Ok(Scene {
            bodies: out,
            ground,
            ground_geometry,
        })
    }

    /// The values of the cable mounts at `q`, `t` (the generated
    /// `attachments` without its Jacobians; see [`super::mounts`]).
    pub fn mounts(&self, sys: &System, q: &[f64], t: f64) -> Result<Vec<f64>, MechError> {
        let ev = self.eval();
        let u = vec![0.0; self.tree.nu];
        let k = ev.kinematics(&State {
            q,
            u: &u,
            t,
            inputs: &[],
        })?;
        super::mounts::mount_values(sys, &self.tree, &self.env, &k)
    }

    /// The frames of the bodies cable nodes touch at `(q, u)`, `t`, flat
    /// (the first values of the generated `contact_frames`; see
    /// [`super::mounts::frame_values`]).
    pub fn contact_frames(
        &self,
        sys: &System,
        q: &[f64],
        u: &[f64],
        t: f64,
    ) -> Result<Vec<f64>, MechError> {
        let ev = self.eval();
        let k = ev.kinematics(&State {
            q,
            u,
            t,
            inputs: &[],
        })?;
        super::mounts::frame_values(sys, &self.tree, &self.env, &ev, &k)
    }

    /// The gap `g` and normal speed `ġ` of every contact row at `(q, u)`
    /// (the generated `contacts` without `γ` and `w`; see
    /// [`super::contacts`]).
    pub fn contacts(
        &self,
        sys: &System,
        q: &[f64],
        u: &[f64],
        t: f64,
    ) -> Result<Vec<(f64, f64)>, MechError> {
        let ev = self.eval();
        let k = ev.kinematics(&State {
            q,
            u,
            t,
            inputs: &[],
        })?;
        super::contacts::gaps(sys, &self.tree, &self.env, &ev, &k, q, u)
    }

    /// The unit line of centres of every `Spheres` contact at `q` (`None`
    /// for the other kinds; see [`super::contacts::sphere_normals`]).
    pub fn sphere_normals(
        &self,
        sys: &System,
        q: &[f64],
    ) -> Result<Vec<Option<[f64; 3]>>, MechError> {
        let ev = self.eval();
        let u = vec![0.0; sys.nu()];
        let k = ev.kinematics(&State {
            q,
            u: &u,
            t: 0.0,
            inputs: &[],
        })?;
        Ok(
            super::contacts::sphere_normals(sys, &self.tree, &self.env, &ev, &k)?
                .into_iter()
                .map(|n| n.map(|n| n.0))
                .collect(),
        )
    }

    /// World position and velocity of `point` (body coordinates) on
    /// system body `body`.
    pub fn point(
        &self,
        body: usize,
        point: [f64; 3],
        q: &[f64],
        u: &[f64],
        t: f64,
    ) -> Result<([f64; 3], [f64; 3]), MechError> {
        let ev = self.eval();
        let k = ev.kinematics(&State {
            q,
            u,
            t,
            inputs: &[],
        })?;
        let (x, v) = ev.point(
            &k,
            self.tree.index_of_body.get(body).copied().flatten(),
            crate::sym::Vec3(point),
        );
        Ok((x.0, v.0))
    }

    /// World position and velocity of `point` on system body `body`, at
    /// beam node `node` of a flexible body (node coordinates: the point
    /// moves with the node's translation and small rotation).
    pub fn node_point(
        &self,
        body: usize,
        node: usize,
        point: [f64; 3],
        q: &[f64],
        u: &[f64],
        t: f64,
    ) -> Result<([f64; 3], [f64; 3]), MechError> {
        let ev = self.eval();
        let k = ev.kinematics(&State {
            q,
            u,
            t,
            inputs: &[],
        })?;
        let (x, v) = ev.site(
            &k,
            &super::applied::Site {
                body: self.tree.index_of_body.get(body).copied().flatten(),
                node: Some(node),
                point: crate::sym::Vec3(point),
            },
        );
        Ok((x.0, v.0))
    }

    /// Force and moment that tree joint `joint` transmits to its child, in
    /// the child joint frame at its origin, at accelerations `ud`;
    /// `None` for a joint outside the tree.
    pub fn joint_reaction(
        &self,
        joint: usize,
        q: &[f64],
        u: &[f64],
        ud: &[f64],
        t: f64,
    ) -> Result<Option<Force<f64>>, MechError> {
        let Some(i) = self.tree.bodies.iter().position(|b| b.joint == joint) else {
            return Ok(None);
        };
        let ev = self.eval();
        let k = ev.kinematics(&State {
            q,
            u,
            t,
            inputs: &[],
        })?;
        let (fext, _) = ev.point_forces(&k);
        let f = ev.rnea(&k, ud, &fext).1[i];
        let fc = self.tree.bodies[i].frame_child;
        Ok(Some(Force {
            n: fc.e.tr_mul_vec(f.n - fc.r.cross(f.f)),
            f: fc.e.tr_mul_vec(f.f),
        }))
    }

    /// Force and torque on each cut joint's child (parent-joint-frame
    /// axes) from the multipliers `lambda` of the constraint equations
    /// (the cut joints' rows come first, as `eom-gen` orders them).
    #[allow(clippy::type_complexity)]
    pub fn cut_reactions(
        &self,
        q: &[f64],
        t: f64,
        lambda: &[f64],
    ) -> Result<Vec<(String, [f64; 3], [f64; 3])>, MechError> {
        let zero = vec![0.0; self.tree.nu];
        let k = self.eval().kinematics(&State {
            q,
            u: &zero,
            t,
            inputs: &[],
        })?;
        let mut row = 0;
        let mut out = Vec::new();
        for c in &self.cuts {
            let n = c.equations.len();
            let l: Vec<f64> = (row..row + n)
                .map(|r| lambda.get(r).copied().unwrap_or(f64::NAN))
                .collect();
            row += n;
            let (f, m) = super::constraints::cut_reaction(&self.tree, &k, c, &l);
            out.push((c.name.clone(), f.0, m.0));
        }
        Ok(out)
    }

    /// Closure conditions `Φ(q, t)` of the cut joints.
    pub fn constraints(&self, q: &[f64], t: f64) -> Result<Vec<f64>, MechError> {
        let zero = vec![0.0; self.tree.nu];
        let ev = self.eval();
        let k = ev.kinematics(&State {
            q,
            u: &zero,
            t,
            inputs: &[],
        })?;
        let mut phi = super::constraints::phi(&self.tree, &k, &self.cuts);
        let (holonomic, _) = self.user(q, &zero, t)?;
        phi.extend(holonomic);
        Ok(phi)
    }

    /// The model's own constraints at `(q, u, t)`: holonomic `Φ` and
    /// nonholonomic `A u + b` values.
    fn user(&self, q: &[f64], u: &[f64], t: f64) -> Result<(Vec<f64>, Vec<f64>), MechError> {
        if self.sys_constraints.is_empty() {
            return Ok((Vec::new(), Vec::new()));
        }
        let ev = self.eval();
        let k = ev.kinematics(&State {
            q,
            u,
            t,
            inputs: &[],
        })?;
        let (h, nh) = super::constraints::user_constraints(
            &self.sys_constraints,
            &self.coordinate_names,
            &self.tree,
            &self.env,
            &ev,
            &k,
            q,
            t,
        )?;
        Ok((
            h.into_iter().map(|(_, v)| v).collect(),
            nh.into_iter().map(|(_, v)| v).collect(),
        ))
    }

    /// Nonholonomic constraint values `A(q) u + b(q, t)`.
    pub fn speed_constraints(&self, q: &[f64], u: &[f64], t: f64) -> Result<Vec<f64>, MechError> {
        Ok(self.user(q, u, t)?.1)
    }

    /// `J = ∂Φ̇/∂u`: the holonomic rows by central differences of `Φ` along
    /// `q̇ = N(q) e_k`, then the nonholonomic rows `A`.
    pub fn constraint_jacobian(&self, q: &[f64], t: f64) -> Result<Vec<Vec<f64>>, MechError> {
        let h = 1e-7;
        let nu = self.tree.nu;
        let mut cols = Vec::with_capacity(nu);
        for k in 0..nu {
            let mut e = vec![0.0; nu];
            e[k] = 1.0;
            let qd = self.qdot(q, &e);
            let step = |s: f64| -> Vec<f64> { q.iter().zip(&qd).map(|(q, d)| q + s * d).collect() };
            let (p, m) = (
                self.constraints(&step(h), t)?,
                self.constraints(&step(-h), t)?,
            );
            cols.push(
                p.iter()
                    .zip(&m)
                    .map(|(a, b)| (a - b) / (2.0 * h))
                    .collect::<Vec<f64>>(),
            );
        }
        let rows = cols.first().map_or(0, Vec::len);
        let mut j: Vec<Vec<f64>> = (0..rows)
            .map(|i| cols.iter().map(|c| c[i]).collect())
            .collect();
        // Nonholonomic rows are linear in u: A e_k = (A e_k + b) − b.
        let zero = vec![0.0; nu];
        let b = self.speed_constraints(q, &zero, t)?;
        let mut a = vec![vec![0.0; nu]; b.len()];
        for k in 0..nu {
            let mut e = vec![0.0; nu];
            e[k] = 1.0;
            for (r, v) in self.speed_constraints(q, &e, t)?.iter().enumerate() {
                a[r][k] = v - b[r];
            }
        }
        j.extend(a);
        Ok(j)
    }

    /// Rank of the constraint Jacobian at `q` and the true mobility.
    pub fn mobility(&self, q: &[f64], t: f64) -> Result<Mobility, MechError> {
        let j = self.constraint_jacobian(q, t)?;
        let nu = self.tree.nu;
        let rank = if j.is_empty() || nu == 0 {
            0
        } else {
            let m = nalgebra::DMatrix::from_fn(j.len(), nu, |r, c| j[r][c]);
            let sv = m.svd(false, false).singular_values;
            let largest = sv.iter().copied().fold(0.0, f64::max);
            sv.iter()
                .filter(|&&s| s > 1e-8 * largest.max(1e-300))
                .count()
        };
        Ok(Mobility {
            equations: j.len(),
            rank,
            dof: nu - rank,
        })
    }

    /// `∂Φ/∂t` by central differences (nonzero with prescribed motion).
    fn constraint_rate(&self, q: &[f64], t: f64) -> Result<Vec<f64>, MechError> {
        let h = 1e-6;
        let (p, m) = (self.constraints(q, t + h)?, self.constraints(q, t - h)?);
        let mut rate: Vec<f64> = p.iter().zip(&m).map(|(a, b)| (a - b) / (2.0 * h)).collect();
        rate.extend(self.speed_constraints(q, &vec![0.0; self.tree.nu], t)?);
        Ok(rate)
    }

    /// Assembly (Wittenburg 5.6; Haug 1989 ch. 7) with the reference
    /// algorithms: the runtime's [`eom_sim::constrained::assemble`] on
    /// these `f64` closure conditions.
    pub fn assemble(&self, q0: &[f64], u0: &[f64], t: f64) -> Result<Assembly, MechError> {
        // Surface a mechanics error here rather than as NaN inside.
        self.constraints(q0, t)?;
        Ok(eom_sim::constrained::assemble(self, q0, u0, t))
    }

    /// Normalises the unit quaternions of `q`.
    fn normalize(&self, q: &mut [f64]) {
        for b in &self.tree.bodies {
            if let (super::tree::Coords::Free { q: at, .. }, Some(k)) =
                (&b.coords, b.kind.quaternion_at())
            {
                let a = at + k;
                let n = q[a..a + 4].iter().map(|x| x * x).sum::<f64>().sqrt();
                if n > 0.0 {
                    q[a..a + 4].iter_mut().for_each(|x| *x /= n);
                }
            }
        }
    }
}

/// The reference algorithms as the runtime's assembly sees them: `Φ`,
/// `Φ̇ = J u + Φ_t` and `J` (central differences), no `γ`.
impl eom_sim::constrained::Assemble for Numeric {
    fn speeds(&self) -> usize {
        self.tree.nu
    }
    fn equations(&self) -> usize {
        self.cuts.iter().map(|c| c.equations.len()).sum::<usize>()
            + self
                .user(&vec![0.0; self.tree.nq], &vec![0.0; self.tree.nu], 0.0)
                .map_or(0, |(h, nh)| h.len() + nh.len())
    }
    fn holonomic(&self) -> usize {
        self.constraints(&vec![0.0; self.tree.nq], 0.0)
            .map_or(0, |phi| phi.len())
    }
    fn rates(&self, q: &[f64], u: &[f64], qdot: &mut [f64]) {
        qdot.iter_mut()
            .zip(self.qdot(q, u))
            .for_each(|(d, s)| *d = s);
    }
    fn closure(&self, t: f64, q: &[f64], u: &[f64], c: &mut eom_sim::ConstraintValues) {
        let nan = |n: usize| vec![f64::NAN; n];
        let phi = self.constraints(q, t).unwrap_or_else(|_| nan(c.phi.len()));
        let j = self.constraint_jacobian(q, t).unwrap_or_default();
        let rate = self.constraint_rate(q, t).unwrap_or_else(|_| nan(j.len()));
        for (i, row) in j.iter().enumerate().take(c.jacobian.nrows()) {
            for (k, v) in row.iter().enumerate().take(c.jacobian.ncols()) {
                c.jacobian[(i, k)] = *v;
            }
            let ju: f64 = row.iter().zip(u).map(|(a, b)| a * b).sum();
            c.phidot[i] = ju + rate.get(i).copied().unwrap_or(f64::NAN);
        }
        for (d, s) in c
            .phi
            .iter_mut()
            .zip(phi.iter().chain(std::iter::repeat(&0.0)))
        {
            *d = *s;
        }
    }
    fn unit_quaternions(&self, q: &mut [f64]) {
        self.normalize(q);
    }
}

/// A body's pose in the world (see [`Numeric::world_poses`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WorldPose {
    /// Rotation, rows of the matrix whose columns are the body axes in
    /// world axes.
    pub rotation: [[f64; 3]; 3],
    /// The body origin in world coordinates.
    pub origin: [f64; 3],
}

/// What an animation draws of one tree body (see [`Numeric::scene`]);
/// points and directions in the body's coordinates except
/// `joint_on_parent`, in its parent's (the world's for a body on ground).
#[derive(Clone, Debug, PartialEq)]
pub struct SceneBody {
    /// The body's name.
    pub name: String,
    /// The name of the joint above it.
    pub joint: String,
    /// The parent's tree index (`None`: ground).
    pub parent: Option<usize>,
    /// The joint frame's origin on the parent.
    pub joint_on_parent: [f64; 3],
    /// The joint frame's origin on this body.
    pub joint_on_body: [f64; 3],
    /// The joint's axis (revolute, prismatic, cylindrical, screw).
    pub axis: Option<[f64; 3]>,
    /// True for a prismatic joint (its axis drawn as a slide).
    pub prismatic: bool,
    /// The centre of mass (the joint frame's origin for a massless body).
    pub com: [f64; 3],
    /// The mass.
    pub mass: f64,
    /// The markers: name and position.
    pub markers: Vec<(String, [f64; 3])>,
    /// Where loop-closing (cut) joints hold it.
    pub loop_joints: Vec<[f64; 3]>,
    /// Its shapes, placed on it.
    pub geometry: Vec<PlacedShape>,
}

/// A shape of a body's `geometry` where it sits on the body.
#[derive(Clone, Debug, PartialEq)]
pub struct PlacedShape {
    /// The shape.
    pub shape: crate::system::Shape,
    /// Its frame's origin in body axes.
    pub origin: [f64; 3],
    /// Its frame's axes in body axes (rows).
    pub rotation: [[f64; 3]; 3],
    /// Colour, if given.
    pub color: Option<[f64; 3]>,
}

fn placed(
    low: &super::lower::Lowering<'_, f64>,
    g: &crate::system::GeometryInfo,
) -> Result<PlacedShape, MechError> {
    let pose = low.frame(&g.frame)?;
    Ok(PlacedShape {
        shape: g.shape.clone(),
        origin: pose.r.0,
        rotation: pose.e.0,
        color: g.color,
    })
}

/// What an animation draws (see [`Numeric::scene`]).
#[derive(Clone, Debug, PartialEq)]
pub struct Scene {
    /// The tree bodies, in tree order.
    pub bodies: Vec<SceneBody>,
    /// The points of ground (world coordinates) that cut joints hold.
    pub ground: Vec<[f64; 3]>,
    /// Shapes fixed to the ground (world axes).
    pub ground_geometry: Vec<PlacedShape>,
}
