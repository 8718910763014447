// Exam: the knife edge of examples/knife_edge.toml (centre of mass at the contact point, on a
// plane inclined by alpha) against the closed form derived in docs/gallery/knife_edge.md: with
// phi0 = 0, spin w, initial speed v0 along the blade and c = g sin(alpha),
//
//     phi = w t,   v = v0 + (c/w) sin(w t)
//     x = (v0/w) sin(w t) + c/(2 w^2) sin^2(w t)
//     y = (v0/w) (1 - cos(w t)) + c/(2 w) (t - sin(2 w t)/(2 w))
//
// the blade's reaction lambda = m (v w + c sin(phi)), R = lambda (-sin(phi), cos(phi), 0), and
// the conserved T + V = m/2 (v^2 + rho^2 w^2) - m c x.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <utility>
#include <vector>

#include "gallery/gallery.hpp"

namespace nhdyn::gallery {
namespace {

struct KnifeErrors {
  double spin = 0.0;      // max |phi' - w| [rad/s]
  double phi = 0.0;       // max |phi - w t| [rad]
  double position = 0.0;  // max |(x, y) - exact| [m]
  double speed = 0.0;     // max |(x', y') - exact| [m/s]
  double reaction = 0.0;  // max |R - R_exact| / (m g)
  double energy = 0.0;    // max |E - E0| / (m g l), l = c / w^2
};

KnifeErrors measure_knife(const Model& model) {
  const double m = parameter(model, "m"), rho = parameter(model, "rho"), g = parameter(model, "g");
  const double c = g * std::sin(parameter(model, "alpha"));
  const double v0 = model.v0(0), w = model.v0(2);
  EXPECT_EQ(model.q0(2), 0.0);  // the closed form below starts along Ox
  const double E0 = 0.5 * m * (v0 * v0 + rho * rho * w * w);
  KnifeErrors err;
  for (const Row& r : run_rows(model, tight_options(10.0, 0.01))) {
    const double t = r.t, S = std::sin(w * t), C = std::cos(w * t);
    const double x = v0 / w * S + c / (2 * w * w) * S * S;
    const double y = v0 / w * (1 - C) + c / (2 * w) * (t - std::sin(2 * w * t) / (2 * w));
    const double v = v0 + c / w * S;
    err.spin = std::max(err.spin, std::abs(r.v(2) - w));
    err.phi = std::max(err.phi, std::abs(r.q(2) - w * t));
    err.position = std::max(err.position, std::hypot(r.q(0) - x, r.q(1) - y));
    err.speed = std::max(err.speed, std::hypot(r.v(0) - v * C, r.v(1) - v * S));
    const double lambda = m * (v * w + c * S);
    err.reaction = std::max({err.reaction, std::abs(r.R(0) + lambda * S) / (m * g),
                             std::abs(r.R(1) - lambda * C) / (m * g), std::abs(r.R(2)) / (m * g)});
    err.energy = std::max(err.energy, std::abs(r.energy - E0) / (m * c * c / (w * w)));
  }
  return err;
}

TEST(KnifeEdge, SpinsAtAConstantRateAndMatchesTheClosedForm) {
  const KnifeErrors err = measure_knife(load_example("knife_edge.toml"));
  EXPECT_LT(err.spin, 1e-12);
  EXPECT_LT(err.phi, 1e-12);
  EXPECT_LT(err.position, 1e-9);
  EXPECT_LT(err.speed, 2e-9);
  EXPECT_LT(err.reaction, 1e-9);
  EXPECT_LT(err.energy, 1e-9);
}

// Other spin rates and initial speeds, among them the classical start at rest along the blade
// (v0 = 0: the skate drifts across the slope on cycloid-like arcs).
TEST(KnifeEdge, MatchesTheClosedFormAtOtherSpinRatesAndSpeeds) {
  for (const auto& [w, v0] : {std::pair{0.7, 0.0}, std::pair{5.0, -2.0}}) {
    const KnifeErrors err = measure_knife(load_example("knife_edge.toml", {{"w", w}, {"v0", v0}}));
    EXPECT_LT(err.spin, 1e-12) << "w = " << w;
    EXPECT_LT(err.position, 1e-9) << "w = " << w;
    EXPECT_LT(err.reaction, 1e-9) << "w = " << w;
  }
}

// Negative controls: the blade's sign flipped, or the slope's, is caught.
TEST(KnifeEdge, TheExamRejectsWrongModels) {
  const Model flipped = load_altered_example("knife_edge.toml", "velocity = \"-sin(phi)*x' + cos(phi)*y'\"",
                                             "velocity = \"sin(phi)*x' + cos(phi)*y'\"");
  EXPECT_GT(measure_knife(flipped).position, 1e-2);
  const Model uphill = load_altered_example("knife_edge.toml", "\"-m*g*sin(alpha) * x\"", "\"m*g*sin(alpha) * x\"");
  EXPECT_GT(measure_knife(uphill).position, 1e-2);
}

}  // namespace
}  // namespace nhdyn::gallery
