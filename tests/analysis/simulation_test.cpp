// Exams of whole simulations against closed forms (Appell's particle; the sled on a horizontal
// plane) and consistency checks along solutions (formulations agree, energy is conserved, the
// paper's reduced equations hold, residuals sit where the error relation says).
#include "nhdyn/analysis/simulation.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "nhdyn/core/error.hpp"
#include "nhdyn/model/appell.hpp"
#include "nhdyn/model/sled.hpp"
#include "support/test_models.hpp"

namespace nhdyn {
namespace {

struct Row {
  double t;
  Vector q, v, qdd, R, f, e;
  double energy;
};

std::vector<Row> run(const Model& model, const SimulationOptions& options, SimulationSummary* summary = nullptr) {
  std::vector<Row> rows;
  const SimulationSummary s = simulate(model, options, [&](const Data& d) {
    rows.push_back({d.t, d.q, d.v, d.qdd, d.R, d.f, d.e, d.energy});
  });
  EXPECT_EQ(s.status, Status::ok) << s.message;
  if (summary) *summary = s;
  return rows;
}

SimulationOptions tight(double t_end, Formulation method = Formulation::sanh, Complement complement = Complement::qr,
                        IntegratorKind kind = IntegratorKind::dopri5) {
  SimulationOptions o;
  o.t_end = t_end;
  o.output_step = 0.05;
  o.formulation = {method, complement};
  o.integrator.kind = kind;
  o.integrator.rtol = 1e-11;
  o.integrator.atol = 1e-12;
  return o;
}

// docs/derivations/appell.md: horizontal direction e fixed, speed u = u0 + c t, c = g a/(1+a^2),
// q(t) = q0 + (u0 t + c t^2/2) (e_x, e_y, a); R = m g/(1+a^2) (a e_x, a e_y, -1).
TEST(AppellExam, MatchesTheClosedFormAtTenSecondsForEveryFormulation) {
  AppellParameters p;
  const Model model = make_appell_model(p);
  const double u0 = std::hypot(model.v0(0), model.v0(1));
  const double ex = model.v0(0) / u0, ey = model.v0(1) / u0;
  const double c = p.g * p.a / (1.0 + p.a * p.a);
  for (Formulation m : {Formulation::sanh, Formulation::lagrange, Formulation::udwadia_kalaba, Formulation::nullspace}) {
    SimulationSummary summary;
    const std::vector<Row> rows = run(model, tight(10.0, m), &summary);
    ASSERT_FALSE(rows.empty());
    for (const Row& r : rows) {
      const double s = u0 * r.t + 0.5 * c * r.t * r.t;
      const double u = u0 + c * r.t;
      Vector q(3), v(3), R(3);
      q << s * ex, s * ey, s * p.a;
      v << u * ex, u * ey, u * p.a;
      R << p.a * ex, p.a * ey, -1.0;
      R *= p.m * p.g / (1.0 + p.a * p.a);
      EXPECT_LT((r.q - q).norm(), 1e-9 * q.norm() + 1e-12) << formulation_name(m) << " t=" << r.t;
      EXPECT_LT((r.v - v).norm(), 1e-9 * v.norm()) << formulation_name(m) << " t=" << r.t;
      EXPECT_LT((r.R - R).norm(), 1e-9 * R.norm()) << formulation_name(m) << " t=" << r.t;
      EXPECT_LT(std::abs(r.energy - rows.front().energy), 1e-9 * (1.0 + std::abs(r.energy))) << formulation_name(m);
    }
    EXPECT_DOUBLE_EQ(rows.back().t, 10.0);
    EXPECT_LT(summary.residuals.acceleration, 1e-12);
  }
}

// docs/derivations/sled.md, alpha = 0: psi(t) = 2 atan(tan(psi0/2) e^(-beta t)),
// phi = phi0 + (rho/a)(psi - psi0), v = K cos psi, phi' = -(K/rho) sin psi.
TEST(SledExam, HorizontalPlaneMatchesTheClosedForm) {
  SledParameters p;
  p.alpha = 0.0;
  p.a = 0.4;
  p.rho = 0.7;
  Model model = make_sled_model(SledVariant::centre_of_mass, p);
  const double phi0 = 0.4, u0 = 0.8, w0 = -2.5;
  model.q0 << 0.0, 0.0, phi0;
  model.v0 << u0 * std::cos(phi0), u0 * std::sin(phi0), w0;
  const double K = std::sqrt(u0 * u0 + p.rho * p.rho * w0 * w0);
  const double psi0 = std::atan2(-p.rho * w0, u0);
  const double beta = K * p.a / (p.rho * p.rho);
  for (IntegratorKind kind : {IntegratorKind::dopri5, IntegratorKind::cvode_bdf, IntegratorKind::cvode_adams}) {
    SimulationOptions o = tight(8.0, Formulation::sanh, Complement::qr, kind);
    const std::vector<Row> rows = run(model, o);
    double worst = 0.0;
    for (const Row& r : rows) {
      const double psi = 2.0 * std::atan(std::tan(psi0 / 2.0) * std::exp(-beta * r.t));
      const double phi = phi0 + (p.rho / p.a) * (psi - psi0);
      const double u = K * std::cos(psi), w = -(K / p.rho) * std::sin(psi);
      const double u_num = std::cos(r.q(2)) * r.v(0) + std::sin(r.q(2)) * r.v(1);
      worst = std::max({worst, std::abs(r.q(2) - phi), std::abs(u_num - u), std::abs(r.v(2) - w)});
    }
    EXPECT_LT(worst, 1e-7) << integrator_name(kind);
    // The closed form moves: the heading turns by more than a radian over the run.
    EXPECT_GT(std::abs(rows.back().q(2) - phi0), 1.0);
  }
}

TEST(SledConsistency, FormulationsAndComplementsGiveTheSameTrajectory) {
  const Model model = make_sled_model();
  const std::vector<Row> reference = run(model, tight(5.0));
  for (Formulation m : {Formulation::sanh, Formulation::lagrange, Formulation::udwadia_kalaba, Formulation::nullspace})
    for (Complement c : {Complement::qr, Complement::partition, Complement::analytic}) {
      if ((m == Formulation::lagrange || m == Formulation::udwadia_kalaba) && c != Complement::qr) continue;
      const std::vector<Row> rows = run(model, tight(5.0, m, c));
      ASSERT_EQ(rows.size(), reference.size());
      for (std::size_t i = 0; i < rows.size(); ++i) {
        EXPECT_LT((rows[i].q - reference[i].q).norm(), 1e-8) << formulation_name(m) << "/" << complement_name(c);
        EXPECT_LT((rows[i].R - reference[i].R).norm(), 1e-7) << formulation_name(m) << "/" << complement_name(c);
      }
    }
}

TEST(SledConsistency, EnergyIsConservedAndResidualsFollowTheErrorRelation) {
  for (SledVariant variant : {SledVariant::centre_of_mass, SledVariant::paper}) {
    const Model model = make_sled_model(variant);
    SimulationSummary summary;
    const std::vector<Row> rows = run(model, tight(10.0), &summary);
    EXPECT_LT(summary.energy.drift, 1e-8 * (1.0 + std::abs(summary.energy.initial))) << model.name;
    // Acceleration level: part of the solved system, round-off. Velocity level: the integration
    // error, small at this tolerance but not round-off.
    EXPECT_LT(summary.residuals.acceleration, 1e-12) << model.name;
    EXPECT_LT(summary.residuals.velocity, 1e-8) << model.name;
    // The sled moves: it has travelled down the slope.
    EXPECT_GT(rows.back().q(0), 10.0) << model.name;
  }
}

TEST(SledConsistency, ThePapersReducedEquationsHoldAlongTheSolution) {
  SledParameters p;
  const Model model = make_sled_model(SledVariant::paper, p);
  const std::vector<Row> rows = run(model, tight(10.0));
  for (const Row& r : rows) {
    const double phi = r.q(2), w = r.v(2);
    ASSERT_LT(std::abs(phi), 1.5);
    const double eq1 = p.m * r.qdd(0) + p.m * std::tan(phi) * r.qdd(1) -
                       (p.m * p.g * std::sin(p.alpha) + p.m * p.a * w * w / std::cos(phi));
    const double eq2 = -p.m * p.a * std::sin(phi) * r.qdd(0) + p.m * p.a * std::cos(phi) * r.qdd(1) +
                       p.m * p.rho * p.rho * r.qdd(2);
    EXPECT_LT(std::abs(eq1), 1e-10) << "t=" << r.t;
    EXPECT_LT(std::abs(eq2), 1e-10) << "t=" << r.t;
    EXPECT_LT(std::abs(r.v(1) - std::tan(phi) * r.v(0)), 1e-8) << "t=" << r.t;
  }
}

TEST(SimulationInput, BadTimesAndTolerancesAreRefusedWithTheValue) {
  const Model model = make_sled_model();
  SimulationOptions o;
  o.t_end = -1.0;
  EXPECT_THROW(simulate(model, o, [](const Data&) {}), InputError);
  o.t_end = 1.0;
  o.output_step = 0.0;
  EXPECT_THROW(simulate(model, o, [](const Data&) {}), InputError);
  o.output_step = 0.1;
  o.integrator.rtol = -1e-6;
  try {
    simulate(model, o, [](const Data&) {});
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("-1e-06"), std::string::npos) << e.what();
  }
  o.integrator.rtol = 1e-8;
  o.integrator.atol = std::nan("");
  EXPECT_THROW(simulate(model, o, [](const Data&) {}), InputError);
}

TEST(SimulationFailure, ARunThatHitsANonFiniteForceStopsWithWhereAndWhy) {
  const Model model = testing::make_blowup_model(1.5);
  for (IntegratorKind kind : {IntegratorKind::rk4, IntegratorKind::dopri5, IntegratorKind::cvode_bdf}) {
    SimulationOptions o;
    o.t_end = 3.0;
    o.output_step = 0.1;
    o.integrator.kind = kind;
    long rows = 0;
    const SimulationSummary s = simulate(model, o, [&](const Data&) { ++rows; });
    EXPECT_EQ(s.status, Status::non_finite) << integrator_name(kind);
    EXPECT_LE(s.t_reached, 1.5) << integrator_name(kind);
    EXPECT_GT(s.t_reached, 1.3) << integrator_name(kind);
    EXPECT_NE(s.message.find("generalized forces Q"), std::string::npos) << s.message;
    EXPECT_LE(rows, 16);
  }
}

TEST(OutputTimes, EndExactlyAtTheEndTime) {
  const std::vector<double> t = make_output_times(0.0, 1.0, 0.3);
  ASSERT_EQ(t.size(), 5u);
  EXPECT_DOUBLE_EQ(t[3], 0.9);
  EXPECT_DOUBLE_EQ(t.back(), 1.0);
  EXPECT_EQ(make_output_times(0.0, 1.0, 0.1).size(), 11u);
  EXPECT_THROW(make_output_times(0.0, 1e9, 1e-9), InputError);
  // A run much shorter than its output step keeps its start row: 1e-9 of the step (1e-11) merged
  // the row of t0 into t_end's at t_end = 1e-13.
  EXPECT_EQ(make_output_times(0.0, 1e-13, 0.01), (std::vector<double>{0.0, 1e-13}));
  // A run shorter than the times nhdyn tells apart failed as a step size underflow.
  try {
    make_output_times(0.0, 5e-324, 0.01);
    ADD_FAILURE() << "t_end = 5e-324 accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("closer than nhdyn tells times apart"), std::string::npos) << e.what();
  }
}

// Given output times that all sit on the start leave no interval to integrate: the library refuses
// them as the command line and Python do, naming the last time and t0.
TEST(OutputTimes, GivenTimesMustEndAfterTheStart) {
  const Model model = make_sled_model();
  SimulationOptions o;
  o.output_times = {model.t0};
  try {
    check_simulation_options(model, o);
    ADD_FAILURE() << "output times {t0} accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("the last output time 0 must be after the model's start time t0 = 0"),
              std::string::npos)
        << e.what();
  }
  o.output_times = {model.t0, model.t0 + 0.5};
  o.t_end = 0.5;
  EXPECT_NO_THROW(check_simulation_options(model, o));
}

