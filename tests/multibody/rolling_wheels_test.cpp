// The axled shapes of [[contacts]] (disk, torus) against closed forms: a wheel rolling straight
// down an incline (the torus's effective radius is R + r, the disk's r), the upright disk's tilt
// stability, and the steady circles of the disk and the torus (docs/derivations/rolling-bodies.md
// sections 6.8 and 6.9).
#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <cstdio>
#include <string>
#include <vector>

#include "nhdyn/analysis/linearization.hpp"
#include "nhdyn/analysis/simulation.hpp"
#include "nhdyn/frontend/load_model.hpp"
#include "nhdyn/io/results.hpp"
#include "support/models.hpp"

namespace nhdyn {
namespace {

int wheel_column(const ResultColumns& columns, const std::string& name) {
  for (std::size_t i = 0; i < columns.all.size(); ++i)
    if (columns.all[i] == name) return static_cast<int>(i);
  ADD_FAILURE() << "no column " << name;
  return 0;
}

// A wheel of mass m and moment J about its axle (the body's y), its centre at (x, y, z) turned by
// Rz(psi) Rx(theta) Ry(phi), on the plane through the origin with normal (sin(alpha), 0,
// cos(alpha)), released at rest upright across the slope. `shape` is the shape's table.
std::string incline_model(const std::string& shape, const std::string& reach) {
  return R"toml(name = "wheel-on-incline"
coordinates = ["x", "y", "z", "psi", "theta", "phi"]
gravity = [0, 0, "-g"]

[parameters]
m = 2.0
J = 0.07
K = 0.05
R = 0.3
r = 0.05
g = 9.81
alpha = 0.4

[[frames]]
name = "wheel"
translation = ["x", "y", "z"]
rotations = [["z", "psi"], ["x", "theta"], ["y", "phi"]]

[[bodies]]
name = "wheel"
frame = "wheel"
mass = "m"
inertia = ["K", "J", "K"]

[[contacts]]
name = "tyre"
body = "wheel"
shape = )toml" + shape +
         R"toml(
ground = { plane = ["sin(alpha)", 0, "cos(alpha)"] }

[initial]
position = { x = ")toml" +
         reach + R"toml(*sin(alpha)", y = 0, z = ")toml" + reach + R"toml(*cos(alpha)", psi = 0, theta = 0, phi = 0 }
)toml";
}

