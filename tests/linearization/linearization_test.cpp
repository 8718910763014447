// Exams of the linearization about steady motions (analysis/linearization.hpp) with known answers:
// the pendulum in Cartesian coordinates (redundant coordinates, one independent), the bead on the
// rotating hoop in its frame (both equilibria), the upright rolling disk (nonholonomic, cyclic
// heading; closed form derived in docs/linearization.md), and the benchmark bicycle's linearized
// equations against the 4 x 4 matrix built here with Eigen. Consistency: the tangent-mode
// derivatives against Richardson differences on a hand-written model. Bad input: not steady,
// time dependent, unknown or ill-chosen names.
#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <memory>
#include <numbers>
#include <string>
#include <vector>

#include "linearization/support.hpp"
#include "nhdyn/analysis/linearization.hpp"
#include "nhdyn/core/error.hpp"
#include "nhdyn/frontend/model_file.hpp"
#include "nhdyn/symbolic/compile.hpp"

namespace nhdyn {
namespace {

using testing::compile_example;
using C = std::complex<double>;

// Expects `what` to throw E whose message contains every string of `parts`.
template <class E, class F>
void expect_error(F what, const std::vector<std::string>& parts) {
  try {
    what();
    ADD_FAILURE() << "no exception";
  } catch (const E& e) {
    const std::string message = e.what();
    for (const std::string& p : parts) EXPECT_NE(message.find(p), std::string::npos) << "'" << p << "' not in: " << message;
  }
}

void expect_eigenvalues(const std::vector<C>& got, std::vector<C> want, double tol) {
  sort_eigenvalues(want);
  ASSERT_EQ(got.size(), want.size());
  for (std::size_t i = 0; i < got.size(); ++i)
    EXPECT_LT(std::abs(got[i] - want[i]), tol * std::max(1.0, std::abs(want[i])))
        << i << ": got " << got[i] << ", want " << want[i];
}

TEST(Linearization, PendulumInCartesianCoordinatesAtTheBottomOscillatesAtSqrtGOverL) {
  const Model model = compile_example("pendulum_cartesian.toml", {{"theta0", 0.0}});
  const Linearization l = calc_linearization(model);
  const double w = std::sqrt(9.81 / 1.5);
  EXPECT_EQ(l.derivatives, DerivativeMethod::tangent);
  ASSERT_EQ(l.state, (std::vector<std::string>{"x", "x'"}));  // y is dependent at the bottom (y = -l)
  expect_eigenvalues(l.eigenvalues, {C(0, w), C(0, -w)}, 1e-13);
  // Negative control: at the top the same model is unstable, +-sqrt(g/l).
  const Linearization top = calc_linearization(compile_example("pendulum_cartesian.toml", {{"theta0", std::numbers::pi}}));
  expect_eigenvalues(top.eigenvalues, {C(w, 0), C(-w, 0)}, 1e-12);
}

TEST(Linearization, PendulumWithYNamedIndependentAtTheBottomIsRefused) {
  const Model model = compile_example("pendulum_cartesian.toml", {{"theta0", 0.0}});
  LinearizationOptions o;
  o.independent = {"y"};  // x' = 0 on the rod at the bottom: x cannot be expressed through y
  expect_error<InputError>([&] { calc_linearization(model, o); }, {"x", "cannot be expressed", "--independent"});
  o.independent = {"x", "y"};
  expect_error<InputError>([&] { calc_linearization(model, o); }, {"--independent names 2", "1 independent"});
  o.independent = {"z"};
  expect_error<InputError>([&] { calc_linearization(model, o); }, {"--independent", "'z'", "x, y"});
}

TEST(Linearization, TheChoiceOfIndependentCoordinateDoesNotChangeTheEigenvalues) {
  // At theta* both x and z can serve as the independent coordinate on the hoop.
  const double star = std::acos(9.81 / (0.5 * 36.0));
  const Model model = compile_example("hoop_bead_rotating.toml", {{"theta0", star}});
  const double w = 6.0 * std::sin(star);
  for (const char* name : {"x", "z"}) {
    LinearizationOptions o;
    o.independent = {name};
    o.speeds = {name};
    const Linearization l = calc_linearization(model, o);
    EXPECT_EQ(l.state, (std::vector<std::string>{name, std::string(name) + "'"}));
    expect_eigenvalues(l.eigenvalues, {C(0, w), C(0, -w)}, 1e-12);
  }
}

TEST(Linearization, BeadOnTheRotatingHoopHasBothClosedFormEquilibria) {
  const double g = 9.81, r = 0.5, Omega = 6.0;
  // The bottom: unstable above the critical rate, +-sqrt(Omega^2 - g/r).
  const Linearization bottom = calc_linearization(compile_example("hoop_bead_rotating.toml", {{"theta0", 0.0}}));
  const double a = std::sqrt(Omega * Omega - g / r);
  expect_eigenvalues(bottom.eigenvalues, {C(a, 0), C(-a, 0)}, 1e-12);
  // Below the critical rate the bottom is stable: +-i sqrt(g/r - Omega^2).
  const Linearization slow =
      calc_linearization(compile_example("hoop_bead_rotating.toml", {{"theta0", 0.0}, {"Omega", 3.0}}));
  const double c = std::sqrt(g / r - 9.0);
  expect_eigenvalues(slow.eigenvalues, {C(0, c), C(0, -c)}, 1e-12);
  // The off-bottom equilibrium theta* = acos(g / (r Omega^2)): +-i Omega sin(theta*).
  const double star = std::acos(g / (r * Omega * Omega));
  const Linearization side = calc_linearization(compile_example("hoop_bead_rotating.toml", {{"theta0", star}}));
  const double w = Omega * std::sin(star);
  expect_eigenvalues(side.eigenvalues, {C(0, w), C(0, -w)}, 1e-12);
}

TEST(Linearization, NotSteadyNamesTheLargestViolation) {
  // The pendulum at 0.5 rad, at rest: it accelerates, x'' = -g sin(theta) cos(theta) the largest.
  const Model model = compile_example("pendulum_cartesian.toml", {{"theta0", 0.5}});
  expect_error<ModelError>([&] { calc_linearization(model); },
                           {"not a steady motion", "acceleration", "x''", "tolerance 1e-09"});
  // A non-cyclic coordinate that moves.
  std::string text = R"(name = "moving"
coordinates = ["phi"]
kinetic_energy = "phi'^2/2"
potential_energy = "phi^2/2"
[initial]
position = { phi = 0 }
velocity = { phi = 0.25 }
)";
  const Model moving = symbolic::compile_model(load_model_string(text, "moving.toml"));
  expect_error<ModelError>([&] { calc_linearization(moving); }, {"not a steady motion", "velocity phi' = 0.25", "at rest"});
  // The hoop bead just off its equilibrium: the message gives the size.
  const double star = std::acos(9.81 / (0.5 * 36.0));
  const Model off = compile_example("hoop_bead_rotating.toml", {{"theta0", star + 1e-3}});
  expect_error<ModelError>([&] { calc_linearization(off); }, {"not a steady motion", "acceleration"});
  // A looser tolerance accepts a state that is steady within it.
  LinearizationOptions loose;
  loose.steady_tolerance = 1e-1;
  EXPECT_NO_THROW(calc_linearization(off, loose));
}

TEST(Linearization, TimeDependentModelIsRefused) {
  const Model model = compile_example("hoop_bead.toml");
  expect_error<ModelError>([&] { calc_linearization(model); }, {"depends on time t explicitly", "hoop-bead"});
}

TEST(Linearization, InitialStateOffTheConstraintIsRefused) {
  const std::string text = R"(name = "off"
coordinates = ["x", "y"]
kinetic_energy = "(x'^2 + y'^2)/2"
potential_energy = "y"
[[constraints]]
name = "rod"
position = "x^2 + y^2 - 1"
[initial]
position = { x = 0, y = -1.5 }
)";
  const Model model = symbolic::compile_model(load_model_string(text, "off.toml"));
  expect_error<ModelError>([&] { calc_linearization(model); }, {"violates the constraint 'rod'", "position level", "1.250e+00"});
}

