// The transcription of [optimize] problems (optimize/transcription.hpp) on its own, without IPOPT:
// its exact Jacobian (tangent mode, the dD-free form (O7) of
// docs/derivations/optimal-programs.md) against central differences of its constraints at random
// points, its gradient against differences of its objective, the Hessian of its Lagrangian against
// second differences of the Lagrangian's value, and the reader's refusals.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <utility>
#include <string>
#include <vector>

#include "nhdyn/core/error.hpp"
#include "nhdyn/frontend/load_model.hpp"
#include "nhdyn/frontend/optimize_problem.hpp"
#include "nhdyn/optimize/transcription.hpp"

namespace nhdyn {
namespace {

std::string example(const std::string& name) { return std::string(NHDYN_SOURCE_DIR) + "/examples/" + name; }

OptimalControlProblem problem_of(const ModelSource& source) {
  const LoadedModel loaded = load_model_described(source);
  return load_optimal_control_problem(source, loaded);
}

OptimalControlProblem problem_from_file(const std::string& file) { return problem_of(read_model_source(example(file))); }

// Central differences of g and f against jacobian_values and gradient at x.
void check_derivatives(Transcription& nlp, const std::vector<double>& x0) {
  const int nv = nlp.variables(), nc = nlp.constraints(), nz = nlp.jacobian_nonzeros();
  std::vector<int> rows(static_cast<std::size_t>(nz)), cols(static_cast<std::size_t>(nz));
  nlp.jacobian_pattern(rows.data(), cols.data());
  std::vector<double> values(static_cast<std::size_t>(nz)), grad(static_cast<std::size_t>(nv));
  ASSERT_TRUE(nlp.jacobian_values(x0.data(), values.data()));
  ASSERT_TRUE(nlp.gradient(x0.data(), grad.data()));
  // Dense exact Jacobian (entries of the pattern may repeat: none do, but sum to be safe).
  std::vector<double> exact(static_cast<std::size_t>(nv) * static_cast<std::size_t>(nc), 0.0);
  for (int e = 0; e < nz; ++e) exact[static_cast<std::size_t>(cols[e]) * nc + rows[e]] += values[e];
  std::vector<double> gp(static_cast<std::size_t>(nc)), gm(gp.size());
  double worst = 0.0, worst_gradient = 0.0;
  for (int c = 0; c < nv; ++c) {
    std::vector<double> x = x0;
    const double h = 1e-6 * std::max(1.0, std::abs(x0[c]));
    x[static_cast<std::size_t>(c)] = x0[static_cast<std::size_t>(c)] + h;
    ASSERT_TRUE(nlp.constraint_values(x.data(), gp.data()));
    double fp = 0, fm = 0;
    ASSERT_TRUE(nlp.objective(x.data(), fp));
    x[static_cast<std::size_t>(c)] = x0[static_cast<std::size_t>(c)] - h;
    ASSERT_TRUE(nlp.constraint_values(x.data(), gm.data()));
    ASSERT_TRUE(nlp.objective(x.data(), fm));
    for (int r = 0; r < nc; ++r) {
      const double difference = (gp[r] - gm[r]) / (2 * h);
      const double e = exact[static_cast<std::size_t>(c) * nc + r];
      worst = std::max(worst, std::abs(difference - e) / std::max(1.0, std::abs(e)));
    }
    worst_gradient = std::max(worst_gradient, std::abs((fp - fm) / (2 * h) - grad[c]) / std::max(1.0, std::abs(grad[c])));
  }
  // Central differences err by O(h^2) + round-off/h ~ 1e-8 here; a missing term (the dD term of
  // (O7), a T column) errs by O(1).
  EXPECT_LT(worst, 1e-6);
  EXPECT_LT(worst_gradient, 1e-6);
}

// The Hessian of the Lagrangian sigma f + lambda^T g (hessian_values: central differences of the
// exact gradient, grouped by the block structure) against second differences of the Lagrangian's
// value alone, over every pair of variables: an entry outside the pattern, a block that misses a
// coupling, or a wrong T row errs by O(1).
void check_hessian(Transcription& nlp, const std::vector<double>& x0, unsigned seed) {
  const int nv = nlp.variables(), nc = nlp.constraints(), nz = nlp.hessian_nonzeros();
  ASSERT_GT(nz, 0);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> d(-2.0, 2.0);
  std::vector<double> lambda(static_cast<std::size_t>(nc));
  for (double& l : lambda) l = d(rng);
  const double sigma = 0.7;
  std::vector<int> rows(static_cast<std::size_t>(nz)), cols(static_cast<std::size_t>(nz));
  nlp.hessian_pattern(rows.data(), cols.data());
  std::vector<double> values(static_cast<std::size_t>(nz));
  ASSERT_TRUE(nlp.hessian_values(x0.data(), sigma, lambda.data(), values.data()));
  std::vector<double> H(static_cast<std::size_t>(nv) * static_cast<std::size_t>(nv), 0.0);
  for (int e = 0; e < nz; ++e) {
    ASSERT_GE(rows[e], cols[e]);  // one triangle
    H[static_cast<std::size_t>(rows[e]) * nv + cols[e]] += values[e];
    if (rows[e] != cols[e]) H[static_cast<std::size_t>(cols[e]) * nv + rows[e]] += values[e];
  }
  std::vector<double> g(static_cast<std::size_t>(nc));
  const auto lagrangian = [&](const std::vector<double>& x) {
    double f = 0.0;
    EXPECT_TRUE(nlp.objective(x.data(), f));
    EXPECT_TRUE(nlp.constraint_values(x.data(), g.data()));
    double value = sigma * f;
    for (int r = 0; r < nc; ++r) value += lambda[static_cast<std::size_t>(r)] * g[static_cast<std::size_t>(r)];
    return value;
  };
  double worst = 0.0;
  for (int i = 0; i < nv; ++i)
    for (int j = 0; j <= i; ++j) {
      const double hi = 3e-4 * std::max(1.0, std::abs(x0[static_cast<std::size_t>(i)]));
      const double hj = 3e-4 * std::max(1.0, std::abs(x0[static_cast<std::size_t>(j)]));
      double sum = 0.0;
      for (const auto& [si, sj] : {std::pair{1, 1}, std::pair{1, -1}, std::pair{-1, 1}, std::pair{-1, -1}}) {
        std::vector<double> x = x0;
        x[static_cast<std::size_t>(i)] += si * hi;
        x[static_cast<std::size_t>(j)] += sj * hj;
        sum += si * sj * lagrangian(x);
      }
      const double difference = sum / (4 * hi * hj);
      const double e = H[static_cast<std::size_t>(i) * nv + j];
      worst = std::max(worst, std::abs(difference - e) / std::max(1.0, std::abs(e)));
    }
  // Second differences of values err by O(h^2) + round-off/h^2, about 1e-6 here (the car's
  // Lagrangian is of order 1e4).
  EXPECT_LT(worst, 1e-5);
}

std::vector<double> random_point(const Transcription& nlp, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> d(-0.8, 0.8);
  std::vector<double> x = nlp.start();
  for (double& v : x) v += d(rng);
  if (nlp.problem().free_time) x.back() = 0.9;
  return x;
}

TEST(Transcription, BrachistochroneJacobianIsExactWithFreeTime) {
  // A velocity constraint nonlinear in theta, a free final time, Hermite-Simpson: every block.
  OptimalControlProblem p = problem_from_file("brachistochrone.toml");
  p.nodes = 4;
  Transcription nlp(p);
  check_derivatives(nlp, random_point(nlp, 1));
  p.method = CollocationMethod::trapezoidal;
  Transcription trapezoidal(p);
  check_derivatives(trapezoidal, random_point(trapezoidal, 2));
}

TEST(Transcription, BrockettJacobianIsExactAtTheLevelGiven) {
  OptimalControlProblem p = problem_from_file("brockett.toml");
  p.nodes = 4;
  Transcription nlp(p);
  check_derivatives(nlp, random_point(nlp, 3));
  p.level = OptimizeConstraintLevel::acceleration;
  Transcription acceleration(p);
  check_derivatives(acceleration, random_point(acceleration, 4));
}

TEST(Transcription, PathConstraintsAndFinalTermAreDifferentiated) {
  const std::string text = R"toml(name = "plane"
coordinates = ["x", "y"]
kinetic_energy = "m/2 * (x'^2 + y'^2)"
[parameters]
m = 2.0
[optimize]
controls = [{ name = "F", actuator = ["cos(y)", "x*y'"] }, { name = "G", actuator = "y" }]
objective = "F^2 + G^2 + t*x*y'"
objective_final = "x^2 + y'^2 + t"
t_end = { free = [0.5, 3] }
nodes = 4
method = "trapezoidal"
initial = { x = 0, y = 0 }
path = ["x^2 + y^2*F >= t - 1"]
)toml";
  const OptimalControlProblem p = problem_of(model_source_from_text(text, "plane.toml"));
  Transcription nlp(p);
  check_derivatives(nlp, random_point(nlp, 5));
}

TEST(Transcription, HessianOfTheLagrangianMatchesSecondDifferences) {
  // Free time, a velocity constraint nonlinear in theta (both methods); two knife edges, two
  // controls and path constraints (parking); a final term and a time-dependent integrand (plane).
  OptimalControlProblem p = problem_from_file("brachistochrone.toml");
  p.nodes = 3;
  Transcription nlp(p);
  check_hessian(nlp, random_point(nlp, 11), 12);
  p.method = CollocationMethod::trapezoidal;
  Transcription trapezoidal(p);
  check_hessian(trapezoidal, random_point(trapezoidal, 13), 14);
  OptimalControlProblem parking = problem_from_file("parking.toml");
  parking.nodes = 2;
  Transcription car(parking);
  check_hessian(car, random_point(car, 15), 16);
  const std::string text = R"toml(name = "plane"
coordinates = ["x", "y"]
kinetic_energy = "m/2 * (x'^2 + y'^2)"
[parameters]
m = 2.0
[optimize]
controls = [{ name = "F", actuator = ["cos(y)", "x*y'"] }, { name = "G", actuator = "y" }]
objective = "F^2*x + G^2 + t*x*y'"
objective_final = "x^2*y + y'^2 + t^2"
t_end = { free = [0.5, 3] }
nodes = 3
initial = { x = 0, y = 0 }
path = ["x^2 + y^2*F >= t - 1"]
)toml";
  const OptimalControlProblem plane = problem_of(model_source_from_text(text, "plane.toml"));
  Transcription planar(plane);
  check_hessian(planar, random_point(planar, 17), 18);
}

