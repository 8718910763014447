// Events (events.hpp) on problems whose crossings are known in closed form: the zeros of cos t
// found by every integrator that locates events, to round-off for the explicit pairs on their
// continuous extensions; the direction filter; several crossings in one step reported in time
// order; a stop that ends the run at the crossing; a dip through zero and back inside one step,
// found when the event may dip; rk4 refused; Brent's method on its own.
#include "nhdyn/integrators/events.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include "nhdyn/core/error.hpp"
#include "nhdyn/integrators/ode.hpp"

namespace nhdyn {
namespace {

constexpr double pi = std::numbers::pi;

// x'' = -x, y(0) = (1, 0): x = cos t.
class EventOscillator : public OdeSystem {
 public:
  int size() const override { return 2; }
  Status rhs(double /*t*/, const double* y, double* ydot) override {
    ydot[0] = y[1];
    ydot[1] = -y[0];
    return Status::ok;
  }
};

struct Hit {
  int index;
  double t;
  double x;
};

// g_0 = x with a chosen direction; optionally g_1 = t - a, g_2 = t - b (crossing once, rising).
class Events : public EventFunctions {
 public:
  Events(CrossingDirection direction, std::vector<double> times = {}, int stop_after = -1)
      : direction_(direction), times_(std::move(times)), stop_after_(stop_after) {}
  int count() const override { return 1 + static_cast<int>(times_.size()); }
  CrossingDirection direction(int i) const override { return i == 0 ? direction_ : CrossingDirection::rising; }
  Status evaluate(double t, const double* y, double* g) override {
    g[0] = y[0];
    for (std::size_t i = 0; i < times_.size(); ++i) g[i + 1] = t - times_[i];
    return Status::ok;
  }
  Status on_event(int i, double t, const double* y) override {
    hits.push_back({i, t, y[0]});
    return static_cast<int>(hits.size()) == stop_after_ ? Status::stopped : Status::ok;
  }
  std::vector<Hit> hits;

