// An implicit shape ([[contacts]] with shape = { surface = "f(X, Y, Z)", coordinates = [...] }):
// the contact point is three coordinates of the model held by f = 0 and the normals' alignment
// (docs/derivations/rolling-bodies.md section 9). The ellipsoid written as f must give the
// trajectory and the contact force of the closed-form ellipsoid (examples/ellipsoid_rocking.toml).
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "nhdyn/analysis/simulation.hpp"
#include "nhdyn/core/error.hpp"
#include "nhdyn/frontend/load_model.hpp"
#include "nhdyn/io/results.hpp"
#include "support/text.hpp"

namespace nhdyn {
namespace {

std::string ellipsoid_example_text() {
  std::ifstream in(std::string(NHDYN_SOURCE_DIR) + "/examples/ellipsoid_rocking.toml");
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

using test::replace_once;

// The example with the ellipsoid written as the surface f = 0 and its contact point (px, py, pz)
// started at the support point of the tilted ellipsoid (rolling-bodies.md section 2).
std::string implicit_ellipsoid_text() {
  std::string text = ellipsoid_example_text();
  replace_once(text, "coordinates = [\"x\", \"y\", \"z\", \"psi\", \"theta\", \"phi\"]",
               "coordinates = [\"x\", \"y\", \"z\", \"psi\", \"theta\", \"phi\", \"px\", \"py\", \"pz\"]");
  replace_once(text, "shape = { ellipsoid = [\"a\", \"b\", \"c\"] }",
               "shape = { surface = \"X^2/a^2 + Y^2/b^2 + Z^2/c^2 - 1\", coordinates = [\"px\", \"py\", \"pz\"] }");
  replace_once(text, "phi = \"tilt\" }",
               "phi = \"tilt\", px = \"a^2*sin(tilt)/sqrt(a^2*sin(tilt)^2 + c^2*cos(tilt)^2)\", py = 0, "
               "pz = \"-c^2*cos(tilt)/sqrt(a^2*sin(tilt)^2 + c^2*cos(tilt)^2)\" }");
  return text;
}

std::vector<std::vector<double>> implicit_run(const Model& model, bool turned) {
  Model m = model;
  SimulationOptions options;
  options.t_end = 1.0;
  options.output_step = 0.01;
  options.integrator.rtol = 1e-12;
  options.integrator.atol = 1e-14;
  if (turned) {
    m.v0(3) = 2.0;  // psi'
    m.v0(4) = 1.0;  // theta'
    options.fix_initial = true;  // the rolling velocities (and the contact point's) from these
  }
  std::vector<std::vector<double>> rows;
  std::vector<double> row;
  simulate(m, options, [&](const Data& data) {
    fill_result_row(m, data, row);
    rows.push_back(row);
  });
  return rows;
}

int implicit_column(const Model& model, const std::string& name) {
  const ResultColumns columns = make_result_columns(model);
  for (std::size_t i = 0; i < columns.all.size(); ++i)
    if (columns.all[i] == name) return static_cast<int>(i);
  ADD_FAILURE() << "no column " << name;
  return 0;
}

// The same on the terrain h = 0 (both contact points coordinates: px, py, pz on the body, u, v on
// the ground; rolling-bodies.md sections 8 and 9).
std::string implicit_ellipsoid_on_terrain_text() {
  std::string text = implicit_ellipsoid_text();
  replace_once(text, "\"px\", \"py\", \"pz\"]\ngravity", "\"px\", \"py\", \"pz\", \"u\", \"v\"]\ngravity");
  replace_once(text, "coordinates = [\"px\", \"py\", \"pz\"] }\n",
               "coordinates = [\"px\", \"py\", \"pz\"] }\nground = { terrain = \"0*X\", coordinates = [\"u\", \"v\"] }\n");
  replace_once(text, "py = 0, ", "py = 0, u = \"(a^2 - c^2)*sin(tilt)*cos(tilt)/sqrt(a^2*sin(tilt)^2 + c^2*cos(tilt)^2)\", v = 0, ");
  return text;
}

TEST(RollingImplicit, EllipsoidAsASurfaceFollowsTheClosedFormEllipsoid) {
  const Model closed = load_model(std::string(NHDYN_SOURCE_DIR) + "/examples/ellipsoid_rocking.toml", {{"tilt", 0.3}});
  const Model on_plane = load_model_text(implicit_ellipsoid_text(), "<implicit>", {{"tilt", 0.3}});
  const Model on_terrain = load_model_text(implicit_ellipsoid_on_terrain_text(), "<implicit>", {{"tilt", 0.3}});
  for (const auto& [implicit, turned] : {std::pair<const Model&, bool>{on_plane, false}, {on_plane, true},
                                         {on_terrain, false}, {on_terrain, true}}) {
    const std::vector<std::vector<double>> a = implicit_run(closed, turned), b = implicit_run(implicit, turned);
    ASSERT_EQ(a.size(), 101u);
    ASSERT_EQ(b.size(), a.size());
    double largest = 0.0, moved = 0.0;
    for (std::size_t k = 0; k < a.size(); ++k) {
      for (int i = 1; i <= 6; ++i) {  // x, y, z, psi, theta, phi
        largest = std::max(largest, std::abs(a[k][static_cast<std::size_t>(i)] - b[k][static_cast<std::size_t>(i)]));
        moved = std::max(moved, std::abs(a[k][static_cast<std::size_t>(i)] - a[0][static_cast<std::size_t>(i)]));
      }
      const double Na = a[k][static_cast<std::size_t>(implicit_column(closed, "foot_N"))];
      const double Nb = b[k][static_cast<std::size_t>(implicit_column(implicit, "foot_N"))];
      EXPECT_NEAR(Na, Nb, 1e-8 * 9.81) << k;
      // The contact point, the same in both, on the ellipsoid.
      for (const char* c : {"foot_X", "foot_Y", "foot_Z"})
        EXPECT_NEAR(a[k][static_cast<std::size_t>(implicit_column(closed, c))],
                    b[k][static_cast<std::size_t>(implicit_column(implicit, c))], 1e-9);
    }
    EXPECT_GT(moved, 0.05) << "turned " << turned;  // the test is not about a body at rest
    EXPECT_LT(largest, 1e-9) << "turned " << turned;
  }
}

// Not a function of the body's axes only, or not smooth: refused with the shape's file:line.
// The egg of the gallery (docs/gallery/egg.toml): a convex surface with a cubic term, known only as
// f = 0, rocking and spinning. Nothing does work, so the energy stays at its start; the contact
// point stays on f = 0 (with X, Y, Z its body coordinates); the ground pushes up; and the body turns.
// Its equations (nhdyn equations, the report's) are written without looking for a partition of
// b, whose symbolic inverse took minutes.
TEST(RollingImplicit, TheGallerysEggKeepsItsEnergyAndItsContactOnItsSurface) {
  const std::string file = std::string(NHDYN_SOURCE_DIR) + "/docs/gallery/egg.toml";
  const Model model = load_model(file);
  SimulationOptions options;
  options.t_end = 4.0;
  options.output_step = 0.01;
  options.integrator.rtol = 1e-10;  // the file's
  options.integrator.atol = 1e-12;
  const double a = 0.03, b = 0.022, c = 0.022, e = 0.3, m = 0.06, g = 9.81;
  const int px = implicit_column(model, "foot_px"), py = implicit_column(model, "foot_py"),
            pz = implicit_column(model, "foot_pz"), energy = implicit_column(model, "energy"),
            N = implicit_column(model, "foot_N"), psi = implicit_column(model, "psi");
  std::vector<double> row;
  double e0 = 0.0, drift = 0.0, off = 0.0, lowest_N = 1e300, turned = 0.0;
  int rows = 0;
  simulate(model, options, [&](const Data& data) {
    fill_result_row(model, data, row);
    const auto at = [&](int i) { return row[static_cast<std::size_t>(i)]; };
    if (rows++ == 0) e0 = at(energy);
    drift = std::max(drift, std::abs(at(energy) - e0));
    const double X = at(px), Y = at(py), Z = at(pz);
    off = std::max(off, std::abs(X * X / (a * a) + Y * Y / (b * b) + Z * Z / (c * c) + e * X * X * X / (a * a * a) - 1));
    lowest_N = std::min(lowest_N, at(N));
    turned = std::max(turned, std::abs(at(psi)));
  });
  EXPECT_EQ(rows, 401);
  EXPECT_LT(drift, 1e-9 * e0);
  EXPECT_LT(off, 1e-7);
  EXPECT_GT(lowest_N, 0.1 * m * g);  // it stays on the ground
  EXPECT_GT(turned, 10.0);           // spinning at 20 rad/s
  const std::string equations = model_equations(read_model_source(file), {}, EquationsFormat::text);
  EXPECT_NE(equations.find("too large"), std::string::npos) << equations.substr(0, 400);
}

TEST(RollingImplicit, BadSurfacesAreRefused) {
  std::string text = implicit_ellipsoid_text();
  replace_once(text, "Z^2/c^2 - 1\"", "Z^2/c^2 - 1 + x\"");
  try {
    load_model_text(text, "e.toml");
    FAIL() << "expected ModelError";
  } catch (const ModelError& e) {
    EXPECT_NE(std::string(e.what()).find("e.toml:"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("depends on t or on a coordinate"), std::string::npos) << e.what();
  }
  text = implicit_ellipsoid_text();
  replace_once(text, "X^2/a^2", "abs(X)^3/a^3");
  try {
    load_model_text(text, "e.toml");
    FAIL() << "expected ModelError";
  } catch (const ModelError& e) {
    EXPECT_NE(std::string(e.what()).find("is not differentiable"), std::string::npos) << e.what();
  }
  text = implicit_ellipsoid_text();
  replace_once(text, "coordinates = [\"px\", \"py\", \"pz\"] }", "coordinates = [\"px\", \"py\"] }");
  try {
    load_model_text(text, "e.toml");
    FAIL() << "expected ModelError";
  } catch (const ModelError& e) {
    EXPECT_NE(std::string(e.what()).find("a surface shape needs the 3 coordinates"), std::string::npos) << e.what();
  }
}

// The shape must be convex toward the ground where the run starts (rolling-bodies.md section 9):
// released upright (tilt = 0) at (0, 0, -c), the principal curvatures there are those of the
// surface along x and y, H_xx / |grad f| and H_yy / |grad f|, signed positive where it bends away
// from the ground.
std::string convexity_refusal(const std::string& text) {
  try {
    load_model_text(text, "e.toml", {{"tilt", 0.0}});
  } catch (const ModelError& e) {
    return e.what();
  }
  ADD_FAILURE() << "expected ModelError";
  return {};
}

void expect_parts(const std::string& message, const std::vector<std::string>& parts) {
  for (const std::string& part : parts)
    EXPECT_NE(message.find(part), std::string::npos) << message << "\n  lacks: " << part;
}

// A plane as a body's surface (f = Z - r, X, X + Y + Z - r) has no curvature: its measures of
// convexity divided by zero inside GiNaC, an internal error (exit 3) for every command.
TEST(RollingImplicit, FlatSurfaceIsRefused) {
  std::ifstream in(std::string(NHDYN_SOURCE_DIR) + "/examples/ball_thrown_sliding.toml");
  const std::string ball{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  for (const char* flat : {"Z - r", "X", "X + Y + Z - r"}) {
    std::string text = ball;
    replace_once(text, "shape = { sphere = \"r\" }", std::string("shape = { surface = \"") + flat + "\" }");
    try {
      load_model_text(text, "f.toml");
      ADD_FAILURE() << flat << ": expected ModelError";
    } catch (const ModelError& e) {
      expect_parts(e.what(), {"f.toml:", "contact 'ball'", "the shape's surface is flat"});
    }
  }
}

TEST(RollingImplicit, SaddleIsRefused) {
  // X^2/a^2 - Y^2/b^2 + Z^2/c^2 = 1 (a hyperboloid of one sheet) passes through (0, 0, -c) with
  // the ellipsoid's normal: curvatures c/a^2 = 2.5 along x and -c/b^2 = -4.44444 along y.
  std::string text = implicit_ellipsoid_text();
  replace_once(text, "X^2/a^2 + Y^2/b^2", "X^2/a^2 - Y^2/b^2");
  expect_parts(convexity_refusal(text),
               {"e.toml:", "contact 'foot'", "not strictly convex", "-4.44444 and 2.5", "f < 0 inside"});
}

TEST(RollingImplicit, ConcaveShapeIsRefused) {
  // An underside hollowed like an upturned bowl, Z = -c - (X^2 + Y^2) / (2 a): curvatures -1/a.
  std::string text = implicit_ellipsoid_text();
  replace_once(text, "X^2/a^2 + Y^2/b^2 + Z^2/c^2 - 1", "-Z - c - (X^2 + Y^2)/(2*a)");
  expect_parts(convexity_refusal(text), {"e.toml:", "contact 'foot'", "not strictly convex", "-5 and -5"});
  // The ellipsoid started at its highest point: the start is not the lowest point either.
  text = implicit_ellipsoid_text();
  replace_once(text, "pz = \"-c^2*cos(tilt)", "pz = \"c^2*cos(tilt)");
  expect_parts(convexity_refusal(text), {"contact 'foot'", "not strictly convex", "-4.44444 and -2.5"});
}

TEST(RollingImplicit, FlatterThanTheTerrainsHollowIsRefused) {
  // A bowl Z = k (X^2 + Y^2) / 2 has the curvature k at its bottom: k = 10 is more curved than the
  // ellipsoid (2.5, 4.44444), k = 1 is not.
  std::string text = implicit_ellipsoid_on_terrain_text();
  replace_once(text, "terrain = \"0*X\"", "terrain = \"5*(X^2 + Y^2)\"");
  expect_parts(convexity_refusal(text), {"e.toml:", "contact 'foot'", "flatter than the hollow",
                                         "2.5 and 4.44444", "-7.5 and -5.55556"});
  text = implicit_ellipsoid_on_terrain_text();
  replace_once(text, "terrain = \"0*X\"", "terrain = \"0.5*(X^2 + Y^2)\"");
  EXPECT_NO_THROW(load_model_text(text, "e.toml", {{"tilt", 0.0}}));
}

// A shape convex at the start but not everywhere: X^2/a^2 + Y^4/b^4 + Z^2/c^2 = 1 is flat along Y
// where Y = 0. Released tilted about x, its contact point swings through Y = 0: the run ends as it
// gets there, naming the shape (on the plane, the hollow's message would be the wrong cause). Near
// the bottom the curvatures are kappa_X = c/a^2 and kappa_Y = 6 c Y^2/b^4 (f's Hessian over
// |grad f| = 2/c), so the measure 4 kappa_X kappa_Y/(kappa_X + kappa_Y)^2 falls below 1e-4 at
// |Y| = b^2/a sqrt(1e-4/24) to first order.
TEST(RollingImplicit, AShapeThatStopsBeingConvexAlongTheRunEndsItThere) {
  std::string text = ellipsoid_example_text();
  replace_once(text, "shape = { ellipsoid = [\"a\", \"b\", \"c\"] }",
               "shape = { surface = \"X^2/a^2 + Y^4/b^4 + Z^2/c^2 - 1\" }");
  replace_once(text, "z = \"sqrt(a^2*sin(tilt)^2 + c^2*cos(tilt)^2)\", psi = 0, theta = 0, phi = \"tilt\"",
               "psi = 0, theta = \"tilt\", phi = 0");
  const Model model = load_model_text(text, "q.toml");
  SimulationOptions options;
  options.t_end = 1.0;
  options.output_step = 0.005;
  options.fix_initial = true;  // z onto the plane, and the contact point's coordinates
  const int py = implicit_column(model, "foot_py");
  std::vector<double> row;
  std::vector<double> ys;
  const SimulationSummary summary = simulate(model, options, [&](const Data& data) {
    fill_result_row(model, data, row);
    ys.push_back(row[static_cast<std::size_t>(py)]);
  });
  EXPECT_EQ(summary.status, Status::singular_system) << summary.message;
  expect_parts(summary.message, {"q.toml:", "contact 'foot': the shape is no longer strictly convex at its contact point",
                                 "det K_shape / (tr K_shape / 2)^2 on the tangent plane = "});
  const std::size_t at = summary.message.find("foot_py = ");
  ASSERT_NE(at, std::string::npos) << summary.message;
  const double a = 0.2, b = 0.15, limit = b * b / a * std::sqrt(1e-4 / 24);
  const double stopped = std::abs(std::stod(summary.message.substr(at + 10)));
  EXPECT_LT(stopped, 1.05 * limit) << summary.message;
  EXPECT_GT(stopped, 0.95 * limit) << summary.message;
  ASSERT_GT(ys.size(), 2u);
  EXPECT_GT(std::abs(ys.front()), 0.1 * b);  // started well off Y = 0, every row on the same side
  for (double y : ys) EXPECT_GT(y * ys.front(), stopped * std::abs(ys.front()));
}

}  // namespace
}  // namespace nhdyn
