// Consistency checks of the N-trailer chain built in C++ (symbolic/chain.hpp, docs/gallery/chain.md):
// the counts and the sparsity of the constraints, the initial state on the constraints with the
// energy T0 of the page, T conserved and the residuals held along a run (N = 3 and 10), the exact
// uniform straight motion of an aligned chain (N = 2), and bad parameters refused. The comparison
// with the Chaplygin sleigh's file (N = 1) and the model file's round trip are in
// tests/gallery/chain_test.cpp, which may read model files.
#include "nhdyn/symbolic/chain.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <limits>
#include <string>

#include "nhdyn/analysis/residuals.hpp"
#include "nhdyn/analysis/simulation.hpp"
#include "nhdyn/core/error.hpp"
#include "nhdyn/formulation/formulation.hpp"
#include "nhdyn/symbolic/compile.hpp"

namespace nhdyn::symbolic {
namespace {

// T0 = N m v0^2/2 + (J + m a^2) w0^2/2 sum_{i<N} (r/f)^(2i), docs/gallery/chain.md.
double initial_energy(const ChainParameters& p) {
  double sum = 0.0;
  for (int i = 0; i < p.bodies; ++i) sum += std::pow(p.rear_hitch / p.front_hitch, 2 * i);
  return p.bodies * p.mass * p.speed * p.speed / 2 +
         (p.inertia + p.mass * p.com_offset * p.com_offset) * p.turn_rate * p.turn_rate / 2 * sum;
}

SimulationOptions tight(double t_end) {
  SimulationOptions o;
  o.t_end = t_end;
  o.output_step = 0.05;
  o.formulation = {Formulation::sanh, Complement::qr};
  o.integrator.kind = IntegratorKind::dopri5;
  o.integrator.rtol = 1e-10;
  o.integrator.atol = 1e-12;
  return o;
}

TEST(Chain, CountsAndSparsity) {
  ChainParameters p;
  p.bodies = 4;
  const Spec spec = make_chain_spec(p);
  EXPECT_EQ(spec.n(), 12);
  EXPECT_EQ(spec.s(), 10);  // 3N - 2: k = 2
  for (const SpecConstraint& c : spec.constraints) {
    int touched = 0;
    int first = -1, last = -1;
    for (int i = 0; i < spec.n(); ++i)
      if (c.expression.has(spec.symbols.coordinate(i)) || c.expression.has(spec.symbols.velocity(i))) {
        ++touched;
        if (first < 0) first = i;
        last = i;
      }
    EXPECT_LE(touched, 6) << c.name;
    EXPECT_LT(last / 3 - first / 3, 2) << c.name << ": touches bodies that are not neighbours";
  }
  EXPECT_EQ(spec.constraints[0].name, "blade1");
  EXPECT_EQ(spec.constraints[1].name, "pin1_x");
  EXPECT_EQ(spec.constraints[1].level, ConstraintLevel::position);
}

TEST(Chain, InitialStateIsOnTheConstraintsWithTheEnergyOfThePage) {
  for (int bodies : {1, 3, 10}) {
    ChainParameters p;
    p.bodies = bodies;
    const Model model = compile_model(make_chain_spec(p));
    Data data = make_data(model);
    const FormulationOptions options{Formulation::sanh, Complement::qr};
    ASSERT_EQ(compute_dynamics(model, data, options, 0.0, model.q0.data(), model.v0.data()), Status::ok);
    compute_residuals(model, data);
    compute_energy(model, data);
    EXPECT_LT(data.phi.size() ? data.phi.cwiseAbs().maxCoeff() : 0.0, 1e-14) << bodies;
    EXPECT_LT(data.f.cwiseAbs().maxCoeff(), 1e-14) << bodies;
    EXPECT_NEAR(data.energy / initial_energy(p), 1.0, 1e-14) << bodies;
    const double last = p.turn_rate * std::pow(-p.rear_hitch / p.front_hitch, bodies - 1);
    EXPECT_NEAR(model.v0(3 * bodies - 1) / last, 1.0, 1e-14) << bodies;
  }
}

// Past body 65 the turning rate w0 (-r/f)^(i-1) is written with exp and log (the expression
// reader refuses exponents beyond 64); checked on the Spec, without the cost of a derivation.
TEST(Chain, TurningRatesPastTheExponentLimit) {
  ChainParameters p;
  p.bodies = 67;
  const Spec spec = make_chain_spec(p);
  for (int i : {64, 65, 66, 67}) {
    const GiNaC::ex value = GiNaC::evalf(spec.v0[static_cast<std::size_t>(3 * i - 1)].subs(spec.parameter_values()));
    ASSERT_TRUE(GiNaC::is_a<GiNaC::numeric>(value)) << i;
    const double exact = p.turn_rate * std::pow(-p.rear_hitch / p.front_hitch, i - 1);
    EXPECT_NEAR(GiNaC::ex_to<GiNaC::numeric>(value).to_double() / exact, 1.0, 1e-13) << i;
  }
}

TEST(Chain, ConservesEnergyAndHoldsTheConstraints) {
  for (int bodies : {3, 10}) {
    ChainParameters p;
    p.bodies = bodies;
    p.turn_rate = 1.5;
    const Model model = compile_model(make_chain_spec(p));
    const SimulationSummary s = simulate(model, tight(5.0), [](const Data&) {});
    ASSERT_EQ(s.status, Status::ok) << s.message;
    const double T0 = initial_energy(p);
    EXPECT_LT(s.energy.drift / T0, 1e-8) << bodies;
    EXPECT_LT(s.residuals.position, 1e-8) << bodies;
    EXPECT_LT(s.residuals.velocity, 1e-8) << bodies;
    EXPECT_LT(s.residuals.acceleration, 1e-10) << bodies;
    std::printf("chain N = %d: energy drift %.2e relative, residuals pos %.2e vel %.2e acc %.2e\n", bodies,
                s.energy.drift / T0, s.residuals.position, s.residuals.velocity, s.residuals.acceleration);
  }
}

TEST(Chain, AlignedChainMovesStraightAndUniformly) {
  ChainParameters p;
  p.bodies = 2;
  p.turn_rate = 0.0;
  p.speed = 1.3;
  const Model model = compile_model(make_chain_spec(p));
  double worst = 0.0;
  const SimulationSummary s = simulate(model, tight(4.0), [&](const Data& d) {
    for (int i = 0; i < 6; ++i) {
      const double exact = model.q0(i) + (i % 3 == 0 ? p.speed * d.t : 0.0);
      worst = std::max({worst, std::abs(d.q(i) - exact), std::abs(d.v(i) - model.v0(i)), std::abs(d.qdd(i)),
                        std::abs(d.R(i))});
    }
  });
  ASSERT_EQ(s.status, Status::ok) << s.message;
  EXPECT_LT(worst, 1e-12);
}

void expect_refused(const ChainParameters& p, const std::string& value, const std::string& limit) {
  try {
    (void)make_chain_spec(p);
    ADD_FAILURE() << "accepted " << value;
  } catch (const InputError& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find(value), std::string::npos) << message;
    EXPECT_NE(message.find(limit), std::string::npos) << message;
  }
  EXPECT_THROW((void)write_chain_toml(p), InputError);
}

TEST(Chain, RefusesBadParameters) {
  const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
  ChainParameters p;
  p.bodies = 0;
  expect_refused(p, "bodies = 0", "from 1 to 10000");
  p.bodies = -3;
  expect_refused(p, "bodies = -3", "from 1 to 10000");
  p.bodies = kMaxChainBodies + 1;
  expect_refused(p, "bodies = 10001", "from 1 to 10000");
  const auto with = [](auto change) {
    ChainParameters q;
    change(q);
    return q;
  };
  expect_refused(with([](ChainParameters& q) { q.mass = 0.0; }), "mass m = 0", "positive finite");
  expect_refused(with([&](ChainParameters& q) { q.inertia = nan; }), "inertia J = nan", "positive finite");
  expect_refused(with([](ChainParameters& q) { q.front_hitch = -1.0; }), "front hitch f = -1", "positive finite");
  expect_refused(with([&](ChainParameters& q) { q.rear_hitch = inf; }), "rear hitch r = inf", "positive finite");
  expect_refused(with([](ChainParameters& q) { q.com_offset = -0.1; }), "offset a = -0.1", ">= 0");
  expect_refused(with([&](ChainParameters& q) { q.speed = nan; }), "speed v0 = nan", "finite");
  expect_refused(with([](ChainParameters& q) {
                   q.bodies = 1000;
                   q.rear_hitch = 2.0;
                   q.front_hitch = 0.1;
                 }),
                 "last body", "below 1e100");
}

}  // namespace
}  // namespace nhdyn::symbolic
