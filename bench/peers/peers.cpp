// Times Pinocchio (ABA, RNEA, CRBA, computeABADerivatives) and MuJoCo
// (mj_forward, mjd_transitionFD) on one model,
// over the same random states as `eom-gen bench --per-call` (SplitMix64 with
// the same seed and the same order of draws: per state nq positions in
// [-pi, pi], then nv speeds, nv forces and nv accelerations in [-1, 1]),
// and prints the accelerations of both at the first CHECK states for the
// comparison with eom, and the derivatives of both at those states with zero
// forces (what `eom-gen linearize` gives at a state). No Python anywhere in
// here.
//
//   peers MODEL.urdf MODEL.xml STATES REPS SEED CHECK [DERIV]
//
// (DERIV 0 skips timing the derivatives, which peers.py does for the
// models it gives no derivative row: over 10 speeds, and the robots.)
//
// Output: one JSON object on stdout.
//
// Pinocchio is used header-only, compiled here with -O3 -march=native. Its
// URDF parser lives in the wheel's libpinocchio_parsers, built for baseline
// x86-64: a program compiled with AVX and linked to it crashes in ~Model (the
// layout of pinocchio::Model differs, even with Eigen's alignment forced to
// 16 bytes). So the URDF is read with urdfdom (plain C++, no Eigen) and the
// model built with Pinocchio's own API, mapped as Pinocchio's parser does
// (revolute about x, y or z -> JointModelRX/RY/RZ, else RevoluteUnaligned;
// inertia rotated from the inertial frame). peers.py checks the result
// against Pinocchio's own parser (through its Python bindings) as well.

#include <pinocchio/algorithm/aba-derivatives.hpp>
#include <pinocchio/algorithm/aba.hpp>
#include <pinocchio/algorithm/crba.hpp>
#include <pinocchio/algorithm/rnea.hpp>
#include "pinocchio_urdf.hpp"

#include <mujoco/mujoco.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

