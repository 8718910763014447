// The crossing eigenvalue followed through the sweep (analysis/sweep.cpp, step 2): small models
// whose eigenvalues are known in closed form, q'' = -C(p) q' - K(p) q written as forces, with the
// cases that lead a follower astray: an eigenvalue 0 at every p on the crossing's path (as the
// bicycle's forward speed adds), eigenvectors nearly parallel, a grid point exactly at the
// crossing, two crossings in one grid cell, a stiff mode elsewhere that makes every uncertainty
// large, a double zero.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "nhdyn/analysis/sweep.hpp"
#include "nhdyn/frontend/load_model.hpp"

namespace nhdyn {
namespace {

// A model with coordinates x, y (and z when `force_z` is given), unit masses, the parameter p
// and the given forces.
Sweep tracking_sweep(const std::string& force_x, const std::string& force_y, double from, double to, int steps,
                     const std::string& force_z = "") {
  const bool z = !force_z.empty();
  std::string text = "name = \"tracking\"\n";
  text += z ? "coordinates = [\"x\", \"y\", \"z\"]\n" : "coordinates = [\"x\", \"y\"]\n";
  text += z ? "kinetic_energy = \"(x'^2 + y'^2 + z'^2)/2\"\n" : "kinetic_energy = \"(x'^2 + y'^2)/2\"\n";
  text += "[parameters]\np = 1.0\neps = 0.1\n[forces]\n";
  text += "x = \"" + force_x + "\"\ny = \"" + force_y + "\"\n";
  if (z) text += "z = \"" + force_z + "\"\n";
  SweepOptions o;
  o.parameter = "p";
  o.from = from;
  o.to = to;
  o.steps = steps;
  return sweep_model_parameter(model_source_from_text(text), {}, o);
}

// x'' = -x' - (p - 1) x: the eigenvalues (-1 +- sqrt(5 - 4 p))/2, one of them crossing zero at
// p = 1 (falling); y'' = -y': an eigenvalue 0 at every p (y is ignorable) and -1.
TEST(SweepTracking, ARealCrossingBesideAnEigenvalueZero) {
  const Sweep sweep = tracking_sweep("-x' - (p - 1)*x", "-y'", 0.3, 1.7, 8);
  ASSERT_EQ(sweep.crossings.size(), 1u);
  const StabilityCrossing& c = sweep.crossings[0];
  EXPECT_NEAR(c.value, 1.0, 1e-13);
  EXPECT_LT(c.bracket, 1e-13);
  EXPECT_FALSE(c.oscillatory);
  EXPECT_EQ(c.unstable_before, 1);
  EXPECT_EQ(c.unstable_after, 0);
}

// K = -(p - 1) [[0, 1/eps], [0, 1]], C = I: the eigenvalue 0 (eigenvector x) for all p, and
// lambda^2 + lambda = p - 1 with eigenvector (1, eps) in q, nearly parallel to the first
// (overlap 0.995 for eps = 0.1): the follower must not step onto the zero.
TEST(SweepTracking, NearlyParallelEigenvectors) {
  const Sweep sweep = tracking_sweep("-x' + (p - 1)/eps*y", "-y' + (p - 1)*y", 0.3, 1.7, 8);
  ASSERT_EQ(sweep.crossings.size(), 1u);
  EXPECT_NEAR(sweep.crossings[0].value, 1.0, 1e-13);
  EXPECT_LT(sweep.crossings[0].bracket, 1e-13);
  EXPECT_EQ(sweep.crossings[0].unstable_before, 0);
  EXPECT_EQ(sweep.crossings[0].unstable_after, 1);
}

// x'' = (p - 2) x' - 4 x: the pair (p - 2)/2 +- i sqrt(4 - (p - 2)^2/4) crosses at p = 2 with
// frequency 2, beside y's eigenvalue 0.
TEST(SweepTracking, AHopfPairBesideAnEigenvalueZero) {
  const Sweep sweep = tracking_sweep("(p - 2)*x' - 4*x", "-y'", 0.35, 3.1, 12);
  ASSERT_EQ(sweep.crossings.size(), 1u);
  const StabilityCrossing& c = sweep.crossings[0];
  EXPECT_NEAR(c.value, 2.0, 1e-12);
  EXPECT_TRUE(c.oscillatory);
  EXPECT_NEAR(c.frequency, 2.0, 1e-9);
  EXPECT_EQ(c.unstable_before, 0);
  EXPECT_EQ(c.unstable_after, 2);
}

// Eigenvalues p - 1 and -p - 5 (x), p - 1.05 and -3 (y): crossings at 1 and 1.05, both on grid
// points (spacing 0.01), where the crossing eigenvalue is 0, undecided, at the end of its cell.
// The follower went no further than the cell and kept the count's threshold, 7.8e-13 late with
// a bracket of 4e-16.
TEST(SweepTracking, GridPointsOnTheCrossings) {
  const Sweep sweep = tracking_sweep("-6*x' + (p-1)*(p+5)*x", "(p - 4.05)*y' + 3*(p - 1.05)*y", 0.3, 1.7, 141);
  ASSERT_EQ(sweep.crossings.size(), 2u);
  EXPECT_NEAR(sweep.crossings[0].value, 1.0, 1e-13);
  EXPECT_NEAR(sweep.crossings[1].value, 1.05, 1e-13);
  for (const StabilityCrossing& c : sweep.crossings) EXPECT_LT(c.bracket, 1e-13);
}

// The same eigenvalues on a grid of spacing 0.2: both crossings in the cell [0.9, 1.1], where the
// count goes from 0 to 2. Each is found in turn (the second was reported as part of the first).
TEST(SweepTracking, TwoCrossingsInOneCell) {
  const Sweep sweep = tracking_sweep("-6*x' + (p-1)*(p+5)*x", "(p - 4.05)*y' + 3*(p - 1.05)*y", 0.3, 1.7, 8);
  ASSERT_EQ(sweep.crossings.size(), 2u);
  EXPECT_NEAR(sweep.crossings[0].value, 1.0, 1e-13);
  EXPECT_NEAR(sweep.crossings[1].value, 1.05, 1e-13);
  EXPECT_EQ(sweep.crossings[0].unstable_before, 0);
  EXPECT_EQ(sweep.crossings[0].unstable_after, 1);
  EXPECT_EQ(sweep.crossings[1].unstable_before, 1);
  EXPECT_EQ(sweep.crossings[1].unstable_after, 2);
}

// The cases above with a stiff mode added, z'' = -1000 z' - 1e6 z (eigenvalues -500 +- 866 i):
// the uncertainties grow with the state matrix's norm (about 0.1 near the crossing here), the
// count changes 0.11 before the crossing, and the crossing eigenvalue is still undecided at the
// cell's end. The crossing must lie in the bracket reported (it was 0.11 away from a bracket of
// 7e-16).
TEST(SweepTracking, AStiffModeElsewhereWidensTheBracketAroundTheCrossing) {
  const std::string stiff = "-1000*z' - 1e6*z";
  struct Case {
    const char* what;
    Sweep sweep;
    double crossing;
  };
  const std::vector<Case> cases = {
      {"real", tracking_sweep("-x' - (p - 1)*x", "-y'", 0.3, 1.7, 8, stiff), 1.0},
      {"parallel", tracking_sweep("-x' + (p - 1)/eps*y", "-y' + (p - 1)*y", 0.3, 1.7, 8, stiff), 1.0},
      {"Hopf", tracking_sweep("(p - 2)*x' - 4*x", "-y'", 0.35, 3.1, 12, stiff), 2.0},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.what);
    ASSERT_EQ(c.sweep.crossings.size(), 1u);
    const StabilityCrossing& x = c.sweep.crossings[0];
    EXPECT_LE(std::abs(x.value - c.crossing), 0.5 * x.bracket) << x.value << " +- " << 0.5 * x.bracket;
    EXPECT_LT(x.bracket, 1.0);
  }
}

// c = -3 (p - 1), k = 2 (p - 1)^2: the eigenvalues p - 1 and 2 (p - 1), a double zero with a
// Jordan block at p = 1, where both become unstable. Known there to about sqrt(eps) s only, they
// leave the uncertainty one after the other: two divergences, each bracketing p = 1.
TEST(SweepTracking, ADoubleZero) {
  const Sweep sweep = tracking_sweep("3*(p-1)*x' - 2*(p-1)^2*x", "-y' - y", 0.3, 1.7, 8);
  ASSERT_EQ(sweep.crossings.size(), 2u);
  for (int i = 0; i < 2; ++i) {
    const StabilityCrossing& c = sweep.crossings[static_cast<std::size_t>(i)];
    EXPECT_LE(std::abs(c.value - 1.0), 0.5 * c.bracket + 1e-15) << c.value << " +- " << 0.5 * c.bracket;
    EXPECT_LT(c.bracket, 1e-5);
    EXPECT_FALSE(c.oscillatory);
    EXPECT_EQ(c.unstable_before, i);
    EXPECT_EQ(c.unstable_after, i + 1);
  }
}

}  // namespace
}  // namespace nhdyn