TEST(Linearization, InitialVelocityOffTheConstraintIsRefused) {
  // A knife edge pointing along x, moving sideways: the blade forbids it.
  const std::string text = R"(name = "skid"
coordinates = ["x", "y", "phi"]
kinetic_energy = "(x'^2 + y'^2 + phi'^2)/2"
[[constraints]]
name = "blade"
velocity = "-sin(phi)*x' + cos(phi)*y'"
[initial]
position = { x = 0, y = 0, phi = 0 }
velocity = { x = 1, y = 0.5 }
)";
  const Model model = symbolic::compile_model(load_model_string(text, "skid.toml"));
  expect_error<ModelError>([&] { calc_linearization(model); }, {"violates the constraint 'blade'", "velocity level", "5.000e-01"});
}

TEST(Linearization, UnknownCyclicNameIsRefused) {
  const Model model = compile_example("rolling_disk_upright.toml");
  LinearizationOptions o;
  o.cyclic = {"heading"};
  expect_error<InputError>([&] { calc_linearization(model, o); }, {"--cyclic", "'heading'", "x, y, psi, theta, phi"});
  o.cyclic = {"psi"};
  o.independent = {"x"};
  expect_error<InputError>([&] { calc_linearization(model, o); }, {"--independent", "'x' is cyclic"});
  o.independent.clear();
  o.speeds = {"theta"};
  expect_error<InputError>([&] { calc_linearization(model, o); }, {"--speeds names 1", "3 independent speed"});
}

