// Model files (frontend/model_file.hpp, docs/model-format.md). Exams: the shipped examples and every
// complete example of the format's documentation load, and compiled they give the same A, Q, G,
// b, b0, residuals, energy, D and initial state as the hand-written built-in models, at random
// states. Then one test per kind of bad input, each checking the error's type, its words and the
// file:line:column it points at (lines and columns as an editor counts them, from 1).
#include "nhdyn/frontend/model_file.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <numbers>
#include <random>
#include <sstream>
#include <string>
#include <string_view>
#include <vector>

#include "nhdyn/core/error.hpp"
#include "nhdyn/core/types.hpp"
#include "nhdyn/formulation/formulation.hpp"
#include "nhdyn/integrators/ode.hpp"
#include "nhdyn/model/appell.hpp"
#include "nhdyn/model/model.hpp"
#include "nhdyn/model/sled.hpp"
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

// Loads `text` as "test.toml" and expects a ModelError whose message starts with
// "test.toml:<location>: " ("test.toml:<line>:" when location is "<line>:", "test.toml" when it
// is empty) and contains every one of `words`.
void expect_error(std::string_view text, const std::string& location, std::initializer_list<std::string_view> words) {
  try {
    (void)load_model_string(text, "test.toml");
    ADD_FAILURE() << "expected a ModelError at " << location << " for:\n" << text;
  } catch (const ModelError& e) {
    const std::string message = e.what();
    const std::string prefix = location.empty()        ? std::string("test.toml")
                               : location.ends_with(':') ? "test.toml:" + location
                                                         : "test.toml:" + location + ": ";
    EXPECT_EQ(message.rfind(prefix, 0), 0u) << message;
    for (std::string_view word : words) EXPECT_NE(message.find(word), std::string::npos) << "'" << word << "' in: " << message;
  }
}

// ---- The shipped examples ----------------------------------------------------------------------

TEST(ModelFile, AppellExampleLoads) {
  const symbolic::Spec spec = load_model_file(source_dir / "examples/appell.toml");
  EXPECT_EQ(spec.name, "appell");
  EXPECT_EQ(spec.coordinates, (std::vector<std::string>{"x", "y", "z"}));
  ASSERT_EQ(spec.parameters.size(), 3u);
  EXPECT_EQ(spec.parameters[0].name, "m");  // in the order of the file
  EXPECT_EQ(spec.parameters[1].name, "g");
  EXPECT_EQ(spec.parameters[1].unit, "m/s^2");
  EXPECT_EQ(spec.parameters[2].name, "a");
  EXPECT_EQ(spec.parameters[2].value, 0.5);
  ASSERT_EQ(spec.s(), 1);
  EXPECT_EQ(spec.constraints[0].name, "appell");
  EXPECT_EQ(spec.constraints[0].level, ConstraintLevel::velocity);
  EXPECT_EQ(spec.independent, (std::vector<std::string>{"x", "y"}));
  ASSERT_TRUE(spec.path);
  EXPECT_EQ(spec.path->first, "x");
  EXPECT_EQ(spec.path->second, "y");
}

TEST(ModelFile, SledExamplesLoad) {
  for (const char* file : {"examples/sled.toml", "examples/sled_paper.toml"}) {
    const symbolic::Spec spec = load_model_file(source_dir / file);
    EXPECT_EQ(spec.coordinates, (std::vector<std::string>{"x", "y", "phi"})) << file;
    ASSERT_EQ(spec.parameters.size(), 5u) << file;
    EXPECT_EQ(spec.parameters[3].name, "alpha");
    EXPECT_NEAR(spec.parameters[3].value, std::numbers::pi / 6, 1e-15);  // written "pi/6"
    EXPECT_EQ(spec.parameters[3].unit, "rad");
    ASSERT_EQ(spec.s(), 1);
    EXPECT_EQ(spec.constraints[0].name, "blade");
    EXPECT_EQ(spec.independent, (std::vector<std::string>{"x", "phi"}));
    EXPECT_EQ(spec.defaults.t_end, 10.0);
    EXPECT_EQ(spec.defaults.output_step, 0.01);
  }
}

