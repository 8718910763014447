// Consistency: the rolling disk built from its body (examples/rolling_disk_bodies.toml, the
// multibody front end) against the hand-written five-coordinate model (examples/rolling_disk.toml,
// docs/gallery/rolling_disk.md), in the same coordinates: T and V at random states, the rows of b
// and b0, and q'' and the reactions R at random states that satisfy the rolling constraints.
// Negative control: a body with the wrong axial inertia is told apart.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "multibody/multibody_support.hpp"
#include "nhdyn/frontend/model_file.hpp"
#include "nhdyn/symbolic/compile.hpp"
#include "nhdyn/symbolic/derivation.hpp"
#include "support/text.hpp"

namespace nhdyn::multibody_test {
namespace {

using nhdyn::test::example;

std::string read_text(const std::string& path) {
  std::ifstream in(path);
  std::stringstream buffer;
  buffer << in.rdbuf();
  return buffer.str();
}

// A state (q, v) with the disk rolling: x' = r phi' cos(psi), y' = r phi' sin(psi).
void rolling_state(std::mt19937& rng, double r, std::vector<double>& q, std::vector<double>& v) {
  q = {uniform(rng, -2, 2), uniform(rng, -2, 2), uniform(rng, -3, 3), uniform(rng, -1.2, 1.2), uniform(rng, -3, 3)};
  v = {0, 0, uniform(rng, -3, 3), uniform(rng, -3, 3), uniform(rng, -8, 8)};
  v[0] = r * v[4] * std::cos(q[2]);
  v[1] = r * v[4] * std::sin(q[2]);
}

double relative(double a, double b, double scale) { return std::abs(a - b) / std::max(scale, 1e-300); }

TEST(RollingDiskBodies, HasTheTwoNoSlipConstraintsAndNoContactConstraint) {
  const symbolic::Spec spec = load_model_file(example("rolling_disk_bodies.toml"));
  ASSERT_EQ(spec.n(), 5);
  ASSERT_EQ(spec.s(), 2);  // n.P = 0 holds identically in these coordinates
  EXPECT_EQ(spec.constraints[0].name, "disk_slip1");
  EXPECT_EQ(spec.constraints[1].name, "disk_slip2");
  EXPECT_EQ(spec.constraints[0].level, ConstraintLevel::velocity);
}

TEST(RollingDiskBodies, TAndVAgreeWithTheHandWrittenModelAtRandomStates) {
  const symbolic::Spec bodies = load_model_file(example("rolling_disk_bodies.toml"));
  const symbolic::Spec hand = load_model_file(example("rolling_disk.toml"));
  std::mt19937 rng(7);
  for (int trial = 0; trial < 20; ++trial) {
    std::vector<double> q(5), v(5);
    for (double& x : q) x = uniform(rng, -3, 3);
    for (double& x : v) x = uniform(rng, -3, 3);
    const double Tb = evaluate(bodies, bodies.kinetic_energy, q, v), Th = evaluate(hand, hand.kinetic_energy, q, v);
    const double Vb = evaluate(bodies, bodies.potential_energy, q, v), Vh = evaluate(hand, hand.potential_energy, q, v);
    EXPECT_LT(relative(Tb, Th, std::abs(Th)), 1e-13) << Tb << " vs " << Th;
    EXPECT_LT(std::abs(Vb - Vh), 1e-13 * (1 + std::abs(Vh))) << Vb << " vs " << Vh;
  }
}

TEST(RollingDiskBodies, ConstraintsAndAccelerationsAndReactionsAgreeAtRollingStates) {
  const Model bodies = symbolic::compile_model(load_model_file(example("rolling_disk_bodies.toml")));
  const Model hand = symbolic::compile_model(load_model_file(example("rolling_disk.toml")));
  std::mt19937 rng(11);
  const double r = 0.2;
  for (int trial = 0; trial < 25; ++trial) {
    std::vector<double> q, v;
    rolling_state(rng, r, q, v);
    const Data b = dynamics_at(bodies, q, v), h = dynamics_at(hand, q, v);
    // The same constraint rows: t1 = x, t2 = y for the ground z = 0.
    EXPECT_LT((b.b - h.b).norm(), 1e-14 * h.b.norm());
    EXPECT_LT((b.b0 - h.b0).norm(), 1e-13 * (1 + h.b0.norm()));
    EXPECT_LT((b.A - h.A).norm(), 1e-14 * h.A.norm());
    EXPECT_LT((b.Q + b.G - h.Q - h.G).norm(), 1e-13 * (1 + (h.Q + h.G).norm()));
    EXPECT_LT((b.qdd - h.qdd).norm(), 1e-12 * h.qdd.norm()) << trial;
    EXPECT_LT((b.R - h.R).norm(), 1e-12 * h.R.norm()) << trial;
  }
}

// Negative control: the axial moment m r^2/4 in place of m r^2/2 changes q'' far beyond the
// tolerance above.
TEST(RollingDiskBodies, AWrongAxialInertiaIsToldApart) {
  std::string text = read_text(example("rolling_disk_bodies.toml"));
  const std::string from = "[\"m*r^2/4\", \"m*r^2/2\", \"m*r^2/4\"]";
  text.replace(text.find(from), from.size(), "[\"m*r^2/4\", \"m*r^2/4\", \"m*r^2/4\"]");
  const Model wrong = symbolic::compile_model(load_model_string(text, "altered.toml"));
  const Model hand = symbolic::compile_model(load_model_file(example("rolling_disk.toml")));
  std::mt19937 rng(11);
  std::vector<double> q, v;
  rolling_state(rng, 0.2, q, v);
  const Data b = dynamics_at(wrong, q, v), h = dynamics_at(hand, q, v);
  EXPECT_GT((b.qdd - h.qdd).norm(), 1e-3 * h.qdd.norm());
}

}  // namespace
}  // namespace nhdyn::multibody_test
