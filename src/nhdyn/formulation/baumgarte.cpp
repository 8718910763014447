#include "nhdyn/formulation/baumgarte.hpp"

#include <fmt/format.h>

#include <cmath>

#include "nhdyn/core/error.hpp"

namespace nhdyn {

void check_baumgarte_gains(const BaumgarteGains& gains) {
  for (const auto& [name, value] : {std::pair{"alpha", gains.alpha}, std::pair{"beta", gains.beta}})
    if (!std::isfinite(value) || value < 0.0)
      throw InputError(fmt::format("the Baumgarte gain {} = {} must be finite and non-negative (a rate in 1/s, "
                                   "e.g. 10; alpha = beta damps the position residual critically)",
                                   name, value));
}

void compute_baumgarte_terms(const Model& model, Data& data, const BaumgarteGains& gains) {
  const Evaluator& ev = *model.evaluator;
  if (data.phi.size() > 0) ev.position_residual(data.t, data.q.data(), data.scratch.data(), data.phi.data());
  if (data.f.size() > 0) ev.velocity_residual(data.t, data.q.data(), data.v.data(), data.scratch.data(), data.f.data());
  // phi holds the position constraints in order; f the position and velocity ones in order.
  Eigen::Index ip = 0, iv = 0;
  for (int i = 0; i < model.s(); ++i) {
    double term = 0.0;
    switch (model.constraints[static_cast<std::size_t>(i)].level) {
      case ConstraintLevel::position: term = 2.0 * gains.alpha * data.f(iv++) + gains.beta * gains.beta * data.phi(ip++); break;
      case ConstraintLevel::velocity: term = 2.0 * gains.alpha * data.f(iv++); break;
      case ConstraintLevel::acceleration: break;
    }
    data.stabilization(i) = term;
  }
}

}  // namespace nhdyn
