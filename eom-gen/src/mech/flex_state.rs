//! A flexible body at one state (Shabana ch. 5): the deformed inertia,
//! the momentum columns of the elastic rates and the velocity terms that
//! [`FlexModel::state`](super::flexible::FlexModel::state) computes and
//! the geometric stiffening adds to; and a node's frame at one state.

use super::spatial::{Force, Motion, Pose, RigidInertia};

/// A node at one state, as the child of a joint from the body frame whose
/// speeds are `q̇_f`.
#[derive(Clone, Debug)]
pub struct NodeState<S> {
    /// The node frame in body coordinates.
    pub pose: Pose<S>,
    /// Motion subspace: the node frame's motion relative to the body frame
    /// per unit `q̇_f,k` (node coordinates).
    pub columns: Vec<Motion<S>>,
    /// Its velocity relative to the body frame, `Σ columns q̇_f`.
    pub velocity: Motion<S>,
    /// `c = (d/dt columns) q̇_f`, the derivative of the columns' node
    /// coordinates along the motion (Featherstone's `S̊ q̇`).
    pub bias: Motion<S>,
}

/// A flexible body at one state.
#[derive(Clone, Debug)]
pub struct FlexState<S> {
    /// `q_f`.
    pub q: Vec<S>,
    /// `q̇_f`.
    pub qd: Vec<S>,
    /// The deformed body's inertia about the frame origin (without the
    /// rigid part the body may carry).
    pub inertia: RigidInertia<S>,
    /// `P`: the spatial momentum of each unit `q̇_f` (body coordinates).
    pub coupling: Vec<Force<S>>,
    /// `b`: velocity terms of the frame's force beyond `v ×* I v`.
    pub bias: Force<S>,
    /// `b_f`: velocity (and stiffening) terms of the elastic equations.
    pub elastic_bias: Vec<S>,
}