// Rolling straight down the slope (rolling-bodies.md (6.8)): the centre accelerates along
// d = (cos(alpha), 0, -sin(alpha)) at a = g sin(alpha) / (1 + J / (m rho^2)), rho the distance
// from the centre to the contact (R + r
// for the torus: the tube's radius adds to the rim's), and turns at phi' = s' / rho; the ground
// pushes N = m g cos(alpha) and holds the wheel back with m g sin(alpha) k / (1 + k), k = J/(m rho^2).
// With `level_in_file`, the file says alpha = 0 (a level plane, its normal along z) and --set's
// value makes it the incline: the plane must follow the parameter.
void check_incline(const std::string& shape, const std::string& reach_text, double rho, bool level_in_file = false) {
  std::string text = incline_model(shape, reach_text);
  if (level_in_file) {
    const std::size_t at = text.find("alpha = 0.4");
    ASSERT_NE(at, std::string::npos);
    text.replace(at, 11, "alpha = 0.0");
  }
  const Model model = level_in_file ? load_model_text(text, "<incline>", {{"alpha", 0.4}}) : load_model_text(text);
  const double m = 2.0, J = 0.07, g = 9.81, alpha = 0.4;
  const double k = J / (m * rho * rho), a = g * std::sin(alpha) / (1 + k);
  const double x0 = rho * std::sin(alpha), z0 = rho * std::cos(alpha);
  const ResultColumns columns = make_result_columns(model);
  const int x = wheel_column(columns, "x"), y = wheel_column(columns, "y"), z = wheel_column(columns, "z");
  const int theta = wheel_column(columns, "theta"), phi = wheel_column(columns, "phi"), phid = wheel_column(columns, "phi'");
  const int N = wheel_column(columns, "tyre_N"), Fx = wheel_column(columns, "tyre_Fx"), Fz = wheel_column(columns, "tyre_Fz");
  const int Z = wheel_column(columns, "tyre_Z"), X = wheel_column(columns, "tyre_X");
  SimulationOptions options;
  options.t_end = 1.0;
  options.output_step = 0.05;
  options.integrator.rtol = 1e-11;
  options.integrator.atol = 1e-13;
  std::vector<double> row;
  int rows = 0;
  simulate(model, options, [&](const Data& data) {
    fill_result_row(model, data, row);
    const auto at = [&](int i) { return row[static_cast<std::size_t>(i)]; };
    const double t = data.t, s = a * t * t / 2;
    EXPECT_NEAR(at(x), x0 + s * std::cos(alpha), 1e-10) << shape << " t " << t;
    EXPECT_NEAR(at(z), z0 - s * std::sin(alpha), 1e-10) << shape << " t " << t;
    EXPECT_NEAR(at(y), 0.0, 1e-12);
    EXPECT_NEAR(at(theta), 0.0, 1e-12);
    EXPECT_NEAR(at(phi), s / rho, 1e-9);
    EXPECT_NEAR(at(phid), a * t / rho, 1e-9);
    const double normal = m * g * std::cos(alpha), friction = m * g * std::sin(alpha) * k / (1 + k);
    EXPECT_NEAR(at(N), normal, 1e-10 * m * g);
    // F = N n - friction d.
    EXPECT_NEAR(at(Fx), normal * std::sin(alpha) - friction * std::cos(alpha), 1e-10 * m * g);
    EXPECT_NEAR(at(Fz), normal * std::cos(alpha) + friction * std::sin(alpha), 1e-10 * m * g);
    // The contact point is on the plane, straight below the centre along -n.
    EXPECT_NEAR(at(X) * std::sin(alpha) + at(Z) * std::cos(alpha), 0.0, 1e-12);
    EXPECT_NEAR(at(X), at(x) - rho * std::sin(alpha), 1e-12);
    ++rows;
  });
  EXPECT_EQ(rows, 21);
}

TEST(RollingWheels, TorusRollsDownAnInclineWithTheOuterRadius) {
  check_incline(R"toml({ torus = ["R", "r"], axis = "y" })toml", "(R + r)", 0.35);
}

TEST(RollingWheels, DiskRollsDownAnInclineWithItsRadius) { check_incline(R"toml({ disk = "R", axis = "y" })toml", "R", 0.3); }

// The plane's normal written in a parameter, axis-aligned at the file's value: --set tilts it.
TEST(RollingWheels, SetTiltsAPlaneThatIsLevelInTheFile) {
  check_incline(R"toml({ disk = "R", axis = "y" })toml", "R", 0.3, true);
}

// A uniform disk of radius r, centre (x, y, z), heading psi, tilt theta about the heading's x axis,
// spin phi about the axle y: the frames of examples/rolling_disk_bodies.toml with the centre's
// height held by the contact condition instead of placed.
const std::string disk_model =
    test::free_disk_text("disk", "w = 6.0\ntheta0 = 0.3\nOmega = 2.0\n",
                         "\n[[contacts]]\nname = \"disk\"\nbody = \"disk\"\nshape = { disk = \"r\", axis = \"y\" }\n",
                         "velocity = { x = \"r*w\", phi = \"w\" }\n");

