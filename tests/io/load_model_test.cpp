// The GiNaC-free loading API (io/load_model.hpp): sources, overrides, run options from
// [simulation] with the defaults of RunOptions, errors with file and line, and the variants of a
// batch equal to models loaded one by one. This file includes no GiNaC header, like a C++ user.
#include "nhdyn/io/load_model.hpp"

#include <gtest/gtest.h>

#include <string>

#include "nhdyn/analysis/batch.hpp"
#include "nhdyn/analysis/run_options.hpp"
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
  EXPECT_EQ(options.formulation.method, Method::lagrange);
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

}  // namespace
}  // namespace nhdyn
