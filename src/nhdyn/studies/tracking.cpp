#include "nhdyn/studies/tracking.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "nhdyn/analysis/exact_solution.hpp"
#include "nhdyn/core/error.hpp"
#include "nhdyn/model/data.hpp"
#include "nhdyn/studies/run_times.hpp"

namespace nhdyn {
namespace {

void check_list(const std::vector<double>& values, const char* what, bool zero_allowed) {
  if (values.empty()) throw InputError(fmt::format("the tracking study needs at least one {}", what));
  for (std::size_t i = 0; i < values.size(); ++i) {
    const double x = values[i];
    if (!std::isfinite(x) || x < 0.0 || (x == 0.0 && !zero_allowed))
      throw InputError(fmt::format("{} {} is not a {} number; give {}s such as {}", what, x,
                                   zero_allowed ? "non-negative" : "positive", what,
                                   zero_allowed ? "0,1,10" : "1e-4,1e-8"));
    for (std::size_t j = 0; j < i; ++j)
      if (values[j] == x) throw InputError(fmt::format("{} {} is given twice; give each once", what, x));
  }
}

}  // namespace

Tracking study_tracking(const Model& model, const TrackingOptions& options) {
  if (model.m() == 0)
    throw InputError(fmt::format("model '{}' has no programs ([[programs]]), so there is nothing to track; the "
                                 "tracking study needs a model with programs (docs/derivations/program-motion.md)",
                                 model.name));
  check_list(options.tolerances, "tolerance", false);
  check_list(options.gains, "gain", true);
  if (!(options.atol_factor > 0.0 && std::isfinite(options.atol_factor)))
    throw InputError(fmt::format("the atol factor {} is not a positive number", options.atol_factor));
  if (options.integrator == IntegratorKind::rk4)
    throw InputError("rk4 takes a fixed step, so its runs do not depend on the tolerance: use " +
                     adaptive_integrator_names() + " for the tracking study");
  check_study_run_times(model, options.t_end, options.output_step);
  if (!model.evaluator->has_solution())
    throw InputError(fmt::format("model '{}' gives no exact solution, and the tracking study measures the error "
                                 "against it: give the programmed motion in a [solution] table of the model file "
                                 "(docs/model-format.md)",
                                 model.name));
  check_solution(model);  // a [solution] that does not start at [initial] or solve the equations

  Tracking out;
  out.gains = options.gains;
  out.tolerances = options.tolerances;
  out.runs.reserve(out.gains.size() * out.tolerances.size());
  const int n = model.n();
  // The exact solution is evaluated with the scratch of a Data of its own.
  Data exact = make_data(model);
  std::vector<double> qva(static_cast<std::size_t>(3 * n));
  for (const double gain : out.gains)
    for (const double tolerance : out.tolerances) {
      SimulationOptions run_options;
      run_options.t_end = options.t_end > 0.0 ? options.t_end : model.defaults.t_end;
      run_options.output_step = options.output_step > 0.0 ? options.output_step : model.defaults.output_step;
      run_options.integrator.kind = options.integrator;
      run_options.integrator.rtol = tolerance;
      run_options.integrator.atol = options.atol_factor * tolerance;
      if (gain > 0.0) run_options.formulation.program_feedback = {true, gain, gain};
      TrackingRun run;
      run.gain = gain;
      run.tolerance = tolerance;
      run.summary = simulate(model, run_options, [&](const Data& d) {
        model.evaluator->solution(d.t, exact.scratch.data(), qva.data());
        for (int i = 0; i < n; ++i) {
          run.max_error_q = std::max(run.max_error_q, std::abs(d.q(i) - qva[static_cast<std::size_t>(i)]));
          run.max_error_v = std::max(run.max_error_v, std::abs(d.v(i) - qva[static_cast<std::size_t>(n + i)]));
        }
        run.max_residual_pos = std::max(run.max_residual_pos, max_abs(d.motion.phi));
        run.max_residual_vel = std::max(run.max_residual_vel, max_abs(d.motion.f));
        run.max_residual_acc = std::max(run.max_residual_acc, max_abs(d.motion.e));
      });
      out.runs.push_back(std::move(run));
    }
  return out;
}

}  // namespace nhdyn
