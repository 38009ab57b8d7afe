//! Flexible bodies inside the recursive algorithms (floating frame of
//! reference; Shabana 5.2–5.5), over any [`Scalar`].
//!
//! A flexible body's frame moves through its joint like a rigid body; its
//! elastic coordinates `q_f` (`k` of them, rates `q̇_f`) are speeds of their
//! own. In the body's coordinates, with the frame's spatial velocity
//! `v = (ω, v_O)` and acceleration `a` (Featherstone's, so `a` is the
//! derivative of the body-coordinate components of `v`), the body's
//! equations are those of [`crate::flex::ffr`] with `Ṙ = A v_O`,
//! `R̈ = A (v̇_O + ω × v_O)`:
//!
//! ```text
//! f   = I(q_f) a + v ×* I(q_f) v + b(q_f, ω, q̇_f) + P(q_f) q̈_f − f_ext
//! τ_f = P(q_f)ᵀ a + M_ff q̈_f + b_f(q_f, ω, v_O, q̇_f) + K_ff q_f + D_ff q̇_f
//! ```
//!
//! - `I(q_f)`: a rigid inertia with the deformed body's mass `m`, first
//!   moment `h = I₁ + S̄ q_f` and inertia tensor `Ī_θθ(q_f)` about the origin;
//! - `P(q_f)`: `k` spatial forces, the momentum of unit `q̇_f`, moment
//!   `Ī_θf(q_f)` and force `S̄`;
//! - `b`: the velocity terms `v ×* I v` does not hold, force
//!   `2 ω × S̄ q̇_f`, moment `2 (tr C_v 1 − C_vᵀ) ω + ω × (c_p · q̇_f, c_r q̇_f)`
//!   with `C_v = ∫ρ ū (S q̇_f)ᵀ dV` (`c_r`: the sections' rotary inertia of
//!   a Timoshenko beam, [`crate::flex::invariants`]);
//! - `b_f = S̄ᵀ (ω × v_O) + ∫ρ Sᵀ ω̃ω̃ ū dV + 2 ∫ρ Sᵀ ω̃ S dV q̇_f`.
//!
//! With `stiffening`, the beam's foreshortening adds to `I`, `P`, `b` and
//! `b_f` ([`super::stiffening`]): the geometric stiffness of the axial
//! inertia load (centrifugal, axial acceleration, gravity; Kane, Ryan and
//! Banerjee 1987), symmetric and energy-consistent.
//!
//! Gravity enters through the base acceleration as for rigid bodies
//! (`P ᵀ a` holds `−S̄ᵀ g`, `I a` the deformed first moment). The elastic
//! force `−K_ff q_f − D_ff q̇_f` is a generalised force
//! ([`super::kinematics::Evaluator::generalized_forces`]), with potential
//! `½ q_fᵀ K_ff q_f`.
//!
//! Bodies, joints and markers attach either to the frame or to a node
//! ([`NodeShape`], [`NodeState`]). A node's frame sits at `ū₀ + S_n q_f`
//! in body coordinates, turned by the small rotation `θ = Φ_n q_f`
//! (`R = R_z(θ_z) R_y(θ_y) R_x(θ_x)`, equal to `1 + θ̃` to first order and
//! orthonormal at any size, so kinematics and energy stay exact for the
//! linear FFR body). Relative to the body frame it moves like the child of a
//! joint whose speeds are `q̇_f`: column `k` of its motion subspace is the
//! node's rotation and translation per unit `q̇_f,k` (node coordinates),
//! `q_f`-dependent through `R`. A body hung at a node therefore carries
//! these columns besides its own joint's, with the flexible body's elastic
//! speeds: RNEA and CRBA handle them as extra joint columns, and the
//! articulated-body algorithm eliminates `q̈_f` at the flexible body
//! together with the articulated subtrees hung at its nodes (see
//! [`super::kinematics::Evaluator::aba`]). Bodies on the frame ride it; `q̈_f`
//! couples to them only through the frame's acceleration.

