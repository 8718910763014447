// The rattleback's equations as nhdyn derives them from examples/rattleback.toml against the same
// equations written by hand with vector mechanics (bench/check/rattleback_stacked.hpp: the same
// coordinates, the rolling condition on all three components of the contact point's velocity, an
// analytic D), at random states on and off the constraints: q'' and the reactions agree to
// round-off. The hand-written form is the yardstick of `make bench-check`'s rattleback_rhs_*
// ratios; this keeps it the same mechanics as the model.
#include <gtest/gtest.h>

#include <random>

#include "check/rattleback_stacked.hpp"
#include "nhdyn/formulation/formulation.hpp"
#include "nhdyn/frontend/load_model.hpp"
#include "nhdyn/model/data.hpp"
#include "support/text.hpp"

namespace nhdyn {
namespace {

TEST(RattlebackByHand, DerivedEquationsEqualTheHandWrittenOnesAtRandomStates) {
  const Model model = load_model(test::example("rattleback.toml"));
  ASSERT_EQ(model.n(), 6);
  ASSERT_EQ(model.s(), 3);
  Data data = make_data(model);
  const bench::RattlebackParameters p;
  std::mt19937 random(7);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  double largest_qdd = 0.0;
  for (int trial = 0; trial < 50; ++trial) {
    // Any position and velocity (the equations hold off the constraints too); theta within
    // +-1.2 rad, away from the frame's gimbal lock at +-pi/2.
    const double q[6] = {unit(random), unit(random), 0.02 + 0.01 * unit(random), 3.0 * unit(random),
                         1.2 * unit(random), 3.0 * unit(random)};
    double v[6];
    for (double& x : v) x = 3.0 * unit(random);
    bench::Vector6 qdd, reaction;
    ASSERT_TRUE(bench::rattleback_stacked(p, q, v, qdd, reaction));
    for (Complement complement : {Complement::qr, Complement::partition}) {
      ASSERT_EQ(compute_dynamics(model, data, {Formulation::sanh, complement}, 0.0, q, v), Status::ok);
      const double scale = 1.0 + qdd.norm();
      EXPECT_LT((data.qdd - qdd).norm(), 1e-11 * scale) << "trial " << trial;
      EXPECT_LT((data.R - reaction).norm(), 1e-11 * (1.0 + reaction.norm())) << "trial " << trial;
    }
    largest_qdd = std::max(largest_qdd, qdd.norm());
  }
  EXPECT_GT(largest_qdd, 1.0);  // the states move: the comparison is not of zeros
}

}  // namespace
}  // namespace nhdyn