TEST(Transcription, DoubleIntegratorStartsOnTheStraightLine) {
  const OptimalControlProblem p = problem_from_file("double_integrator.toml");
  Transcription nlp(p);
  EXPECT_EQ(nlp.points(), 2 * (p.nodes - 1) + 1);
  EXPECT_EQ(nlp.width(), 4);
  const std::vector<double>& x = nlp.start();
  EXPECT_DOUBLE_EQ(x[static_cast<std::size_t>(nlp.q_index(nlp.points() - 1, 0))], 1.0);
  EXPECT_DOUBLE_EQ(x[static_cast<std::size_t>(nlp.q_index((nlp.points() - 1) / 2, 0))], 0.5);
}

std::string plane_problem(const std::string& optimize) {
  return "name = \"plane\"\ncoordinates = [\"x\", \"y\"]\nkinetic_energy = \"m/2 * (x'^2 + y'^2)\"\n"
         "[parameters]\nm = 2.0\n[optimize]\n" + optimize;
}

std::string error_of(const std::string& optimize) {
  try {
    problem_of(model_source_from_text(plane_problem(optimize), "plane.toml"));
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

TEST(OptimizeSection, RefusesBadInputNamingWhere) {
  const std::string base = "controls = [{ name = \"F\", actuator = \"x\" }]\nt_end = 1\nnodes = 5\n";
  // an unknown symbol in the objective: file:line:column of the symbol, and the nearest name
  const std::string unknown = error_of(base + "objective = \"F^2 + xx\"\n");
  EXPECT_NE(unknown.find("plane.toml:10:20"), std::string::npos) << unknown;
  EXPECT_NE(unknown.find("xx"), std::string::npos) << unknown;
  // lower > upper
  const std::string bounds = error_of(base + "objective = \"F^2\"\nbounds = { F = [1, -1] }\n");
  EXPECT_NE(bounds.find("plane.toml:11:16"), std::string::npos) << bounds;
  EXPECT_NE(bounds.find("lower 1 > upper -1"), std::string::npos) << bounds;
  // a control that acts on nothing
  const std::string nothing =
      error_of("controls = [{ name = \"F\", actuator = [0, \"0*m\"] }]\nt_end = 1\nnodes = 5\nobjective = \"F^2\"\n");
  EXPECT_NE(nothing.find("plane.toml:7:"), std::string::npos) << nothing;
  EXPECT_NE(nothing.find("acts on nothing"), std::string::npos) << nothing;
  // an actuator that is not a coordinate
  const std::string actuator = error_of("controls = [{ name = \"F\", actuator = \"z\" }]\nt_end = 1\nnodes = 5\nobjective = \"F^2\"\n");
  EXPECT_NE(actuator.find("not a coordinate"), std::string::npos) << actuator;
  // an unknown key, a bad method, too few nodes, a state that is not one
  EXPECT_NE(error_of(base + "objective = \"F^2\"\nobjectiv = 1\n").find("did you mean 'objective'"), std::string::npos);
  EXPECT_NE(error_of(base + "objective = \"F^2\"\nmethod = \"euler\"\n").find("trapezoidal"), std::string::npos);
  EXPECT_NE(error_of("controls = [{ name = \"F\", actuator = \"x\" }]\nt_end = 1\nnodes = 2\nobjective = \"F^2\"\n")
                .find("nodes must be an integer from 3"),
            std::string::npos);
  EXPECT_NE(error_of(base + "objective = \"F^2\"\nfinal = { w = 1 }\n").find("'w' in final is not a coordinate"),
            std::string::npos);
  // "time" needs a free final time; a control named like a coordinate
  EXPECT_NE(error_of(base + "objective = \"time\"\n").find("free final time"), std::string::npos);
  EXPECT_NE(error_of("controls = [{ name = \"x\", actuator = \"x\" }]\nt_end = 1\nnodes = 5\nobjective = \"x^2\"\n")
                .find("named like a coordinate"),
            std::string::npos);
}

TEST(OptimizeSection, ReadsFlatAndNestedBoundaryStatesAndParameterExpressions) {
  const OptimalControlProblem p = problem_of(model_source_from_text(
      plane_problem("controls = [{ name = \"F\", actuator = \"x\" }]\nt_end = \"2*m\"\nnodes = \"m + 3\"\n"
                    "objective = \"F^2\"\ninitial = { x = 1, \"y'\" = \"m\" }\n"
                    "final = { position = { y = 3 }, velocity = { x = 0 } }\nbounds = { \"x'\" = [-1, \"m\"] }\n"),
      "plane.toml"));
  EXPECT_DOUBLE_EQ(p.t_end, 4.0);
  EXPECT_EQ(p.nodes, 5);
  ASSERT_EQ(p.initial.size(), 2U);
  EXPECT_FALSE(p.initial[0].velocity);
  EXPECT_TRUE(p.initial[1].velocity);
  EXPECT_DOUBLE_EQ(p.initial[1].value, 2.0);
  ASSERT_EQ(p.final.size(), 2U);
  EXPECT_DOUBLE_EQ(p.state_upper[2], 2.0);
  ASSERT_EQ(p.warnings.size(), 0U);
}

TEST(OptimizeSection, FinalAsAStringIsTheTermAtTheFinalTime) {
  const std::string base = "controls = [{ name = \"F\", actuator = \"x\" }]\nt_end = 1\nnodes = 5\nobjective = \"F^2\"\n";
  const OptimalControlProblem p = problem_of(model_source_from_text(plane_problem(base + "final = \"(x - 1)^2\"\n"), "plane.toml"));
  EXPECT_TRUE(p.final_term.has_value());
  EXPECT_TRUE(p.final.empty());
  EXPECT_NE(error_of(base + "final = \"x^2\"\nobjective_final = \"y^2\"\n").find("keep one"), std::string::npos);
}

TEST(OptimizeSection, WarnsOfAControlThatCostsNothing) {
  const OptimalControlProblem p = problem_of(model_source_from_text(
      plane_problem("controls = [{ name = \"F\", actuator = \"x\" }, { name = \"G\", actuator = \"y\" }]\n"
                    "t_end = 1\nnodes = 5\nobjective = \"F^2\"\n"),
      "plane.toml"));
  ASSERT_EQ(p.warnings.size(), 1U);
  EXPECT_NE(p.warnings[0].find("'G' costs nothing"), std::string::npos);
}

TEST(Transcription, RefusesAControlTheConstraintsAbsorb) {
  // A point on the line y = x (a position constraint) pushed across it, along (1, -1).
  const std::string model = R"(name = "rail"
coordinates = ["x", "y"]
kinetic_energy = "(x'^2 + y'^2)/2"
[[constraints]]
name = "rail"
position = "y - x"
[optimize]
controls = [{ name = "F", actuator = [1, -1] }]
objective = "F^2"
t_end = 1
nodes = 5
)";
  const OptimalControlProblem p = problem_of(model_source_from_text(model, "rail.toml"));
  try {
    Transcription nlp(p);
    FAIL() << "accepted a control the constraint absorbs";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("'F' does not act on the system"), std::string::npos) << e.what();
  }
}