// A wheel (mass 0.5, moments Ia about its axle y and Id about a diameter) with the frames of
// examples/rolling_disk_bodies.toml but its centre's height held by the contact condition, started
// on a steady circle: tilt theta0, heading rate Omega, spin rate `spin`, centre velocity V along x.
std::string steady_circle_model(const std::string& shape, double Ia, double Id, double height, double V, double Omega,
                      double spin, double theta0) {
  const auto number = [](double x) {
    char buffer[40];
    std::snprintf(buffer, sizeof buffer, "%.17g", x);
    return std::string(buffer);
  };
  return R"toml(name = "wheel"
coordinates = ["x", "y", "z", "psi", "theta", "phi"]
gravity = [0, 0, "-g"]

[parameters]
m = 0.5
g = 9.81

[[frames]]
name = "wheel"
translation = ["x", "y", "z"]
rotations = [["z", "psi"], ["x", "theta"], ["y", "phi"]]

[[bodies]]
name = "wheel"
frame = "wheel"
mass = "m"
inertia = [)toml" + number(Id) + ", " + number(Ia) + ", " + number(Id) + R"toml(]

[[contacts]]
name = "wheel"
body = "wheel"
shape = )toml" + shape + R"toml(

[initial]
position = { x = 0, y = 0, z = )toml" + number(height) + ", psi = 0, theta = " + number(theta0) +
         R"toml(, phi = 0 }
velocity = { x = )toml" + number(V) + ", psi = " + number(Omega) + ", phi = " + number(spin) + " }\n";
}

// Upright rolling at the spin rate w: the tilt obeys theta'' = (4/5) (g/r - 3 w^2) theta
// (examples/rolling_disk_upright.toml), so about it the linearization has the pair
// +-i sqrt((4/5)(3 w^2 - g/r)) and zeros; below w^2 = g/(3 r) the pair is real.
TEST(RollingWheels, UprightDiskTiltFrequencyMatchesTheClosedForm) {
  const std::string& text = disk_model;
  for (const double w : {6.0, 2.0}) {
    const Model model = load_model_text(text, "<disk>", {{"w", w}});
    LinearizationOptions options;
    options.cyclic = {"psi"};
    const Linearization l = calc_linearization(model, options);
    const double g = 9.81, r = 0.2, lambda2 = 0.8 * (g / r - 3 * w * w);
    std::vector<std::complex<double>> nonzero;
    for (const std::complex<double>& e : l.eigenvalues)
      if (std::abs(e) > 1e-6) nonzero.push_back(e);
    ASSERT_EQ(nonzero.size(), 2u) << "w " << w;
    const double expected = std::sqrt(std::abs(lambda2));
    for (const std::complex<double>& e : nonzero) {
      EXPECT_NEAR(std::abs(e), expected, 1e-10 * expected) << e;
      if (lambda2 < 0) EXPECT_NEAR(e.real(), 0.0, 1e-10) << e;
      else EXPECT_NEAR(e.imag(), 0.0, 1e-10) << e;
    }
    // And it rolls on straight, upright, at the speed r w.
    SimulationOptions run;
    run.t_end = 2.0;
    run.output_step = 0.1;
    run.integrator.rtol = 1e-11;
    run.integrator.atol = 1e-13;
    simulate(model, run, [&](const Data& data) {
      EXPECT_NEAR(data.q(0), r * w * data.t, 1e-10);
      EXPECT_NEAR(data.q(1), 0.0, 1e-12);
      EXPECT_NEAR(data.q(4), 0.0, 1e-12);
    });
  }
}

