#include "nhdyn/analysis/exact_solution.hpp"

#include <fmt/format.h>

#include <cmath>
#include <string>
#include <vector>

#include "nhdyn/core/error.hpp"
#include "nhdyn/formulation/formulation.hpp"
#include "nhdyn/model/data.hpp"

namespace nhdyn {

void check_solution(const Model& model) {
  if (!model.evaluator->has_solution())
    throw InputError(fmt::format("model '{}' gives no analytic solution, so --reference analytic cannot be used; "
                                 "give its exact motion in a [solution] table of the model file "
                                 "(docs/model-format.md), or use --reference tight (a run at rtol 1e-13)",
                                 model.name));
  const int n = model.n();
  Data data = make_data(model);
  std::vector<double> qva(static_cast<std::size_t>(3 * n));
  model.evaluator->solution(model.t0, data.scratch.data(), qva.data());
  const auto name = [&](int order, int i) {
    return model.coordinates[static_cast<std::size_t>(i)] + std::string(static_cast<std::size_t>(order), '\'');
  };
  for (int order = 0; order < 3; ++order)
    for (int i = 0; i < n; ++i)
      if (!std::isfinite(qva[static_cast<std::size_t>(order * n + i)]))
        throw ModelError(fmt::format("model '{}': its analytic solution gives {} = {} at t0 = {}; check [solution] "
                                     "for an expression that cannot be evaluated at these parameter values (a "
                                     "division by zero, the square root of a negative number)",
                                     model.name, name(order, i), qva[static_cast<std::size_t>(order * n + i)],
                                     model.t0));
  // A solution that does not start where the runs start is the motion of another initial state:
  // every error measured against it would be wrong.
  for (int order = 0; order < 2; ++order)
    for (int i = 0; i < n; ++i) {
      const double exact = qva[static_cast<std::size_t>(order * n + i)];
      const double initial = order == 0 ? model.q0[i] : model.v0[i];
      if (!(std::abs(exact - initial) <= 1e-9 * (1.0 + std::abs(initial))))
        throw ModelError(fmt::format(
            "model '{}': its analytic solution does not start at the initial state: at t0 = {} it gives {} = {:.17g}, "
            "the initial state has {} = {:.17g}; correct [solution] or [initial] (after --set, both must still agree)",
            model.name, model.t0, name(order, i), exact, name(order, i), initial));
    }
  // A closed form that starts right can still be wrong: its acceleration must be the equations'.
  if (compute_dynamics(model, data, FormulationOptions{}, model.t0, model.q0.data(), model.v0.data()) != Status::ok)
    throw ModelError(fmt::format("model '{}': the accelerations at the initial state cannot be computed, so its "
                                 "analytic solution cannot be checked",
                                 model.name));
  double scale = 1.0;
  for (int i = 0; i < n; ++i) scale = std::max(scale, std::abs(data.qdd(i)));
  for (int i = 0; i < n; ++i) {
    const double exact = qva[static_cast<std::size_t>(2 * n + i)];
    if (!(std::abs(exact - data.qdd(i)) <= 1e-8 * scale))
      throw ModelError(fmt::format("model '{}': its analytic solution does not solve the equations of motion: at t0 = "
                                   "{} it gives {} = {:.17g}, the equations give {:.17g}; correct [solution]",
                                   model.name, model.t0, name(2, i), exact, data.qdd(i)));
  }
}

}  // namespace nhdyn