 private:
  CrossingDirection direction_;
  std::vector<double> times_;
  int stop_after_;
};

IntegrationResult run(IntegratorKind kind, Events& events, double t_end, double rtol, double max_step = 0.0) {
  EventOscillator oscillator;
  IntegratorOptions options;
  options.kind = kind;
  options.rtol = rtol;
  options.atol = rtol * 1e-2;
  options.max_step = max_step;
  const double y0[2] = {1.0, 0.0};
  const std::vector<double> times = {0.0, t_end};
  return integrate(oscillator, options, 0.0, y0, times, [](double, const double*) { return Status::ok; }, &events);
}

TEST(Events, ZerosOfCosineFromEveryIntegratorWithEvents) {
  // The crossings of x = cos t are at (k + 1/2) pi; the located time carries the integration
  // error (about rtol) and no more: the root on the interpolant is exact to round-off.
  const struct {
    IntegratorKind kind;
    double rtol;
    double tolerance;
  } cases[] = {{IntegratorKind::dopri5, 1e-10, 1e-8},
               {IntegratorKind::dop853, 1e-13, 1e-11},
               {IntegratorKind::cvode_adams, 1e-10, 1e-7},
               {IntegratorKind::cvode_bdf, 1e-10, 1e-6}};
  for (const auto& c : cases) {
    Events events(CrossingDirection::both);
    const IntegrationResult result = run(c.kind, events, 10.0, c.rtol);
    ASSERT_EQ(result.status, Status::ok) << integrator_name(c.kind) << ": " << result.message;
    ASSERT_EQ(events.hits.size(), 3u) << integrator_name(c.kind);  // pi/2, 3pi/2, 5pi/2 < 10
    for (std::size_t k = 0; k < events.hits.size(); ++k) {
      EXPECT_NEAR(events.hits[k].t, (static_cast<double>(k) + 0.5) * pi, c.tolerance) << integrator_name(c.kind);
      EXPECT_NEAR(events.hits[k].x, 0.0, c.tolerance) << integrator_name(c.kind);
    }
  }
}

TEST(Events, ExplicitPairsLocateTheRootOfTheirInterpolantToRoundOff) {
  // The state reported is on the far side of the crossing, or exactly on it, and within a few
  // ulps of the crossing of the interpolant: |x| is at the level of round-off.
  for (IntegratorKind kind : {IntegratorKind::dopri5, IntegratorKind::dop853}) {
    Events events(CrossingDirection::both);
    ASSERT_EQ(run(kind, events, 10.0, 1e-6).status, Status::ok);
    ASSERT_EQ(events.hits.size(), 3u);
    for (std::size_t k = 0; k < events.hits.size(); ++k) {
      EXPECT_LT(std::abs(events.hits[k].x), 1e-14) << integrator_name(kind);
      // falling at pi/2 (x becomes negative), rising at 3pi/2, falling at 5pi/2
      const double expected_sign = k % 2 == 0 ? -1.0 : 1.0;
      EXPECT_GE(expected_sign * events.hits[k].x, 0.0) << integrator_name(kind);
    }
  }
}

TEST(Events, DirectionSelectsTheCrossings) {
  for (IntegratorKind kind : {IntegratorKind::dopri5, IntegratorKind::dop853, IntegratorKind::cvode_adams}) {
    Events rising(CrossingDirection::rising);
    ASSERT_EQ(run(kind, rising, 10.0, 1e-10).status, Status::ok);
    ASSERT_EQ(rising.hits.size(), 1u) << integrator_name(kind);
    EXPECT_NEAR(rising.hits[0].t, 1.5 * pi, 1e-7);
    Events falling(CrossingDirection::falling);
    ASSERT_EQ(run(kind, falling, 10.0, 1e-10).status, Status::ok);
    ASSERT_EQ(falling.hits.size(), 2u) << integrator_name(kind);
    EXPECT_NEAR(falling.hits[0].t, 0.5 * pi, 1e-7);
    EXPECT_NEAR(falling.hits[1].t, 2.5 * pi, 1e-7);
  }
}

TEST(Events, SeveralCrossingsInOneStepComeInTimeOrder) {
  // Loose tolerances make steps of about a second: the crossings of t - 0.9, t - 0.7 and
  // x (at pi/2) share steps, and are listed in the order of their times, not of their indices.
  for (IntegratorKind kind : {IntegratorKind::dopri5, IntegratorKind::dop853, IntegratorKind::cvode_adams}) {
    Events events(CrossingDirection::falling, {1.5, 0.9, 0.7});
    ASSERT_EQ(run(kind, events, 3.0, 1e-3).status, Status::ok);
    ASSERT_EQ(events.hits.size(), 4u) << integrator_name(kind);
    EXPECT_EQ(events.hits[0].index, 3);
    EXPECT_EQ(events.hits[1].index, 2);
    EXPECT_EQ(events.hits[2].index, 1);
    EXPECT_EQ(events.hits[3].index, 0);
    EXPECT_NEAR(events.hits[0].t, 0.7, 1e-12);
    EXPECT_NEAR(events.hits[1].t, 0.9, 1e-12);
    EXPECT_NEAR(events.hits[2].t, 1.5, 1e-12);
    EXPECT_NEAR(events.hits[3].t, 0.5 * pi, 1e-2);
  }
}

TEST(Events, StopEndsTheRunAtTheCrossing) {
  for (IntegratorKind kind : {IntegratorKind::dopri5, IntegratorKind::dop853, IntegratorKind::cvode_bdf}) {
    Events events(CrossingDirection::both, {}, 2);
    const IntegrationResult result = run(kind, events, 10.0, 1e-10);
    EXPECT_EQ(result.status, Status::stopped);
    ASSERT_EQ(events.hits.size(), 2u);
    EXPECT_EQ(result.t_reached, events.hits[1].t);
    EXPECT_NEAR(result.t_reached, 1.5 * pi, 1e-6);
  }
}

// y' = 1 from 0: the error estimate is zero, so each step is ten times the last, and one of
// them spans t = 1 ... 10. g = (y - 5)^2 - a^2 dips below zero between 5 - a and 5 + a inside it,
// positive at both its ends: seen only when the event may dip (EventFunctions::may_dip).
class Uniform : public OdeSystem {
 public:
  int size() const override { return 1; }
  Status rhs(double /*t*/, const double* /*y*/, double* ydot) override {
    ydot[0] = 1.0;
    return Status::ok;
  }
};

class Dip : public EventFunctions {
 public:
  Dip(CrossingDirection direction, double a2, bool may_dip) : direction_(direction), a2_(a2), may_dip_(may_dip) {}
  int count() const override { return 1; }
  CrossingDirection direction(int) const override { return direction_; }
  Status evaluate(double, const double* y, double* g) override {
    g[0] = (y[0] - 5.0) * (y[0] - 5.0) - a2_;
    return Status::ok;
  }
  Status on_event(int, double t, const double*) override {
    hits.push_back(t);
    return Status::ok;
  }
  bool may_dip(int) const override { return may_dip_; }
  std::vector<double> hits;