// A location inside an expression string is the constraint's, the string's first character.
TEST(ModelFile, LocationsPointIntoTheFile) {
  const symbolic::Spec spec = load_model_file(source_dir / "examples/sled_paper.toml");
  const std::string text = read_text(source_dir / "examples/sled_paper.toml");
  const symbolic::SourceLocation& where = spec.constraints[0].where;
  EXPECT_EQ(where.file, (source_dir / "examples/sled_paper.toml").string());
  std::istringstream lines(text);
  std::string line;
  for (int i = 0; i < where.line; ++i) std::getline(lines, line);
  ASSERT_GT(where.column, 0);
  EXPECT_EQ(line.substr(static_cast<std::size_t>(where.column - 1)).rfind("y' - tan(phi)*x'", 0), 0u) << line;
}

// ---- Compiled examples against the hand-written models ---------------------------------------

struct Terms {
  Matrix A, b, D;
  Vector Q, G, b0, f;
  double energy = 0.0;
};

Terms evaluate(const Model& model, double t, const Vector& q, const Vector& v) {
  const int n = model.n(), s = model.s();
  Terms out{Matrix(n, n), Matrix(s, n), Matrix(n - s, n), Vector(n), Vector(n), Vector(s), Vector(model.velocity_constraints())};
  std::vector<double> scratch(model.evaluator->scratch_size());
  model.evaluator->terms(t, q.data(), v.data(), scratch.data(), {out.A.data(), out.Q.data(), out.G.data(), out.b.data(), out.b0.data()});
  if (model.evaluator->has_complement()) model.evaluator->complement(t, q.data(), v.data(), scratch.data(), out.D.data());
  model.evaluator->velocity_residual(t, q.data(), v.data(), scratch.data(), out.f.data());
  if (model.evaluator->has_energy()) out.energy = model.evaluator->energy(t, q.data(), v.data(), scratch.data());
  return out;
}

void expect_near(const Matrix& actual, const Matrix& expected, double tolerance, const std::string& what) {
  ASSERT_EQ(actual.rows(), expected.rows()) << what;
  ASSERT_EQ(actual.cols(), expected.cols()) << what;
  for (Eigen::Index i = 0; i < actual.rows(); ++i)
    for (Eigen::Index j = 0; j < actual.cols(); ++j)
      EXPECT_NEAR(actual(i, j), expected(i, j), tolerance * (1.0 + std::fabs(expected(i, j))))
          << what << "(" << i << ", " << j << ")";
}

void expect_same_description(const Model& file, const Model& builtin) {
  EXPECT_EQ(file.name, builtin.name);
  EXPECT_EQ(file.coordinates, builtin.coordinates);
  ASSERT_EQ(file.s(), builtin.s());
  for (int i = 0; i < file.s(); ++i) {
    EXPECT_EQ(file.constraints[static_cast<std::size_t>(i)].name, builtin.constraints[static_cast<std::size_t>(i)].name);
    EXPECT_EQ(file.constraints[static_cast<std::size_t>(i)].level, builtin.constraints[static_cast<std::size_t>(i)].level);
  }
  ASSERT_EQ(file.parameters.size(), builtin.parameters.size());
  for (std::size_t i = 0; i < file.parameters.size(); ++i) {
    EXPECT_EQ(file.parameters[i].name, builtin.parameters[i].name);
    EXPECT_NEAR(file.parameters[i].value, builtin.parameters[i].value, 1e-15);
    EXPECT_EQ(file.parameters[i].unit, builtin.parameters[i].unit);
  }
  EXPECT_EQ(file.t0, builtin.t0);
  expect_near(file.q0, builtin.q0, 1e-15, "q0");
  expect_near(file.v0, builtin.v0, 1e-15, "v0");
  EXPECT_EQ(file.defaults.t_end, builtin.defaults.t_end);
  EXPECT_EQ(file.defaults.output_step, builtin.defaults.output_step);
  ASSERT_TRUE(file.path);
  ASSERT_TRUE(builtin.path);
  EXPECT_EQ(file.path->x, builtin.path->x);
  EXPECT_EQ(file.path->y, builtin.path->y);
  EXPECT_EQ(file.evaluator->has_energy(), builtin.evaluator->has_energy());
  EXPECT_TRUE(file.evaluator->has_complement());  // from `independent`
}

