// Contact points whose coordinates nhdyn adds ([[contacts]] without `coordinates`,
// docs/derivations/rolling-bodies.md section 10): the ball over a bump with NAME_u, NAME_v added
// follows the example with u, v written; the ellipsoid written as f = 0 starts at its closed-form
// support point; --fix-initial moves only the values [initial] leaves free; and the refusals (a
// name taken, a start where the point cannot be found, a written value that would have to move).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <functional>
#include <sstream>
#include <string>
#include <vector>

#include "nhdyn/analysis/initial_state.hpp"
#include "nhdyn/analysis/simulation.hpp"
#include "nhdyn/core/error.hpp"
#include "nhdyn/frontend/load_model.hpp"
#include "nhdyn/io/results.hpp"
#include "support/text.hpp"

namespace nhdyn {
namespace {

std::string example_text(const std::string& file) {
  std::ifstream in(std::string(NHDYN_SOURCE_DIR) + "/examples/" + file);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

using test::replace_once;

// examples/ball_over_bump.toml without u, v: nhdyn adds ball_u, ball_v.
std::string bump_added() {
  std::string text = example_text("ball_over_bump.toml");
  replace_once(text, R"(coordinates = ["x", "y", "z", "u", "v", "psi", "theta", "phi"])",
               R"(coordinates = ["x", "y", "z", "psi", "theta", "phi"])");
  replace_once(text, R"(, coordinates = ["u", "v"] })", " }");
  replace_once(text, " u = 0, v = 0,", "");
  replace_once(text, R"x( u = "V*w^2/(w^2 + 2*H*r)",)x", "");
  return text;
}

int column_of(const ResultColumns& columns, const std::string& name) {
  for (std::size_t i = 0; i < columns.all.size(); ++i)
    if (columns.all[i] == name) return static_cast<int>(i);
  ADD_FAILURE() << "no column " << name;
  return 0;
}

std::vector<std::vector<double>> run_rows(const Model& model, const SimulationOptions& options,
                                          SimulationSummary* summary = nullptr) {
  std::vector<std::vector<double>> rows;
  std::vector<double> row;
  const SimulationSummary s = simulate(model, options, [&](const Data& data) {
    fill_result_row(model, data, row);
    rows.push_back(row);
  });
  if (summary) *summary = s;
  return rows;
}

std::string message_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const std::exception& e) {
    return e.what();
  }
  ADD_FAILURE() << "expected an error";
  return "";
}

TEST(RollingAddedCoordinates, BallOverABumpFollowsTheOneWithWrittenCoordinates) {
  const Model written = load_model(std::string(NHDYN_SOURCE_DIR) + "/examples/ball_over_bump.toml");
  const Model added = load_model_text(bump_added(), "bump.toml");
  ASSERT_EQ(added.n(), written.n());
  EXPECT_EQ(added.coordinates[6], "ball_u");
  EXPECT_EQ(added.coordinates[7], "ball_v");
  // The start found: on the top u = v = 0, u' = V w^2 / (w^2 + 2 H r) (the example's closed form).
  EXPECT_EQ(added.q0(6), 0.0);
  EXPECT_EQ(added.q0(7), 0.0);
  EXPECT_NEAR(added.v0(6), 0.3 * 0.09 / (0.09 + 2 * 0.05 * 0.05), 1e-15);
  EXPECT_NEAR(added.v0(7), 0.0, 1e-15);
  SimulationOptions options;
  options.t_end = 1.5;
  options.output_step = 0.05;
  options.integrator.rtol = 1e-10;
  options.integrator.atol = 1e-12;
  SimulationSummary summary;
  const std::vector<std::vector<double>> a = run_rows(written, options);
  const std::vector<std::vector<double>> b = run_rows(added, options, &summary);
  ASSERT_EQ(a.size(), b.size());
  const ResultColumns ca = make_result_columns(written), cb = make_result_columns(added);
  const std::vector<std::pair<std::string, std::string>> same = {
      {"x", "x"}, {"y", "y"}, {"z", "z"}, {"psi", "psi"}, {"theta", "theta"}, {"phi", "phi"}, {"u", "ball_u"},
      {"v", "ball_v"}, {"u'", "ball_u'"}, {"x'", "x'"}, {"psi'", "psi'"}, {"ball_N", "ball_N"}, {"ball_X", "ball_X"}};
  // The same equations with the coordinates in another order: equal to round-off (1e-12 relative).
  for (const auto& [from, to] : same) {
    const int i = column_of(ca, from), j = column_of(cb, to);
    for (std::size_t row = 0; row < a.size(); ++row) {
      const double expected = a[row][static_cast<std::size_t>(i)];
      EXPECT_NEAR(b[row][static_cast<std::size_t>(j)], expected, 1e-12 * std::max(1.0, std::abs(expected)))
          << to << " at row " << row;
    }
  }
  EXPECT_GT(std::abs(a.back()[static_cast<std::size_t>(column_of(ca, "y"))]), 0.01);  // it did turn
  EXPECT_LT(std::abs(summary.energy.change), 1e-9);                                  // energy conserved
}

// examples/ellipsoid_rocking.toml with the ellipsoid written as f = 0 and no coordinates.
std::string ellipsoid_added() {
  std::string text = example_text("ellipsoid_rocking.toml");
  replace_once(text, R"(shape = { ellipsoid = ["a", "b", "c"] })",
               R"(shape = { surface = "X^2/a^2 + Y^2/b^2 + Z^2/c^2 - 1" })");
  return text;
}

TEST(RollingAddedCoordinates, ImplicitShapeStartsAtItsSupportPoint) {
  std::string text = ellipsoid_added();
  // Turned and moving: psi, theta and their rates, so that y and y' are not trivial.
  replace_once(text, "psi = 0, theta = 0, phi = \"tilt\" }",
               "psi = 0.4, theta = 0.2, phi = \"tilt\" }\nvelocity = { psi = 1.5, theta = -0.7, phi = 2.0 }");
  replace_once(text, "z = \"sqrt(a^2*sin(tilt)^2 + c^2*cos(tilt)^2)\"", "z = 0.2");  // checked below: not used
  const Model model = load_model_text(text, "ellipsoid.toml");
  ASSERT_EQ(model.coordinates[6], "foot_px");
  const double a = 0.2, b = 0.15, c = 0.1;
  const Eigen::Vector3d y = model.q0.segment(6, 3);
  EXPECT_NEAR(y(0) * y(0) / (a * a) + y(1) * y(1) / (b * b) + y(2) * y(2) / (c * c) - 1.0, 0.0, 1e-12);
  // The support point along nu = R^T e_z: y* = -M^-1 nu / sqrt(nu^T M^-1 nu) (section 2).
  const double psi = 0.4, theta = 0.2, phi = model.q0(5);
  const Eigen::Matrix3d R = (Eigen::AngleAxisd(psi, Eigen::Vector3d::UnitZ()) *
                             Eigen::AngleAxisd(theta, Eigen::Vector3d::UnitX()) *
                             Eigen::AngleAxisd(phi, Eigen::Vector3d::UnitY()))
                                .toRotationMatrix();
  const Eigen::Vector3d nu = R.transpose() * Eigen::Vector3d::UnitZ();
  const Eigen::Vector3d Minv_nu(a * a * nu(0), b * b * nu(1), c * c * nu(2));
  const Eigen::Vector3d expected = -Minv_nu / std::sqrt(nu.dot(Minv_nu));
  EXPECT_LT((y - expected).cwiseAbs().maxCoeff(), 1e-12) << y.transpose() << " vs " << expected.transpose();
  // Every constraint that holds y, and its time derivative, is satisfied at the start.
  Data data = make_data(model);
  for (const ConstraintResidual& r : calc_initial_residuals(model, data, model.t0, model.q0, model.v0))
    if (r.constraint.rfind("foot_on", 0) == 0 || r.constraint.rfind("foot_normal", 0) == 0) {
      EXPECT_LT(std::abs(r.value), 1e-12) << r.constraint;
    }
}

TEST(RollingAddedCoordinates, ImplicitShapeFollowsTheClosedFormEllipsoid) {
  const Model closed = load_model(std::string(NHDYN_SOURCE_DIR) + "/examples/ellipsoid_rocking.toml");
  const Model implicit = load_model_text(ellipsoid_added(), "ellipsoid.toml");
  SimulationOptions options;
  options.t_end = 1.0;
  options.output_step = 0.05;
  options.integrator.rtol = 1e-12;
  options.integrator.atol = 1e-14;
  const std::vector<std::vector<double>> a = run_rows(closed, options), b = run_rows(implicit, options);
  ASSERT_EQ(a.size(), b.size());
  const ResultColumns ca = make_result_columns(closed), cb = make_result_columns(implicit);
  for (const char* name : {"z", "phi", "x", "foot_N", "foot_X"}) {
    const int i = column_of(ca, name), j = column_of(cb, name);
    for (std::size_t row = 0; row < a.size(); ++row)
      EXPECT_NEAR(b[row][static_cast<std::size_t>(j)], a[row][static_cast<std::size_t>(i)], 1e-9) << name << " " << row;
  }
}

TEST(RollingAddedCoordinates, ANameTakenIsRefusedWithItsPlace) {
  std::string text = bump_added();
  replace_once(text, "spin = { value = 20.0", "ball_u = 1.0\nspin = { value = 20.0");
  const std::string message = message_of([&] { load_model_text(text, "bump.toml"); });
  EXPECT_NE(message.find("bump.toml:"), std::string::npos) << message;
  EXPECT_NE(message.find("'ball_u' is already a parameter"), std::string::npos) << message;
  EXPECT_NE(message.find("coordinates = [\"u\", \"v\"]"), std::string::npos) << message;  // what to do
}

TEST(RollingAddedCoordinates, AShapeWhoseCentreIsOutsideItIsRefused) {
  std::string text = ellipsoid_added();
  replace_once(text, R"(surface = "X^2/a^2 + Y^2/b^2 + Z^2/c^2 - 1")", R"(surface = "1 - X^2/a^2 - Y^2/b^2 - Z^2/c^2")");
  const std::string message = message_of([&] { load_model_text(text, "ellipsoid.toml"); });
  EXPECT_NE(message.find("ellipsoid.toml:"), std::string::npos) << message;
  EXPECT_NE(message.find("contact 'foot'"), std::string::npos) << message;
  EXPECT_NE(message.find("cannot find the contact point at the start"), std::string::npos) << message;
}

TEST(RollingAddedCoordinates, ABodyOffTheGroundKeepsItsGapInTheRefusal) {
  // The point is found (the lowest point of the shape), the gap is the user's: refused with it.
  std::string text = ellipsoid_added();
  replace_once(text, "z = \"sqrt(a^2*sin(tilt)^2 + c^2*cos(tilt)^2)\"",
               "z = \"sqrt(a^2*sin(tilt)^2 + c^2*cos(tilt)^2) + 0.01\"");
  const Model model = load_model_text(text, "ellipsoid.toml");
  SimulationOptions options;
  options.t_end = 0.1;
  const std::string message = message_of([&] { run_rows(model, options); });
  EXPECT_NE(message.find("foot_contact (position level): residual 0.01"), std::string::npos) << message;
}

// --fix-initial with z left out of [initial]: it and the added ball_u, ball_v move, the values
// written stay; the ball ends on the top of the bump.
TEST(RollingAddedCoordinates, FixInitialMovesOnlyTheValuesLeftFree) {
  std::string text = bump_added();
  replace_once(text, R"( z = "H + r",)", "");
  replace_once(text, R"(velocity = { x = "V",)", R"(velocity = { x = "V", y = 0.1,)");
  const Model model = load_model_text(text, "bump.toml");
  Data data = make_data(model);
  Vector q = model.q0, v = model.v0;
  complete_initial_state(model, data, model.t0, q, v);
  const InitialFix fix = fix_free_initial_values(model, data, model.t0, q, v);
  const double H = 0.05, r = 0.05;
  EXPECT_NEAR(fix.q(2), H + r, 1e-13);  // z, free, onto the top
  for (int i : {0, 1, 3, 4, 5}) EXPECT_EQ(fix.dq(i), 0.0) << model.coordinates[static_cast<std::size_t>(i)];
  // Written velocities stay: x' = V, y' = 0.1, phi' = V/r, psi' = spin; rolling then asks theta'.
  EXPECT_EQ(fix.v(0), 0.3);
  EXPECT_EQ(fix.v(1), 0.1);
  EXPECT_EQ(fix.v(3), 20.0);
  EXPECT_NEAR(fix.v(4), -0.1 / r, 1e-12);  // y' = -r theta' at theta = 0 (the no-slip row along y)
  EXPECT_LT(fix.position_residual, 1e-12);
  EXPECT_LT(fix.velocity_residual, 1e-12);
  // The contact point's coordinates satisfy their constraints.
  for (const ConstraintResidual& c : calc_initial_residuals(model, data, model.t0, fix.q, fix.v))
    EXPECT_LT(std::abs(c.value), 1e-12) << c.constraint;
}

TEST(RollingAddedCoordinates, FixInitialRefusesToMoveAWrittenValue) {
  // z written 1 cm above the top: only z could close the gap, and it is written.
  std::string text = bump_added();
  replace_once(text, R"(z = "H + r")", R"(z = "H + r + 0.01")");
  const Model model = load_model_text(text, "bump.toml");
  SimulationOptions options;
  options.t_end = 0.1;
  options.fix_initial = true;
  const std::string message = message_of([&] { run_rows(model, options); });
  EXPECT_NE(message.find("keeps every value [initial] writes"), std::string::npos) << message;
  EXPECT_NE(message.find("'ball_contact' (position level"), std::string::npos) << message;
  EXPECT_NE(message.find("residual 0.01"), std::string::npos) << message;
}

}  // namespace
}  // namespace nhdyn
