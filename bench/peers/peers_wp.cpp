// Work-precision runs of the peers (issue 8): 10 s of motion of one model
// from a given initial state, integrated by
//
//   mujoco-rk4:N       MuJoCo's mj_step with integrator RK4, N equal steps;
//   pinocchio-dop853:T Pinocchio's ABA (zero joint torques) inside DOP853
//                      with rtol = atol = T, written here in C++ after
//                      eom-sim's DOP853 (same coefficients, Hairer's
//                      dop853.f: same error norm, controller and initial
//                      step; no dense output, no stiffness test), so the two
//                      differ only in the right-hand side;
//
// and prints, per run, the state at T_END, the step and right-hand-side
// counts and the CPU time (median of the repetitions). No Python in here.
//
//   peers_wp MODEL.urdf MODEL.xml T_END REPS BUDGET_S Q0 U0 RUN...
//
// Q0 and U0 are comma-separated (the eom model's initial state); each run
// is repeated REPS times, or fewer (at least 3) once BUDGET_S seconds have
// been spent on it. Output: one JSON object per line.

#include <pinocchio/algorithm/aba.hpp>

#include "pinocchio_urdf.hpp"

#include <mujoco/mujoco.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

namespace {

// DOP853 coefficients (Hairer's dop853.f, as in eom-sim/src/integrate/dop853.rs).
constexpr double C2 = 0.526001519587677318785587544488e-01;
constexpr double C3 = 0.789002279381515978178381316732e-01;
constexpr double C4 = 0.118350341907227396726757197510e+00;
constexpr double C5 = 0.281649658092772603273242802490e+00;
constexpr double C6 = 0.333333333333333333333333333333e+00;
constexpr double C7 = 0.25e+00;
constexpr double C8 = 0.307692307692307692307692307692e+00;
constexpr double C9 = 0.651282051282051282051282051282e+00;
constexpr double C10 = 0.6e+00;
constexpr double C11 = 0.857142857142857142857142857142e+00;
constexpr double B1 = 5.42937341165687622380535766363e-2;
constexpr double B6 = 4.45031289275240888144113950566e0;
constexpr double B7 = 1.89151789931450038304281599044e0;
constexpr double B8 = -5.8012039600105847814672114227e0;
constexpr double B9 = 3.1116436695781989440891606237e-1;
constexpr double B10 = -1.52160949662516078556178806805e-1;
constexpr double B11 = 2.01365400804030348374776537501e-1;
constexpr double B12 = 4.47106157277725905176885569043e-2;
constexpr double BHH1 = 0.244094488188976377952755905512e+00;
constexpr double BHH2 = 0.733846688281611857341361741547e+00;
constexpr double BHH3 = 0.220588235294117647058823529412e-01;
constexpr double ER1 = 0.1312004499419488073250102996e-01;
constexpr double ER6 = -0.1225156446376204440720569753e+01;
constexpr double ER7 = -0.4957589496572501915214079952e+00;
constexpr double ER8 = 0.1664377182454986536961530415e+01;
constexpr double ER9 = -0.3503288487499736816886487290e+00;
constexpr double ER10 = 0.3341791187130174790297318841e+00;
constexpr double ER11 = 0.8192320648511571246570742613e-01;
constexpr double ER12 = -0.2235530786388629525884427845e-01;
constexpr double A21 = 5.26001519587677318785587544488e-2;
constexpr double A31 = 1.97250569845378994544595329183e-2;
constexpr double A32 = 5.91751709536136983633785987549e-2;
constexpr double A41 = 2.95875854768068491816892993775e-2;
constexpr double A43 = 8.87627564304205475450678981324e-2;
constexpr double A51 = 2.41365134159266685502369798665e-1;
constexpr double A53 = -8.84549479328286085344864962717e-1;
constexpr double A54 = 9.24834003261792003115737966543e-1;
constexpr double A61 = 3.7037037037037037037037037037e-2;
constexpr double A64 = 1.70828608729473871279604482173e-1;
constexpr double A65 = 1.25467687566822425016691814123e-1;
constexpr double A71 = 3.7109375e-2;
constexpr double A74 = 1.70252211019544039314978060272e-1;
constexpr double A75 = 6.02165389804559606850219397283e-2;
constexpr double A76 = -1.7578125e-2;
constexpr double A81 = 3.70920001185047927108779319836e-2;
constexpr double A84 = 1.70383925712239993810214054705e-1;
constexpr double A85 = 1.07262030446373284651809199168e-1;
constexpr double A86 = -1.53194377486244017527936158236e-2;
constexpr double A87 = 8.27378916381402288758473766002e-3;
constexpr double A91 = 6.24110958716075717114429577812e-1;
constexpr double A94 = -3.36089262944694129406857109825e0;
constexpr double A95 = -8.68219346841726006818189891453e-1;
constexpr double A96 = 2.75920996994467083049415600797e1;
constexpr double A97 = 2.01540675504778934086186788979e1;
constexpr double A98 = -4.34898841810699588477366255144e1;
constexpr double A101 = 4.77662536438264365890433908527e-1;
constexpr double A104 = -2.48811461997166764192642586468e0;
constexpr double A105 = -5.90290826836842996371446475743e-1;
constexpr double A106 = 2.12300514481811942347288949897e1;
constexpr double A107 = 1.52792336328824235832596922938e1;
constexpr double A108 = -3.32882109689848629194453265587e1;
constexpr double A109 = -2.03312017085086261358222928593e-2;
constexpr double A111 = -9.3714243008598732571704021658e-1;
constexpr double A114 = 5.18637242884406370830023853209e0;
constexpr double A115 = 1.09143734899672957818500254654e0;
constexpr double A116 = -8.14978701074692612513997267357e0;
constexpr double A117 = -1.85200656599969598641566180701e1;
constexpr double A118 = 2.27394870993505042818970056734e1;
constexpr double A119 = 2.49360555267965238987089396762e0;
constexpr double A1110 = -3.0467644718982195003823669022e0;
constexpr double A121 = 2.27331014751653820792359768449e0;
constexpr double A124 = -1.05344954667372501984066689879e1;
constexpr double A125 = -2.00087205822486249909675718444e0;
constexpr double A126 = -1.79589318631187989172765950534e1;
constexpr double A127 = 2.79488845294199600508499808837e1;
constexpr double A128 = -2.85899827713502369474065508674e0;
constexpr double A129 = -8.87285693353062954433549289258e0;
constexpr double A1210 = 1.23605671757943030647266201528e1;
constexpr double A1211 = 6.43392746015763530355970484046e-1;

using Vec = Eigen::VectorXd;

struct Counts {
  long steps = 0, accepted = 0, rejected = 0, rhs = 0;
};

// Hairer's HINIT (as eom-sim's `hinit`), for order `order`.
template <class F>
double hinit(F& f, double t, Vec const& y, Vec const& f0, double hmax, double rtol,
             double atol, int order, Counts& c) {
  long const n = y.size();
  double dnf = 0, dny = 0;
  for (long i = 0; i < n; ++i) {
    double const sk = atol + rtol * std::fabs(y[i]);
    dnf += (f0[i] / sk) * (f0[i] / sk);
    dny += (y[i] / sk) * (y[i] / sk);
  }
  double h = (dnf <= 1e-10 || dny <= 1e-10) ? 1e-6 : std::sqrt(dny / dnf) * 0.01;
  h = std::min(h, hmax);
  Vec y1 = y + h * f0, f1(n);
  f(t + h, y1, f1);
  ++c.rhs;
  double der2 = 0;
  for (long i = 0; i < n; ++i) {
    double const sk = atol + rtol * std::fabs(y[i]);
    der2 += ((f1[i] - f0[i]) / sk) * ((f1[i] - f0[i]) / sk);
  }
  der2 = std::sqrt(der2) / h;
  double const der12 = std::max(der2, std::sqrt(dnf));
  double const h1 = (der12 <= 1e-15 || !std::isfinite(der12))
                        ? std::max(1e-6, h * 1e-3)
                        : std::pow(0.01 / der12, 1.0 / order);
  return std::min({100 * h, h1, hmax});
}

// DOP853 from t0 to t_end (forward), y updated in place; Hairer's defaults
// (safety 0.9, step ratio in [1/6, 1/0.333], beta 0, hmax = t_end - t0).
// Returns false if the step size underflows or the state stops being finite.
template <class F>
bool dop853(F& f, double t0, double t_end, Vec& y, double rtol, double atol, Counts& c) {
  long const n = y.size();
  double const safe = 0.9, facc1 = 1 / 0.333, facc2 = 1 / 6.0, expo1 = 1.0 / 8.0;
  double const hmax = t_end - t0, uround = 2.3e-16;
  Vec k1(n), k2(n), k3(n), k4(n), k5(n), k6(n), k7(n), k8(n), k9(n), k10(n), k11(n), k12(n),
      yt(n), y12(n), y1(n);
  f(t0, y, k1);
  ++c.rhs;
  double h = hinit(f, t0, y, k1, hmax, rtol, atol, 8, c);
  double t = t0, facold = 1e-4;
  bool reject = false, last = false;
  while (true) {
    if (0.1 * std::fabs(h) <= std::fabs(t) * uround || !(h > 0)) return false;
    if (t + 1.01 * h - t_end > 0) {
      h = t_end - t;
      last = true;
    }
    ++c.steps;
    yt = y + h * A21 * k1;
    f(t + C2 * h, yt, k2);
    yt = y + h * (A31 * k1 + A32 * k2);
    f(t + C3 * h, yt, k3);
    yt = y + h * (A41 * k1 + A43 * k3);
    f(t + C4 * h, yt, k4);
    yt = y + h * (A51 * k1 + A53 * k3 + A54 * k4);
    f(t + C5 * h, yt, k5);
    yt = y + h * (A61 * k1 + A64 * k4 + A65 * k5);
    f(t + C6 * h, yt, k6);
    yt = y + h * (A71 * k1 + A74 * k4 + A75 * k5 + A76 * k6);
    f(t + C7 * h, yt, k7);
    yt = y + h * (A81 * k1 + A84 * k4 + A85 * k5 + A86 * k6 + A87 * k7);
    f(t + C8 * h, yt, k8);
    yt = y + h * (A91 * k1 + A94 * k4 + A95 * k5 + A96 * k6 + A97 * k7 + A98 * k8);
    f(t + C9 * h, yt, k9);
    yt = y + h * (A101 * k1 + A104 * k4 + A105 * k5 + A106 * k6 + A107 * k7 + A108 * k8 +
                  A109 * k9);
    f(t + C10 * h, yt, k10);
    yt = y + h * (A111 * k1 + A114 * k4 + A115 * k5 + A116 * k6 + A117 * k7 + A118 * k8 +
                  A119 * k9 + A1110 * k10);
    f(t + C11 * h, yt, k11);
    double const tph = t + h;
    y12 = y + h * (A121 * k1 + A124 * k4 + A125 * k5 + A126 * k6 + A127 * k7 + A128 * k8 +
                   A129 * k9 + A1210 * k10 + A1211 * k11);
    f(tph, y12, k12);
    c.rhs += 11;
    double err = 0, err2 = 0;
    bool finite = true;
    for (long i = 0; i < n; ++i) {
      double const bsum = B1 * k1[i] + B6 * k6[i] + B7 * k7[i] + B8 * k8[i] + B9 * k9[i] +
                          B10 * k10[i] + B11 * k11[i] + B12 * k12[i];
      y1[i] = y[i] + h * bsum;
      finite = finite && std::isfinite(y1[i]);
      double const sk = atol + rtol * std::max(std::fabs(y[i]), std::fabs(y1[i]));
      double const e3 = bsum - BHH1 * k1[i] - BHH2 * k9[i] - BHH3 * k12[i];
      double const e5 = ER1 * k1[i] + ER6 * k6[i] + ER7 * k7[i] + ER8 * k8[i] + ER9 * k9[i] +
                        ER10 * k10[i] + ER11 * k11[i] + ER12 * k12[i];
      err2 += (e3 / sk) * (e3 / sk);
      err += (e5 / sk) * (e5 / sk);
    }
    double deno = err + 0.01 * err2;
    if (deno <= 0) deno = 1;
    err = std::fabs(h) * err * std::sqrt(1.0 / (double(n) * deno));
    if (!finite || std::isnan(err)) err = INFINITY;
    double const fac11 = std::pow(err, expo1);
    if (err <= 1) {
      double const fac = std::max(facc2, std::min(facc1, fac11 / safe));
      double hnew = std::min(h / fac, hmax);
      facold = std::max(err, 1e-4);
      if (reject) hnew = std::min(hnew, h);
      reject = false;
      ++c.accepted;
      f(tph, y1, k1);  // FSAL: the first stage of the next step
      ++c.rhs;
      y = y1;
      t = last ? t_end : tph;
      if (last) return true;
      h = hnew;
    } else {
      h /= std::min(facc1, fac11 / safe);
      reject = true;
      last = false;
      ++c.rejected;
      if (!finite && !(h > 0)) return false;
    }
  }
}

std::vector<double> list(char const* s) {
  std::vector<double> out;
  std::string const text(s);
  size_t pos = 0;
  while (pos <= text.size()) {
    size_t const comma = std::min(text.find(',', pos), text.size());
    if (comma > pos) {
      char* end = nullptr;
      std::string const item = text.substr(pos, comma - pos);
      double const x = std::strtod(item.c_str(), &end);
      if (end == item.c_str() || *end != '\0') {
        std::fprintf(stderr, "not a number: %s\n", item.c_str());
        std::exit(2);
      }
      out.push_back(x);
    }
    pos = comma + 1;
  }
  return out;
}

std::string json(double const* v, long n) {
  std::string out = "[";
  char buf[40];
  for (long i = 0; i < n; ++i) {
    std::snprintf(buf, sizeof buf, "%s%.17g", i ? "," : "", v[i]);
    out += buf;
  }
  return out + "]";
}

// Keeps the compiler from dropping the work (as benchmark::DoNotOptimize).
inline void keep(double const* p) { asm volatile("" : : "g"(p) : "memory"); }

// Runs `run` (which returns false on failure) up to `reps` times, at least
// 3 unless `budget` seconds are exceeded by fewer; median seconds.
template <class R>
double median_time(int reps, double budget, R run, int& done, bool& ok) {
  std::vector<double> s;
  double total = 0;
  ok = true;
  for (int r = 0; r < reps; ++r) {
    auto const t0 = std::chrono::steady_clock::now();
    ok = run() && ok;
    auto const t1 = std::chrono::steady_clock::now();
    s.push_back(std::chrono::duration<double>(t1 - t0).count());
    total += s.back();
    if (!ok || (total > budget && r + 1 >= 3)) break;
  }
  done = int(s.size());
  std::sort(s.begin(), s.end());
  size_t const k = s.size();
  return k % 2 ? s[k / 2] : 0.5 * (s[k / 2 - 1] + s[k / 2]);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 9) {
    std::fprintf(stderr,
                 "usage: peers_wp MODEL.urdf MODEL.xml T_END REPS BUDGET_S Q0 U0 RUN...\n"
                 "  RUN: mujoco-rk4:STEPS or pinocchio-dop853:TOL\n");
    return 2;
  }
  double const t_end = std::strtod(argv[3], nullptr);
  int const reps = std::atoi(argv[4]);
  double const budget = std::strtod(argv[5], nullptr);
  std::vector<double> const q0 = list(argv[6]), u0 = list(argv[7]);
  if (!(t_end > 0) || reps < 1 || !(budget >= 0)) {
    std::fprintf(stderr, "T_END and REPS must be positive, BUDGET_S non-negative\n");
    return 2;
  }