use super::error::MechError;
use super::flex_state::{FlexState, NodeState};
use super::flex_tunable::{EA, EI_Y, EI_Z, GJ, RHO_A, RHO_IP, SectionScales};
use super::lower::Lowering;
use super::spatial::{Force, Motion, Pose, RigidInertia};
use super::stiffening::Stiffening;
use crate::sym::{Axis, Mat3, Scalar, Vec3};
use crate::system::FlexInfo;
use std::ops::Add;

/// The constants of a flexible body: its inertia shape integrals and modal
/// matrices, inlined (entries below `1e-13` of their block's largest are
/// exact zeros, so the symbolic terms drop them).
#[derive(Clone, Debug)]
pub struct FlexModel<S> {
    /// First index of `q_f` in `q`.
    pub q: usize,
    /// First index of `q̇_f` in `u`.
    pub u: usize,
    /// `m`.
    pub mass: S,
    /// `I₁`.
    pub first_moment: Vec3<S>,
    /// `Ī` of the undeformed body (with the sections' spin inertia).
    pub inertia: Mat3<S>,
    /// Columns of `S̄` (k).
    pub s_bar: Vec<Vec3<S>>,
    /// `S̄_ij` (k×k), indexed `[i][j]`.
    pub s_ij: [[Vec<Vec<S>>; 3]; 3],
    /// `X_ij` (k), indexed `[i][j]`.
    pub x_s: [[Vec<S>; 3]; 3],
    /// `c_p` (k).
    pub spin: Vec<S>,
    /// `c_r`: the rotary inertia of a Timoshenko beam's sections about `y`
    /// and `z` per unit `q̇_f` (2 × k; zeros otherwise).
    pub rotary: [Vec<S>; 2],
    /// `M_ff`.
    pub modal_mass: Vec<Vec<S>>,
    /// `K_ff`.
    pub stiffness: Vec<Vec<S>>,
    /// `D_ff = 2 ζ diag(ω_i)`.
    pub damping: Vec<Vec<S>>,
    /// The foreshortening matrices, if stiffening.
    pub stiffening: Option<Stiffening<S>>,
    /// The nodes something attaches to, in ascending node order.
    pub nodes: Vec<NodeShape<S>>,
    /// The section stiffnesses `EA`, `EI_y`, `EI_z`, `GJ` (runtime fields
    /// where tunable), for the section forces.
    pub section: [S; 4],
}

/// The shapes of one node of a flexible body (body axes).
#[derive(Clone, Debug)]
pub struct NodeShape<S> {
    /// The beam node's index.
    pub node: usize,
    /// `ū₀`: its undeformed place.
    pub place: Vec3<S>,
    /// `S_n`: its translation per unit `q_f,k` (`k` columns).
    pub translation: Vec<Vec3<S>>,
    /// `Φ_n`: its small rotation per unit `q_f,k` (`k` columns).
    pub rotation: Vec<Vec3<S>>,
}

fn clean_block(values: &[f64]) -> impl Fn(f64) -> f64 {
    let top = values.iter().fold(0.0_f64, |a, b| a.max(b.abs()));
    move |x| if x.abs() <= 1e-13 * top { 0.0 } else { x }
}

/// `m` cleaned by `c`, each entry through `to` (inlined or scaled by a
/// tunable datum).
fn scaled_matrix<S: Scalar>(
    m: &nalgebra::DMatrix<f64>,
    c: &dyn Fn(f64) -> f64,
    to: &dyn Fn(f64) -> S,
) -> Vec<Vec<S>> {
    (0..m.nrows())
        .map(|r| (0..m.ncols()).map(|j| to(c(m[(r, j)]))).collect())
        .collect()
}

