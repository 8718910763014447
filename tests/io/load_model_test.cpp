// The GiNaC-free loading API (frontend/load_model.hpp): sources, overrides, run options from
// [simulation] with the defaults of RunOptions, errors with file and line, and the variants of a
// batch equal to models loaded one by one. This file includes no GiNaC header, like a C++ user.
#include "nhdyn/frontend/load_model.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <exception>
#include <string>
#include <utility>
#include <vector>

#include "nhdyn/analysis/batch.hpp"
#include "nhdyn/analysis/run_options.hpp"
#include "nhdyn/analysis/sweep.hpp"
#include "nhdyn/core/error.hpp"
#include "nhdyn/model/parameters.hpp"

namespace nhdyn {
namespace {

const std::string examples = std::string(NHDYN_SOURCE_DIR) + "/examples/";

double parameter(const Model& model, const std::string& name) {
  for (const Parameter& p : model.parameters)
    if (p.name == name) return p.value;
  ADD_FAILURE() << "no parameter " << name;
  return 0.0;
}

Trajectory run(const Model& model) {
  SimulationOptions options = make_simulation_options(model);
  options.t_end = 1.0;
  Trajectory tr;
  tr.reset(model);
  EXPECT_EQ(simulate(model, options, [&](const Data& data) { tr.append(data); }).status, Status::ok);
  return tr;
}

const char* fall = R"(name = "fall"
coordinates = ["x"]
kinetic_energy = "m/2*x'^2"
potential_energy = "-m*g*x"
[parameters]
m = 1.0
g = 9.81
[initial]
position = { x = 0 }
velocity = { x = 0 }
)";

TEST(LoadModel, FromAPathABuiltinNameOrText) {
  const Model file = load_model(examples + "sled.toml", {{"a", 0.3}, {"rho", std::string("0.8")}});
  EXPECT_EQ(file.name, "sled");
  EXPECT_EQ(parameter(file, "a"), 0.3);
  EXPECT_EQ(parameter(file, "rho"), 0.8);
  const Model builtin = load_model("sled");
  EXPECT_EQ(builtin.n(), 3);
  const Model text = load_model_text(fall, "fall.toml", {{"g", 1.0}});
  EXPECT_EQ(parameter(text, "g"), 1.0);
  // Free fall under g = 1: x = t^2 / 2 (dopri5 is exact for it up to round-off).
  const Trajectory tr = run(text);
  for (long i = 0; i < tr.rows(); ++i) EXPECT_NEAR(tr.q[static_cast<std::size_t>(i)], tr.t[static_cast<std::size_t>(i)] * tr.t[static_cast<std::size_t>(i)] / 2, 1e-12);
}

TEST(LoadModel, RunOptionsComeFromSimulationWithDefaultsWrittenOnce) {
  const Model plain = load_model_text(fall, "fall.toml");
  const RunOptions defaults;
  EXPECT_EQ(plain.defaults.rtol, defaults.rtol);
  EXPECT_EQ(plain.defaults.atol, defaults.atol);
  EXPECT_EQ(plain.defaults.integrator, defaults.integrator);
  EXPECT_EQ(plain.defaults.method, defaults.method);
  const Model set = load_model_text(std::string(fall) + R"([simulation]
t_end = 2
output_step = 0.5
integrator = "rk4"
method = "lagrange"
rtol = 1e-6
atol = 1e-9
)", "fall.toml");
  EXPECT_EQ(set.defaults.t_end, 2.0);
  EXPECT_EQ(set.defaults.output_step, 0.5);
  EXPECT_EQ(set.defaults.integrator, "rk4");
  EXPECT_EQ(set.defaults.method, "lagrange");
  EXPECT_EQ(set.defaults.rtol, 1e-6);
  EXPECT_EQ(set.defaults.atol, 1e-9);
  const SimulationOptions options = make_simulation_options(set);
  EXPECT_EQ(options.integrator.kind, IntegratorKind::rk4);
  EXPECT_EQ(options.formulation.method, Formulation::lagrange);
  EXPECT_EQ(options.integrator.rtol, 1e-6);
}

TEST(LoadModel, ErrorsNameTheFileLineOrParameter) {
  try {
    load_model_text("name = \"x\"\ncoordinates = 3\n", "broken.toml");
    FAIL() << "no error";
  } catch (const ModelError& e) {
    EXPECT_EQ(std::string(e.what()).rfind("broken.toml:2:", 0), 0u) << e.what();
  }
  try {
    load_model(examples + "sled.toml", {{"rh", 1.0}});
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("'rh'"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("'rho'"), std::string::npos) << e.what();
  }
  EXPECT_THROW(load_model("sled", {{"aa", 0.3}}), InputError);  // built-in models take parameters, known ones
  EXPECT_EQ(get_parameter(load_model("sled", {{"a", 0.3}}), "a"), 0.3);
  EXPECT_EQ(get_parameter(load_model(examples + "sled.toml", {{"a", std::string("rho/2")}}), "a"), 0.35);
  EXPECT_THROW(load_model(examples + "sled.toml", {{"a", std::string("half")}}), InputError);
  EXPECT_THROW(load_model("no-such-model"), InputError);
  EXPECT_THROW(load_model(examples + "missing.toml"), FileError);
  EXPECT_THROW(model_equations(read_model_source("sled"), {}, EquationsFormat::latex), InputError);
}

TEST(LoadModel, VariantsEqualModelsLoadedOneByOne) {
  const ModelSource source = read_model_source(examples + "sled.toml");
  const std::vector<std::vector<double>> values{{0.3, 0.7}, {0.45, 0.9}};
  const std::vector<Model> variants = load_model_variants(source, {{"g", 9.8}}, {"a", "rho"}, values);
  ASSERT_EQ(variants.size(), 2u);
  for (std::size_t i = 0; i < values.size(); ++i) {
    const Model one = load_model(source, {{"g", 9.8}, {"a", values[i][0]}, {"rho", values[i][1]}});
    EXPECT_EQ(run(variants[i]).q, run(one).q);
    EXPECT_EQ(parameter(variants[i], "g"), 9.8);
  }
  EXPECT_NE(run(variants[0]).q, run(variants[1]).q);
  EXPECT_THROW(load_model_variants(source, {}, {"b"}, {{1.0}}), InputError);
}

TEST(LoadModel, EquationsAsTextAndLatex) {
  const ModelSource source = read_model_source(examples + "sled.toml");
  EXPECT_NE(model_equations(source, {}, EquationsFormat::latex).find("\\begin{align*}"), std::string::npos);
  EXPECT_NE(model_equations(source, {}, EquationsFormat::text).find("T ="), std::string::npos);
}

// The sweep loads the model once and sets the parameter at every point (parameters are data):
// the upright rolling disk's stability limit w = sqrt(g / (3 r)) from a file, a second parameter
// changed by an override; a built-in model is swept like a file (the CLI's sweep takes both).
TEST(LoadModel, SweepSetsTheParameterOnOneLoadedModel) {
  SweepOptions options;
  options.parameter = "w";
  options.from = 1.0;
  options.to = 10.0;
  options.steps = 10;
  options.linearization.cyclic = {"psi"};
  for (const double r : {0.2, 0.3}) {
    const Sweep sweep =
        sweep_model_parameter(read_model_source(examples + "rolling_disk_upright.toml"), {{"r", r}}, options);
    ASSERT_EQ(sweep.crossings.size(), 1u) << r;
    // A real pair turns into an imaginary one through a double zero (a Jordan block): the count
    // changes where the computed discriminant does, within eps |S|^2 / slope, about 1e-11 here.
    EXPECT_NEAR(sweep.crossings[0].value, std::sqrt(9.81 / (3.0 * r)), 1e-10) << r;
  }
  const std::vector<std::pair<std::string, double>> listed = model_parameters(read_model_source("sled"), {{"m", 2.0}});
  const Model sled = load_model("sled", {{"m", 2.0}});
  ASSERT_EQ(listed.size(), sled.parameters.size());
  for (std::size_t i = 0; i < listed.size(); ++i) {
    EXPECT_EQ(listed[i].first, sled.parameters[i].name);
    EXPECT_EQ(listed[i].second, sled.parameters[i].value);
  }
  EXPECT_EQ(parameter(sled, "m"), 2.0);
  // The built-in sled starts turning, which is no steady motion: the sweep gets as far as saying so.
  options.parameter = "m";
  options.linearization.cyclic = {};
  try {
    sweep_model_parameter(read_model_source("sled"), {}, options);
    ADD_FAILURE() << "the turning sled was swept";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("not a steady motion"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace nhdyn