// docs/linearization.md, "The upright rolling disk": theta'' = (4/5) (g/r - 3 w^2) theta, and the
// heading and spin rates are conserved to first order (two zero eigenvalues).
TEST(Linearization, UprightRollingDiskMatchesTheClosedForm) {
  const double g = 9.81, r = 0.2;
  LinearizationOptions o;
  o.cyclic = {"psi"};
  for (double w : {6.0, 2.0, 4.0}) {
    const Linearization l = calc_linearization(compile_example("rolling_disk_upright.toml", {{"w", w}}), o);
    EXPECT_EQ(l.cyclic, (std::vector<std::string>{"x", "y", "psi", "phi"}));
    EXPECT_EQ(l.state, (std::vector<std::string>{"theta", "psi'", "theta'", "phi'"})) << w;
    const double lambda2 = 0.8 * (g / r - 3.0 * w * w);
    const C root = std::sqrt(C(lambda2, 0.0));
    expect_eigenvalues(l.eigenvalues, {root, -root, C(0, 0), C(0, 0)}, 1e-11);
  }
  // Without naming psi cyclic it stays in the state (it enters the rolling constraints): the
  // motion keeps psi = 0, so this linearization is exact too, and gives the same tilt eigenvalues
  // and one more zero (the heading itself).
  const Linearization full = calc_linearization(compile_example("rolling_disk_upright.toml", {{"w", 6.0}}));
  EXPECT_EQ(full.cyclic, (std::vector<std::string>{"x", "y", "phi"}));
  EXPECT_EQ(full.state, (std::vector<std::string>{"psi", "theta", "psi'", "theta'", "phi'"}));
  const C root = std::sqrt(C(0.8 * (g / r - 3.0 * 36.0), 0.0));
  expect_eigenvalues(full.eigenvalues, {root, -root, C(0, 0), C(0, 0), C(0, 0)}, 1e-11);
}

TEST(Linearization, BenchmarkBicycleEqualsTheIndependentStateMatrix) {
  const testing::BicycleMatrices bike;
  for (double v : {0.0, 1.0, 3.7, testing::kWeaveSpeed, 5.0, testing::kCapsizeSpeed, 8.0, 10.0}) {
    const Linearization l = calc_linearization(compile_example("bicycle_linear.toml", {{"v", v}}));
    ASSERT_EQ(l.state, (std::vector<std::string>{"phi", "delta", "phi'", "delta'"}));
    const Eigen::Matrix4d S = bike.state_matrix(v);
    EXPECT_LT((l.state_matrix - S).lpNorm<Eigen::Infinity>(), 1e-11 * S.lpNorm<Eigen::Infinity>()) << v;
    expect_eigenvalues(l.eigenvalues, bike.eigenvalues(v), 1e-10);
  }
}

