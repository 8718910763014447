// Analytic solutions ([solution] in a model file, Evaluator::solution): the shipped closed forms
// satisfy the equations of motion that nhdyn derives independently (q'' of the solution against
// the formulation's q'' at the solution's state, and the constraints), the file's Appell agrees
// with the built-in one, a wrong closed form is caught by the same check, and bad [solution]
// tables are refused naming the file, line and symbol.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "nhdyn/analysis/exact_solution.hpp"
#include "nhdyn/core/error.hpp"
#include "nhdyn/formulation/formulation.hpp"
#include "nhdyn/frontend/model_file.hpp"
#include "nhdyn/model/appell.hpp"
#include "nhdyn/model/data.hpp"
#include "nhdyn/symbolic/compile.hpp"

namespace nhdyn {
namespace {

namespace fs = std::filesystem;
const fs::path source_dir = NHDYN_SOURCE_DIR;

std::string read_text(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

std::vector<double> solution_at(const Model& model, double t) {
  std::vector<double> scratch(model.evaluator->scratch_size()), qva(static_cast<std::size_t>(3 * model.n()));
  model.evaluator->solution(t, scratch.data(), qva.data());
  return qva;
}

// The largest relative disagreement, over the times given, between the solution's q'' and the
// q'' that sanh computes at the solution's state, and the largest |f| relative to |q'|^2 + 1.
struct Check {
  double acceleration = 0.0;
  double constraint = 0.0;
};

Check check_against_equations(const Model& model, const std::vector<double>& times) {
  const int n = model.n();
  Data data = make_data(model);
  Check out;
  for (double t : times) {
    const std::vector<double> qva = solution_at(model, t);
    const Status status = compute_dynamics(model, data, FormulationOptions{}, t, qva.data(), qva.data() + n);
    EXPECT_EQ(status, Status::ok) << "t = " << t;
    double scale = 1.0, v2 = 1.0;
    for (int i = 0; i < n; ++i) {
      scale = std::max(scale, std::abs(qva[static_cast<std::size_t>(2 * n + i)]));
      v2 += qva[static_cast<std::size_t>(n + i)] * qva[static_cast<std::size_t>(n + i)];
    }
    for (int i = 0; i < n; ++i)
      out.acceleration =
          std::max(out.acceleration, std::abs(data.qdd(i) - qva[static_cast<std::size_t>(2 * n + i)]) / scale);
    std::vector<double> scratch(model.evaluator->scratch_size());
    Vector f(model.velocity_constraints());
    model.evaluator->velocity_residual(t, qva.data(), qva.data() + n, scratch.data(), f.data());
    for (Eigen::Index i = 0; i < f.size(); ++i) out.constraint = std::max(out.constraint, std::abs(f(i)) / v2);
  }
  return out;
}

const std::vector<double> times{0.0, 0.37, 1.3, 4.71, 9.9};

TEST(Solution, AppellFileSatisfiesTheDerivedEquations) {
  const Model model = symbolic::compile_model(load_model_file(source_dir / "examples/appell.toml"));
  ASSERT_TRUE(model.evaluator->has_solution());
  const Check c = check_against_equations(model, times);
  EXPECT_LT(c.acceleration, 1e-12);
  EXPECT_LT(c.constraint, 1e-14);
}

TEST(Solution, KnifeEdgeFileSatisfiesTheDerivedEquations) {
  const Model model = symbolic::compile_model(load_model_file(source_dir / "examples/knife_edge.toml"));
  ASSERT_TRUE(model.evaluator->has_solution());
  const Check c = check_against_equations(model, times);
  EXPECT_LT(c.acceleration, 1e-12);
  EXPECT_LT(c.constraint, 1e-14);
}

TEST(Solution, BuiltInAppellSatisfiesTheEquationsAndAgreesWithTheFile) {
  const Model builtin = make_appell_model();
  const Model file = symbolic::compile_model(load_model_file(source_dir / "examples/appell.toml"));
  ASSERT_TRUE(builtin.evaluator->has_solution());
  const Check c = check_against_equations(builtin, times);
  EXPECT_LT(c.acceleration, 1e-12);
  EXPECT_LT(c.constraint, 1e-14);
  for (double t : times) {
    const std::vector<double> a = solution_at(builtin, t), b = solution_at(file, t);
    for (std::size_t i = 0; i < a.size(); ++i) EXPECT_NEAR(a[i], b[i], 1e-12 * (1.0 + std::abs(a[i]))) << i << " at " << t;
  }
}

// The check the tests above rely on can fail: a closed form with a wrong drift term starts at the
// right state (so compile_model accepts it) but does not satisfy the equations.
TEST(Solution, AWrongClosedFormFailsTheCheck) {
  std::string text = read_text(source_dir / "examples/knife_edge.toml");
  const std::string right = "g*sin(alpha)/(2*w^2)*sin(w*t)^2";
  const std::size_t at = text.find(right);
  ASSERT_NE(at, std::string::npos);
  text.replace(at, right.size(), "g*sin(alpha)/(3*w^2)*sin(w*t)^2");
  const Model model = symbolic::compile_model(load_model_string(text, "wrong.toml"));
  EXPECT_GT(check_against_equations(model, times).acceleration, 1e-2);
  // check_solution, run before any comparison, catches it at t0.
  try {
    check_solution(model);
    ADD_FAILURE() << "a wrong closed form passed check_solution";
  } catch (const ModelError& e) {
    EXPECT_NE(std::string(e.what()).find("does not solve the equations of motion"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("x''"), std::string::npos) << e.what();
  }
}

TEST(Solution, TheShippedSolutionsPassTheCheck) {
  EXPECT_NO_THROW(check_solution(make_appell_model()));
  EXPECT_NO_THROW(check_solution(symbolic::compile_model(load_model_file(source_dir / "examples/appell.toml"))));
  EXPECT_NO_THROW(check_solution(symbolic::compile_model(load_model_file(source_dir / "examples/knife_edge.toml"))));
}

// A closed form valid only for some parameters (v0/w) must not stop the model from compiling and
// simulating at the others; it is refused only where it would be used as a reference.
TEST(Solution, ASolutionThatDividesByZeroIsRefusedOnlyWhenUsed) {
  symbolic::Spec spec = load_model_file(source_dir / "examples/knife_edge.toml");
  spec.set_parameter("w", 0.0);
  const Model model = symbolic::compile_model(spec);
  try {
    check_solution(model);
    ADD_FAILURE() << "a NaN solution passed check_solution";
  } catch (const ModelError& e) {
    EXPECT_NE(std::string(e.what()).find("division by zero"), std::string::npos) << e.what();
  }
}

TEST(Solution, TheBuiltInAppellIsCheckedAgainstTheInitialStateItIsRunFrom) {
  Model model = make_appell_model();
  model.v0[0] = 2.0;  // its solution starts from x' = 1
  try {
    check_solution(model);
    ADD_FAILURE() << "a solution from another initial state passed check_solution";
  } catch (const ModelError& e) {
    EXPECT_NE(std::string(e.what()).find("does not start at the initial state"), std::string::npos) << e.what();
  }
}

TEST(Solution, AModelWithoutASolutionIsRefusedSayingHowToGiveOne) {
  try {
    check_solution(symbolic::compile_model(load_model_file(source_dir / "examples/sled.toml")));
    ADD_FAILURE() << "the sled has no solution";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("[solution]"), std::string::npos) << e.what();
  }
}

// ---- Bad [solution] tables ------------------------------------------------------------------

const std::string head = R"toml(name = "fall"
coordinates = ["x", "z"]
kinetic_energy = "m/2 * (x'^2 + z'^2)"
potential_energy = "-m*g*z"
[parameters]
m = 1.0
g = 9.81
[initial]
velocity = { x = 1 }
)toml";

std::string error_of(const std::string& text) {
  try {
    check_solution(symbolic::compile_model(load_model_string(text, "test.toml")));
  } catch (const ModelError& e) {
    return e.what();
  }
  return "(no error)";
}

bool has(const std::string& message, const std::string& word) { return message.find(word) != std::string::npos; }

TEST(SolutionError, AFreeFallIsAccepted) {
  const Model model = symbolic::compile_model(load_model_string(head + "[solution]\nx = \"t\"\nz = \"g*t^2/2\"\n", "t.toml"));
  const std::vector<double> qva = solution_at(model, 2.0);
  EXPECT_DOUBLE_EQ(qva[0], 2.0);
  EXPECT_DOUBLE_EQ(qva[1], 9.81 * 2.0);
  EXPECT_DOUBLE_EQ(qva[3], 9.81 * 2.0);  // z'
  EXPECT_DOUBLE_EQ(qva[5], 9.81);        // z''
}

TEST(SolutionError, DependsOnACoordinate) {
  const std::string m = error_of(head + "[solution]\nx = \"t\"\nz = \"x*t\"\n");
  EXPECT_TRUE(has(m, "test.toml:12:")) << m;
  EXPECT_TRUE(has(m, "t and the parameters only")) << m;
  EXPECT_TRUE(has(m, "'x'")) << m;
}

TEST(SolutionError, DependsOnAVelocity) {
  const std::string m = error_of(head + "[solution]\nx = \"x'*t\"\nz = \"0\"\n");
  EXPECT_TRUE(has(m, "test.toml:11:")) << m;
  EXPECT_TRUE(has(m, "'x''")) << m;
}

TEST(SolutionError, MissesACoordinate) {
  const std::string m = error_of(head + "[solution]\nx = \"t\"\n");
  EXPECT_TRUE(has(m, "not for z")) << m;
}

TEST(SolutionError, NamesAnUnknownCoordinate) {
  const std::string m = error_of(head + "[solution]\nx = \"t\"\nzz = \"0\"\n");
  EXPECT_TRUE(has(m, "test.toml:12:")) << m;
  EXPECT_TRUE(has(m, "'zz'")) << m;
  EXPECT_TRUE(has(m, "did you mean 'z'")) << m;
}

TEST(SolutionError, UnknownSymbol) {
  const std::string m = error_of(head + "[solution]\nx = \"t\"\nz = \"gg*t^2/2\"\n");
  EXPECT_TRUE(has(m, "test.toml:12:")) << m;
  EXPECT_TRUE(has(m, "gg")) << m;
}

TEST(SolutionError, NotAStringOrNumber) {
  const std::string m = error_of(head + "[solution]\nx = true\nz = \"0\"\n");
  EXPECT_TRUE(has(m, "test.toml:11:")) << m;
  EXPECT_TRUE(has(m, "solution.x")) << m;
}

TEST(SolutionError, DoesNotStartAtTheInitialState) {
  // x' = 2 at t0, but [initial] says 1.
  const std::string m = error_of(head + "[solution]\nx = \"2*t\"\nz = \"g*t^2/2\"\n");
  EXPECT_TRUE(has(m, "model 'fall'")) << m;
  EXPECT_TRUE(has(m, "does not start at the initial state")) << m;
  EXPECT_TRUE(has(m, "x' = 2")) << m;
  EXPECT_TRUE(has(m, "x' = 1")) << m;
}

TEST(SolutionError, NotARealNumberOnceTheParametersAreSet) {
  const std::string m = error_of(head + "[solution]\nx = \"t\"\nz = \"sqrt(-g)*t^2\"\n");
  // The parameters are read at run time, so the NaN is the one sqrt returns (its sign varies).
  EXPECT_TRUE(has(m, "z = nan") || has(m, "z = -nan")) << m;
  EXPECT_TRUE(has(m, "cannot be evaluated")) << m;
}

}  // namespace
}  // namespace nhdyn
