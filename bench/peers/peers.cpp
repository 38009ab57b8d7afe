// Times Pinocchio (ABA, RNEA, CRBA) and MuJoCo (mj_forward) on one model,
// over the same random states as `eom-gen bench --per-call` (SplitMix64 with
// the same seed and the same order of draws: per state nq positions in
// [-pi, pi], then nv speeds, nv forces and nv accelerations in [-1, 1]),
// and prints the accelerations of both at the first CHECK states for the
// comparison with eom. No Python anywhere in here.
//
//   peers MODEL.urdf MODEL.xml STATES REPS SEED CHECK
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
};

// One warm-up pass, then REPS timed passes over N states; ns per call.
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
  return {at(0.5), at(0.25), at(0.75), at(0.0), at(1.0)};
}

std::string json(Stats const& s) {
  char buf[256];
  std::snprintf(buf, sizeof buf,
                "{\"median\":%.6g,\"q1\":%.6g,\"q3\":%.6g,\"min\":%.6g,\"max\":%.6g}",
                s.median, s.q1, s.q3, s.min, s.max);
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
  if (argc != 7) {
    std::fprintf(stderr, "usage: peers MODEL.urdf MODEL.xml STATES REPS SEED CHECK\n");
    return 2;
  }
  int const n = std::atoi(argv[3]), reps = std::atoi(argv[4]);
  uint64_t const seed = std::strtoull(argv[5], nullptr, 10);
  int const check = std::atoi(argv[6]);
  if (n < 1 || reps < 1 || check < 0 || check > n) {
    std::fprintf(stderr, "STATES and REPS must be positive, 0 <= CHECK <= STATES\n");
    return 2;
  }

  // Pinocchio: fixed base, gravity (0, 0, -9.81) by default.
  pinocchio::Model model;
  if (!peers::load_urdf(argv[1], model)) return 1;
  pinocchio::Data data(model);
  int const nq = model.nq, nv = model.nv;

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

  // The states, drawn in eom-gen's order.
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

  auto mj_set = [&](int k) {
    mju_copy(d->qpos, q[k].data(), nq);
    mju_copy(d->qvel, v[k].data(), nv);
    mju_copy(d->qfrc_applied, tau[k].data(), nv);
  };

  // Accelerations at the check states.
  std::string checks = "[";
  for (int k = 0; k < check; ++k) {
    pinocchio::aba(model, data, q[k], v[k], tau[k]);
    mj_set(k);
    mj_forward(m, d);
    checks += std::string(k ? "," : "") + "{\"q\":" + json(q[k].data(), nq) +
              ",\"u\":" + json(v[k].data(), nv) + ",\"tau\":" + json(tau[k].data(), nv) +
              ",\"pinocchio\":" + json(data.ddq.data(), nv) + ",\"mujoco\":" + json(d->qacc, nv) +
              "}";
  }
  checks += "]";

  Stats aba = time_it(n, reps, [&](int k) {
    pinocchio::aba(model, data, q[k], v[k], tau[k]);
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

  std::printf(
      "{\"nq\":%d,\"nv\":%d,\"pinocchio_version\":\"%s\",\"mujoco_version\":\"%s\",\"mujoco_max_armature\":%g,"
      "\"mujoco_max_damping\":%g,\"mujoco_disableflags\":%d,\"mujoco_gravity\":[%g,%g,%g],"
      "\"pinocchio_gravity\":[%g,%g,%g],\"pinocchio_aba\":%s,\"pinocchio_rnea\":%s,"
      "\"pinocchio_crba\":%s,\"mujoco_forward\":%s,\"check\":%s}\n",
      nq, nv, PINOCCHIO_VERSION, mj_versionString(), max_armature, max_damping, m->opt.disableflags,
      m->opt.gravity[0], m->opt.gravity[1], m->opt.gravity[2], model.gravity.linear()[0],
      model.gravity.linear()[1], model.gravity.linear()[2], json(aba).c_str(),
      json(rnea).c_str(), json(crba).c_str(), json(fwd).c_str(), checks.c_str());
  mj_deleteData(d);
  mj_deleteModel(m);
  return 0;
}
