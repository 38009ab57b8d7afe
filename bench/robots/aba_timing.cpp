// Times Pinocchio's ABA, CRBA and RNEA on one real robot (fixed base), over
// random states drawn like `eom-gen bench --per-call` draws them (SplitMix64;
// per state nq positions in [-pi, pi], then nv speeds, nv forces and nv
// accelerations in [-1, 1]), and prints the accelerations at the first state
// so that compare.py can check this program's model against Pinocchio's own
// URDF parser. No Python anywhere in here.
//
//   aba_timing ROBOT.urdf STATES REPS SEED
//
// As in bench/peers (see the head of peers.cpp for why): the URDF is read
// with urdfdom and the model built with Pinocchio's API, mapped as
// Pinocchio's parser maps it — revolute about x, y or z -> JointModelRX/RY/RZ,
// else RevoluteUnaligned; prismatic likewise; a fixed joint appends its
// child's inertia to the parent's joint at the composed placement (massless
// links included). Continuous joints are mapped as revolute (one angle, like
// eom's coordinate) where Pinocchio's parser uses the unbounded (cos, sin)
// joint. Children in urdfdom's order, which is the parser's.
//
// The forward dynamics timed include the URDF damping, tau - D v, as eom's
// do.
//
// Output: one JSON object on stdout.

#include <pinocchio/algorithm/aba.hpp>
#include <pinocchio/algorithm/crba.hpp>
#include <pinocchio/algorithm/rnea.hpp>
#include <pinocchio/multibody.hpp>
#include <urdf_parser/urdf_parser.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

namespace {

pinocchio::SE3 se3(urdf::Pose const& p) {
  Eigen::Quaterniond r(p.rotation.w, p.rotation.x, p.rotation.y, p.rotation.z);
  return pinocchio::SE3(r.toRotationMatrix(),
                        Eigen::Vector3d(p.position.x, p.position.y, p.position.z));
}

pinocchio::Inertia inertia_of(urdf::Link const& link) {
  auto const& in = link.inertial;
  if (!in) return pinocchio::Inertia::Zero();
  pinocchio::SE3 const frame = se3(in->origin);
  Eigen::Matrix3d i;
  i << in->ixx, in->ixy, in->ixz, in->ixy, in->iyy, in->iyz, in->ixz, in->iyz, in->izz;
  Eigen::Matrix3d const r = frame.rotation();
  return pinocchio::Inertia(in->mass, frame.translation(), r * i * r.transpose());
}

// Adds the joints below `link`, which sits at `at` in the frame of joint
// `parent` (depth first, children in urdfdom's order). Damping per speed
// goes to `damping`.
bool add_subtree(pinocchio::Model& model, urdf::LinkConstSharedPtr const& link,
                 pinocchio::JointIndex parent, pinocchio::SE3 const& at,
                 std::vector<double>& damping) {
  for (auto const& joint : link->child_joints) {
    urdf::LinkConstSharedPtr child;
    for (auto const& c : link->child_links) {
      if (c->name == joint->child_link_name) child = c;
    }
    if (!child) return false;
    pinocchio::SE3 const placement = at * se3(joint->parent_to_joint_origin_transform);
    if (joint->type == urdf::Joint::FIXED) {
      model.appendBodyToJoint(parent, inertia_of(*child), placement);
      if (!add_subtree(model, child, parent, placement, damping)) return false;
      continue;
    }
    Eigen::Vector3d const axis(joint->axis.x, joint->axis.y, joint->axis.z);
    bool const revolute =
        joint->type == urdf::Joint::REVOLUTE || joint->type == urdf::Joint::CONTINUOUS;
    if (!revolute && joint->type != urdf::Joint::PRISMATIC) {
      std::fprintf(stderr, "joint %s: only revolute, continuous, prismatic and fixed joints\n",
                   joint->name.c_str());
      return false;
    }
    pinocchio::JointIndex id;
    std::string const& name = joint->name;
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
    } else {
      if (axis == Eigen::Vector3d::UnitX()) {
        id = model.addJoint(parent, pinocchio::JointModelPX(), placement, name);
      } else if (axis == Eigen::Vector3d::UnitY()) {
        id = model.addJoint(parent, pinocchio::JointModelPY(), placement, name);
      } else if (axis == Eigen::Vector3d::UnitZ()) {
        id = model.addJoint(parent, pinocchio::JointModelPZ(), placement, name);
      } else {
        id = model.addJoint(parent, pinocchio::JointModelPrismaticUnaligned(axis.normalized()),
                            placement, name);
      }
    }
    damping.push_back(joint->dynamics ? joint->dynamics->damping : 0.0);
    model.appendBodyToJoint(id, inertia_of(*child), pinocchio::SE3::Identity());
    if (!add_subtree(model, child, id, pinocchio::SE3::Identity(), damping)) return false;
  }
  return true;
}

