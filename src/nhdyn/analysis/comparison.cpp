#include "nhdyn/analysis/comparison.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>

#include "nhdyn/analysis/detail/contact_switches.hpp"
#include "nhdyn/analysis/exact_solution.hpp"
#include "nhdyn/core/error.hpp"

namespace nhdyn {
namespace {

double time_one_solve(const Model& model, const FormulationOptions& formulation, int samples) {
  if (samples <= 0) return std::numeric_limits<double>::quiet_NaN();
  DataOptions data_options;
  data_options.method = formulation.method;
  data_options.projection = false;
  Data data = make_data(model, data_options);
  // Contacts with modes: solved in the modes the run starts in (all rolling may be no motion at all,
  // when the contacts are never all held).
  choose_initial_contact_modes(model, data, formulation, model.t0, model.q0, model.v0);
  if (compute_dynamics(model, data, formulation, model.t0, model.q0.data(), model.v0.data()) != Status::ok)
    return std::numeric_limits<double>::quiet_NaN();
  // The best of three batches: a batch that another process interrupted says nothing of the solve.
  double best = std::numeric_limits<double>::infinity();
  for (int batch = 0; batch < 3; ++batch) {
    const auto start = std::chrono::steady_clock::now();
    for (int i = 0; i < samples; ++i)
      compute_dynamics(model, data, formulation, model.t0, model.q0.data(), model.v0.data());
    best = std::min(best, std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  }
  return best / samples * 1e9;
}

// Whether a row simulate() hands over at time t is the one of output time `target` (rows of events
// and contact switches come between the output times; a switch within round-off after an output
// time takes that time's row, contact_switches.hpp).
bool is_output_row(double t, double target) {
  return std::abs(t - target) <= 64.0 * std::numeric_limits<double>::epsilon() * std::max(1.0, std::abs(target));
}

}  // namespace

Comparison compare_formulations(const Model& model, const ComparisonOptions& options) {
  if (options.cases.empty()) throw InputError("compare needs at least one method and one integrator");
  check_simulation_options(model, options.run);
  Comparison out;
  out.times = make_output_times(model.t0, options.run.t_end, options.run.output_step);
  const std::size_t rows = out.times.size();
  const int n = model.n();

  std::vector<double> ref(rows * static_cast<std::size_t>(2 * n), 0.0);
  std::size_t row = 0;
  if (options.reference == Reference::analytic) {
    check_solution(model);
    Data data = make_data(model);
    std::vector<double> qva(static_cast<std::size_t>(3 * n));
    for (row = 0; row < rows; ++row) {
      model.evaluator->solution(out.times[row], data.scratch.data(), qva.data());
      for (int i = 0; i < 2 * n; ++i)
        if (!std::isfinite(qva[static_cast<std::size_t>(i)]))
          throw ModelError(fmt::format("model '{}': its analytic solution gives {}{} = {} at t = {}; it cannot be a "
                                       "reference there (shorten --t-end or check [solution])",
                                       model.name, model.coordinates[static_cast<std::size_t>(i % n)],
                                       i < n ? "" : "'", qva[static_cast<std::size_t>(i)], out.times[row]));
      std::copy(qva.begin(), qva.begin() + 2 * n, ref.begin() + static_cast<std::ptrdiff_t>(row * 2 * n));
    }
  } else {
    SimulationOptions tight = options.run;
    tight.formulation.method = Formulation::sanh;
    tight.integrator.kind = IntegratorKind::dopri5;
    tight.integrator.rtol = 1e-13;
    tight.integrator.atol = 1e-15;
    out.reference = simulate(model, tight, [&](const Data& data) {
      if (row >= rows || !is_output_row(data.t, out.times[row])) return;
      std::copy(data.q.data(), data.q.data() + n, ref.begin() + static_cast<std::ptrdiff_t>(row * 2 * n));
      std::copy(data.v.data(), data.v.data() + n, ref.begin() + static_cast<std::ptrdiff_t>(row * 2 * n + n));
      ++row;
    });
    if (out.reference.status != Status::ok)
      throw ModelError(fmt::format("model '{}': the reference run (sanh, dopri5, rtol 1e-13) failed at t = {:.6g}: {}",
                                   model.name, out.reference.t_reached, out.reference.message));
  }

  for (const ComparisonCase& c : options.cases) {
    SimulationOptions run = options.run;
    run.formulation.method = c.method;
    run.integrator.kind = c.integrator;
    ComparisonResult r;
    r.which = c;
    const double nan = std::numeric_limits<double>::quiet_NaN();
    r.error.assign(rows, nan);
    r.position_residual.assign(rows, nan);
    r.velocity_residual.assign(rows, nan);
    check_simulation_options(model, run);  // before the timing solve: a method the model refuses
    FormulationOptions formulation = run.formulation;
    formulation.baumgarte.enabled = run.stabilization == Stabilization::baumgarte;
    r.solve_ns = time_one_solve(model, formulation, options.cost_samples);
    row = 0;
    r.summary = simulate(model, run, [&](const Data& data) {
      if (row >= rows || !is_output_row(data.t, out.times[row])) return;
      const double* q_ref = ref.data() + row * 2 * n;
      double eq = 0.0, ev = 0.0;
      for (int i = 0; i < n; ++i) {
        eq = std::max(eq, std::abs(data.q(i) - q_ref[i]));
        ev = std::max(ev, std::abs(data.v(i) - q_ref[n + i]));
      }
      r.max_error_q = std::max(r.max_error_q, eq);
      r.max_error_v = std::max(r.max_error_v, ev);
      r.error[row] = std::max(eq, ev);
      r.position_residual[row] = max_abs(data.phi);
      r.velocity_residual[row] = max_abs(data.f);
      ++row;
    });
    out.results.push_back(std::move(r));
  }
  return out;
}

}  // namespace nhdyn