/// `D_ff` with tunable section data: for the beam's normal modes (pure per
/// deformation, so `M_ff` and `K_ff` stay diagonal at any values) the
/// modal damping `D_ii = 2 ζ √(K_ii M_ii)` (`2 ζ ω_i` per unit modal mass);
/// refused for other bases, whose normal modes change with the data.
fn tunable_damping<S: Scalar>(
    flex: &FlexInfo,
    body: &str,
    zeta: S,
    mass: &[Vec<S>],
    stiffness: &[Vec<S>],
) -> Result<Vec<Vec<S>>, MechError> {
    let diagonal = |m: &[Vec<S>]| {
        m.iter()
            .enumerate()
            .all(|(r, row)| row.iter().enumerate().all(|(c, x)| r == c || x.is_zero()))
    };
    let normal = matches!(flex.source, crate::system::FlexSource::Beam)
        && flex.modes.basis == crate::flex::Basis::Normal;
    if !normal || !diagonal(mass) || !diagonal(stiffness) {
        return Err(MechError::TunableFlex {
            body: body.to_string(),
            field: "damping",
            why: "modal damping needs the reduced body's normal modes, which change with the data unless the basis is the beam's own normal modes (not Craig–Bampton or assumed modes)",
            span: flex.damping.span,
        });
    }
    let two = S::from_f64(2.0);
    Ok((0..mass.len())
        .map(|r| {
            (0..mass.len())
                .map(|c| {
                    if r == c {
                        two * zeta * (stiffness[r][r] * mass[r][r]).sqrt()
                    } else {
                        S::zero()
                    }
                })
                .collect()
        })
        .collect())
}

/// `Σ a_i b_i`, skipping exact zeros.
fn dot<S: Scalar>(a: &[S], b: &[S]) -> S {
    a.iter()
        .zip(b)
        .filter(|(x, y)| !x.is_zero() && !y.is_zero())
        .fold(S::zero(), |acc, (&x, &y)| acc + x * y)
}

fn mat_vec<S: Scalar>(m: &[Vec<S>], x: &[S]) -> Vec<S> {
    m.iter().map(|row| dot(row, x)).collect()
}

fn axpy<S: Scalar>(out: &mut [S], k: S, x: &[S]) {
    if k.is_zero() {
        return;
    }
    for (o, &v) in out.iter_mut().zip(x) {
        if !v.is_zero() {
            *o = *o + k * v;
        }
    }
}

