// Derived outputs through the C++ API (model/output.hpp, docs/model-format.md [outputs]):
// exams against closed forms along a run. The Cartesian pendulum's energy as an output stays at
// -m g l cos(theta0); its rod tension taken from the reactions, -(x R_x + y R_y)/l, agrees with
// m (g cos(theta) + l theta'^2) and with m g (3 cos(theta) - 2 cos(theta0)); an event on the
// tension (which needs the solved dynamics) finds the rod going slack where
// cos(theta) = 2 cos(theta0)/3. The rolling disk built from bodies gets its centre's position and
// velocity as columns without writing anything, equal to their closed forms in q and q'.
// Parameters are data for outputs too, and bad outputs are refused naming their place.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "nhdyn/analysis/simulation.hpp"
#include "nhdyn/core/error.hpp"
#include "nhdyn/frontend/load_model.hpp"
#include "nhdyn/io/results.hpp"
#include "nhdyn/model/parameters.hpp"
#include "nhdyn/symbolic/events.hpp"

namespace nhdyn {
namespace {

namespace fs = std::filesystem;

std::string example_text(const std::string& name) {
  std::ifstream in(fs::path(NHDYN_SOURCE_DIR) / "examples" / name, std::ios::binary);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

int column(const ResultColumns& c, const std::string& name) {
  const auto it = std::find(c.all.begin(), c.all.end(), name);
  EXPECT_NE(it, c.all.end()) << name;
  return static_cast<int>(it - c.all.begin());
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

TEST(Outputs, PendulumEnergyAndTensionAgainstClosedForms) {
  const Model model = load_model_text(example_text("pendulum_outputs.toml"), "pendulum_outputs.toml");
  const ResultColumns c = make_result_columns(model);
  ASSERT_EQ(c.outputs, (std::vector<std::string>{"total_energy", "tension", "tension_closed_form", "theta", "speed"}));
  // The outputs come last, in file order.
  EXPECT_TRUE(std::equal(c.outputs.begin(), c.outputs.end(), c.all.end() - 5));
  EXPECT_FALSE(model.outputs.list[0].dynamics);
  EXPECT_TRUE(model.outputs.list[1].dynamics);  // reads R
  const double m = parameter_of(model, "m"), g = parameter_of(model, "g"), l = parameter_of(model, "l");
  const double theta0 = parameter_of(model, "theta0");
  const double E0 = -m * g * l * std::cos(theta0);
  const int x = column(c, "x"), y = column(c, "y"), vx = column(c, "x'"), vy = column(c, "y'");
  const int E = column(c, "total_energy"), N = column(c, "tension"), Nc = column(c, "tension_closed_form");
  const int th = column(c, "theta"), speed = column(c, "speed");

  SimulationOptions options = tight(5.0);
  options.events = model.events;
  std::vector<double> row;
  double worst_energy = 0.0, worst_tension = 0.0, worst_energy_tension = 0.0, worst_angle = 0.0;
  long rows = 0;
  const SimulationSummary summary = simulate(model, options, [&](const Data& data) {
    fill_result_row(model, data, row);
    ASSERT_EQ(row.size(), c.all.size());
    ++rows;
    const double cos_theta = -row[static_cast<std::size_t>(y)] / l;
    worst_energy = std::max(worst_energy, std::abs(row[static_cast<std::size_t>(E)] - E0));
    // Independent of the reactions: the tension from the state alone, and from the energy.
    const double v2 = row[static_cast<std::size_t>(vx)] * row[static_cast<std::size_t>(vx)] +
                      row[static_cast<std::size_t>(vy)] * row[static_cast<std::size_t>(vy)];
    worst_tension = std::max(worst_tension, std::abs(row[static_cast<std::size_t>(N)] - m * (g * cos_theta + v2 / l)));
    worst_energy_tension = std::max(
        worst_energy_tension, std::abs(row[static_cast<std::size_t>(N)] - m * g * (3 * cos_theta - 2 * std::cos(theta0))));
    worst_angle = std::max(worst_angle, std::abs(row[static_cast<std::size_t>(th)] -
                                                 std::atan2(row[static_cast<std::size_t>(x)], -row[static_cast<std::size_t>(y)])));
    EXPECT_DOUBLE_EQ(row[static_cast<std::size_t>(speed)], std::sqrt(v2));
    EXPECT_NEAR(row[static_cast<std::size_t>(Nc)], m * (g * cos_theta + v2 / l), 1e-12);
  });
  ASSERT_EQ(summary.status, Status::ok) << summary.message;
  EXPECT_GT(rows, 500);
  // m g l = 7.4 J, N up to about m g (3 + 0.83) = 19 N: a wrong expression misses by orders more.
  EXPECT_LT(worst_energy, 1e-8);
  EXPECT_LT(worst_tension, 1e-7);
  EXPECT_LT(worst_energy_tension, 1e-7);
  EXPECT_LT(worst_angle, 1e-14);

  // The rod goes slack once per swing up (period 3.26 s: at least three times in 5 s), each time
  // where 3 cos(theta) = 2 cos(theta0).
  int slack = 0;
  for (const EventRecord& e : summary.events.crossings) {
    ASSERT_EQ(e.name, "slack");
    ++slack;
    EXPECT_NEAR(-e.q[1] / l, 2.0 * std::cos(theta0) / 3.0, 1e-9) << "t = " << e.t;
  }
  EXPECT_GE(slack, 3);
}

TEST(Outputs, ParametersAreData) {
  Model model = load_model_text(example_text("pendulum_outputs.toml"), "pendulum_outputs.toml");
  set_parameter(model, "m", 2.0);
  const ResultColumns c = make_result_columns(model);
  std::vector<double> row;
  SimulationOptions options = tight(0.01);
  bool first = true;
  simulate(model, options, [&](const Data& d) {
    if (!first) return;
    first = false;
    fill_result_row(model, d, row);
    // At rest at theta0: N = m g cos(theta0), E = -m g l cos(theta0), with the new m.
    const double g = parameter_of(model, "g"), l = parameter_of(model, "l"), theta0 = parameter_of(model, "theta0");
    EXPECT_NEAR(row[static_cast<std::size_t>(column(c, "tension"))], 2.0 * g * std::cos(theta0), 1e-9);
    EXPECT_NEAR(row[static_cast<std::size_t>(column(c, "total_energy"))], -2.0 * g * l * std::cos(theta0), 1e-12);
  });
  EXPECT_FALSE(first);
}

TEST(Outputs, StopConditionOnAnOutput) {
  const Model model = load_model_text(example_text("pendulum_outputs.toml"), "pendulum_outputs.toml");
  SimulationOptions options = tight(5.0);
  options.events.push_back(symbolic::make_stop_condition(model, "speed > 4"));
  const ResultColumns c = make_result_columns(model);
  std::vector<double> last;
  const SimulationSummary summary = simulate(model, options, [&](const Data& data) { fill_result_row(model, data, last); });
  ASSERT_EQ(summary.status, Status::ok) << summary.message;
  ASSERT_EQ(summary.events.stopped_by, 0);
  EXPECT_NEAR(last[static_cast<std::size_t>(column(c, "speed"))], 4.0, 1e-9);
  // The speed from the energy: v^2 = 2 g (y0 - y).
  const double g = parameter_of(model, "g"), l = parameter_of(model, "l"), theta0 = parameter_of(model, "theta0");
  EXPECT_NEAR(2.0 * g * (-l * std::cos(theta0) - last[static_cast<std::size_t>(column(c, "y"))]), 16.0, 1e-7);
  // An event reading the reactions through an output is located on the solved dynamics too:
  // released above the horizontal, the rod pushes (N < 0) until 3 cos(theta) = 2 cos(theta0).
  options.events = {symbolic::make_stop_condition(model, "tension > 0")};
  const SimulationSummary slack = simulate(model, options, [&](const Data& data) { fill_result_row(model, data, last); });
  ASSERT_EQ(slack.events.stopped_by, 0) << slack.message;
  EXPECT_NEAR(-last[static_cast<std::size_t>(column(c, "y"))] / l, 2.0 * std::cos(theta0) / 3.0, 1e-9);
}

TEST(Outputs, RollingDiskCentreFromBodies) {
  const Model model = load_model_text(example_text("rolling_disk_bodies.toml"), "rolling_disk_bodies.toml");
  const ResultColumns c = make_result_columns(model);
  // The heading frame (at the contact point) and the disk's centre; the lean frame turns about
  // the heading's origin and adds no column.
  for (const char* name : {"heading_x", "heading_vz", "disk_x", "disk_y", "disk_z", "disk_vx", "disk_vy", "disk_vz"})
    EXPECT_NE(std::find(c.outputs.begin(), c.outputs.end(), name), c.outputs.end()) << name;
  for (const std::string& name : c.outputs) EXPECT_NE(name.rfind("lean_", 0), 0u) << name;
  const double r = parameter_of(model, "r");
  SimulationOptions options = tight(2.0);
  std::vector<double> row;
  long rows = 0;
  const SimulationSummary summary = simulate(model, options, [&](const Data& data) {
    fill_result_row(model, data, row);
    ++rows;
    const auto at = [&](const std::string& name) { return row[static_cast<std::size_t>(column(c, name))]; };
    const double X = at("x"), Y = at("y"), psi = at("psi"), theta = at("theta");
    const double dX = at("x'"), dY = at("y'"), dpsi = at("psi'"), dtheta = at("theta'");
    // Centre = contact + r (lean frame's z axis) = contact + r (sin psi sin theta, -cos psi sin theta, cos theta).
    EXPECT_NEAR(at("disk_x"), X + r * std::sin(psi) * std::sin(theta), 1e-13);
    EXPECT_NEAR(at("disk_y"), Y - r * std::cos(psi) * std::sin(theta), 1e-13);
    EXPECT_NEAR(at("disk_z"), r * std::cos(theta), 1e-13);
    EXPECT_NEAR(at("disk_vx"), dX + r * (std::cos(psi) * dpsi * std::sin(theta) + std::sin(psi) * std::cos(theta) * dtheta),
                1e-12);
    EXPECT_NEAR(at("disk_vy"), dY + r * (std::sin(psi) * dpsi * std::sin(theta) - std::cos(psi) * std::cos(theta) * dtheta),
                1e-12);
    EXPECT_NEAR(at("disk_vz"), -r * std::sin(theta) * dtheta, 1e-12);
    EXPECT_EQ(at("heading_x"), X);
    EXPECT_EQ(at("heading_vy"), dY);
  });
  ASSERT_EQ(summary.status, Status::ok) << summary.message;
  EXPECT_GT(rows, 100);
}

std::string load_error(const std::string& text) {
  try {
    load_model_text(text, "p.toml");
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

// The pendulum with `outputs` as its [outputs] table (appended at the end of the file).
std::string pendulum_with(const std::string& outputs) {
  std::string text = example_text("pendulum_cartesian.toml");
  return text + "\n[outputs]\n" + outputs;
}

TEST(Outputs, BadOutputsAreRefusedWithTheirPlace) {
  const std::string base = example_text("pendulum_cartesian.toml");
  const int line = static_cast<int>(std::count(base.begin(), base.end(), '\n')) + 3;  // the first output's line
  std::string message = load_error(pendulum_with("E = \"m/2*(x'^2 + y'^2) + m*gg*y\"\n"));
  EXPECT_NE(message.find("p.toml:" + std::to_string(line) + ":28: "), std::string::npos) << message;
  EXPECT_NE(message.find("unknown symbol 'gg'; did you mean 'g'?"), std::string::npos) << message;
  message = load_error(pendulum_with("E = \"R_z*2\"\n"));
  EXPECT_NE(message.find("unknown symbol 'R_z'"), std::string::npos) << message;
  EXPECT_NE(message.find("did you mean 'R_"), std::string::npos) << message;
  message = load_error(pendulum_with("E = \"x +* y\"\n"));
  EXPECT_NE(message.find("p.toml:" + std::to_string(line) + ":9: syntax error"), std::string::npos) << message;
  // Named like a column of the results.
  for (const std::string name : {"energy", "residual_pos_rod", "t"}) {
    message = load_error(pendulum_with(name + " = \"x\"\n"));
    EXPECT_NE(message.find("p.toml:" + std::to_string(line) + ":1: "), std::string::npos) << message;
    EXPECT_NE(message.find("output '" + name + "'"), std::string::npos) << message;
  }
  message = load_error(pendulum_with("R_x = \"x\"\n"));
  EXPECT_NE(message.find("reaction on 'x'"), std::string::npos) << message;
  message = load_error(pendulum_with("x = \"y\"\n"));
  EXPECT_NE(message.find("already a coordinate"), std::string::npos) << message;
  message = load_error(pendulum_with("a = \"x\"\nb = \"a + 1\"\nresidual_vel_rod = \"b\"\n"));
  EXPECT_NE(message.find("p.toml:" + std::to_string(line + 2) + ":1: output 'residual_vel_rod'"), std::string::npos)
      << message;
  // A forward reference is named as one (it was "unknown symbol 'a'").
  message = load_error(pendulum_with("b = \"a + 1\"\na = \"x\"\n"));
  EXPECT_NE(message.find("'a' is an output declared below 'b'"), std::string::npos) << message;
  // An output used by a later one is replaced by its expression.
  const Model model = load_model_text(pendulum_with("a = \"2*x\"\nb = \"a + y\"\n"), "p.toml");
  EXPECT_EQ(model.outputs.count(), 2);
}

}  // namespace
}  // namespace nhdyn
