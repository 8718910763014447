// Hand-written references for the cost of one acceleration solve, on the models and states of
// bench_cases.hpp, to put nhdyn's kernels (acceleration_bench.cpp) in proportion:
//   reference/<model>/closed_form       the final equations in closed form, plain doubles:
//                                       q'' from docs/derivations/sled.md section 7.1 (regular
//                                       constraint form) or docs/derivations/appell.md (2.1) (valid
//                                       off the constraint too), then R = A q'' - Q - G
//   reference/<model>/stacked_matrix3d  the Do Sanh stacked system [D A; b] q'' = [D (Q + G); -b0]
//                                       with fixed-size Eigen (Matrix3d, analytic D, the model's own
//                                       form of b and b0), solved by Matrix3d::partialPivLu, then R:
//                                       "the hand-written C++ right-hand side (stacked solve)"
// Each reference is one function taking (q, q') and returning q'' and R, as an integrator would
// call a hand-written right-hand side; it is kept out of line so that, like nhdyn's kernels, it is
// paid as a call. Constants of the model (g sin(alpha), rho^2, ...) are computed once, as a
// hand-written right-hand side would. Before the first timing, every reference is checked against
// nhdyn's sanh (every choice of D) and against the values printed in the derivations; a
// disagreement beyond 1e-12 aborts the program. Results: docs/performance.md.
#include <benchmark/benchmark.h>

#include <Eigen/Dense>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>

#include "bench_cases.hpp"
#include "nhdyn/formulation/formulation.hpp"
#include "nhdyn/model/data.hpp"

