// Exams: events on the contact forces (model/event.hpp, Event::contact_forces) through the C++ API.
// The falling disk of docs/derivations/contact-forces.md section 6.4, released at rest at theta0 =
// 0.1, has the normal force N = (m g / 5)(1 - 8 k c + 12 c^2) (k = cos(theta0), c = cos(theta)),
// which falls through zero at cos(theta*) = (2 k + sqrt(4 k^2 - 3)) / 6 and comes back at the
// other root; on the way the lean rate follows r theta'^2 = (8 g / 5)(k - c). The located crossings
// of disk_N (a model file's [[events]], --event, --stop-when) must be those roots to the accuracy
// of the integration, and the disk_N of the event's row zero to round-off. Bad input: contact
// columns in a model without contacts, a contact force the model does not determine (NaN by
// design), an output that reads a contact force.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "nhdyn/analysis/simulation.hpp"
#include "nhdyn/core/error.hpp"
#include "nhdyn/frontend/load_model.hpp"
#include "nhdyn/model/contact_forces.hpp"
#include "nhdyn/symbolic/events.hpp"
#include "support/models.hpp"
#include "support/text.hpp"

namespace nhdyn::multibody_test {
namespace {

using nhdyn::test::example;

// The closed forms of section 6.4 for the disk at rest at theta0 (m, g, r of the example file).
struct LiftoffClosedForm {
  double m = 0.5, r = 0.2, g = 9.81, theta0 = 0.1;
  double k() const { return std::cos(theta0); }
  double N(double theta) const {
    const double c = std::cos(theta);
    return m * g / 5 * (1 - 8 * k() * c + 12 * c * c);
  }
  // theta where N = fraction * m g, on the way down (the larger cos): 12 c^2 - 8 k c + 1 - 5 fraction = 0.
  double theta_at(double fraction, bool first = true) const {
    const double root = std::sqrt(64 * k() * k() - 48 * (1 - 5 * fraction));
    return std::acos((8 * k() + (first ? root : -root)) / 24);
  }
  double theta_rate(double theta) const { return std::sqrt(8 * g / (5 * r) * (k() - std::cos(theta))); }
};

// The integration tolerance of these runs. Each crossing is found to a few ulps of the step's
// fraction on the continuous extension, and disk_N is computed from the state to round-off, so
// the located state is as accurate as the solution itself: a global error of a modest multiple of
// rtol (the fall takes ~70 steps of a smooth motion). 100 rtol = 1e-9 rad bounds it with room,
// and is far below what a wrong root (a shifted N, a wrong direction, a linear interpolation
// between rows: 2e-5) would give.
constexpr double kLiftoffRtol = 1e-11;
constexpr double kLiftoffAtol = 1e-12;
constexpr double kLiftoffTolerance = 100 * kLiftoffRtol;

SimulationOptions liftoff_options(const Model& model) {
  SimulationOptions options;
  options.t_end = 0.55;
  options.output_step = 0.01;
  options.integrator.rtol = kLiftoffRtol;
  options.integrator.atol = kLiftoffAtol;
  options.events = model.events;
  return options;
}

TEST(ContactEvents, FileEventStopsTheDiskWhereItsNormalForceVanishes) {
  const Model model = load_model(example("rolling_disk_liftoff.toml"));
  ASSERT_EQ(model.events.size(), 1u);
  const Event& liftoff = model.events.front();
  EXPECT_TRUE(liftoff.contact_forces);
  EXPECT_TRUE(liftoff.dynamics);
  EXPECT_EQ(liftoff.direction, EventDirection::falling);
  const LiftoffClosedForm exact;
  const double theta_star = exact.theta_at(0.0);
  ASSERT_NEAR(theta_star, 1.052986, 5e-7);  // the value of the derivation

  std::vector<double> t_rows, N_rows;
  const SimulationSummary summary = simulate(model, liftoff_options(model), [&](const Data& data) {
    t_rows.push_back(data.t);
    N_rows.push_back(data.contact.values(3));
  });
  ASSERT_EQ(summary.status, Status::ok) << summary.message;
  ASSERT_EQ(summary.events.crossings.size(), 1u);
  EXPECT_EQ(summary.events.stopped_by, 0);
  const EventRecord& e = summary.events.crossings.front();
  EXPECT_EQ(e.name, "liftoff");
  EXPECT_NEAR(e.q[3], theta_star, kLiftoffTolerance);
  EXPECT_NEAR(e.v[3], exact.theta_rate(theta_star), kLiftoffTolerance * exact.theta_rate(theta_star));
  EXPECT_NEAR(e.t, 0.49015, 2e-5);  // the derivation's independent RK4 integration, to its digits
  // The contact point stays put: the disk only topples.
  EXPECT_NEAR(e.q[0], 0.0, 1e-12);
  EXPECT_NEAR(e.q[1], 0.0, 1e-12);
  // The run stopped there, and its last row is the event's: N zero to the resolution of t there
  // (|dN/dt| ~ 30 N/s times a few ulps of t, with round-off of m g), positive before.
  ASSERT_FALSE(t_rows.empty());
  EXPECT_EQ(t_rows.back(), e.t);
  EXPECT_EQ(summary.t_reached, e.t);
  EXPECT_LT(std::abs(N_rows.back()), 1e-12 * exact.m * exact.g) << N_rows.back();
  for (std::size_t i = 0; i + 1 < N_rows.size(); ++i) EXPECT_GT(N_rows[i], 0.0) << "t = " << t_rows[i];
}

TEST(ContactEvents, RecordEventFindsBothRootsAndStopConditionItsThreshold) {
  const Model model = load_model(example("rolling_disk_liftoff.toml"));
  const LiftoffClosedForm exact;
  // --event pull=disk_N: the bilateral contact goes on pulling, and N comes back through zero.
  SimulationOptions options = liftoff_options(model);
  options.events = {symbolic::make_record_event(model, "pull=disk_N")};
  ASSERT_TRUE(options.events.front().contact_forces);
  SimulationSummary summary = simulate(model, options, [](const Data&) {});
  ASSERT_EQ(summary.status, Status::ok) << summary.message;
  ASSERT_EQ(summary.events.crossings.size(), 2u);
  EXPECT_NEAR(summary.events.crossings[0].q[3], exact.theta_at(0.0, true), kLiftoffTolerance);
  EXPECT_NEAR(summary.events.crossings[1].q[3], exact.theta_at(0.0, false), kLiftoffTolerance);
  EXPECT_EQ(summary.t_reached, options.t_end);  // a record event does not stop the run

  // --stop-when "disk_N < m*g/10": an expression of the column and the parameters; N = m g / 10
  // is reached earlier, at 12 c^2 - 8 k c + 1/2 = 0.
  options.events = {symbolic::make_stop_condition(model, "disk_N < m*g/10")};
  summary = simulate(model, options, [](const Data&) {});
  ASSERT_EQ(summary.status, Status::ok) << summary.message;
  ASSERT_EQ(summary.events.crossings.size(), 1u);
  EXPECT_EQ(summary.events.stopped_by, 0);
  const double theta_tenth = exact.theta_at(0.1);
  EXPECT_LT(theta_tenth, exact.theta_at(0.0) - 0.05);  // a different state from the liftoff
  EXPECT_NEAR(summary.events.crossings[0].q[3], theta_tenth, kLiftoffTolerance);
}

// test::kFlatSledBodies, the sled held flat by its frames: its blade's N and Fz are NaN by design,
// its lateral force is determined.
template <typename Error, typename F>
std::string contact_event_error(F&& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.what();
  }
  ADD_FAILURE() << "no error thrown";
  return "";
}

TEST(ContactEvents, UndeterminedOrMissingContactForcesAreRefused) {
  const Model sled = load_model_text(test::kFlatSledBodies, "sled.toml");
  std::string message =
      contact_event_error<InputError>([&] { symbolic::make_stop_condition(sled, "blade_N < 0"); });
  EXPECT_NE(message.find("--stop-when \"blade_N < 0\""), std::string::npos) << message;
  EXPECT_NE(message.find("'blade_N', which model 'sled-bodies' does not determine"), std::string::npos) << message;
  message = contact_event_error<InputError>([&] { symbolic::make_record_event(sled, "up=blade_Fz + 1"); });
  EXPECT_NE(message.find("'blade_Fz'"), std::string::npos) << message;
  // The determined components are accepted.
  EXPECT_TRUE(symbolic::make_record_event(sled, "side=blade_Flat").contact_forces);

  // In the model file: refused at load, with the place of `when`.
  message = contact_event_error<ModelError>([&] {
    load_model_text(std::string(test::kFlatSledBodies) + "\n[[events]]\nname = \"lift\"\nwhen = \"blade_N\"\n", "sled.toml");
  });
  EXPECT_NE(message.find("sled.toml:37:9: event 'lift' reads the contact force 'blade_N'"), std::string::npos)
      << message;

  // A model without contact forces: the name is unknown, and the message says why.
  const Model pendulum = load_model(example("pendulum_cartesian.toml"));
  message = contact_event_error<InputError>([&] { symbolic::make_stop_condition(pendulum, "disk_N < 0"); });
  EXPECT_NE(message.find("unknown symbol 'disk_N'"), std::string::npos) << message;
  EXPECT_NE(message.find("model 'pendulum-cartesian' has no contact forces"), std::string::npos) << message;

  // An output may not read a contact force (its column is in the results already).
  message = contact_event_error<ModelError>([&] {
    load_model_text(std::string(test::kFlatSledBodies) + "\n[outputs]\nside = \"2*blade_Flat\"\n", "sled.toml");
  });
  EXPECT_NE(message.find("output 'side' reads the contact force 'blade_Flat'"), std::string::npos) << message;
}

}  // namespace
}  // namespace nhdyn::multibody_test