impl<S: Scalar> FlexModel<S> {
    /// The constants of `flex` on body `body` (its damping ratio and its
    /// section data may be tunable, [`super::flex_tunable`]), with the
    /// shapes of the nodes `attached` (ascending beam node indices).
    pub fn new(
        flex: &FlexInfo,
        body: &str,
        attached: &[usize],
        low: &Lowering<'_, S>,
    ) -> Result<Self, MechError> {
        let sc = SectionScales::new(flex, body, low)?;
        let inv = &flex.invariants;
        let k = flex.count();
        let a = |v: f64| sc.scale(RHO_A, v);
        let cs = clean_block(inv.s_bar.as_slice());
        let s_bar = (0..k)
            .map(|j| Vec3(std::array::from_fn(|r| a(cs(inv.s_bar[(r, j)])))))
            .collect();
        // One scale for the nine blocks: a block that is round-off
        // throughout (e.g. `S̄_xx` of bending modes, which do not move
        // axially) must vanish, not be kept relative to its own noise.
        let all_s: Vec<f64> = inv
            .s_ij
            .iter()
            .flatten()
            .flat_map(|m| m.iter().copied())
            .collect();
        let cs_ij = clean_block(&all_s);
        let s_ij = std::array::from_fn(|i| {
            std::array::from_fn(|j| scaled_matrix(&inv.s_ij[i][j], &cs_ij, &a))
        });
        let all_x: Vec<f64> = inv
            .x_s
            .iter()
            .flatten()
            .flat_map(|v| v.iter().copied())
            .collect();
        let cx = clean_block(&all_x);
        let x_s = std::array::from_fn(|i| {
            std::array::from_fn(|j| inv.x_s[i][j].iter().map(|&x| a(cx(x))).collect())
        });
        // `c_p` joins `Ī_θf`'s torsion row: the same scale as `X`, so that
        // without torsion modes it vanishes instead of keeping round-off.
        let x_and_spin: Vec<f64> = all_x
            .iter()
            .chain(inv.spin_modes.iter())
            .chain(inv.rotary_modes.iter())
            .copied()
            .collect();
        let cp = clean_block(&x_and_spin);
        let spin = inv
            .spin_modes
            .iter()
            .map(|&x| sc.scale(RHO_IP, cp(x)))
            .collect();
        // M_ff = Σ_i S̄_ii (ρA) + M_p (ρI_p); K_ff = Σ shares of EA, EI_y, EI_z, GJ.
        let none = nalgebra::DMatrix::zeros(k, k);
        let shares = flex.shares.as_ref();
        let spin_mass = shares.map_or(&none, |s| &s.spin_mass);
        let translational = &inv.s_ij[0][0] + &inv.s_ij[1][1] + &inv.s_ij[2][2];
        let cm = clean_block(inv.modal_mass.as_slice());
        let modal_mass: Vec<Vec<S>> = (0..k)
            .map(|r| {
                (0..k)
                    .map(|c| {
                        sc.entry(
                            inv.modal_mass[(r, c)],
                            &[(RHO_A, translational[(r, c)]), (RHO_IP, spin_mass[(r, c)])],
                            &cm,
                        )
                    })
                    .collect()
            })
            .collect();
        let ck = clean_block(inv.modal_stiffness.as_slice());
        let stiffness: Vec<Vec<S>> = (0..k)
            .map(|r| {
                (0..k)
                    .map(|c| {
                        let parts: Vec<(usize, f64)> = shares.map_or(Vec::new(), |s| {
                            [EA, EI_Y, EI_Z, GJ]
                                .iter()
                                .zip(&s.stiffness)
                                .map(|(&d, m)| (d, m[(r, c)]))
                                .collect()
                        });
                        sc.entry(inv.modal_stiffness[(r, c)], &parts, &ck)
                    })
                    .collect()
            })
            .collect();
        let zeta = low.quantity(&flex.damping)?;
        let damping = if sc.any() && !zeta.is_zero() {
            tunable_damping(flex, body, zeta, &modal_mass, &stiffness)?
        } else if let Some((unit, fixed)) = flex.damping_matrices() {
            // Assumed modes, imported data: D_ff = ζ D_1 + D_0 in the written coordinates.
            let cu = clean_block(unit.as_slice());
            let c0 = fixed.map(|d| clean_block(d.as_slice()));
            (0..k)
                .map(|r| {
                    (0..k)
                        .map(|c| {
                            let mut d = S::zero();
                            let u = cu(unit[(r, c)]);
                            if u != 0.0 && !zeta.is_zero() {
                                d = S::from_f64(u) * zeta;
                            }
                            if let (Some(fixed), Some(c0)) = (fixed, &c0) {
                                let v = c0(fixed[(r, c)]);
                                if v != 0.0 {
                                    d = d + S::from_f64(v);
                                }
                            }
                            d
                        })
                        .collect()
                })
                .collect()
        } else {
            (0..k)
                .map(|r| {
                    (0..k)
                        .map(|c| {
                            if r == c && !zeta.is_zero() {
                                S::from_f64(2.0 * flex.modes.frequencies[r]) * zeta
                            } else {
                                S::zero()
                            }
                        })
                        .collect()
                })
                .collect()
        };
        let stiffening = flex.stiffening.then(|| Stiffening::new(flex, &a));
        let nodes = attached
            .iter()
            .map(|&n| {
                let at = flex.modes.at_node(n);
                // Translations and rotations are cleaned against their own kind.
                let rows = |r0: usize| -> Vec<f64> {
                    (r0..r0 + 3)
                        .flat_map(|r| (0..k).map(move |j| (r, j)))
                        .map(|(r, j)| at[(r, j)])
                        .collect()
                };
                let (tr, rot) = (rows(0), rows(3));
                let (c_t, c_r) = (clean_block(&tr), clean_block(&rot));
                let col = |j: usize, off: usize, c: &dyn Fn(f64) -> f64| {
                    Vec3(std::array::from_fn(|r| S::from_f64(c(at[(off + r, j)]))))
                };
                NodeShape {
                    node: n,
                    place: Vec3::from_f64(flex.node_place(n)),
                    translation: (0..k).map(|j| col(j, 0, &c_t)).collect(),
                    rotation: (0..k).map(|j| col(j, 3, &c_r)).collect(),
                }
            })
            .collect();
        // Ī = tr(J₀) 1 − J₀ (ρA) + J_p e_x e_xᵀ (ρI_p).
        let ci = clean_block(inv.inertia.as_slice());
        let rigid = crate::flex::invariants::inertia_from(&inv.second_moment);
        let c1 = clean_block(inv.first_moment.as_slice());
        Ok(FlexModel {
            q: flex.q_index,
            u: flex.u_index,
            mass: a(inv.mass),
            first_moment: Vec3(std::array::from_fn(|r| a(c1(inv.first_moment[r])))),
            inertia: Mat3(std::array::from_fn(|r| {
                std::array::from_fn(|c| {
                    let spin = if (r, c) == (0, 0) {
                        inv.spin_inertia
                    } else {
                        0.0
                    };
                    sc.entry(
                        inv.inertia[(r, c)],
                        &[(RHO_A, rigid[(r, c)]), (RHO_IP, spin)],
                        &ci,
                    )
                })
            })),
            s_bar,
            s_ij,
            x_s,
            spin,
            rotary: std::array::from_fn(|r| {
                inv.rotary_modes
                    .row(r)
                    .iter()
                    .map(|&x| sc.scale(RHO_A, cp(x)))
                    .collect()
            }),
            modal_mass,
            stiffness,
            damping,
            stiffening,
            nodes,
            section: [
                sc.values[EA],
                sc.values[EI_Y],
                sc.values[EI_Z],
                sc.values[GJ],
            ],
        })
    }