namespace {

// SplitMix64 mapped to [-1, 1), as in eom-gen's timing program.
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

// Keeps the compiler from dropping or hoisting work (as benchmark::DoNotOptimize).
template <class T>
inline void keep(T const* p) {
  asm volatile("" : : "g"(p) : "memory");
}

struct Stats {
  double median, q1, q3, min, max;
  int passes;
};

// One warm-up pass, then REPS timed passes over N states; ns per call. With
// a BUDGET (seconds, > 0), stops after at least 3 passes once the budget is
// spent (MuJoCo's finite differences of a 50-link chain take a millisecond
// per call).
template <class F>
Stats time_it(int n, int reps, F f, double budget = 0) {
  auto start = std::chrono::steady_clock::now();
  for (int k = 0; k < n; ++k) f(k);
  std::vector<double> ns;
  for (int r = 0; r < reps; ++r) {
    double spent = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (budget > 0 && r >= 3 && spent > budget) break;
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
  return {at(0.5), at(0.25), at(0.75), at(0.0), at(1.0), int(ns.size())};
}

std::string json(Stats const& s) {
  char buf[256];
  std::snprintf(buf, sizeof buf,
                "{\"median\":%.6g,\"q1\":%.6g,\"q3\":%.6g,\"min\":%.6g,\"max\":%.6g,"
                "\"passes\":%d}",
                s.median, s.q1, s.q3, s.min, s.max, s.passes);
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
  if (argc != 7 && argc != 8) {
    std::fprintf(stderr, "usage: peers MODEL.urdf MODEL.xml STATES REPS SEED CHECK [DERIV]\n");
    return 2;
  }
  // DERIV 0: the derivatives are not timed (their columns read 0 passes).
  bool const time_derivatives = argc < 8 || std::atoi(argv[7]) != 0;
  int const n = std::atoi(argv[3]), reps = std::atoi(argv[4]);
  uint64_t const seed = std::strtoull(argv[5], nullptr, 10);
  int const check = std::atoi(argv[6]);
  if (n < 1 || reps < 1 || check < 0 || check > n) {
    std::fprintf(stderr, "STATES and REPS must be positive, 0 <= CHECK <= STATES\n");
    return 2;
  }

  // Pinocchio: fixed base, gravity (0, 0, -9.81) by default.
  pinocchio::Model model;
  std::vector<double> damping;  // per speed, Pinocchio's order (URDF <dynamics damping>)
  if (!peers::load_urdf(argv[1], model, damping)) return 1;
  pinocchio::Data data(model);
  int const nq = model.nq, nv = model.nv;
  if (int(damping.size()) != nv || nq != nv) {
    std::fprintf(stderr, "only one coordinate and one speed per joint (nq %d, nv %d)\n", nq, nv);
    return 1;
  }

  // MuJoCo.
  char err[1000] = "";
  mjModel* m = mj_loadXML(argv[2], nullptr, err, sizeof err);
  if (!m) {
    std::fprintf(stderr, "MuJoCo cannot load %s: %s\n", argv[2], err);
    return 1;
  }
  mjData* d = mj_makeData(m);
  if (m->nq != nq || m->nv != nv) {
    std::fprintf(stderr, "sizes differ: Pinocchio nq %d nv %d, MuJoCo nq %d nv %d\n", nq, nv,
                 m->nq, m->nv);
    return 1;
  }
  double max_armature = 0, max_damping = 0;
  for (int i = 0; i < m->nv; ++i) {
    max_armature = std::max(max_armature, std::fabs(m->dof_armature[i]));
    max_damping = std::max(max_damping, std::fabs(m->dof_damping[i]));
  }
  // MuJoCo's coordinate and speed of each of Pinocchio's joints, by name (a
  // tree's bodies can come in another order); the identity on the chains.
  std::vector<int> mj_q(nq), mj_v(nv);
  std::vector<double> mj_damping(nv);
  std::string names = "[";
  for (pinocchio::JointIndex j = 1; j < model.njoints; ++j) {
    std::string const& name = model.names[j];
    int const id = mj_name2id(m, mjOBJ_JOINT, name.c_str());
    if (id < 0) {
      std::fprintf(stderr, "MuJoCo's model has no joint `%s`\n", name.c_str());
      return 1;
    }
    int const iq = model.joints[j].idx_q(), iv = model.joints[j].idx_v();
    mj_q[iq] = m->jnt_qposadr[id];
    mj_v[iv] = m->jnt_dofadr[id];
    mj_damping[iv] = m->dof_damping[m->jnt_dofadr[id]];
    names += std::string(j > 1 ? "," : "") + "\"" + name + "\"";
  }
  names += "]";

  // The states, drawn in eom-gen's order.
  Rng rng{seed};
  std::vector<Eigen::VectorXd> q(n), v(n), tau(n), a(n), tau_d(n);
  for (int k = 0; k < n; ++k) {
    q[k].resize(nq);
    v[k].resize(nv);
    tau[k].resize(nv);
    a[k].resize(nv);
    for (int i = 0; i < nq; ++i) q[k][i] = M_PI * rng.uniform();
    for (int i = 0; i < nv; ++i) v[k][i] = rng.uniform();
    for (int i = 0; i < nv; ++i) tau[k][i] = rng.uniform();
    for (int i = 0; i < nv; ++i) a[k][i] = rng.uniform();
    // Pinocchio's ABA is given the damper's force as well: τ − D v (drawn
    // before the timing, the same for every pass; D = 0 on the chains).
    tau_d[k] = tau[k];
    for (int i = 0; i < nv; ++i) tau_d[k][i] -= damping[size_t(i)] * v[k][i];
  }

  auto mj_set = [&](int k) {
    for (int i = 0; i < nq; ++i) d->qpos[mj_q[size_t(i)]] = q[k][i];
    for (int i = 0; i < nv; ++i) {
      d->qvel[mj_v[size_t(i)]] = v[k][i];
      d->qfrc_applied[mj_v[size_t(i)]] = tau[k][i];
    }
  };
  // MuJoCo's accelerations in Pinocchio's order.
  std::vector<double> mj_acc(nv);
  auto mj_qacc = [&]() {
    for (int i = 0; i < nv; ++i) mj_acc[size_t(i)] = d->qacc[mj_v[size_t(i)]];
    return mj_acc.data();
  };

  // Accelerations at the check states.
  //
  // And the derivatives at the same q, v with zero applied forces (the
  // dampers' −D v only: eom's operating point), by rows: Pinocchio's
  // ddq_dq, ddq_dv (at fixed τ: the dampers' −M⁻¹ D is peers.py's to add)
  // and Minv (computeABADerivatives fills only the upper triangle of Minv;
  // the lower is copied from it here), and
  // MuJoCo's centred finite differences of its transition read back as
  // derivatives of qacc. MuJoCo's Euler step is v' = v + h qacc(q, v),
  // q' = q + h v' (no damping here), so the rows of v' in A are
  // h dqacc/dq and I + h dqacc/dv. (These are in MuJoCo's order and without
  // the damping: peers.py compares them only on the chains, which have
  // neither a reordering nor dampers.)
  int const nx = 2 * nv + m->na;
  std::vector<mjtNum> A(size_t(nx) * nx);
  double const h = m->opt.timestep;
  Eigen::VectorXd damper(nv);
  std::string checks = "[";
  for (int k = 0; k < check; ++k) {
    pinocchio::aba(model, data, q[k], v[k], tau_d[k]);
    mj_set(k);
    mj_forward(m, d);
    checks += std::string(k ? "," : "") + "{\"q\":" + json(q[k].data(), nq) +
              ",\"u\":" + json(v[k].data(), nv) + ",\"tau\":" + json(tau[k].data(), nv) +
              ",\"pinocchio\":" + json(data.ddq.data(), nv) + ",\"mujoco\":" + json(mj_qacc(), nv);
    for (int i = 0; i < nv; ++i) damper[i] = -damping[size_t(i)] * v[k][i];
    pinocchio::computeABADerivatives(model, data, q[k], v[k], damper);
    Eigen::MatrixXd dq = data.ddq_dq, dv = data.ddq_dv, minv = data.Minv;
    for (int i = 0; i < nv; ++i)
      for (int j = 0; j < i; ++j) minv(i, j) = minv(j, i);
    Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> rq = dq, rv = dv, rm = minv;
    mj_set(k);
    mju_zero(d->qfrc_applied, nv);
    mjd_transitionFD(m, d, 1e-6, 1, A.data(), nullptr, nullptr, nullptr);
    std::vector<double> mq(size_t(nv) * nv), mv(size_t(nv) * nv);
    for (int i = 0; i < nv; ++i)
      for (int j = 0; j < nv; ++j) {
        mq[size_t(i) * nv + j] = A[size_t(nv + i) * nx + j] / h;
        mv[size_t(i) * nv + j] = (A[size_t(nv + i) * nx + nv + j] - (i == j ? 1.0 : 0.0)) / h;
      }
    checks += ",\"pinocchio_ddq_dq\":" + json(rq.data(), nv * nv) +
              ",\"pinocchio_ddq_dv\":" + json(rv.data(), nv * nv) +
              ",\"pinocchio_minv_upper\":" + json(rm.data(), nv * nv) +
              ",\"mujoco_fd_dq\":" + json(mq.data(), nv * nv) +
              ",\"mujoco_fd_dv\":" + json(mv.data(), nv * nv) + "}";
  }
  checks += "]";

  Stats aba = time_it(n, reps, [&](int k) {
    pinocchio::aba(model, data, q[k], v[k], tau_d[k]);
    keep(data.ddq.data());
  });
  Stats rnea = time_it(n, reps, [&](int k) {
    pinocchio::rnea(model, data, q[k], v[k], a[k]);
    keep(data.tau.data());
  });
  Stats crba = time_it(n, reps, [&](int k) {
    pinocchio::crba(model, data, q[k]);
    keep(data.M.data());
  });
  Stats fwd = time_it(n, reps, [&](int k) {
    mj_set(k);
    mj_forward(m, d);
    keep(d->qacc);
  });

  // Pinocchio's analytic derivatives of ABA: ddq_dq, ddq_dv, Minv (upper
  // triangle) and ddq, at the timed states (with their forces).
  Stats const skipped{0, 0, 0, 0, 0, 0};
  Stats daba = !time_derivatives ? skipped : time_it(n, reps, [&](int k) {
    pinocchio::computeABADerivatives(model, data, q[k], v[k], tau[k]);
    keep(data.ddq_dq.data());
    keep(data.ddq_dv.data());
    keep(data.Minv.data());
  });
  // MuJoCo's finite differences of its discrete-time transition
  // x' = step(x, ctrl), x = (q, v, act) in the tangent space: A only (no
  // actuators here, so B is empty; no sensors, so no C, D). Forward
  // differences (one nominal step and one per state coordinate, 2 nv + 1
  // steps, velocity perturbations skipping the position stages) are its
  // cheapest setting; centred (4 nv + 1) shown too. eps = 1e-6 (the
  // cost does not depend on it).
  auto fd = [&](mjtByte centered) {
    return time_it(
        n, reps,
        [&](int k) {
          mj_set(k);
          mjd_transitionFD(m, d, 1e-6, centered, A.data(), nullptr, nullptr, nullptr);
          keep(A.data());
        },
        2.0);
  };
  Stats fd_forward = time_derivatives ? fd(0) : skipped;
  Stats fd_centered = time_derivatives ? fd(1) : skipped;

  std::printf(
      "{\"nq\":%d,\"nv\":%d,\"pinocchio_version\":\"%s\",\"mujoco_version\":\"%s\",\"mujoco_max_armature\":%g,"
      "\"mujoco_max_damping\":%g,\"mujoco_disableflags\":%d,\"mujoco_gravity\":[%g,%g,%g],"
      "\"pinocchio_gravity\":[%g,%g,%g],\"pinocchio_aba\":%s,\"pinocchio_rnea\":%s,"
      "\"pinocchio_crba\":%s,\"mujoco_forward\":%s,\"pinocchio_aba_derivatives\":%s,"
      "\"mujoco_transition_fd_forward\":%s,\"mujoco_transition_fd_centered\":%s,"
      "\"mujoco_integrator\":%d,\"mujoco_timestep\":%g,\"joints\":%s,\"damping\":%s,"
      "\"mujoco_damping\":%s,\"check\":%s}\n",
      nq, nv, PINOCCHIO_VERSION, mj_versionString(), max_armature, max_damping, m->opt.disableflags,
      m->opt.gravity[0], m->opt.gravity[1], m->opt.gravity[2], model.gravity.linear()[0],
      model.gravity.linear()[1], model.gravity.linear()[2], json(aba).c_str(),
      json(rnea).c_str(), json(crba).c_str(), json(fwd).c_str(), json(daba).c_str(),
      json(fd_forward).c_str(), json(fd_centered).c_str(), m->opt.integrator, m->opt.timestep,
      names.c_str(), json(damping.data(), nv).c_str(), json(mj_damping.data(), nv).c_str(),
      checks.c_str());
  mj_deleteData(d);
  mj_deleteModel(m);
  return 0;
}