// The file's constraint row is f = z'^2 - a^2 (x'^2 + y'^2) differentiated: 2 z' times the
// hand-written model's row, which is the paper's form divided by 2 z'.
TEST(ModelFile, AppellMatchesTheBuiltInModel) {
  const Model file = symbolic::compile_model(load_model_file(source_dir / "examples/appell.toml"));
  const Model builtin = make_appell_model();
  expect_same_description(file, builtin);
  std::mt19937 random(20240611);
  std::uniform_real_distribution<double> uniform(-2.0, 2.0), speed(0.2, 2.0);
  for (int trial = 0; trial < 50; ++trial) {
    const double t = uniform(random);
    const Vector q = Vector::NullaryExpr(3, [&] { return uniform(random); });
    Vector v = Vector::NullaryExpr(3, [&] { return uniform(random); });
    v(2) = (trial % 2 == 0 ? 1.0 : -1.0) * speed(random);  // z' != 0: the paper's form divides by it
    const Terms a = evaluate(file, t, q, v), e = evaluate(builtin, t, q, v);
    expect_near(a.A, e.A, 1e-12, "A");
    expect_near(a.Q, e.Q, 1e-12, "Q");
    expect_near(a.G, e.G, 1e-12, "G");
    expect_near(a.b / (2.0 * v(2)), e.b, 1e-12, "b / 2 z'");
    expect_near(a.b0 / (2.0 * v(2)), e.b0, 1e-12, "b0 / 2 z'");
    expect_near(a.f, e.f, 1e-12, "f");
    expect_near(a.D, e.D, 1e-12, "D");  // the partitioned D of x, y is the paper's
    EXPECT_NEAR(a.energy, e.energy, 1e-12 * (1.0 + std::fabs(e.energy)));
  }
}

void expect_sled_matches(const char* file_name, SledVariant variant) {
  const Model file = symbolic::compile_model(load_model_file(source_dir / file_name));
  const Model builtin = make_sled_model(variant);
  expect_same_description(file, builtin);
  std::mt19937 random(7);
  // Headings inside (-pi/2, pi/2) with margin: the paper's form has tan(phi).
  std::uniform_real_distribution<double> uniform(-2.0, 2.0), heading(-1.2, 1.2);
  for (int trial = 0; trial < 50; ++trial) {
    const double t = uniform(random);
    const Vector q{{uniform(random), uniform(random), heading(random)}};
    const Vector v = Vector::NullaryExpr(3, [&] { return uniform(random); });
    const Terms a = evaluate(file, t, q, v), e = evaluate(builtin, t, q, v);
    expect_near(a.A, e.A, 1e-12, "A");
    expect_near(a.Q, e.Q, 1e-12, "Q");
    expect_near(a.G, e.G, 1e-12, "G");
    expect_near(a.b, e.b, 1e-12, "b");
    expect_near(a.b0, e.b0, 1e-12, "b0");
    expect_near(a.f, e.f, 1e-12, "f");
    EXPECT_NEAR(a.energy, e.energy, 1e-12 * (1.0 + std::fabs(e.energy)));
    // The partitioned D of (x, phi) is the paper's [[1, tan phi, 0], [0, 0, 1]]; the hand-written
    // centre-of-mass sled has its first row times cos(phi).
    Matrix expected_D = e.D;
    if (variant == SledVariant::centre_of_mass) expected_D.row(0) /= std::cos(q(2));
    expect_near(a.D, expected_D, 1e-12, "D");
  }
}

TEST(ModelFile, SledMatchesTheBuiltInModel) { expect_sled_matches("examples/sled.toml", SledVariant::centre_of_mass); }

TEST(ModelFile, SledPaperMatchesTheBuiltInModel) { expect_sled_matches("examples/sled_paper.toml", SledVariant::paper); }

// ---- The documentation's examples --------------------------------------------------------------

// Every ```toml block of docs/model-format.md is a complete model file that loads and compiles.
TEST(ModelFile, DocumentationExamplesLoad) {
  const std::string doc = read_text(source_dir / "docs/model-format.md");
  ASSERT_FALSE(doc.empty());
  int blocks = 0;
  std::size_t at = 0;
  while ((at = doc.find("```toml\n", at)) != std::string::npos) {
    const std::size_t begin = at + 8;
    const std::size_t end = doc.find("```\n", begin);
    ASSERT_NE(end, std::string::npos);
    const std::string block = doc.substr(begin, end - begin);
    ++blocks;
    const std::string name = "model-format.md block " + std::to_string(blocks);
    try {
      const symbolic::Spec spec = load_model_string(block, name);
      (void)symbolic::compile_model(spec);
    } catch (const Error& e) {
      ADD_FAILURE() << e.what() << "\n" << block;
    }
    at = end + 4;
  }
  EXPECT_GE(blocks, 3);
}