  pinocchio::Model model;
  if (!peers::load_urdf(argv[1], model)) return 1;
  pinocchio::Data data(model);
  int const nq = model.nq, nv = model.nv;

  char err[1000] = "";
  mjModel* m = mj_loadXML(argv[2], nullptr, err, sizeof err);
  if (!m) {
    std::fprintf(stderr, "MuJoCo cannot load %s: %s\n", argv[2], err);
    return 1;
  }
  mjData* d = mj_makeData(m);
  if (m->nq != nq || m->nv != nv || int(q0.size()) != nq || int(u0.size()) != nv) {
    std::fprintf(stderr, "sizes differ: Pinocchio nq %d nv %d, MuJoCo nq %d nv %d, Q0 %zu U0 %zu\n",
                 nq, nv, m->nq, m->nv, q0.size(), u0.size());
    return 1;
  }

  for (int a = 8; a < argc; ++a) {
    std::string const run(argv[a]);
    size_t const colon = run.find(':');
    std::string const method = run.substr(0, colon);
    double const setting = colon == std::string::npos ? NAN : std::strtod(run.c_str() + colon + 1, nullptr);
    Counts c;
    std::vector<double> q(nq), u(nv);
    int done = 0;
    bool ok = true;
    double cpu = NAN;
    if (method == "mujoco-rk4" && setting >= 1) {
      long const steps = long(setting);
      m->opt.integrator = mjINT_RK4;
      m->opt.timestep = t_end / double(steps);
      cpu = median_time(reps, budget, [&] {
        mj_resetData(m, d);
        mju_copy(d->qpos, q0.data(), nq);
        mju_copy(d->qvel, u0.data(), nv);
        for (long k = 0; k < steps; ++k) mj_step(m, d);
        keep(d->qpos);
        return std::isfinite(d->qpos[0]);
      }, done, ok);
      c.steps = c.accepted = steps;
      c.rhs = 4 * steps;  // mj_forward, then three more stages in mj_RungeKutta
      mju_copy(q.data(), d->qpos, nq);
      mju_copy(u.data(), d->qvel, nv);
      std::printf("{\"method\":\"mujoco-rk4\",\"steps\":%ld,\"dt\":%.17g,\"t\":%.17g,", steps,
                  m->opt.timestep, d->time);
    } else if (method == "pinocchio-dop853" && setting > 0) {
      Vec const zero = Vec::Zero(nv);
      auto rhs = [&](double, Vec const& y, Vec& dy) {
        dy.head(nq) = y.tail(nv);  // revolute joints only: q̇ = v
        pinocchio::aba(model, data, y.head(nq), y.tail(nv), zero);
        dy.tail(nv) = data.ddq;
      };
      Vec y(nq + nv);
      cpu = median_time(reps, budget, [&] {
        for (int i = 0; i < nq; ++i) y[i] = q0[i];
        for (int i = 0; i < nv; ++i) y[nq + i] = u0[i];
        c = Counts{};
        bool const good = dop853(rhs, 0.0, t_end, y, setting, setting, c);
        keep(y.data());
        return good;
      }, done, ok);
      for (int i = 0; i < nq; ++i) q[i] = y[i];
      for (int i = 0; i < nv; ++i) u[i] = y[nq + i];
      std::printf("{\"method\":\"pinocchio-dop853\",\"rtol\":%.17g,\"atol\":%.17g,\"t\":%.17g,",
                  setting, setting, t_end);
    } else {
      std::fprintf(stderr, "unknown run %s (mujoco-rk4:STEPS, pinocchio-dop853:TOL)\n", run.c_str());
      return 2;
    }
    std::printf(
        "\"ok\":%s,\"accepted\":%ld,\"rejected\":%ld,\"rhs_evals\":%ld,\"cpu_s\":%.9g,\"reps\":%d,"
        "\"q\":%s,\"u\":%s,\"pinocchio_version\":\"%s\",\"mujoco_version\":\"%s\"}\n",
        ok ? "true" : "false", c.accepted, c.rejected, c.rhs, cpu, done,
        json(q.data(), nq).c_str(), json(u.data(), nv).c_str(), PINOCCHIO_VERSION,
        mj_versionString());
    std::fflush(stdout);
  }
  mj_deleteData(d);
  mj_deleteModel(m);
  return 0;
}
