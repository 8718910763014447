// Shared by the multibody tests: evaluate a spec's expressions at a state by name, and run the
// compiled model's kernels at a state.
#pragma once

#include <gtest/gtest.h>

#include <ginac/ginac.h>

#include <random>
#include <string>
#include <vector>

#include "nhdyn/formulation/formulation.hpp"
#include "nhdyn/model/data.hpp"
#include "nhdyn/model/terms.hpp"
#include "nhdyn/symbolic/spec.hpp"

namespace nhdyn::multibody_test {

// An expression of `spec` at (t, q, v, qdd), with the spec's parameter values.
inline double evaluate(const symbolic::Spec& spec, const GiNaC::ex& e, const std::vector<double>& q,
                       const std::vector<double>& v, const std::vector<double>& qdd = {}, double t = 0.0) {
  GiNaC::lst values = spec.parameter_values();
  values.append(spec.symbols.time() == t);
  for (int i = 0; i < spec.n(); ++i) {
    const auto k = static_cast<std::size_t>(i);
    values.append(spec.symbols.coordinate(i) == q[k]);
    values.append(spec.symbols.velocity(i) == v[k]);
    values.append(spec.symbols.acceleration(i) == (qdd.empty() ? 0.0 : qdd[k]));
  }
  const GiNaC::ex value = e.subs(values).evalf();
  EXPECT_TRUE(GiNaC::is_a<GiNaC::numeric>(value)) << value;
  return GiNaC::ex_to<GiNaC::numeric>(value).to_double();
}

// compute_dynamics (sanh, QR complement) at (0, q, v); the data keeps A, Q, G, b, b0, q'' and R.
inline Data dynamics_at(const Model& model, const std::vector<double>& q, const std::vector<double>& v) {
  Data data = make_data(model);
  const Status status = compute_dynamics(model, data, {Formulation::sanh, Complement::qr}, 0.0, q.data(), v.data());
  EXPECT_EQ(status, Status::ok);
  return data;
}

inline double uniform(std::mt19937& rng, double lo, double hi) {
  return std::uniform_real_distribution<double>(lo, hi)(rng);
}

}  // namespace nhdyn::multibody_test