// The analytic D of a file, given as numbers and expressions, reaches the compiled model.
TEST(ModelFile, ComplementGivesTheAnalyticD) {
  const Model model = symbolic::compile_model(load_model_string(R"toml(name = "sled-paper-D"
coordinates = ["x", "y", "phi"]
kinetic_energy = "m/2 * (x'^2 + y'^2) + m*a*phi' * (cos(phi)*y' - sin(phi)*x') + m*rho^2/2 * phi'^2"
potential_energy = "-m*g*sin(alpha) * x"
complement = [[1, "tan(phi)", 0], [0, 0, 1.0]]
parameters = { m = 1.0, a = 0.5, rho = 0.7, alpha = "pi/6", g = 9.81 }
constraints = [{ name = "blade", velocity = "y' - tan(phi)*x'" }]
)toml", "inline.toml"));
  const Model builtin = make_sled_model(SledVariant::paper);
  const Vector q{{0.3, -0.2, 0.4}}, v{{1.0, 0.5, -0.3}};
  const Terms a = evaluate(model, 0.0, q, v), e = evaluate(builtin, 0.0, q, v);
  expect_near(a.D, e.D, 1e-14, "D");
  expect_near(a.b, e.b, 1e-14, "b");
  // No [initial]: every coordinate and velocity starts at 0.
  EXPECT_EQ(model.q0, Vector::Zero(3));
  EXPECT_EQ(model.v0, Vector::Zero(3));
}

// Forces, a time-dependent position constraint and an acceleration constraint, [initial] with t0
// and expressions, and every key of [simulation].
TEST(ModelFile, EveryKeyLoads) {
  const symbolic::Spec spec = load_model_string(R"toml(name = "everything"
description = "a particle on a moving circle, damped, with a motor on z"
coordinates = ["x", "y", "z"]
kinetic_energy = "m/2 * (x'^2 + y'^2 + z'^2)"
potential_energy = "m*g*y"
[parameters]
m = { value = 2, unit = "kg" }
g = 9.81
r = { value = "1/2" }
w = "2*pi*r"
c = 0.1
[forces]
x = "-c*x'"
z = "sin(w*t)"
[[constraints]]
name = "circle"
position = "x^2 + y^2 - (r + t/10)^2"
[[constraints]]
acceleration = "z'' + x''"
[initial]
t0 = 0.5
position = { x = "r + 1/20", y = 0 }
velocity.y = "w*r"
[simulation]
t_end = 5
output_step = 0.05
integrator = "rk4"
method = "lagrange"
rtol = 1e-9
atol = 1e-11
[plot]
path = ["x", "y"]
)toml",
                                                "everything.toml");
  (void)spec;
}

// The names the loader accepts for [simulation] are those of the formulation and integrator modules.
TEST(ModelFile, SimulationNamesAgreeWithTheLibrary) {
  const std::string head = "name = \"p\"\ncoordinates = [\"x\"]\nkinetic_energy = \"x'^2/2\"\n[simulation]\n";
  for (Formulation method : {Formulation::sanh, Formulation::lagrange, Formulation::udwadia_kalaba, Formulation::nullspace}) {
    const symbolic::Spec spec = load_model_string(head + "method = \"" + std::string(formulation_name(method)) + "\"\n", "m.toml");
    EXPECT_EQ(parse_formulation(spec.method), method);
  }
  for (IntegratorKind kind : {IntegratorKind::rk4, IntegratorKind::dopri5, IntegratorKind::cvode_bdf,
                              IntegratorKind::cvode_adams}) {
    const symbolic::Spec spec =
        load_model_string(head + "integrator = \"" + std::string(integrator_name(kind)) + "\"\n", "i.toml");
    EXPECT_EQ(parse_integrator(spec.integrator), kind);
  }
}

// ---- Bad input: TOML ---------------------------------------------------------------------------

TEST(ModelFileError, TomlSyntax) {
  expect_error("name = \"m\"\ncoordinates = [\"x\",\nkinetic_energy = \"x'^2\"\n", "3:1", {"TOML syntax error"});
}

TEST(ModelFileError, TomlUnterminatedString) {
  expect_error("name = \"m\ncoordinates = [\"x\"]\n", "1:10", {"TOML syntax error"});
}

TEST(ModelFileError, TomlDuplicatedKey) {
  expect_error("name = \"m\"\nname = \"n\"\n", "2:", {"TOML syntax error", "cannot redefine", "name"});
}

// ---- Bad input: missing keys and sections -----------------------------------------------------

