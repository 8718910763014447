// The front door's events (frontend/events.hpp): the command line's --stop-when and --event for a
// loaded model. A model file's are read against the Spec kept in its description, a built-in
// model's (no description) against names declared from its Model; both readings are the same
// event — the same name, direction, action and condition, and, run on the same model, the same
// stop at the same time to the bit and the same recorded crossings. The stop itself is checked
// against its closed form (the pendulum's speed from the energy, v^2 = 2 g (y0 - y)). Bad
// conditions get the same messages either way.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "nhdyn/analysis/simulation.hpp"
#include "nhdyn/core/error.hpp"
#include "nhdyn/frontend/events.hpp"
#include "nhdyn/frontend/load_model.hpp"
#include "nhdyn/io/results.hpp"
#include "nhdyn/model/parameters.hpp"

// A namespace of its own: the unity build joins this file with the other io tests.
namespace nhdyn::run_events_test {
namespace {

namespace fs = std::filesystem;

LoadedModel example(const std::string& name) {
  return load_model_described(read_model_source((fs::path(NHDYN_SOURCE_DIR) / "examples" / name).string()));
}

double parameter_of(const Model& model, const std::string& name) {
  for (const Parameter& p : model.parameters)
    if (p.name == name) return p.value;
  ADD_FAILURE() << name;
  return 0.0;
}

SimulationOptions tight(double t_end) {
  SimulationOptions options;
  options.t_end = t_end;
  options.output_step = 0.01;
  options.integrator.rtol = 1e-11;
  options.integrator.atol = 1e-13;
  return options;
}

struct Outcome {
  SimulationSummary summary;
  std::vector<double> last;  // the last result row
};

Outcome run_with(const Model& model, const Event& event, double t_end) {
  SimulationOptions options = tight(t_end);
  options.events = {event};
  Outcome run;
  run.summary = simulate(model, options, [&](const Data& data) { fill_result_row(model, data, run.last); });
  return run;
}

void expect_same_event(const Event& a, const Event& b) {
  EXPECT_EQ(a.name, b.name);
  EXPECT_EQ(a.expression, b.expression);
  EXPECT_EQ(a.where, b.where);
  EXPECT_EQ(a.direction, b.direction);
  EXPECT_EQ(a.action, b.action);
  EXPECT_EQ(a.condition, b.condition);
  EXPECT_EQ(a.dynamics, b.dynamics);
  EXPECT_EQ(a.contact_forces, b.contact_forces);
}

TEST(RunEvents, AStopConditionOfAModelFileIsReadAgainstItsDescription) {
  const LoadedModel loaded = example("pendulum_outputs.toml");
  ASSERT_NE(loaded.description, nullptr);
  const Event described = make_stop_condition(loaded, "speed > 4");
  const Event declared = make_stop_condition(loaded.model, "speed > 4");
  expect_same_event(described, declared);
  EXPECT_TRUE(described.condition);
  const Outcome a = run_with(loaded.model, described, 5.0);
  const Outcome b = run_with(loaded.model, declared, 5.0);
  ASSERT_EQ(a.summary.status, Status::ok) << a.summary.message;
  ASSERT_EQ(a.summary.events.stopped_by, 0);
  EXPECT_EQ(a.last, b.last);  // the same stop, to the bit
  // The speed from the energy at the stop: v^2 = 2 g (y0 - y) = 16.
  const ResultColumns c = make_result_columns(loaded.model);
  const auto at = [&](const char* name) {
    for (std::size_t i = 0; i < c.all.size(); ++i)
      if (c.all[i] == name) return a.last[i];
    ADD_FAILURE() << "no column " << name;
    return 0.0;
  };
  const Model& m = loaded.model;
  const double g = parameter_of(m, "g"), l = parameter_of(m, "l"), theta0 = parameter_of(m, "theta0");
  EXPECT_NEAR(at("speed"), 4.0, 1e-9);
  EXPECT_NEAR(2.0 * g * (-l * std::cos(theta0) - at("y")), 16.0, 1e-7);
}

TEST(RunEvents, ARecordEventOfAModelFileIsReadAgainstItsDescription) {
  const LoadedModel loaded = example("pendulum_outputs.toml");
  const Event described = make_record_event(loaded, "through=x");
  const Event declared = make_record_event(loaded.model, "through=x");
  expect_same_event(described, declared);
  const Outcome a = run_with(loaded.model, described, 3.0);
  const Outcome b = run_with(loaded.model, declared, 3.0);
  ASSERT_EQ(a.summary.status, Status::ok) << a.summary.message;
  ASSERT_GT(a.summary.events.crossings.size(), 0u);  // the pendulum swings through x = 0
  ASSERT_EQ(a.summary.events.crossings.size(), b.summary.events.crossings.size());
  for (std::size_t i = 0; i < a.summary.events.crossings.size(); ++i)
    EXPECT_EQ(a.summary.events.crossings[i].t, b.summary.events.crossings[i].t) << "crossing " << i;
  EXPECT_EQ(a.last, b.last);
}

// A built-in model has no description: its names come from the Model, as they always did.
TEST(RunEvents, ABuiltInModelGivesItsNamesFromTheModel) {
  const LoadedModel loaded = load_model_described(read_model_source("sled"));
  ASSERT_EQ(loaded.description, nullptr);
  expect_same_event(make_stop_condition(loaded, "abs(phi) > 1"), make_stop_condition(loaded.model, "abs(phi) > 1"));
}

std::string message_of(const std::function<void()>& call) {
  try {
    call();
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

// The messages of bad conditions are those of the names declared from the Model.
TEST(RunEvents, BadConditionsAreToldAlikeEitherWay) {
  const LoadedModel loaded = example("pendulum_outputs.toml");
  for (const std::string condition : {"speed = 4", "speed", "speed > 4 > 3", "> 4", "abs(sped) > 4", "x > R_xx"}) {
    const std::string described = message_of([&] { make_stop_condition(loaded, condition); });
    EXPECT_FALSE(described.empty()) << condition;
    EXPECT_EQ(described, message_of([&] { make_stop_condition(loaded.model, condition); })) << condition;
  }
  for (const std::string definition : {"x", "1a=x", "up=sped"}) {
    const std::string described = message_of([&] { make_record_event(loaded, definition); });
    EXPECT_FALSE(described.empty()) << definition;
    EXPECT_EQ(described, message_of([&] { make_record_event(loaded.model, definition); })) << definition;
  }
}

}  // namespace
}  // namespace nhdyn::run_events_test
