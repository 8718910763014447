// Events through the C++ API: a model file's [[events]] become Model::events, simulate() locates
// the ones of SimulationOptions::events and returns them in the summary, and a parameter an event
// reads is data (set_parameter moves the event without recompiling). A particle at constant speed
// crosses x = L at exactly t = L / u; the ball thrown up at w reaches its top at w / g and lands
// from the height h at (w + sqrt(w^2 + 2 g h)) / g.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "nhdyn/analysis/simulation.hpp"
#include "nhdyn/core/error.hpp"
#include "nhdyn/frontend/load_model.hpp"
#include "nhdyn/model/parameters.hpp"

namespace nhdyn {
namespace {

const std::string ball = R"toml(
name = "ball"
coordinates = ["x", "z"]
kinetic_energy = "m/2 * (x'^2 + z'^2)"
potential_energy = "m*g*z"

[parameters]
m = { value = 1.0 }
g = { value = 9.81 }
u = { value = 2.0 }    # horizontal speed
w = { value = 4.0 }    # initial vertical speed
L = { value = 1.5 }
h = { value = 0.5 }    # initial height

[initial]
position = { z = "h" }
velocity = { x = "u", z = "w" }

[[events]]
name = "passed"
when = "x - L"

[[events]]
name = "top"
when = "z'"
direction = "falling"

[[events]]
name = "landed"
when = "z"
direction = "falling"
action = "stop"
)toml";

TEST(Events, ModelFileEventsThroughTheApi) {
  Model model = load_model_text(ball, "ball.toml");
  ASSERT_EQ(model.events.size(), 3u);
  EXPECT_EQ(model.events[0].name, "passed");
  EXPECT_EQ(model.events[0].direction, EventDirection::both);
  EXPECT_EQ(model.events[0].action, EventAction::record);
  EXPECT_EQ(model.events[1].direction, EventDirection::falling);
  EXPECT_EQ(model.events[2].action, EventAction::stop);
  EXPECT_EQ(model.events[0].where, "ball.toml:21:9");

  SimulationOptions options;
  options.t_end = 5.0;
  options.output_step = 0.1;
  options.events = model.events;
  SimulationSummary summary = simulate(model, options, [](const Data&) {});
  ASSERT_EQ(summary.status, Status::ok) << summary.message;
  // The top at w/g, passed at L/u = 0.75 s, landed at (w + sqrt(w^2 + 2 g h))/g, which stops the run.
  ASSERT_EQ(summary.events.crossings.size(), 3u);
  EXPECT_EQ(summary.events.crossings[0].name, "top");
  EXPECT_NEAR(summary.events.crossings[0].t, 4.0 / 9.81, 1e-12);
  EXPECT_EQ(summary.events.crossings[1].name, "passed");
  EXPECT_NEAR(summary.events.crossings[1].t, 0.75, 1e-12);
  EXPECT_NEAR(summary.events.crossings[1].q[0], 1.5, 1e-12);
  EXPECT_EQ(summary.events.crossings[2].name, "landed");
  EXPECT_NEAR(summary.events.crossings[2].t, (4.0 + std::sqrt(16.0 + 2.0 * 9.81 * 0.5)) / 9.81, 1e-12);
  EXPECT_EQ(summary.events.stopped_by, 2);
  EXPECT_EQ(summary.t_reached, summary.events.crossings[2].t);

  // Parameters are data: L = 0.5 moves the crossing to 0.25 s with the same compiled tapes.
  set_parameter(model, "L", 0.5);
  summary = simulate(model, options, [](const Data&) {});
  ASSERT_EQ(summary.status, Status::ok) << summary.message;
  EXPECT_EQ(summary.events.crossings[0].name, "passed");
  EXPECT_NEAR(summary.events.crossings[0].t, 0.25, 1e-12);

  // Without options.events the run ignores them and reaches t_end.
  options.events.clear();
  summary = simulate(model, options, [](const Data&) {});
  EXPECT_TRUE(summary.events.crossings.empty());
  EXPECT_EQ(summary.t_reached, 5.0);
}

TEST(Events, ModelFileErrorsNameTheirPlace) {
  const auto message = [](const std::string& text) -> std::string {
    try {
      load_model_text(text, "ball.toml");
    } catch (const Error& e) {
      return e.what();
    }
    return "";
  };
  std::string text = ball;
  text.replace(text.find("when = \"z'\""), 11, "when = \"zz'\"");
  EXPECT_NE(message(text).find("ball.toml:25:9: "), std::string::npos) << message(text);
  EXPECT_NE(message(text).find("did you mean 'z''?"), std::string::npos) << message(text);
  // An event may read q'' (and the reactions R_x): it is then evaluated on the solved dynamics.
  text = ball;
  text.replace(text.find("when = \"z'\""), 11, "when = \"z''\"");
  EXPECT_EQ(message(text), "");
  EXPECT_TRUE(load_model_text(text, "ball.toml").events.at(1).dynamics);
  text = ball + "\n[[events]]\nname = \"top\"\nwhen = \"x\"\n";
  EXPECT_NE(message(text).find("event name 'top' is used twice"), std::string::npos) << message(text);
  text = ball;
  text.replace(text.find("action = \"stop\""), 15, "action = \"halt\"");
  EXPECT_NE(message(text).find("action 'halt' is not one of stop, record"), std::string::npos) << message(text);
}

TEST(Events, Rk4AndAnEventAtZeroAreRefusedBeforeTheRun) {
  Model model = load_model_text(ball, "ball.toml");
  SimulationOptions options;
  options.t_end = 1.0;
  options.events = model.events;
  options.integrator.kind = IntegratorKind::rk4;
  EXPECT_THROW(check_simulation_options(model, options), InputError);
  options.integrator.kind = IntegratorKind::dopri5;
  set_parameter(model, "L", 0.0);  // x - L = 0 at the start
  try {
    simulate(model, options, [](const Data&) {});
    FAIL() << "an event at zero at the start was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("ball.toml:21:9: event 'passed' (x - L) is already at zero at the start"),
              std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace nhdyn