TEST(ModelFileError, MissingName) {
  expect_error("coordinates = [\"x\"]\nkinetic_energy = \"x'^2/2\"\n", "1:1", {"missing key 'name'", "name = \""});
}

TEST(ModelFileError, MissingCoordinates) {
  expect_error("name = \"m\"\nkinetic_energy = \"x'^2/2\"\n", "1:1", {"missing key 'coordinates'"});
}

TEST(ModelFileError, MissingKineticEnergy) {
  expect_error("name = \"m\"\ncoordinates = [\"x\"]\n", "1:1", {"missing key 'kinetic_energy'"});
}

TEST(ModelFileError, EmptyCoordinates) {
  expect_error("name = \"m\"\ncoordinates = []\nkinetic_energy = \"0\"\n", "2:15", {"'coordinates' is empty"});
}

TEST(ModelFileError, ParameterWithoutValue) {
  expect_error(R"toml(name = "m"
coordinates = ["x"]
kinetic_energy = "k*x'^2/2"
[parameters]
k = { unit = "kg" }
)toml",
               "5:5", {"parameter 'k' has no value", "value ="});
}

TEST(ModelFileError, ConstraintWithoutLevel) {
  expect_error(R"toml(name = "m"
coordinates = ["x", "y"]
kinetic_energy = "x'^2/2 + y'^2/2"
[[constraints]]
name = "line"
)toml",
               "4:1", {"constraint 'line' has no expression", "position", "velocity", "acceleration"});
}

TEST(ModelFileError, ConstraintWithTwoLevels) {
  expect_error(R"toml(name = "m"
coordinates = ["x", "y"]
kinetic_energy = "x'^2/2 + y'^2/2"
[[constraints]]
position = "x - y"
velocity = "x' - y'"
)toml",
               "6:1", {"both as position and as velocity", "exactly one"});
}

// ---- Bad input: types --------------------------------------------------------------------------

TEST(ModelFileError, NumberForAnExpression) {
  expect_error("name = \"m\"\ncoordinates = [\"x\"]\nkinetic_energy = 5\n", "3:18",
               {"'kinetic_energy' must be an expression written as a string", "an integer"});
}

TEST(ModelFileError, NumberForAName) {
  expect_error("name = 3.5\n", "1:8", {"'name' must be a string", "a floating-point number"});
}

TEST(ModelFileError, StringForCoordinates) {
  expect_error("name = \"m\"\ncoordinates = \"x\"\n", "2:15", {"'coordinates' must be an array", "a string"});
}

TEST(ModelFileError, NumberAmongCoordinates) {
  expect_error("name = \"m\"\ncoordinates = [\"x\", 2]\n", "2:21", {"'coordinates[2]' must be a string", "an integer"});
}

TEST(ModelFileError, BooleanParameter) {
  expect_error("name = \"m\"\ncoordinates = [\"x\"]\nkinetic_energy = \"x'^2\"\n[parameters]\nk = true\n", "5:5",
               {"parameter 'k' must be a number", "a boolean"});
}

TEST(ModelFileError, ForcesNotATable) {
  expect_error("name = \"m\"\ncoordinates = [\"x\"]\nkinetic_energy = \"x'^2\"\nforces = \"-x\"\n", "4:10",
               {"'forces' must be a table", "a string"});
}

TEST(ModelFileError, NumberForAConstraint) {
  expect_error("name = \"m\"\ncoordinates = [\"x\", \"y\"]\nkinetic_energy = \"x'^2\"\n[[constraints]]\nvelocity = 0.0\n",
               "5:12", {"'c1.velocity' must be an expression written as a string"});
}

TEST(ModelFileError, StringForANumber) {
  expect_error("name = \"m\"\ncoordinates = [\"x\"]\nkinetic_energy = \"x'^2\"\n[simulation]\nt_end = \"10\"\n", "5:9",
               {"'simulation.t_end' must be a number", "a string"});
}

TEST(ModelFileError, BooleanInitialValue) {
  expect_error("name = \"m\"\ncoordinates = [\"x\"]\nkinetic_energy = \"x'^2\"\n[initial]\nvelocity = { x = false }\n",
               "5:18", {"'initial.velocity.x' must be a number or an expression", "a boolean"});
}

TEST(ModelFileError, DateInComplement) {
  expect_error(
      "name = \"m\"\ncoordinates = [\"x\", \"y\"]\nkinetic_energy = \"x'^2\"\ncomplement = [[1, 1979-05-27]]\n",
      "4:19", {"'complement row 1' must be a number or an expression", "a date"});
}

