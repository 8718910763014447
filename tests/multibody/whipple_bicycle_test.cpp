// Exam: the Whipple bicycle built from its bodies (examples/whipple_bicycle.toml) against the
// linearized equations of the benchmark of Meijaard, Papadopoulos, Ruina and Schwab (Proc. R. Soc.
// A 463, 2007, eq. (A 21)-(A 24)): about the upright straight motion at speed v,
//
//     M [phi'', delta'']^T + v C1 [phi', delta']^T + (g K0 + v^2 K2) [phi, delta]^T = 0,
//
// with their published matrices. The nonlinear model's reduced accelerations are differentiated by
// central differences at states that satisfy every constraint (pitch from the front contact, the
// dependent velocities from the rolling constraints). Then a run at 5 m/s (inside the stable speed
// range, about 4.3 to 6.0 m/s) with a roll-rate kick: the lean decays, the constraints hold and
// T + V is conserved; at 2 m/s (below the weave speed) the same kick grows.
#include <gtest/gtest.h>

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "multibody/multibody_support.hpp"
#include "nhdyn/analysis/simulation.hpp"
#include "nhdyn/frontend/model_file.hpp"
#include "nhdyn/symbolic/compile.hpp"
#include "support/text.hpp"

namespace nhdyn::multibody_test {
namespace {

using nhdyn::test::example;

// Loaded and compiled once: the derivation is the slow part.
struct Bicycle {
  symbolic::Spec spec = load_model_file(example("whipple_bicycle.toml"));
  Model model = symbolic::compile_model(spec);
};
const Bicycle& bicycle() {
  static const Bicycle b;
  return b;
}

// Coordinates: x y psi phi theta delta thetaR thetaF.
constexpr int kPhi = 3, kTheta = 4, kDelta = 5, kThetaR = 6;

// A state with roll phi, steer delta, their rates, rolling at speed v: theta solves the front
// contact constraint (Newton), the other velocities solve b v = 0 given phi', delta', thetaR'.
void consistent_state(double phi, double delta, double phid, double deltad, double v, std::vector<double>& q,
                      std::vector<double>& qd) {
  const Bicycle& bike = bicycle();
  q.assign(8, 0.0);
  q[kPhi] = phi;
  q[kDelta] = delta;
  const symbolic::SpecConstraint* contact = nullptr;
  for (const auto& c : bike.spec.constraints)
    if (c.name == "front_contact") contact = &c;
  EXPECT_NE(contact, nullptr);
  const std::vector<double> zero(8, 0.0);
  for (int it = 0; it < 30; ++it) {
    const double f = evaluate(bike.spec, contact->expression, q, zero);
    if (std::abs(f) < 1e-16) break;
    std::vector<double> qh = q;
    qh[kTheta] += 1e-7;
    const double df = (evaluate(bike.spec, contact->expression, qh, zero) - f) / 1e-7;
    q[kTheta] -= f / df;
  }
  Data data = make_data(bike.model);
  qd.assign(8, 0.0);
  EXPECT_EQ(compute_terms(bike.model, data, 0.0, q.data(), qd.data()), Status::ok);
  const int independent[3] = {kPhi, kDelta, kThetaR};
  const int dependent[5] = {0, 1, 2, kTheta, 7};
  Eigen::Matrix<double, 5, 5> bd;
  Eigen::Matrix<double, 5, 1> rhs;
  const double given[3] = {phid, deltad, -v / 0.3};
  for (int r = 0; r < 5; ++r) {
    for (int c = 0; c < 5; ++c) bd(r, c) = data.b(r, dependent[c]);
    rhs(r) = 0.0;
    for (int c = 0; c < 3; ++c) rhs(r) -= data.b(r, independent[c]) * given[c];
  }
  const Eigen::Matrix<double, 5, 1> vd = bd.partialPivLu().solve(rhs);
  for (int c = 0; c < 3; ++c) qd[static_cast<std::size_t>(independent[c])] = given[c];
  for (int c = 0; c < 5; ++c) qd[static_cast<std::size_t>(dependent[c])] = vd(c);
}

// (phi'', delta'') at the state above.
Eigen::Vector2d lateral_accelerations(const Eigen::Vector4d& x, double v) {
  std::vector<double> q, qd;
  consistent_state(x(0), x(1), x(2), x(3), v, q, qd);
  const Data d = dynamics_at(bicycle().model, q, qd);
  return {d.qdd(kPhi), d.qdd(kDelta)};
}

TEST(WhippleBicycle, LinearizedAboutUprightMotionMatchesTheBenchmark) {
  // The benchmark's matrices for its parameters (Meijaard et al. 2007, section 4).
  Eigen::Matrix2d M, C1, K0, K2;
  M << 80.81722, 2.31941332208709, 2.31941332208709, 0.29784188199686;
  C1 << 0.0, 33.86641391492494, -0.85035641456978, 1.68540397397560;
  K0 << -80.95, -2.59951685249872, -2.59951685249872, -0.80329488458618;
  K2 << 0.0, 76.59734589573222, 0.0, 2.65431523794604;
  const double g = 9.81;
  for (const double v : {5.0, 3.0}) {
    const Eigen::Matrix2d Jq = -M.inverse() * (g * K0 + v * v * K2);
    const Eigen::Matrix2d Jv = -M.inverse() * (v * C1);
    Eigen::Matrix<double, 2, 4> J;
    const double h = 1e-5;
    for (int k = 0; k < 4; ++k) {
      Eigen::Vector4d plus = Eigen::Vector4d::Zero(), minus = Eigen::Vector4d::Zero();
      plus(k) = h;
      minus(k) = -h;
      J.col(k) = (lateral_accelerations(plus, v) - lateral_accelerations(minus, v)) / (2 * h);
    }
    Eigen::Matrix<double, 2, 4> expected;
    expected << Jq, Jv;
    const double scale = expected.cwiseAbs().maxCoeff();
    EXPECT_LT((J - expected).cwiseAbs().maxCoeff(), 1e-7 * scale) << "v = " << v << "\n" << J << "\nvs\n" << expected;
    // Upright straight motion is an equilibrium.
    EXPECT_LT(lateral_accelerations(Eigen::Vector4d::Zero(), v).norm(), 1e-12);
  }
}

// The roll angle after a roll-rate kick of 0.5 rad/s from upright straight motion at speed v:
// the largest |phi| over the first second and over the last second of the run.
struct KickRun {
  double early_phi = 0.0, late_phi = 0.0, max_phi = 0.0, max_residual = 0.0, drift = 0.0;
};

KickRun kick(double v, double t_end) {
  const Bicycle& bike = bicycle();
  symbolic::Spec spec = bike.spec;
  spec.set_parameter("v", v);            // the initial velocities are expressions in v
  spec.v0[kPhi] = GiNaC::numeric(1, 2);  // phi' = 0.5 rad/s: consistent with rolling at the upright state
  const Model model = symbolic::compile_model(spec);
  SimulationOptions options;
  options.t_end = t_end;
  options.output_step = 0.05;
  options.formulation = {Formulation::sanh, Complement::qr};
  options.integrator.kind = IntegratorKind::dopri5;
  options.integrator.rtol = 1e-9;
  options.integrator.atol = 1e-11;
  KickRun run;
  double E0 = 0.0;
  const SimulationSummary summary = simulate(model, options, [&](const Data& d) {
    if (d.t == 0.0) E0 = d.energy;
    const double phi = std::abs(d.q(kPhi));
    run.max_phi = std::max(run.max_phi, phi);
    if (d.t <= 1.0) run.early_phi = std::max(run.early_phi, phi);
    if (d.t >= t_end - 1.0) run.late_phi = std::max(run.late_phi, phi);
    run.drift = std::max(run.drift, std::abs(d.energy - E0) / std::abs(E0));
    for (Eigen::Index i = 0; i < d.f.size(); ++i) run.max_residual = std::max(run.max_residual, std::abs(d.f(i)));
    for (Eigen::Index i = 0; i < d.phi.size(); ++i)
      run.max_residual = std::max(run.max_residual, std::abs(d.phi(i)));
  });
  EXPECT_EQ(summary.status, Status::ok) << summary.message;
  return run;
}

TEST(WhippleBicycle, ARollKickAt5MetresPerSecondDiesOut) {
  const KickRun run = kick(5.0, 5.0);
  EXPECT_GT(run.max_phi, 0.01);                 // the kick did lean it
  EXPECT_LT(run.late_phi, 0.25 * run.max_phi);  // and the lean dies out (self-stable at 5 m/s)
  EXPECT_LT(run.max_residual, 1e-7);
  EXPECT_LT(run.drift, 1e-7);
}

TEST(WhippleBicycle, ARollKickAt2MetresPerSecondGrows) {
  // Below the weave speed (4.29 m/s) the weave mode is unstable (the benchmark's eigenvalues at
  // 2 m/s have a positive real part): the same kick leans it further and further.
  const KickRun run = kick(2.0, 4.0);
  EXPECT_GT(run.late_phi, 2.0 * run.early_phi);
  EXPECT_LT(run.max_residual, 1e-7);
  EXPECT_LT(run.drift, 1e-7);
}

}  // namespace
}  // namespace nhdyn::multibody_test