 private:
  CrossingDirection direction_;
  double a2_;
  bool may_dip_;
};

TEST(Events, ADipInsideOneStepIsFoundWhenTheEventMayDip) {
  for (IntegratorKind kind :
       {IntegratorKind::dopri5, IntegratorKind::dop853, IntegratorKind::cvode_adams, IntegratorKind::cvode_bdf}) {
    const auto dip_run = [&](Dip& dip) {
      Uniform uniform;
      IntegratorOptions options;
      options.kind = kind;
      const double y0[1] = {0.0};
      const std::vector<double> times = {0.0, 10.0};
      const IntegrationResult result =
          integrate(uniform, options, 0.0, y0, times, [](double, const double*) { return Status::ok; }, &dip);
      EXPECT_EQ(result.status, Status::ok) << result.message;
      return result.stats.steps;
    };
    const std::string name(integrator_name(kind));
    Dip unseen(CrossingDirection::falling, 0.01, false);
    const long steps = dip_run(unseen);
    EXPECT_TRUE(unseen.hits.empty()) << name << ": the steps are too long to see it without may_dip";
    EXPECT_LT(steps, 20) << name;
    Dip falling(CrossingDirection::falling, 0.01, true);
    dip_run(falling);
    ASSERT_EQ(falling.hits.size(), 1u) << name;
    EXPECT_NEAR(falling.hits[0], 4.9, 1e-12) << name;
    Dip both(CrossingDirection::both, 0.01, true);
    dip_run(both);
    ASSERT_EQ(both.hits.size(), 2u) << name;
    EXPECT_NEAR(both.hits[0], 4.9, 1e-12) << name;
    EXPECT_NEAR(both.hits[1], 5.1, 1e-12) << name;
    // A near miss (the minimum 1e-4 above zero) is no crossing.
    Dip miss(CrossingDirection::both, -1e-4, true);
    dip_run(miss);
    EXPECT_TRUE(miss.hits.empty()) << name << ": " << miss.hits.front();
  }
}

TEST(Events, Rk4IsRefused) {
  Events events(CrossingDirection::both);
  try {
    run(IntegratorKind::rk4, events, 1.0, 1e-8);
    FAIL() << "rk4 accepted events";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("dopri5"), std::string::npos) << e.what();
  }
}

TEST(Events, BrentFindsRootsToTheResolutionOfDoubles) {
  double root = 0.0;
  const auto f = [](double x, double& fx) {
    fx = std::cos(x) - x;  // the Dottie number
    return Status::ok;
  };
  double fa = 0.0, fb = 0.0;
  f(0.0, fa);
  f(1.0, fb);
  ASSERT_EQ(find_root(f, 0.0, fa, 1.0, fb, root), Status::ok);
  EXPECT_NEAR(root, 0.7390851332151607, 2e-16);
  double fr = 0.0;
  f(root, fr);
  EXPECT_LE(fr, 0.0);  // on b's side: f(1) < 0
}

}  // namespace
}  // namespace nhdyn