namespace nhdyn::bench {
namespace {

struct Result {
  std::array<double, 3> qdd;
  std::array<double, 3> R;
};

// --- constants computed once per model --------------------------------------------------------

struct SledConstants {
  double m, a, rho2, gs;  // gs = g sin(alpha)
  bool centre_of_mass;
};

SledConstants sled_constants(bool centre_of_mass) {
  const SledParameters p = sled_parameters();
  return {p.m, p.a, p.rho * p.rho, p.g * std::sin(p.alpha), centre_of_mass};
}

struct AppellConstants {
  double m, g, a2;  // a2 = a^2
};

AppellConstants appell_constants() {
  const AppellParameters p = appell_parameters();
  return {p.m, p.g, p.a * p.a};
}

// --- (a) closed forms ---------------------------------------------------------------------------

// docs/derivations/sled.md 7.1: exact for any state with the regular form of the constraint; on
// the constraint also the paper form's solution (7.3). Potential of the centre of mass or the
// paper's.
[[gnu::noinline]] void sled_closed_form(const SledConstants& k, const double* q, const double* v, Result& out) {
  const double s = std::sin(q[2]), c = std::cos(q[2]);
  const double w = v[2];
  const double speed = c * v[0] + s * v[1];    // along the blade
  const double P = k.gs * c + k.a * w * w;     // longitudinal acceleration of the contact point
  const double S = speed * w;                  // lateral acceleration of the contact point
  const double torque = k.centre_of_mass ? k.gs * s : 0.0;
  const double xdd = c * P - s * S;
  const double ydd = s * P + c * S;
  const double phidd = -(k.a / k.rho2) * (torque + S);
  out.qdd = {xdd, ydd, phidd};
  // R = A q'' - Q - G with A, Q, G of sled.md sections 1-3.
  const double ma = k.m * k.a;
  out.R[0] = k.m * xdd - ma * s * phidd - k.m * k.gs - ma * c * w * w;
  out.R[1] = k.m * ydd + ma * c * phidd - ma * s * w * w;
  out.R[2] = -ma * s * xdd + ma * c * ydd + k.m * k.rho2 * phidd + k.m * torque * k.a;
}

// docs/derivations/appell.md (2.1): exact for any state with z' != 0.
[[gnu::noinline]] void appell_closed_form(const AppellConstants& k, const double* v, Result& out) {
  const double u2 = v[0] * v[0] + v[1] * v[1];
  const double N = k.a2 * k.a2 * u2 + v[2] * v[2];
  const double f = k.g * k.a2 / N;
  out.qdd = {f * v[0] * v[2], f * v[1] * v[2], f * k.a2 * u2};
  // A = m I, Q = (0, 0, m g), G = 0.
  out.R = {k.m * out.qdd[0], k.m * out.qdd[1], k.m * out.qdd[2] - k.m * k.g};
}

// --- (b) stacked solves with fixed-size Eigen ---------------------------------------------------

using Matrix23 = Eigen::Matrix<double, 2, 3>;

// [D A; b] q'' = [D h; -b0] by partial-pivoting LU, then R = A q'' - h (h = Q + G).
inline void solve_stacked(const Eigen::Matrix3d& A, const Eigen::Vector3d& h, const Matrix23& D,
                          const Eigen::RowVector3d& b, double b0, Result& out) {
  Eigen::Matrix3d M;
  M.topRows<2>().noalias() = D * A;
  M.row(2) = b;
  Eigen::Vector3d rhs;
  rhs.head<2>().noalias() = D * h;
  rhs(2) = -b0;
  Eigen::Map<Eigen::Vector3d> qdd(out.qdd.data());
  Eigen::Map<Eigen::Vector3d> R(out.R.data());
  qdd = M.partialPivLu().solve(rhs);
  R.noalias() = A * qdd;
  R -= h;
}

// The terms of sled.cpp, written again by hand (sled.md sections 1-5).
[[gnu::noinline]] void sled_stacked(const SledConstants& k, const double* q, const double* v, Result& out) {
  const double s = std::sin(q[2]), c = std::cos(q[2]);
  const double w = v[2];
  const double ma = k.m * k.a;
  Eigen::Matrix3d A;
  A << k.m, 0.0, -ma * s,
       0.0, k.m, ma * c,
       -ma * s, ma * c, k.m * k.rho2;
  const Eigen::Vector3d h(k.m * k.gs + ma * c * w * w, ma * s * w * w,
                          k.centre_of_mass ? -k.m * k.gs * k.a * s : 0.0);
  Matrix23 D;
  Eigen::RowVector3d b;
  double b0;
  if (k.centre_of_mass) {  // regular form -sin(phi) x' + cos(phi) y' = 0
    D << c, s, 0.0,
         0.0, 0.0, 1.0;
    b << -s, c, 0.0;
    b0 = -(c * v[0] + s * v[1]) * w;
  } else {  // the paper's form y' - tan(phi) x' = 0
    const double t = s / c;
    D << 1.0, t, 0.0,
         0.0, 0.0, 1.0;
    b << -t, 1.0, 0.0;
    b0 = -v[0] * w / (c * c);
  }
  solve_stacked(A, h, D, b, b0, out);
}

// The paper's acceleration form z'' - (a^2/z') (x' x'' + y' y'') = 0 and analytic D (appell.cpp).
[[gnu::noinline]] void appell_stacked(const AppellConstants& k, const double* v, Result& out) {
  const double r = k.a2 / v[2];
  const Eigen::Matrix3d A = k.m * Eigen::Matrix3d::Identity();
  const Eigen::Vector3d h(0.0, 0.0, k.m * k.g);
  Matrix23 D;
  D << 1.0, 0.0, r * v[0],
       0.0, 1.0, r * v[1];
  const Eigen::RowVector3d b(-r * v[0], -r * v[1], 1.0);
  solve_stacked(A, h, D, b, 0.0, out);
}

Result closed_form(ModelId id, const State& x) {
  Result out{};
  if (id == ModelId::appell)
    appell_closed_form(appell_constants(), x.v.data(), out);
  else
    sled_closed_form(sled_constants(id == ModelId::sled), x.q.data(), x.v.data(), out);
  return out;
}

Result stacked(ModelId id, const State& x) {
  Result out{};
  if (id == ModelId::appell)
    appell_stacked(appell_constants(), x.v.data(), out);
  else
    sled_stacked(sled_constants(id == ModelId::sled), x.q.data(), x.v.data(), out);
  return out;
}

// --- verification, once, before any timing ------------------------------------------------------

constexpr double tolerance = 1e-12;

double max_difference(const double* x, const double* y) {
  double d = 0.0;
  for (int i = 0; i < 3; ++i) d = std::fmax(d, std::fabs(x[i] - y[i]));
  return d;
}

void check(bool ok, const char* what, ModelId id, double difference) {
  if (ok) return;
  std::fprintf(stderr,
               "nhdyn_bench: %s disagree on model '%s' at the benchmark state: max |difference| = %.3e "
               "> %.0e. The references in bench/reference_bench.cpp no longer match nhdyn; fix before "
               "timing.\n",
               what, model_name(id).c_str(), difference, tolerance);
  std::abort();
}

void verify_references() {
  for (ModelId id : all_models()) {
    const Model model = make_bench_model(id);
    Data data = make_data(model);
    const State x = bench_state(id);
    const Result closed = closed_form(id, x);
    const Result stack = stacked(id, x);
    const std::array<double, 3> published = published_qdd(id);
    double d = max_difference(closed.qdd.data(), published.data());
    check(d <= tolerance, "closed-form q'' and the value printed in docs/derivations", id, d);
    for (Complement complement : {Complement::qr, Complement::partition, Complement::analytic}) {
      const Status status =
          compute_dynamics(model, data, {Formulation::sanh, complement}, 0.0, x.q.data(), x.v.data());
      check(status == Status::ok, "sanh failed; its status and the references", id, 0.0);
      d = max_difference(closed.qdd.data(), data.qdd.data());
      check(d <= tolerance, "closed-form q'' and nhdyn's sanh", id, d);
      d = max_difference(stack.qdd.data(), data.qdd.data());
      check(d <= tolerance, "stacked Matrix3d q'' and nhdyn's sanh", id, d);
      d = max_difference(closed.R.data(), data.R.data());
      check(d <= tolerance, "closed-form R and nhdyn's sanh", id, d);
      d = max_difference(stack.R.data(), data.R.data());
      check(d <= tolerance, "stacked Matrix3d R and nhdyn's sanh", id, d);
    }
  }
}

void verify_once() {
  static const bool verified = (verify_references(), true);
  (void)verified;
}

// --- the benchmarks -----------------------------------------------------------------------------

template <class Reference>
void run(benchmark::State& state, ModelId id, Reference reference) {
  verify_once();
  State x = bench_state(id);
  Result out{};
  for (auto _ : state) {
    benchmark::DoNotOptimize(x);  // the state may have changed: nothing is hoisted out of the loop
    reference(x, out);
    benchmark::DoNotOptimize(out);
  }
}

void bench_closed_form(benchmark::State& state, ModelId id) {
  if (id == ModelId::appell) {
    const AppellConstants k = appell_constants();
    run(state, id, [&k](const State& x, Result& out) { appell_closed_form(k, x.v.data(), out); });
  } else {
    const SledConstants k = sled_constants(id == ModelId::sled);
    run(state, id, [&k](const State& x, Result& out) { sled_closed_form(k, x.q.data(), x.v.data(), out); });
  }
}

void bench_stacked(benchmark::State& state, ModelId id) {
  if (id == ModelId::appell) {
    const AppellConstants k = appell_constants();
    run(state, id, [&k](const State& x, Result& out) { appell_stacked(k, x.v.data(), out); });
  } else {
    const SledConstants k = sled_constants(id == ModelId::sled);
    run(state, id, [&k](const State& x, Result& out) { sled_stacked(k, x.q.data(), x.v.data(), out); });
  }
}

const bool registered = [] {
  for (ModelId id : all_models()) {
    benchmark::RegisterBenchmark(("reference/" + model_name(id) + "/closed_form").c_str(), bench_closed_form, id);
    benchmark::RegisterBenchmark(("reference/" + model_name(id) + "/stacked_matrix3d").c_str(), bench_stacked,
                                 id);
  }
  return true;
}();

}  // namespace
}  // namespace nhdyn::bench