    /// The slot in [`Self::nodes`] of beam node `node`.
    pub fn node_slot(&self, node: usize) -> Option<usize> {
        self.nodes.iter().position(|n| n.node == node)
    }

    /// Node `slot` at elastic coordinates `q`, rates `qd`: its frame, the
    /// columns of its motion relative to the body frame, that motion and
    /// its bias. With `R = R_z R_y R_x` the node's angular velocity in its
    /// own axes is `w₁ + w₂ + w₃`, `w₁ = e_x θ̇_x`, `w₂ = R_xᵀ e_y θ̇_y`,
    /// `w₃ = R_xᵀ R_yᵀ e_z θ̇_z`, whose derivative at fixed `θ̇` is
    /// `−w₁ × w₂ − (w₁ + w₂) × w₃`; the translation rate `Rᵀ ḋ` has
    /// derivative `−ω × Rᵀ ḋ`.
    pub fn node_state(&self, slot: usize, q: &[S], qd: &[S]) -> NodeState<S> {
        let shape = &self.nodes[slot];
        let combine = |cols: &[Vec3<S>], x: &[S]| {
            let mut out = Vec3::zero();
            for (c, &xj) in cols.iter().zip(x) {
                for r in 0..3 {
                    if !c.0[r].is_zero() && !xj.is_zero() {
                        out.0[r] = out.0[r] + c.0[r] * xj;
                    }
                }
            }
            out
        };
        let theta = combine(&shape.rotation, q);
        let rot = |axis: Axis, angle: S| {
            if angle.is_zero() {
                Mat3::identity()
            } else {
                Mat3::rot(axis, angle)
            }
        };
        let (rx, ry, rz) = (
            rot(Axis::X, theta.0[0]),
            rot(Axis::Y, theta.0[1]),
            rot(Axis::Z, theta.0[2]),
        );
        let e = rz * ry * rx;
        let pose = Pose {
            e,
            r: shape.place + combine(&shape.translation, q),
        };
        // Node-axes images of the rotation axes: e_x, R_xᵀ e_y, R_xᵀ R_yᵀ e_z.
        let ax = Vec3::unit(Axis::X);
        let ay = rx.tr_mul_vec(Vec3::unit(Axis::Y));
        let az = rx.tr_mul_vec(ry.tr_mul_vec(Vec3::unit(Axis::Z)));
        let angular = |r: Vec3<S>| -> Vec3<S> {
            let mut w = Vec3::zero();
            for (axis, c) in [(ax, r.0[0]), (ay, r.0[1]), (az, r.0[2])] {
                if !c.is_zero() {
                    w = w + axis.scale(c);
                }
            }
            w
        };
        let columns: Vec<Motion<S>> = shape
            .rotation
            .iter()
            .zip(&shape.translation)
            .map(|(r, t)| Motion {
                w: angular(*r),
                v: e.tr_mul_vec(*t),
            })
            .collect();
        let rate = combine(&shape.rotation, qd);
        let w1 = ax.scale(rate.0[0]);
        let w2 = ay.scale(rate.0[1]);
        let w3 = az.scale(rate.0[2]);
        let velocity = Motion {
            w: w1 + w2 + w3,
            v: e.tr_mul_vec(combine(&shape.translation, qd)),
        };
        let bias = Motion {
            w: -(w1.cross(w2)) - (w1 + w2).cross(w3),
            v: -(velocity.w.cross(velocity.v)),
        };
        NodeState {
            pose,
            columns,
            velocity,
            bias,
        }
    }