// Rows closer than the resolution of time are one row (an event at an output time): output times
// or an output step that close would lose rows silently, so they are refused.
TEST(OutputTimes, TimesCloserThanTheResolutionAreRefused) {
  const Model model = make_sled_model();
  SimulationOptions o;
  o.output_times = {0.0, 1e-300};
  o.t_end = 1e-300;
  EXPECT_THROW(check_simulation_options(model, o), InputError);
  o.output_times = {0.0, 0.5, 0.5 + 1e-17};
  o.t_end = 1.0;
  EXPECT_THROW(check_simulation_options(model, o), InputError);
  o.output_times = {0.0, 0.5, 0.5 + 1e-12};
  EXPECT_NO_THROW(check_simulation_options(model, o));
  EXPECT_THROW(make_output_times(1e6, 1e6 + 1e-9, 1e-12), InputError);
  EXPECT_NO_THROW(make_output_times(1e6, 1e6 + 1e-6, 1e-7));
  // A first time just after t0 merges with nothing (the start is then no row).
  o.output_times = {1e-15, 0.5};
  o.t_end = 0.5;
  EXPECT_NO_THROW(check_simulation_options(model, o));
  // A grid whose last time falls within the resolution of t_end ends at t_end itself, one row.
  const std::vector<double> grid = make_output_times(1e5, 1e5 + 1.000000001, 0.1);
  EXPECT_EQ(grid.size(), 11u);
  EXPECT_EQ(grid.back(), 1e5 + 1.000000001);
}

}  // namespace
}  // namespace nhdyn