TEST(ModelFileError, InfiniteNumber) {
  expect_error("name = \"m\"\ncoordinates = [\"x\"]\nkinetic_energy = \"x'^2\"\nparameters = { k = inf }\n", "4:20",
               {"must be a finite number"});
}

TEST(ModelFileError, PlotPathOfOneCoordinate) {
  expect_error("name = \"m\"\ncoordinates = [\"x\"]\nkinetic_energy = \"x'^2\"\n[plot]\npath = [\"x\"]\n", "5:8",
               {"plot.path must name two coordinates"});
}

// ---- Bad input: unknown keys and names ----------------------------------------------------------

TEST(ModelFileError, UnknownTopLevelKeySuggestsTheNearest) {
  expect_error("name = \"m\"\ncoordinates = [\"x\"]\nkinetic_enrgy = \"x'^2\"\n", "3:1",
               {"unknown key 'kinetic_enrgy'", "did you mean 'kinetic_energy'?"});
}

TEST(ModelFileError, UnknownKeyFarFromAnyListsTheKeys) {
  expect_error("name = \"m\"\nzzzzzzzzzzzz = 1\n", "2:1", {"unknown key 'zzzzzzzzzzzz'", "the keys here are: name,"});
}

TEST(ModelFileError, UnknownSimulationKey) {
  expect_error("name = \"m\"\ncoordinates = [\"x\"]\nkinetic_energy = \"x'^2\"\n[simulation]\ntend = 3\n", "5:1",
               {"unknown key 'tend' in [simulation]", "did you mean 't_end'?"});
}

TEST(ModelFileError, UnknownConstraintKey) {
  expect_error("name = \"m\"\ncoordinates = [\"x\", \"y\"]\nkinetic_energy = \"x'^2\"\n[[constraints]]\nvelocty = \"x'\"\n",
               "5:1", {"unknown key 'velocty' in constraint 1", "did you mean 'velocity'?"});
}

TEST(ModelFileError, UnknownParameterKey) {
  expect_error(
      "name = \"m\"\ncoordinates = [\"x\"]\nkinetic_energy = \"x'^2\"\n[parameters]\nk = { value = 1, units = \"N/m\" }\n",
      "5:18", {"unknown key 'units' in parameter 'k'", "did you mean 'unit'?"});
}

TEST(ModelFileError, UnknownInitialAndPlotKeys) {
  expect_error("name = \"m\"\ncoordinates = [\"x\"]\nkinetic_energy = \"x'^2\"\n[initial]\npositions = { x = 1 }\n", "5:1",
               {"unknown key 'positions' in [initial]", "did you mean 'position'?"});
  expect_error("name = \"m\"\ncoordinates = [\"x\"]\nkinetic_energy = \"x'^2\"\n[plot]\npaths = [\"x\", \"x\"]\n", "5:1",
               {"unknown key 'paths' in [plot]", "did you mean 'path'?"});
}

// Keys written below a [section] header belong to that section: say so instead of "unknown".
TEST(ModelFileError, TopLevelKeyBelowASection) {
  expect_error(R"toml(name = "m"
coordinates = ["x"]
[parameters]
k = 1
kinetic_energy = "x'^2/2"
)toml",
               "5:1", {"'kinetic_energy' is in [parameters]", "move 'kinetic_energy' above the first [section]"});
}

TEST(ModelFileError, ForceOnAnUnknownCoordinate) {
  expect_error("name = \"m\"\ncoordinates = [\"x\", \"phi\"]\nkinetic_energy = \"x'^2\"\n[forces]\nph = \"1\"\n", "5:1",
               {"'ph' in [forces] is not a coordinate", "did you mean 'phi'?"});
}

TEST(ModelFileError, InitialValueOfAnUnknownCoordinate) {
  expect_error("name = \"m\"\ncoordinates = [\"x\"]\nkinetic_energy = \"x'^2\"\n[initial]\nvelocity = { y = 1 }\n", "5:14",
               {"'y' in [initial.velocity] is not a coordinate"});
}

TEST(ModelFileError, UnknownIndependentCoordinate) {
  expect_error("name = \"m\"\ncoordinates = [\"x\", \"y\"]\nkinetic_energy = \"x'^2\"\nindependent = [\"x\", \"z\"]\n",
               "4:21", {"'z' in 'independent' is not a coordinate"});
}

