// The URDF of the benchmark models as a Pinocchio model, built with
// Pinocchio's API from urdfdom's parse (see the head of peers.cpp for why not
// with libpinocchio_parsers). Shared by peers.cpp and peers_wp.cpp.
#pragma once

#include <pinocchio/multibody.hpp>
#include <urdf_parser/urdf_parser.h>

#include <cstdio>
#include <string>

namespace peers {

inline pinocchio::SE3 se3(urdf::Pose const& p) {
  Eigen::Quaterniond r(p.rotation.w, p.rotation.x, p.rotation.y, p.rotation.z);
  return pinocchio::SE3(r.toRotationMatrix(),
                        Eigen::Vector3d(p.position.x, p.position.y, p.position.z));
}

// The inertia of a link about its frame's origin, in its axes (rotated from
// the inertial frame); zero for a link without <inertial>.
inline pinocchio::Inertia inertia_of(urdf::Link const& link) {
  auto const& in = link.inertial;
  if (!in) return pinocchio::Inertia::Zero();
  pinocchio::SE3 const frame = se3(in->origin);
  Eigen::Matrix3d inertia;
  inertia << in->ixx, in->ixy, in->ixz, in->ixy, in->iyy, in->iyz, in->ixz, in->iyz, in->izz;
  Eigen::Matrix3d const r = frame.rotation();
  return pinocchio::Inertia(in->mass, frame.translation(), r * inertia * r.transpose());
}

// Adds the joints below `link` (depth first, children in document order),
// `at` the placement of `link` in the frame of joint `parent`: revolute
// (and continuous) about x, y or z -> JointModelRX/RY/RZ, else
// RevoluteUnaligned; prismatic likewise (PX/PY/PZ, PrismaticUnaligned); a
// fixed joint's child is appended to the parent joint at its placement, as
// Pinocchio's parser merges it (the robots of example-robot-data, panda).
inline bool add_subtree(pinocchio::Model& model, urdf::LinkConstSharedPtr const& link,
                        pinocchio::JointIndex parent, pinocchio::SE3 const& at) {
  for (auto const& joint : link->child_joints) {
    urdf::LinkConstSharedPtr child;
    for (auto const& c : link->child_links) {
      if (c->name == joint->child_link_name) child = c;
    }
    if (!child) return false;
    pinocchio::SE3 const placement = at * se3(joint->parent_to_joint_origin_transform);
    if (joint->type == urdf::Joint::FIXED) {
      model.appendBodyToJoint(parent, inertia_of(*child), placement);
      if (!add_subtree(model, child, parent, placement)) return false;
      continue;
    }
    bool const revolute =
        joint->type == urdf::Joint::REVOLUTE || joint->type == urdf::Joint::CONTINUOUS;
    if (!revolute && joint->type != urdf::Joint::PRISMATIC) {
      std::fprintf(stderr, "joint %s: only revolute, prismatic and fixed joints are mapped here\n",
                   joint->name.c_str());
      return false;
    }
    Eigen::Vector3d const axis(joint->axis.x, joint->axis.y, joint->axis.z);
    std::string const& name = joint->name;
    pinocchio::JointIndex id;
    if (revolute) {
      if (axis == Eigen::Vector3d::UnitX()) {
        id = model.addJoint(parent, pinocchio::JointModelRX(), placement, name);
      } else if (axis == Eigen::Vector3d::UnitY()) {
        id = model.addJoint(parent, pinocchio::JointModelRY(), placement, name);
      } else if (axis == Eigen::Vector3d::UnitZ()) {
        id = model.addJoint(parent, pinocchio::JointModelRZ(), placement, name);
      } else {
        id = model.addJoint(parent, pinocchio::JointModelRevoluteUnaligned(axis.normalized()),
                            placement, name);
      }
    } else if (axis == Eigen::Vector3d::UnitX()) {
      id = model.addJoint(parent, pinocchio::JointModelPX(), placement, name);
    } else if (axis == Eigen::Vector3d::UnitY()) {
      id = model.addJoint(parent, pinocchio::JointModelPY(), placement, name);
    } else if (axis == Eigen::Vector3d::UnitZ()) {
      id = model.addJoint(parent, pinocchio::JointModelPZ(), placement, name);
    } else {
      id = model.addJoint(parent, pinocchio::JointModelPrismaticUnaligned(axis.normalized()),
                          placement, name);
    }
    model.appendBodyToJoint(id, inertia_of(*child), pinocchio::SE3::Identity());
    if (!add_subtree(model, child, id, pinocchio::SE3::Identity())) return false;
  }
  return true;
}

// The whole URDF file; false (with a message) if it cannot be mapped.
inline bool load_urdf(char const* path, pinocchio::Model& model) {
  urdf::ModelInterfaceSharedPtr robot = urdf::parseURDFFile(path);
  if (!robot || !add_subtree(model, robot->getRoot(), 0, pinocchio::SE3::Identity())) {
    std::fprintf(stderr, "cannot map %s into a Pinocchio model\n", path);
    return false;
  }
  return true;
}

}  // namespace peers
