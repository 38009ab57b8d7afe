// The URDF of the benchmark models as a Pinocchio model, built with
// Pinocchio's API from urdfdom's parse (see the head of peers.cpp for why not
// with libpinocchio_parsers). Shared by peers.cpp and peers_wp.cpp.
#pragma once

#include <pinocchio/multibody.hpp>
#include <urdf_parser/urdf_parser.h>

#include <cstdio>

namespace peers {

inline pinocchio::SE3 se3(urdf::Pose const& p) {
  Eigen::Quaterniond r(p.rotation.w, p.rotation.x, p.rotation.y, p.rotation.z);
  return pinocchio::SE3(r.toRotationMatrix(),
                        Eigen::Vector3d(p.position.x, p.position.y, p.position.z));
}

// Adds the joints below `link` (depth first, children in document order).
inline bool add_subtree(pinocchio::Model& model, urdf::LinkConstSharedPtr const& link,
                        pinocchio::JointIndex parent) {
  for (auto const& joint : link->child_joints) {
    if (joint->type != urdf::Joint::REVOLUTE && joint->type != urdf::Joint::CONTINUOUS) {
      std::fprintf(stderr, "joint %s: only revolute joints are mapped here\n",
                   joint->name.c_str());
      return false;
    }
    Eigen::Vector3d axis(joint->axis.x, joint->axis.y, joint->axis.z);
    pinocchio::SE3 const placement = se3(joint->parent_to_joint_origin_transform);
    pinocchio::JointIndex id;
    if (axis == Eigen::Vector3d::UnitX()) {
      id = model.addJoint(parent, pinocchio::JointModelRX(), placement, joint->name);
    } else if (axis == Eigen::Vector3d::UnitY()) {
      id = model.addJoint(parent, pinocchio::JointModelRY(), placement, joint->name);
    } else if (axis == Eigen::Vector3d::UnitZ()) {
      id = model.addJoint(parent, pinocchio::JointModelRZ(), placement, joint->name);
    } else {
      id = model.addJoint(parent, pinocchio::JointModelRevoluteUnaligned(axis.normalized()),
                          placement, joint->name);
    }
    urdf::LinkConstSharedPtr child;
    for (auto const& c : link->child_links) {
      if (c->name == joint->child_link_name) child = c;
    }
    if (!child) return false;
    if (auto const& in = child->inertial) {
      pinocchio::SE3 const frame = se3(in->origin);
      Eigen::Matrix3d inertia;
      inertia << in->ixx, in->ixy, in->ixz, in->ixy, in->iyy, in->iyz, in->ixz, in->iyz, in->izz;
      Eigen::Matrix3d const r = frame.rotation();
      model.appendBodyToJoint(
          id, pinocchio::Inertia(in->mass, frame.translation(), r * inertia * r.transpose()),
          pinocchio::SE3::Identity());
    }
    if (!add_subtree(model, child, id)) return false;
  }
  return true;
}

// The whole URDF file; false (with a message) if it cannot be mapped.
inline bool load_urdf(char const* path, pinocchio::Model& model) {
  urdf::ModelInterfaceSharedPtr robot = urdf::parseURDFFile(path);
  if (!robot || !add_subtree(model, robot->getRoot(), 0)) {
    std::fprintf(stderr, "cannot map %s into a Pinocchio model\n", path);
    return false;
  }
  return true;
}

}  // namespace peers