// Meijaard et al. 2007, Table 2: the weave pair at v = 1..10 m/s, and all four at 5 and 10 m/s.
TEST(Linearization, BenchmarkBicycleMatchesThePublishedTable) {
  const C weave[10] = {C(3.52696170990070, 0.807740275199300), C(2.68234517512745, 1.68066296590675),
                       C(1.70675605663975, 2.31582447384325),  C(0.413253315211250, 3.07910818603206),
                       C(-0.775341882195850, 4.46486771378823), C(-1.52644486584142, 5.87673060598709),
                       C(-2.13875644258362, 7.19525913329805),  C(-2.69348683581097, 8.46037971396931),
                       C(-3.21675402252485, 9.69377351531791),  C(-3.72016840437287, 10.9068113947629)};
  for (int v = 1; v <= 10; ++v) {
    const Linearization l = calc_linearization(compile_example("bicycle_linear.toml", {{"v", v}}));
    bool found = false;
    for (const C& e : l.eigenvalues) found = found || std::abs(e - weave[v - 1]) < 1e-12 * std::abs(weave[v - 1]);
    EXPECT_TRUE(found) << "v = " << v << ": the weave eigenvalue " << weave[v - 1] << " is not among the computed";
  }
  const Linearization five = calc_linearization(compile_example("bicycle_linear.toml", {{"v", 5.0}}));
  expect_eigenvalues(five.eigenvalues,
                     {C(-14.07838969279822, 0), C(-0.32286642900409, 0), C(-0.77534188219585, 4.46486771378823),
                      C(-0.77534188219585, -4.46486771378823)},
                     1e-12);
  const Linearization ten = calc_linearization(compile_example("bicycle_linear.toml", {{"v", 10.0}}));
  EXPECT_NEAR(ten.eigenvalues.front().real(), 0.16105338653172, 1e-12);  // capsize, unstable
  EXPECT_NEAR(ten.eigenvalues.back().real(), -24.62459635017404, 1e-11);  // castering
}

// The bicycle's equations by hand, to run the Richardson path (no programs) against the tangent one.
class BicycleEvaluator final : public Evaluator {
 public:
  explicit BicycleEvaluator(double v) : v_(v) {}
  void terms(double, const double* q, const double* qd, double*, const TermsOut& out) const override {
    const Eigen::Map<const Eigen::Vector2d> x(q), xd(qd);
    Eigen::Map<Eigen::Matrix2d>(out.A) = bike_.M;
    Eigen::Map<Eigen::Vector2d>(out.Q) = -v_ * bike_.C1 * xd - (bike_.g * bike_.K0 + v_ * v_ * bike_.K2) * x;
    Eigen::Map<Eigen::Vector2d>(out.G).setZero();
  }

 private:
  testing::BicycleMatrices bike_;
  double v_;
};

TEST(Linearization, HandWrittenModelUsesRichardsonDifferencesAndAgrees) {
  Model model;
  model.name = "bicycle-by-hand";
  model.coordinates = {"phi", "delta"};
  model.q0 = Vector::Zero(2);
  model.v0 = Vector::Zero(2);
  model.evaluator = std::make_shared<BicycleEvaluator>(5.0);
  const Linearization l = calc_linearization(model);
  EXPECT_EQ(l.derivatives, DerivativeMethod::richardson);
  const testing::BicycleMatrices bike;
  EXPECT_LT((l.state_matrix - bike.state_matrix(5.0)).lpNorm<Eigen::Infinity>(), 1e-8);
  expect_eigenvalues(l.eigenvalues, bike.eigenvalues(5.0), 1e-9);
}

}  // namespace
}  // namespace nhdyn
