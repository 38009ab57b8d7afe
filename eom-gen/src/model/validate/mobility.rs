//! The Grübler–Kutzbach count of a system's mobility, planar or spatial.

use crate::mech::initial::Pose;
use crate::system::{ConstraintKind, Grubler, JointType, Motion, System};
use nalgebra::{Matrix3, Vector3};

/// Grübler–Kutzbach count, planar (λ = 3) if every joint keeps the motion
/// in planes normal to one direction, else spatial (λ = 6).
pub(crate) fn grubler(sys: &System, poses: &[Pose<f64>]) -> Grubler {
    let planar_normal = planar_normal(sys, poses);
    let lambda: i64 = if planar_normal.is_some() { 3 } else { 6 };
    let n = (sys.bodies.len() - 1) as i64;
    let mut dof = lambda * n;
    for j in &sys.joints {
        let f = match (&j.motion, planar_normal.is_some()) {
            (Motion::Locked | Motion::Prescribed(_), _) => 0,
            (_, true) => match j.kind {
                JointType::Planar => 3,
                JointType::Fixed => 0,
                _ => 1,
            },
            (_, false) => j.kind.nu() as i64,
        };
        dof -= lambda - f;
    }
    for c in &sys.constraints {
        dof -= c.equations().0 as i64;
    }
    // Every elastic coordinate of a flexible body is a freedom of its own.
    let elastic: i64 = sys
        .bodies
        .iter()
        .filter_map(|b| b.flexible.as_deref())
        .map(|f| f.count() as i64)
        .sum();
    Grubler {
        dof: dof + elastic,
        elastic,
        planar: planar_normal.is_some(),
    }
}

/// The common normal of a planar system, if it is one.
fn planar_normal(sys: &System, poses: &[Pose<f64>]) -> Option<Vector3<f64>> {
    if sys
        .constraints
        .iter()
        .any(|c| matches!(c.kind, ConstraintKind::RollingDisk { .. }))
    {
        return None;
    }
    let mut normal: Option<Vector3<f64>> = None;
    let mut in_plane: Vec<Vector3<f64>> = Vec::new();
    for j in &sys.joints {
        let frame = Matrix3::from(poses[j.parent].e) * j.parent_frame.matrix;
        let n = match &j.kind {
            JointType::Revolute(a) => frame * a.unit,
            JointType::Planar => frame * Vector3::z(),
            JointType::Prismatic(a) => {
                in_plane.push(frame * a.unit);
                continue;
            }
            JointType::Fixed => continue,
            _ => return None,
        };
        match normal {
            None => normal = Some(n),
            Some(m) if m.cross(&n).norm() < 1e-9 => {}
            Some(_) => return None,
        }
    }
    let n = normal?;
    in_plane.iter().all(|a| a.dot(&n).abs() < 1e-9).then_some(n)
}
