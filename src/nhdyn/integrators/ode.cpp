#include "nhdyn/integrators/ode.hpp"

#include <array>
#include <cmath>

#include <fmt/format.h>

#include "nhdyn/core/error.hpp"
#include "nhdyn/integrators/events.hpp"
#include "nhdyn/integrators/detail/explicit_rk.hpp"
#include "nhdyn/integrators/sundials/cvode.hpp"

namespace nhdyn {
namespace {

bool is_adaptive(IntegratorKind kind) {
  const IntegratorInfo* info = find_value(kIntegrators, kind);
  return info && info->adaptive;
}

// Everything the integrators rely on without checking again: bad values here are the user's
// (a model file, a command line), so they throw rather than return a status.
void require_valid_input(const OdeSystem& system, const IntegratorOptions& options, double t0,
                         const double* y0, std::span<const double> output_times) {
  const int n = system.size();
  if (n < 1)
    throw InputError(fmt::format("the system to integrate has {} states; it needs at least 1", n));
  if (const int weighed = system.error_size(); weighed < 1 || weighed > n)
    throw InputError(fmt::format("the system to integrate weighs {} of its {} states in the error norm "
                                 "(error_size); it must weigh from 1 to all of them",
                                 weighed, n));
  if (!std::isfinite(t0)) throw InputError(fmt::format("initial time t0 = {} is not finite", t0));
  for (int i = 0; i < n; ++i)
    if (!std::isfinite(y0[i]))
      throw InputError(fmt::format("initial state y0[{}] = {} is not finite", i, y0[i]));

  if (is_adaptive(options.kind)) {
    if (!(options.rtol >= 0.0) || !std::isfinite(options.rtol))
      throw InputError(fmt::format("rtol = {} must be a finite number >= 0", options.rtol));
    if (!(options.atol > 0.0) || !std::isfinite(options.atol))
      throw InputError(fmt::format(
          "atol = {} must be a finite number > 0 (pure relative error control fails where a "
          "state crosses zero)",
          options.atol));
  }
  if (!(options.step >= 0.0) || !std::isfinite(options.step))
    throw InputError(fmt::format("step = {} must be a finite number >= 0 (0 = automatic)",
                                 options.step));
  if (!(options.max_step >= 0.0) || !std::isfinite(options.max_step))
    throw InputError(fmt::format("max_step = {} must be a finite number >= 0 (0 = unlimited)",
                                 options.max_step));
  if (options.max_steps < 1)
    throw InputError(fmt::format("max_steps = {} must be at least 1", options.max_steps));

  double previous = t0;
  for (std::size_t i = 0; i < output_times.size(); ++i) {
    const double t = output_times[i];
    if (!std::isfinite(t))
      throw InputError(fmt::format("output time {} (index {}) is not finite", t, i));
    if (i == 0 && t < t0)
      throw InputError(fmt::format(
          "output time {} (index 0) is before the initial time t0 = {}; output times must be >= t0",
          t, t0));
    if (i > 0 && !(t > previous))
      throw InputError(fmt::format(
          "output time {} (index {}) is not after the previous one, {}; output times must be "
          "strictly increasing",
          t, i, previous));
    previous = t;
  }
}

}  // namespace

std::string_view integrator_name(IntegratorKind kind) { return name_of(kIntegrators, kind); }

bool supports_events(IntegratorKind kind) {
  const IntegratorInfo* info = find_value(kIntegrators, kind);
  return info && info->events;
}

std::string adaptive_integrator_names(std::string_view last) {
  return list_names_if(kIntegrators, [](const IntegratorInfo& i) { return i.adaptive; }, ", ", last);
}

IntegratorKind parse_integrator(std::string_view name) {
  if (const IntegratorInfo* info = find_named(kIntegrators, name)) return info->value;
  throw InputError(fmt::format("unknown integrator '{}'; valid names are {}", name, list_names(kIntegrators)));
}

IntegrationResult integrate(OdeSystem& system, const IntegratorOptions& options, double t0,
                            const double* y0, std::span<const double> output_times,
                            const OutputFn& output, EventFunctions* events) {
  require_valid_input(system, options, t0, y0, output_times);
  if (events != nullptr && events->count() == 0) events = nullptr;
  if (events != nullptr && !supports_events(options.kind))
    throw InputError(fmt::format(
        "events need an integrator with a continuous extension or root finding; {} has neither: "
        "choose {}",
        integrator_name(options.kind),
        list_names_if(kIntegrators, [](const IntegratorInfo& i) { return i.events; }, ", ", " or ")));
  switch (options.kind) {
    case IntegratorKind::rk4:
      return integrate_rk4(system, options, t0, y0, output_times, output);
    case IntegratorKind::dopri5:
      return integrate_dopri5(system, options, t0, y0, output_times, output, events);
    case IntegratorKind::dop853:
      return integrate_dop853(system, options, t0, y0, output_times, output, events);
    case IntegratorKind::cvode_bdf:
    case IntegratorKind::cvode_adams:
      return integrate_cvode(system, options, t0, y0, output_times, output, events);
  }
  throw InputError(fmt::format("invalid integrator kind {}", static_cast<int>(options.kind)));
}

}  // namespace nhdyn