TEST(Transcription, RefusesInitialValuesOffTheConstraintsAndBoundaryValuesOutsideBounds) {
  // The blade at rest with x' fixed sideways: the constraint cannot hold.
  const std::string model = R"(name = "blade"
coordinates = ["x", "y", "theta"]
kinetic_energy = "(x'^2 + y'^2 + theta'^2)/2"
[[constraints]]
name = "blade"
velocity = "-sin(theta)*x' + cos(theta)*y'"
[optimize]
controls = [{ name = "T", actuator = "theta" }]
objective = "T^2"
t_end = 1
nodes = 5
initial = { position = { theta = 0 }, velocity = { x = 0, y = 1, theta = 0 } }
)";
  const OptimalControlProblem p = problem_of(model_source_from_text(model, "blade.toml"));
  try {
    Transcription nlp(p);
    FAIL() << "accepted initial values off the constraint";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("violate the constraint blade"), std::string::npos) << e.what();
  }
  const OptimalControlProblem q = problem_of(model_source_from_text(
      plane_problem("controls = [{ name = \"F\", actuator = \"x\" }]\nt_end = 1\nnodes = 5\nobjective = \"F^2\"\n"
                    "final = { x = 3 }\nbounds = { x = [0, 2] }\n"),
      "plane.toml"));
  EXPECT_THROW(Transcription{q}, InputError);
}

}  // namespace
}  // namespace nhdyn
