// Generated C++ against the interpreted program it was printed from: the headers in the build
// tree (generated/*.hpp, written by generate.cpp from hand_built_specs.hpp) compile with the
// project's warnings and compute the same terms, complement, residuals and energy to round-off
// at random states, and describe the same Model.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "appell_model.hpp"
#include "codegen/hand_built_specs.hpp"
#include "nhdyn/symbolic/compile.hpp"
#include "sled_model.hpp"
#include "from_file_appell.hpp"
#include "from_file_sled.hpp"
#include "from_file_sled_paper.hpp"
#include "nhdyn/frontend/model_file.hpp"

namespace nhdyn {
namespace {

struct Evaluated {
  std::vector<double> A, Q, G, b, b0, D, phi, f;
  double energy = 0.0;
};

Evaluated evaluate(const Model& model, double t, const double* q, const double* v) {
  const std::size_t n = static_cast<std::size_t>(model.n()), s = static_cast<std::size_t>(model.s());
  Evaluated e;
  e.A.resize(n * n);
  e.Q.resize(n);
  e.G.resize(n);
  e.b.resize(s * n);
  e.b0.resize(s);
  e.D.resize((n - s) * n);
  e.phi.resize(static_cast<std::size_t>(model.position_constraints()));
  e.f.resize(static_cast<std::size_t>(model.velocity_constraints()));
  std::vector<double> scratch(model.evaluator->scratch_size());
  model.evaluator->terms(t, q, v, scratch.data(), TermsOut{e.A.data(), e.Q.data(), e.G.data(), e.b.data(), e.b0.data()});
  model.evaluator->complement(t, q, v, scratch.data(), e.D.data());
  model.evaluator->position_residual(t, q, scratch.data(), e.phi.data());
  model.evaluator->velocity_residual(t, q, v, scratch.data(), e.f.data());
  e.energy = model.evaluator->energy(t, q, v, scratch.data());
  return e;
}

void expect_round_off(const std::vector<double>& got, const std::vector<double>& expected, const char* what) {
  ASSERT_EQ(got.size(), expected.size()) << what;
  for (std::size_t i = 0; i < got.size(); ++i)
    EXPECT_NEAR(got[i], expected[i], 1e-14 * std::abs(expected[i])) << what << "[" << i << "]";
}

void expect_same_model(const Model& generated, const Model& compiled, double z_velocity_floor) {
  EXPECT_EQ(generated.name, compiled.name);
  EXPECT_EQ(generated.description, compiled.description);
  EXPECT_EQ(generated.coordinates, compiled.coordinates);
  ASSERT_EQ(generated.s(), compiled.s());
  for (int i = 0; i < compiled.s(); ++i) {
    EXPECT_EQ(generated.constraints[i].name, compiled.constraints[i].name);
    EXPECT_EQ(generated.constraints[i].level, compiled.constraints[i].level);
    EXPECT_EQ(generated.constraints[i].expression, compiled.constraints[i].expression);
  }
  ASSERT_EQ(generated.parameters.size(), compiled.parameters.size());
  for (std::size_t i = 0; i < compiled.parameters.size(); ++i) {
    EXPECT_EQ(generated.parameters[i].name, compiled.parameters[i].name);
    EXPECT_EQ(generated.parameters[i].value, compiled.parameters[i].value);
    EXPECT_EQ(generated.parameters[i].unit, compiled.parameters[i].unit);
  }
  EXPECT_EQ(generated.t0, compiled.t0);
  EXPECT_EQ(generated.q0, compiled.q0);
  EXPECT_EQ(generated.v0, compiled.v0);
  EXPECT_EQ(generated.defaults.t_end, compiled.defaults.t_end);
  EXPECT_EQ(generated.defaults.output_step, compiled.defaults.output_step);
  ASSERT_EQ(generated.path.has_value(), compiled.path.has_value());
  EXPECT_EQ(generated.path->x, compiled.path->x);
  EXPECT_EQ(generated.path->y, compiled.path->y);
  EXPECT_EQ(generated.evaluator->has_complement(), compiled.evaluator->has_complement());
  EXPECT_EQ(generated.evaluator->has_energy(), compiled.evaluator->has_energy());
  EXPECT_EQ(generated.evaluator->scratch_size(), 0u);

  std::mt19937 random(2024);
  std::uniform_real_distribution<double> uniform(-3.0, 3.0);
  for (int trial = 0; trial < 200; ++trial) {
    const double t = uniform(random);
    const double q[3] = {uniform(random), uniform(random), uniform(random)};
    double v[3] = {uniform(random), uniform(random), uniform(random)};
    if (std::abs(v[2]) < z_velocity_floor) v[2] = 1.0;
    const Evaluated g = evaluate(generated, t, q, v), c = evaluate(compiled, t, q, v);
    expect_round_off(g.A, c.A, "A");
    expect_round_off(g.Q, c.Q, "Q");
    expect_round_off(g.G, c.G, "G");
    expect_round_off(g.b, c.b, "b");
    expect_round_off(g.b0, c.b0, "b0");
    expect_round_off(g.D, c.D, "D");
    expect_round_off(g.phi, c.phi, "phi");
    expect_round_off(g.f, c.f, "f");
    EXPECT_NEAR(g.energy, c.energy, 1e-14 * std::abs(c.energy));
  }
}

TEST(GeneratedCode, SledMatchesTheInterpretedProgram) {
  const testing::HandBuilt built = testing::make_hand_built_sled();
  expect_same_model(generated::make_sled_model(), symbolic::compile_model(built.spec, built.derivation), 0.0);
}

TEST(GeneratedCode, AppellMatchesTheInterpretedProgram) {
  const testing::HandBuilt built = testing::make_hand_built_appell();
  expect_same_model(generated::make_appell_model(), symbolic::compile_model(built.spec, built.derivation), 0.1);
}

// The shipped model files, generated by `nhdyn codegen` at build time.
TEST(GeneratedCode, EveryExampleFileMatchesItsInterpretedProgram) {
  const std::string dir = std::string(NHDYN_SOURCE_DIR) + "/examples/";
  expect_same_model(from_file::make_appell_model(), symbolic::compile_model(load_model_file(dir + "appell.toml")), 0.1);
  expect_same_model(from_file::make_sled_model(), symbolic::compile_model(load_model_file(dir + "sled.toml")), 0.0);
  expect_same_model(from_file::make_sled_paper_model(),
                    symbolic::compile_model(load_model_file(dir + "sled_paper.toml")), 0.0);
}

}  // namespace
}  // namespace nhdyn