// The steady circle (rolling-bodies.md (6.9)) of a wheel whose contact is P - C = -R b - rt n (b
// the wheel's radial direction towards the contact's opposite, n the ground's normal; a disk has
// rt = 0, a torus its tube's radius), moments Ia about the axle and Id about a diameter, at the
// tilt theta0 and heading rate Omega: the spin about the axle is u - Omega sin(theta0) with
//   u = [Omega^2 c s (Id + m rt (R c + rt)) - m g R s] / (Omega (m (R c + rt)(R + rt c) + c Ia)),
// s, c = sin, cos(theta0); the centre moves at V = R u + rt c (u - Omega s) on the circle of radius
// V / Omega, at the height R c + rt, the tilt stays, and the ground pushes m g up and m Omega V
// towards the circle's centre. For the uniform disk u - Omega s = -5/6 Omega s - 2 g tan(theta0)/(3 r Omega)
// (examples/rolling_disk_bodies.toml).
void check_steady_circle(const std::string& shape, double R, double rt, double Ia, double Id) {
  const double m = 0.5, g = 9.81, theta0 = 0.3, Omega = 2.0;
  const double s = std::sin(theta0), c = std::cos(theta0);
  const double u = (Omega * Omega * c * s * (Id + m * rt * (R * c + rt)) - m * g * R * s) /
                   (Omega * (m * (R * c + rt) * (R + rt * c) + c * Ia));
  const double spin = u - Omega * s, V = R * u + rt * c * spin, radius = V / Omega, height = R * c + rt;
  const std::string text = steady_circle_model(shape, Ia, Id, height, V, Omega, spin, theta0);
  const Model model = load_model_text(text, "<wheel>");
  const ResultColumns columns = make_result_columns(model);
  const int Fx = wheel_column(columns, "wheel_Fx"), Fy = wheel_column(columns, "wheel_Fy"), Fz = wheel_column(columns, "wheel_Fz");
  SimulationOptions options;
  options.t_end = 2 * M_PI / Omega;
  options.output_step = 0.05;
  options.integrator.rtol = 1e-11;
  options.integrator.atol = 1e-13;
  std::vector<double> row;
  int rows = 0;
  simulate(model, options, [&](const Data& data) {
    fill_result_row(model, data, row);
    const auto at = [&](int i) { return row[static_cast<std::size_t>(i)]; };
    const double t = data.t;
    EXPECT_NEAR(data.q(0), radius * std::sin(Omega * t), 1e-9) << shape << " t " << t;
    EXPECT_NEAR(data.q(1), radius * (1 - std::cos(Omega * t)), 1e-9) << shape << " t " << t;
    EXPECT_NEAR(data.q(2), height, 1e-11);
    EXPECT_NEAR(data.q(3), Omega * t, 1e-9);
    EXPECT_NEAR(data.q(4), theta0, 1e-9);
    EXPECT_NEAR(data.v(5), spin, 1e-9);
    // The centre's acceleration points at the circle's centre (0, radius): F = m (a_C - g).
    EXPECT_NEAR(at(Fx), -m * Omega * V * std::sin(Omega * t), 1e-9 * m * g);
    EXPECT_NEAR(at(Fy), m * Omega * V * std::cos(Omega * t), 1e-9 * m * g);
    EXPECT_NEAR(at(Fz), m * g, 1e-9 * m * g);
    ++rows;
  });
  EXPECT_GT(rows, 60);
}

TEST(RollingWheels, DiskHoldsTheClosedFormSteadyCircle) {
  const double m = 0.5, r = 0.2, Omega = 2.0, theta0 = 0.3, g = 9.81;
  const double disk_spin = -5.0 / 6 * Omega * std::sin(theta0) - 2 * g * std::tan(theta0) / (3 * r * Omega);
  // The general formula reduces to the disk's (a check of the formula, not of nhdyn).
  const double s = std::sin(theta0), c = std::cos(theta0), Ia = m * r * r / 2, Id = m * r * r / 4;
  EXPECT_NEAR((Omega * Omega * c * s * Id - m * g * r * s) / (Omega * (m * r * c * r + c * Ia)) - Omega * s, disk_spin,
              1e-14);
  check_steady_circle(R"toml({ disk = "0.2", axis = "y" })toml", r, 0.0, Ia, Id);
}

// A tyre of tube 4 cm on a rim of 16 cm: the same tilt and heading rate need another spin, and
// the wheel runs on another circle than the thin wheel of the same outer radius.
TEST(RollingWheels, TorusHoldsItsOwnSteadyCircle) {
  check_steady_circle(R"toml({ torus = ["0.16", "0.04"], axis = "y" })toml", 0.16, 0.04, 0.012, 0.007);
}

}  // namespace
}  // namespace nhdyn