    /// Number of elastic coordinates.
    pub fn count(&self) -> usize {
        self.s_bar.len()
    }

    /// `S̄ x` for `x` in mode space.
    fn s_bar_times(&self, x: &[S]) -> Vec3<S> {
        let mut out = Vec3::zero();
        for (col, &xj) in self.s_bar.iter().zip(x) {
            for r in 0..3 {
                if !col.0[r].is_zero() {
                    out.0[r] = out.0[r] + col.0[r] * xj;
                }
            }
        }
        out
    }

    /// The body at elastic coordinates `q`, rates `qd`, frame velocity `v`
    /// (body coordinates).
    pub fn state(&self, q: &[S], qd: &[S], v: Motion<S>) -> FlexState<S> {
        let k = self.count();
        let w = v.w;
        // S̄_ab q and S̄_ab q̇ (k each).
        let sq: [[Vec<S>; 3]; 3] =
            std::array::from_fn(|a| std::array::from_fn(|b| mat_vec(&self.s_ij[a][b], q)));
        let sqd: [[Vec<S>; 3]; 3] =
            std::array::from_fn(|a| std::array::from_fn(|b| mat_vec(&self.s_ij[a][b], qd)));
        // ∫ρūūᵀ = J₀ + ΔJ, ΔJ_ab = (X_ab + X_ba)·q + qᵀ S̄_ab q;  Ī = tr(J) 1 − J (+ spin).
        let dj = Mat3(std::array::from_fn(|a| {
            std::array::from_fn(|b| {
                dot(&self.x_s[a][b], q) + dot(&self.x_s[b][a], q) + dot(q, &sq[a][b])
            })
        }));
        let inertia_q = self.inertia + Mat3::identity().scale(dj.trace()) - dj;
        let h = self.first_moment + self.s_bar_times(q);
        // Ī_θf column j: ∫ρ ũ S_j dV + (c_p,j, c_r,j) with ∫ρ ū_b S_c = X_bc + S̄_cb q.
        let us = |b: usize, c: usize, j: usize| self.x_s[b][c][j] + sq[c][b][j];
        let plus = |a: S, b: S| if b.is_zero() { a } else { a + b };
        let coupling = (0..k)
            .map(|j| Force {
                n: Vec3::new(
                    us(1, 2, j) - us(2, 1, j) + self.spin[j],
                    plus(us(2, 0, j) - us(0, 2, j), self.rotary[0][j]),
                    plus(us(0, 1, j) - us(1, 0, j), self.rotary[1][j]),
                ),
                f: self.s_bar[j],
            })
            .collect();
        // C_v = ∫ρ ū (S q̇)ᵀ dV: (C_v)_ab = X_ab · q̇ + qᵀ S̄_ab q̇.
        let cv = Mat3(std::array::from_fn(|a| {
            std::array::from_fn(|b| dot(&self.x_s[a][b], qd) + dot(q, &sqd[a][b]))
        }));
        let two = S::from_f64(2.0);
        let sqdot = self.s_bar_times(qd);
        let spin_rate = dot(&self.spin, qd);
        let bias = Force {
            n: (Mat3::identity().scale(cv.trace()) - cv.transpose())
                .mul_vec(w)
                .scale(two)
                + w.cross(Vec3::new(
                    spin_rate,
                    dot(&self.rotary[0], qd),
                    dot(&self.rotary[1], qd),
                )),
            f: w.cross(sqdot).scale(two),
        };
        // b_f = S̄ᵀ(ω × v) + Σ_ab W_ab (X_ba + S̄_ab q) + 2 Σ_ab ω̃_ab S̄_ab q̇,  W = ω̃ω̃.
        let wv = w.cross(v.v);
        let ww = w.skew() * w.skew();
        let wt = w.skew();
        let mut elastic_bias: Vec<S> = self.s_bar.iter().map(|c| c.dot(wv)).collect();
        for a in 0..3 {
            for b in 0..3 {
                let wab = ww.0[a][b];
                axpy(&mut elastic_bias, wab, &self.x_s[b][a]);
                axpy(&mut elastic_bias, wab, &sq[a][b]);
                axpy(&mut elastic_bias, two * wt.0[a][b], &sqd[a][b]);
            }
        }
        let mut st = FlexState {
            q: q.to_vec(),
            qd: qd.to_vec(),
            inertia: RigidInertia {
                m: self.mass,
                h,
                i: inertia_q,
            },
            coupling,
            bias,
            elastic_bias,
        };
        if let Some(s) = &self.stiffening {
            s.apply(q, qd, v, &mut st);
        }
        st
    }