TEST(ModelFileError, UnknownPathCoordinate) {
  expect_error("name = \"m\"\ncoordinates = [\"x\", \"y\"]\nkinetic_energy = \"x'^2\"\n[plot]\npath = [\"x\", \"yy\"]\n",
               "5:14", {"'yy' in plot.path is not a coordinate", "did you mean 'y'?"});
}

TEST(ModelFileError, UnknownMethodAndIntegrator) {
  expect_error("name = \"m\"\ncoordinates = [\"x\"]\nkinetic_energy = \"x'^2\"\n[simulation]\nmethod = \"sahn\"\n", "5:10",
               {"unknown simulation.method 'sahn'", "did you mean 'sanh'?", "udwadia-kalaba"});
  expect_error("name = \"m\"\ncoordinates = [\"x\"]\nkinetic_energy = \"x'^2\"\n[simulation]\nintegrator = \"euler\"\n",
               "5:14", {"unknown simulation.integrator 'euler'", "rk4, dopri5, dop853, cvode-bdf, cvode-adams"});
}

TEST(ModelFileError, IndependentAndComplementTogether) {
  expect_error(R"toml(name = "m"
coordinates = ["x", "y"]
kinetic_energy = "x'^2/2 + y'^2/2"
independent = ["x"]
complement = [[1, 1]]
)toml",
               "5:14", {"either 'independent' or 'complement', not both"});
}

// ---- Bad input: duplicated names ---------------------------------------------------------------

TEST(ModelFileError, DuplicatedConstraintName) {
  expect_error(R"toml(name = "m"
coordinates = ["x", "y", "z"]
kinetic_energy = "x'^2/2 + y'^2/2 + z'^2/2"
[[constraints]]
name = "c"
velocity = "x' - y'"
[[constraints]]
name = "c"
velocity = "y' - z'"
)toml",
               "8:8", {"constraint name 'c' is used twice (first at line 5)"});
}

TEST(ModelFileError, DuplicatedCoordinate) {
  expect_error("name = \"m\"\ncoordinates = [\"x\", \"y\", \"x\"]\nkinetic_energy = \"x'^2\"\n", "2:26", {"'x'"});
}

TEST(ModelFileError, ParameterNamedLikeACoordinate) {
  expect_error("name = \"m\"\ncoordinates = [\"x\", \"y\"]\nkinetic_energy = \"x'^2\"\n[parameters]\ny = 1\n", "5:1", {"'y'"});
}

// ---- Bad input: values -------------------------------------------------------------------------

TEST(ModelFileError, OutputStepNotPositive) {
  expect_error("name = \"m\"\ncoordinates = [\"x\"]\nkinetic_energy = \"x'^2\"\n[simulation]\noutput_step = -0.1\n", "5:15",
               {"output_step = -0.1 must be positive"});
}

TEST(ModelFileError, EndBeforeStart) {
  expect_error(R"toml(name = "m"
coordinates = ["x"]
kinetic_energy = "x'^2"
[initial]
t0 = 2
[simulation]
t_end = 1
)toml",
               "7:9", {"t_end = 1 must be after the initial time t0 = 2"});
}

TEST(ModelFileError, ToleranceNotPositive) {
  expect_error("name = \"m\"\ncoordinates = [\"x\"]\nkinetic_energy = \"x'^2\"\n[simulation]\natol = 0\n", "5:8",
               {"atol = 0 must be positive"});
}

TEST(ModelFileError, ParameterValueUsesACoordinate) {
  expect_error("name = \"m\"\ncoordinates = [\"x\"]\nkinetic_energy = \"k*x'^2\"\n[parameters]\nk = \"2*x\"\n", "5:6",
               {"uses 'x'", "only numbers, pi and the parameters above it"});
}

// ---- Bad input: what SpecBuilder reports, at the file's column ----------------------------------

TEST(ModelFileError, UnknownSymbolInAnExpression) {
  expect_error(R"toml(name = "m"
coordinates = ["x"]
kinetic_energy = "m*rh0^2*x'^2/2"
[parameters]
m = 1
rho = 0.5
)toml",
               "3:21", {"rh0", "did you mean 'rho'?"});
}

TEST(ModelFileError, VelocityOfAnUnknownCoordinate) {
  expect_error("name = \"m\"\ncoordinates = [\"x\"]\nkinetic_energy = \"x'^2/2 + u'^2\"\n", "3:28", {"'u''", "not a coordinate"});
}

TEST(ModelFileError, ExpressionSyntax) {
  expect_error("name = \"m\"\ncoordinates = [\"x\"]\nkinetic_energy = \"x'^2/2\"\npotential_energy = \"x^2 +* 3\"\n", "4:",
               {});
}