struct Rng {
  uint64_t s;
  double uniform() {
    s += 0x9e3779b97f4a7c15ULL;
    uint64_t z = s;
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    z ^= z >> 31;
    return double(z >> 11) / double(1ULL << 53) * 2.0 - 1.0;
  }
};

template <class T>
inline void keep(T const* p) {
  asm volatile("" : : "g"(p) : "memory");
}

struct Stats {
  double median, q1, q3;
};

template <class F>
Stats time_it(int n, int reps, F f) {
  for (int k = 0; k < n; ++k) f(k);
  std::vector<double> ns;
  for (int r = 0; r < reps; ++r) {
    auto t0 = std::chrono::steady_clock::now();
    for (int k = 0; k < n; ++k) f(k);
    auto t1 = std::chrono::steady_clock::now();
    ns.push_back(std::chrono::duration<double, std::nano>(t1 - t0).count() / n);
  }
  std::sort(ns.begin(), ns.end());
  auto at = [&](double p) {
    double x = p * double(ns.size() - 1);
    size_t lo = size_t(std::floor(x)), hi = size_t(std::ceil(x));
    return ns[lo] + (ns[hi] - ns[lo]) * (x - double(lo));
  };
  return {at(0.5), at(0.25), at(0.75)};
}

std::string json(Stats const& s) {
  char buf[160];
  std::snprintf(buf, sizeof buf, "{\"median\":%.6g,\"q1\":%.6g,\"q3\":%.6g}", s.median, s.q1,
                s.q3);
  return buf;
}

std::string json(double const* v, int n) {
  std::string out = "[";
  char buf[40];
  for (int i = 0; i < n; ++i) {
    std::snprintf(buf, sizeof buf, "%s%.17g", i ? "," : "", v[i]);
    out += buf;
  }
  return out + "]";
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 5) {
    std::fprintf(stderr, "usage: aba_timing ROBOT.urdf STATES REPS SEED\n");
    return 2;
  }
  int const n = std::atoi(argv[2]), reps = std::atoi(argv[3]);
  uint64_t const seed = std::strtoull(argv[4], nullptr, 10);
  if (n < 1 || reps < 1) {
    std::fprintf(stderr, "STATES and REPS must be positive\n");
    return 2;
  }
  urdf::ModelInterfaceSharedPtr robot = urdf::parseURDFFile(argv[1]);
  pinocchio::Model model;
  std::vector<double> damping;
  if (!robot || !add_subtree(model, robot->getRoot(), 0, pinocchio::SE3::Identity(), damping)) {
    std::fprintf(stderr, "cannot map %s into a Pinocchio model\n", argv[1]);
    return 1;
  }
  pinocchio::Data data(model);
  int const nq = model.nq, nv = model.nv;
  Eigen::Map<Eigen::VectorXd> const d(damping.data(), nv);

  Rng rng{seed};
  std::vector<Eigen::VectorXd> q(n), v(n), tau(n), a(n);
  for (int k = 0; k < n; ++k) {
    q[k].resize(nq);
    v[k].resize(nv);
    tau[k].resize(nv);
    a[k].resize(nv);
    for (int i = 0; i < nq; ++i) q[k][i] = M_PI * rng.uniform();
    for (int i = 0; i < nv; ++i) v[k][i] = rng.uniform();
    for (int i = 0; i < nv; ++i) tau[k][i] = rng.uniform();
    for (int i = 0; i < nv; ++i) a[k][i] = rng.uniform();
  }
  Eigen::VectorXd effort(nv);

  // The check state: no damping, to compare with the parser's model as is.
  pinocchio::aba(model, data, q[0], v[0], tau[0]);
  std::string const check = "{\"q\":" + json(q[0].data(), nq) + ",\"v\":" + json(v[0].data(), nv) +
                            ",\"tau\":" + json(tau[0].data(), nv) +
                            ",\"a\":" + json(data.ddq.data(), nv) + "}";

  Stats const aba = time_it(n, reps, [&](int k) {
    effort.noalias() = tau[k] - d.cwiseProduct(v[k]);
    pinocchio::aba(model, data, q[k], v[k], effort);
    keep(data.ddq.data());
  });
  Stats const rnea = time_it(n, reps, [&](int k) {
    pinocchio::rnea(model, data, q[k], v[k], a[k]);
    keep(data.tau.data());
  });
  Stats const crba = time_it(n, reps, [&](int k) {
    pinocchio::crba(model, data, q[k]);
    keep(data.M.data());
  });
  std::printf(
      "{\"nq\":%d,\"nv\":%d,\"pinocchio_version\":\"%s\",\"aba\":%s,\"rnea\":%s,\"crba\":%s,"
      "\"check\":%s}\n",
      nq, nv, PINOCCHIO_VERSION, json(aba).c_str(), json(rnea).c_str(), json(crba).c_str(),
      check.c_str());
  return 0;
}