    /// `M_ff x`.
    pub fn modal_mass_times(&self, x: &[S]) -> Vec<S> {
        mat_vec(&self.modal_mass, x)
    }

    /// The elastic forces `−K_ff q_f − D_ff q̇_f` and the strain energy `½ q_fᵀ K_ff q_f`.
    pub fn elastic_forces(&self, q: &[S], qd: &[S]) -> (Vec<S>, S) {
        let kq = mat_vec(&self.stiffness, q);
        let dq = mat_vec(&self.damping, qd);
        let energy = S::from_f64(0.5) * dot(q, &kq);
        (kq.iter().zip(&dq).map(|(&a, &b)| -a - b).collect(), energy)
    }

    /// `½ q̇ᵀ M_ff q̇ + vᵀ P q̇`: the kinetic energy of the deformation rate.
    pub fn elastic_kinetic(&self, st: &FlexState<S>, v: Motion<S>) -> S {
        let mqd = self.modal_mass_times(&st.qd);
        let pqd = st
            .coupling
            .iter()
            .zip(&st.qd)
            .fold(Force::zero(), |acc, (p, &x)| acc.add(p.scale(x)));
        S::from_f64(0.5) * dot(&st.qd, &mqd) + v.dot(pqd)
    }

    /// `P q̇`: the momentum of the deformation rate (body coordinates).
    pub fn elastic_momentum(&self, st: &FlexState<S>) -> Force<S> {
        st.coupling
            .iter()
            .zip(&st.qd)
            .fold(Force::zero(), |acc, (p, &x)| acc.add(p.scale(x)))
    }
}
