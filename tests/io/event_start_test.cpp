// An event whose expression is zero at the start (analysis/events.hpp, docs/model-format.md
// [[events]]): with a direction the start is not a crossing, so "back where it started" is found
// where it comes back; without one it is refused. Checked against the closed form of a ball thrown
// up from the ground, z = w t - g t^2 / 2, back at z = 0 at t = 2 w / g.
#include <gtest/gtest.h>

#include <string>

#include "nhdyn/analysis/simulation.hpp"
#include "nhdyn/core/error.hpp"
#include "nhdyn/frontend/load_model.hpp"

namespace nhdyn {
namespace {

const std::string thrown = R"toml(
name = "thrown"
coordinates = ["z"]
kinetic_energy = "m/2 * z'^2"
potential_energy = "m*g*z"

[parameters]
m = { value = 1.0 }
g = { value = 9.81 }
w = { value = 4.0 }

[initial]
position = { z = 0 }
velocity = { z = "w" }

[[events]]
name = "back"
when = "z"
direction = "falling"
action = "stop"
)toml";

TEST(EventAtTheStart, WithADirectionItIsFoundWhereItComesBack) {
  const Model model = load_model_text(thrown, "thrown.toml");
  for (const IntegratorKind kind : {IntegratorKind::dopri5, IntegratorKind::dop853, IntegratorKind::cvode_bdf}) {
    SimulationOptions options;
    options.t_end = 5.0;
    options.output_step = 0.1;
    options.integrator.kind = kind;
    options.integrator.rtol = 1e-10;
    options.integrator.atol = 1e-12;
    options.events = model.events;
    const SimulationSummary summary = simulate(model, options, [](const Data&) {});
    ASSERT_EQ(summary.status, Status::ok) << summary.message;
    ASSERT_EQ(summary.events.crossings.size(), 1u) << integrator_name(kind);
    EXPECT_EQ(summary.events.stopped_by, 0);
    EXPECT_NEAR(summary.events.crossings[0].t, 2 * 4.0 / 9.81, 1e-8) << integrator_name(kind);
    EXPECT_NEAR(summary.t_reached, 2 * 4.0 / 9.81, 1e-8) << integrator_name(kind);
  }
}

TEST(EventAtTheStart, WithoutADirectionItIsRefusedSayingWhatToDo) {
  std::string text = thrown;
  text.erase(text.find("direction = \"falling\"\n"), 22);
  const Model model = load_model_text(text, "thrown.toml");
  SimulationOptions options;
  options.t_end = 5.0;
  options.events = model.events;
  try {
    simulate(model, options, [](const Data&) {});
    FAIL() << "an event at zero at the start without a direction was accepted";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("event 'back' (z) is already at zero at the start"), std::string::npos) << what;
    EXPECT_NE(what.find("give it a direction"), std::string::npos) << what;
  }
}

}  // namespace
}  // namespace nhdyn
