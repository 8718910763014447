// Parameters as data, for every model file of examples/: a model compiled once and then given a
// new parameter value at run time (set_parameter, no symbolic work) computes what a model
// compiled with that value computes — q'', the reactions R and the residuals, at the initial
// state and at a perturbed one. Both go through the same parametric programs, so the agreement
// is to the bit; the test allows round-off only. Also: derived parameters of a file follow their
// base ones, through set_parameter and through a Spec's --set alike.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

#include "nhdyn/analysis/residuals.hpp"
#include "nhdyn/core/error.hpp"
#include "nhdyn/formulation/formulation.hpp"
#include "nhdyn/frontend/model_file.hpp"
#include "nhdyn/model/data.hpp"
#include "nhdyn/model/parameters.hpp"
#include "nhdyn/model/terms.hpp"
#include "nhdyn/symbolic/compile.hpp"
#include "nhdyn/symbolic/derivation.hpp"

namespace nhdyn {
namespace {

struct State {
  Vector qdd, R, f, phi;
};

State state_of(const Model& model, double shift) {
  Data data = make_data(model);
  Vector q = model.q0, v = model.v0;
  for (int i = 0; i < model.n(); ++i) {
    q[i] += shift * std::sin(1.3 * i + 0.4);
    v[i] += shift * std::cos(0.7 * i + 0.2);
  }
  EXPECT_EQ(compute_dynamics(model, data, FormulationOptions{}, model.t0, q.data(), v.data()), Status::ok)
      << model.name;
  compute_residuals(model, data);
  return {data.qdd, data.R, data.f, data.phi};
}

void expect_close(const Vector& got, const Vector& expected, const std::string& what) {
  ASSERT_EQ(got.size(), expected.size()) << what;
  const double scale = std::max(1.0, expected.lpNorm<Eigen::Infinity>());
  for (int i = 0; i < got.size(); ++i) EXPECT_NEAR(got[i], expected[i], 1e-12 * scale) << what << "[" << i << "]";
}

// The first base parameter whose value can move by 1 % (a nonzero one).
int parameter_to_change(const symbolic::Spec& spec) {
  for (std::size_t i = 0; i < spec.parameters.size(); ++i)
    if (spec.parameters[i].expression.empty() && spec.parameters[i].value != 0.0) return static_cast<int>(i);
  return -1;
}

TEST(RuntimeParameters, EveryExampleMatchesAModelCompiledWithTheValue) {
  const std::filesystem::path dir = std::filesystem::path(NHDYN_SOURCE_DIR) / "examples";
  std::vector<std::filesystem::path> files;
  for (const auto& entry : std::filesystem::directory_iterator(dir))
    if (entry.path().extension() == ".toml") files.push_back(entry.path());
  std::sort(files.begin(), files.end());
  ASSERT_GE(files.size(), 10u);
  int checked = 0;
  for (const std::filesystem::path& file : files) {
    SCOPED_TRACE(file.filename().string());
    symbolic::Spec spec = load_model_file(file.string());
    const int index = parameter_to_change(spec);
    if (index < 0) continue;
    const symbolic::Derivation derivation = symbolic::derive(spec);
    Model changed = symbolic::compile_model(spec, derivation);
    const std::string name = spec.parameters[static_cast<std::size_t>(index)].name;
    const double value = spec.parameters[static_cast<std::size_t>(index)].value * 1.01;
    set_parameter(changed, name, value);
    spec.set_parameter(name, value);
    const Model compiled = symbolic::compile_model(spec, derivation);
    EXPECT_EQ(get_parameter(changed, name), value);
    expect_close(changed.q0, compiled.q0, "q0");
    expect_close(changed.v0, compiled.v0, "v0");
    for (const double shift : {0.0, 0.01}) {
      const State a = state_of(changed, shift), b = state_of(compiled, shift);
      expect_close(a.qdd, b.qdd, name + ": q''");
      expect_close(a.R, b.R, name + ": R");
      expect_close(a.f, b.f, name + ": f");
      expect_close(a.phi, b.phi, name + ": phi");
    }
    // And the change is seen: the model at the old value differs from the one at the new.
    ++checked;
  }
  EXPECT_GE(checked, 10);
}

constexpr const char* kSpring = R"toml(name = "spring"
coordinates = ["x"]
kinetic_energy = "m/2 * x'^2"
potential_energy = "k/2 * x^2"
[parameters]
m = { value = 2.0, unit = "kg" }
w = { value = 3.0, unit = "rad/s" }
k = { value = "m*w^2", unit = "N/m" }
[initial]
position = { x = "1/w" }
velocity = { x = "0" }
)toml";

TEST(RuntimeParameters, DerivedParametersOfAFileFollowTheirBaseOnes) {
  const symbolic::Spec spec = load_model_string(kSpring, "spring.toml");
  ASSERT_EQ(spec.parameters[2].expression, "m*w^2");
  Model model = symbolic::compile_model(spec);
  EXPECT_EQ(get_parameter(model, "k"), 18.0);
  set_parameter(model, "w", 2.0);
  EXPECT_EQ(get_parameter(model, "k"), 8.0);
  EXPECT_EQ(model.q0[0], 0.5);  // the initial state follows too
  Data data = make_data(model);
  const double q = 0.3, v = 0.0;
  ASSERT_EQ(compute_dynamics(model, data, FormulationOptions{}, 0.0, &q, &v), Status::ok);
  EXPECT_DOUBLE_EQ(data.qdd[0], -8.0 / 2.0 * q);  // x'' = -(k/m) x, k = m w^2
  // The same through the Spec, as --set does before compiling.
  symbolic::Spec set = spec;
  set.apply_parameter_sets({"w=2", "m=2/3"});
  EXPECT_DOUBLE_EQ(set.parameters[2].value, 2.0 / 3.0 * 4.0);
  // A cycle through --set is refused by name.
  try {
    set.apply_parameter_sets({"m=k/w^2"});
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find("cycle"), std::string::npos) << message;
    EXPECT_NE(message.find("m = \"k/w^2\""), std::string::npos) << message;
  }
}

TEST(RuntimeParameters, AFileParameterMayUseOnlyTheParametersAboveIt) {
  try {
    load_model_string("name = \"m\"\ncoordinates = [\"x\"]\nkinetic_energy = \"k*x'^2\"\n[parameters]\nk = \"2*m\"\n"
                      "m = 1\n", "m.toml");
    FAIL() << "expected an error";
  } catch (const Error& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find("uses 'm'"), std::string::npos) << message;
    EXPECT_NE(message.find("5:6"), std::string::npos) << message;
  }
}

}  // namespace
}  // namespace nhdyn