TEST(ModelFileError, PositionConstraintWithAVelocity) {
  expect_error(R"toml(name = "m"
coordinates = ["x", "y"]
kinetic_energy = "x'^2/2 + y'^2/2"
[[constraints]]
name = "bad"
position = "x - y'"
)toml",
               "6:", {"bad"});
}

TEST(ModelFileError, AsManyConstraintsAsCoordinates) {
  expect_error(R"toml(name = "m"
coordinates = ["x"]
kinetic_energy = "x'^2/2"
[[constraints]]
velocity = "x'"
)toml",
               "", {"constraint"});
}

TEST(ModelFileError, BadInitialExpression) {
  expect_error("name = \"m\"\ncoordinates = [\"x\"]\nkinetic_energy = \"x'^2\"\n[initial]\nposition = { x = \"2*q\" }\n",
               "5:21", {"'q'"});
}

TEST(ModelFileError, BadComplementExpression) {
  expect_error(R"toml(name = "m"
coordinates = ["x", "y"]
kinetic_energy = "x'^2/2 + y'^2/2"
complement = [[1, "tan(ph)"]]
[[constraints]]
velocity = "x' - y'"
)toml",
               "4:24", {"'ph'"});
}

// SpecBuilder counts columns in the text as TOML delivers it; the loader moves them to the file,
// across escapes and the line continuations of multi-line strings.
TEST(ModelFileError, PositionsFollowEscapes) {
  expect_error("name = \"m\"\ncoordinates = [\"x\"]\nkinetic_energy = \"x'^2 \\u002B rh0\"\n", "3:31",
               {"unknown symbol 'rh0'"});
}

TEST(ModelFileError, PositionsFollowMultilineStrings) {
  expect_error("name = \"m\"\ncoordinates = [\"x\"]\nkinetic_energy = \"\"\"\nx'^2/2 + \\\n    rh0\"\"\"\n", "5:5",
               {"unknown symbol 'rh0'"});
  expect_error("name = \"m\"\ncoordinates = [\"x\"]\nkinetic_energy = \'\'\'x'^2/2\n + rh0\'\'\'\n", "4:4",
               {"unknown symbol 'rh0'"});
}

// ---- Files --------------------------------------------------------------------------------------

TEST(ModelFileError, MissingFile) {
  const fs::path path = fs::temp_directory_path() / "nhdyn-no-such-model.toml";
  try {
    (void)load_model_file(path);
    FAIL() << "expected FileError";
  } catch (const FileError& e) {
    const std::string message = e.what();
    EXPECT_EQ(message.rfind(path.string() + ": no such model file", 0), 0u) << message;
  }
}

TEST(ModelFileError, DirectoryInsteadOfAFile) {
  try {
    (void)load_model_file(source_dir / "examples");
    FAIL() << "expected FileError";
  } catch (const FileError& e) {
    EXPECT_NE(std::string(e.what()).find("is a directory, not a model file"), std::string::npos) << e.what();
  }
}

TEST(ModelFileError, UnreadableFile) {
  if (geteuid() == 0) GTEST_SKIP() << "root reads every file";
  const fs::path path = fs::temp_directory_path() / ("nhdyn-unreadable-" + std::to_string(getpid()) + ".toml");
  { std::ofstream(path) << "name = \"m\"\n"; }
  fs::permissions(path, fs::perms::none);
  try {
    (void)load_model_file(path);
    ADD_FAILURE() << "expected FileError";
  } catch (const FileError& e) {
    EXPECT_NE(std::string(e.what()).find("cannot open the model file"), std::string::npos) << e.what();
  }
  fs::remove(path);
}

// A ModelError from a file names the file as the user gave it.
TEST(ModelFileError, FileErrorsNameThePath) {
  const fs::path path = fs::temp_directory_path() / ("nhdyn-bad-" + std::to_string(getpid()) + ".toml");
  { std::ofstream(path) << "name = \"m\"\ncoordinates = [\"x\"]\nkinetic_energy = 1\n"; }
  try {
    (void)load_model_file(path);
    ADD_FAILURE() << "expected ModelError";
  } catch (const ModelError& e) {
    EXPECT_EQ(std::string(e.what()).rfind(path.string() + ":3:18: ", 0), 0u) << e.what();
  }
  fs::remove(path);
}

}  // namespace
}  // namespace nhdyn
