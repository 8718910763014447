#include "nhdyn/integrators/sundials/cvode.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <exception>
#include <limits>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

#include <cvode/cvode.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunmatrix/sunmatrix_dense.h>

#include <fmt/format.h>

#include "nhdyn/integrators/events.hpp"

namespace nhdyn {
namespace {

static_assert(std::is_same_v<realtype, double>, "nhdyn needs SUNDIALS built in double precision");

// Owners of SUNDIALS objects, so that every return and every exception frees them (CvodeObjects
// below holds them in the order of their destruction).
struct ContextFree {
  void operator()(SUNContext context) const { SUNContext_Free(&context); }
};
struct VectorFree {
  void operator()(N_Vector v) const { N_VDestroy(v); }
};
struct MatrixFree {
  void operator()(SUNMatrix m) const { SUNMatDestroy(m); }
};
struct LinearSolverFree {
  void operator()(SUNLinearSolver s) const { SUNLinSolFree(s); }
};
struct CvodeFree {
  void operator()(void* memory) const { CVodeFree(&memory); }
};
struct CharFree {
  void operator()(char* p) const { std::free(p); }
};
using ContextPtr = std::unique_ptr<std::remove_pointer_t<SUNContext>, ContextFree>;
using VectorPtr = std::unique_ptr<std::remove_pointer_t<N_Vector>, VectorFree>;
using MatrixPtr = std::unique_ptr<std::remove_pointer_t<SUNMatrix>, MatrixFree>;
using LinearSolverPtr = std::unique_ptr<std::remove_pointer_t<SUNLinearSolver>, LinearSolverFree>;
using CvodePtr = std::unique_ptr<void, CvodeFree>;

// What the C callbacks report back across CVODE.
struct CallbackState {
  OdeSystem* system = nullptr;
  EventFunctions* events = nullptr;
  Status rhs_status = Status::ok;
  double t_fail = 0.0;
  std::exception_ptr exception;
  std::string cvode_message;  // CVODE's last error message, instead of its printing to stderr
};

// A non-ok status is unrecoverable for CVODE (-1): the interface stops at the first one rather
// than letting CVODE retry with a smaller step. Exceptions must not unwind through C frames.
int cvode_rhs(realtype t, N_Vector y, N_Vector ydot, void* user_data) noexcept {
  CallbackState& state = *static_cast<CallbackState*>(user_data);
  try {
    const Status status = state.system->rhs(t, N_VGetArrayPointer(y), N_VGetArrayPointer(ydot));
    if (status == Status::ok) return 0;
    state.rhs_status = status;
    state.t_fail = t;
  } catch (...) {
    state.exception = std::current_exception();
  }
  return -1;
}

// The event functions for CVODE's root finding; a failure ends the run like a failed rhs.
int cvode_roots(realtype t, N_Vector y, realtype* g, void* user_data) noexcept {
  CallbackState& state = *static_cast<CallbackState*>(user_data);
  try {
    const Status status = state.events->evaluate(t, N_VGetArrayPointer(y), g);
    if (status == Status::ok) return 0;
    state.rhs_status = status;
    state.t_fail = t;
  } catch (...) {
    state.exception = std::current_exception();
  }
  return -1;
}

// The library never prints: keep CVODE's error message for the result, drop its warnings.
void cvode_error_handler(int error_code, const char* /*module*/, const char* /*function*/,
                         char* message, void* user_data) noexcept {
  if (error_code >= 0) return;
  try {
    static_cast<CallbackState*>(user_data)->cvode_message.assign(message);
  } catch (...) {
  }
}

struct Counters {
  long steps = 0;
  long rejected_steps = 0;
  long rhs_evaluations = 0;
};

Counters read_counters(void* cvode) {
  long steps = 0, error_test_fails = 0, solve_fails = 0, rhs = 0, rhs_jacobian = 0;
  CVodeGetNumSteps(cvode, &steps);
  CVodeGetNumErrTestFails(cvode, &error_test_fails);
  CVodeGetNumStepSolveFails(cvode, &solve_fails);
  CVodeGetNumRhsEvals(cvode, &rhs);
  CVodeGetNumLinRhsEvals(cvode, &rhs_jacobian);
  return {steps, error_test_fails + solve_fails, rhs + rhs_jacobian};
}

// The step size below which t + h no longer differs usefully from t.
bool below_floor(double h, double t) {
  return !(std::abs(h) >= 16.0 * std::numeric_limits<double>::epsilon() *
                              std::max(std::abs(t), std::numeric_limits<double>::min()));
}

std::string flag_name(int flag) {
  const std::unique_ptr<char, CharFree> name(CVodeGetReturnFlagName(flag));
  return name ? std::string(name.get()) : fmt::format("flag {}", flag);
}

// A sign change is a crossing only where g is continuous (events.hpp, is_jump): CVODE's root
// finding stops at a pole (1/x) or a wrap-around (atan2) too, where |g| stays as large as at the
// ends of the step. Writes g at the root t_new (state y_root) and at the ends of CVODE's last step
// [tn - h, tn] (its interpolant is valid over the whole step); a non-finite g (status non_finite:
// a pole) still has its values written. Returns false when another failure leaves the roots
// unjudged (they are then reported as CVODE found them). The root last, so that on_event follows it.
bool evaluate_around_root(void* mem, EventFunctions& events, double t_new, const double* y_root, N_Vector y_dky,
                          std::vector<double>& g_root, std::vector<double>& g_start, std::vector<double>& g_end) {
  double t_step_end = t_new, h_last = 0.0;
  CVodeGetCurrentTime(mem, &t_step_end);
  CVodeGetLastStep(mem, &h_last);
  const auto usable = [](Status status) { return status == Status::ok || status == Status::non_finite; };
  const auto at = [&](double t, std::vector<double>& g) {
    if (CVodeGetDky(mem, t, 0, y_dky) != CV_SUCCESS) return false;
    return usable(events.evaluate(t, N_VGetArrayPointer(y_dky), g.data()));
  };
  return at(t_step_end - h_last, g_start) && at(t_step_end, g_end) &&
         usable(events.evaluate(t_new, y_root, g_root.data()));
}

// The SUNDIALS objects of one run. Declared in the order they are created; destruction in
// reverse frees CVODE before the solver, matrix and vectors it uses, and the context last.
struct CvodeObjects {
  ContextPtr context;
  VectorPtr y;      // the state CVODE advances
  VectorPtr y_dky;  // a state interpolated by CVodeGetDky
  MatrixPtr jacobian;
  LinearSolverPtr linear_solver;
  CvodePtr cvode;
};

// The buffers of CVODE's root finding, sized once per run (empty without events).
struct RootBuffers {
  std::vector<int> directions, roots;
  std::vector<double> g_root, g_start, g_end;  // g at a root and at the ends of its step (is_jump)
};

// Creates CVODE for y' = f from (t0, y0) up to t_end with the options, its dense linear solver and,
// with events, its root finding. Returns the name of the call that failed, or nullptr.
const char* create_cvode(CvodeObjects& o, RootBuffers& r, CallbackState& state, const IntegratorOptions& options,
                         int n, double t0, const double* y0, double t_end, EventFunctions* events) {
  SUNContext raw_context = nullptr;
  if (SUNContext_Create(nullptr, &raw_context) != 0) return "SUNContext_Create";
  o.context.reset(raw_context);
  o.y.reset(N_VNew_Serial(n, o.context.get()));
  o.y_dky.reset(N_VNew_Serial(n, o.context.get()));
  if (!o.y || !o.y_dky) return "N_VNew_Serial";
  std::copy(y0, y0 + n, N_VGetArrayPointer(o.y.get()));
  o.jacobian.reset(SUNDenseMatrix(n, n, o.context.get()));
  if (!o.jacobian) return "SUNDenseMatrix";
  o.linear_solver.reset(SUNLinSol_Dense(o.y.get(), o.jacobian.get(), o.context.get()));
  if (!o.linear_solver) return "SUNLinSol_Dense";
  const int lmm = options.kind == IntegratorKind::cvode_adams ? CV_ADAMS : CV_BDF;
  o.cvode.reset(CVodeCreate(lmm, o.context.get()));
  if (!o.cvode) return "CVodeCreate";
  void* mem = o.cvode.get();
  // The handler first, so that the messages of the calls below are kept rather than printed.
  if (CVodeSetErrHandlerFn(mem, cvode_error_handler, &state) != CV_SUCCESS) return "CVodeSetErrHandlerFn";
  if (CVodeInit(mem, cvode_rhs, t0, o.y.get()) != CV_SUCCESS) return "CVodeInit";
  if (CVodeSetUserData(mem, &state) != CV_SUCCESS) return "CVodeSetUserData";
  if (CVodeSStolerances(mem, options.rtol, options.atol) != CV_SUCCESS) return "CVodeSStolerances";
  // No Jacobian function: CVODE's difference quotients, counted in CVodeGetNumLinRhsEvals.
  if (CVodeSetLinearSolver(mem, o.linear_solver.get(), o.jacobian.get()) != CV_SUCCESS)
    return "CVodeSetLinearSolver";
  if (options.max_step > 0.0 && CVodeSetMaxStep(mem, options.max_step) != CV_SUCCESS) return "CVodeSetMaxStep";
  if (options.step > 0.0 && CVodeSetInitStep(mem, options.step) != CV_SUCCESS) return "CVodeSetInitStep";
  if (CVodeSetStopTime(mem, t_end) != CV_SUCCESS) return "CVodeSetStopTime";
  // Events: CVODE's own root finding on its interpolating polynomial (CVodeRootInit), which
  // returns at each root with the state there (CV_ROOT_RETURN) before the step's end.
  if (events != nullptr && events->count() > 0) {
    state.events = events;
    const int m = events->count();
    for (int i = 0; i < m; ++i) r.directions.push_back(static_cast<int>(events->direction(i)));
    r.roots.assign(static_cast<std::size_t>(m), 0);
    r.g_root.assign(static_cast<std::size_t>(m), 0.0);
    r.g_start.assign(static_cast<std::size_t>(m), 0.0);
    r.g_end.assign(static_cast<std::size_t>(m), 0.0);
    if (CVodeRootInit(mem, m, cvode_roots) != CV_SUCCESS) return "CVodeRootInit";
    if (CVodeSetRootDirection(mem, r.directions.data()) != CV_SUCCESS) return "CVodeSetRootDirection";
  }
  return nullptr;
}

// One run of integrate_cvode: its options, its SUNDIALS objects and where it stands.
struct CvodeRun {
  std::string_view method;
  const IntegratorOptions& options;
  std::span<const double> output_times;
  const OutputFn& output;
  EventFunctions* events;
  CallbackState state;
  CvodeObjects objects;
  RootBuffers roots;
  Counters totals;  // counters of the CVODE runs before the last re-initialization
  IntegrationResult result;
  double t = 0.0;        // where the solution is known
  std::size_t next = 0;  // the first output time not yet written
  // Dips of the event functions that may dip (EventFunctions::may_dip): CVODE's root finding sees
  // only the sign changes between its steps' ends, this the minima inside them.
  std::optional<EventTracker> dips;
  std::vector<EventTracker::Crossing> crossings;
  double dips_t = 0.0;  // where the dips were last looked for up to

  // The run's result: its status, message and counters, reached at t.
  IntegrationResult finish(Status status, std::string message) {
    void* cvode = objects.cvode.get();
    const Counters current = cvode ? read_counters(cvode) : Counters{};
    result.status = status;
    result.t_reached = t;
    result.stats.steps = totals.steps + current.steps;
    result.stats.rejected_steps = totals.rejected_steps + current.rejected_steps;
    result.stats.rhs_evaluations = totals.rhs_evaluations + current.rhs_evaluations;
    result.message = std::move(message);
    return result;
  }
};

// The outputs before t_limit, from CVODE's interpolating polynomial (valid until a
// re-initialization). A failed interpolation or a stop ends the run (its result).
std::optional<IntegrationResult> write_outputs_before(CvodeRun& run, double t_limit) {
  void* mem = run.objects.cvode.get();
  for (; run.next < run.output_times.size() && run.output_times[run.next] < t_limit; ++run.next) {
    const double t_out = run.output_times[run.next];
    const int dky_flag = CVodeGetDky(mem, t_out, 0, run.objects.y_dky.get());
    if (dky_flag != CV_SUCCESS)
      return run.finish(Status::integrator_failure,
                        fmt::format("{}: interpolation at output time {} failed ({}): {}", run.method, t_out,
                                    flag_name(dky_flag), run.state.cvode_message));
    if (run.output(t_out, N_VGetArrayPointer(run.objects.y_dky.get())) == Status::stopped) {
      run.t = t_out;
      return run.finish(Status::stopped, {});
    }
  }
  return std::nullopt;
}

// CVODE returned at a root t_new inside its step, y the state there (the next call returns the
// step's end, CV_ONE_STEP, where after_step acts): the outputs before it, then each event whose
// g crossed zero there continuously (not a pole or a wrap-around, is_jump).
std::optional<IntegrationResult> handle_roots(CvodeRun& run, double t_new) {
  if (auto stop = write_outputs_before(run, t_new)) return stop;
  void* mem = run.objects.cvode.get();
  double* y_data = N_VGetArrayPointer(run.objects.y.get());
  RootBuffers& r = run.roots;
  CVodeGetRootInfo(mem, r.roots.data());
  const bool judged =
      evaluate_around_root(mem, *run.events, t_new, y_data, run.objects.y_dky.get(), r.g_root, r.g_start, r.g_end);
  for (std::size_t i = 0; i < r.roots.size(); ++i) {
    if (r.roots[i] == 0) continue;
    if (judged && is_jump(r.g_root[i], r.g_start[i], r.g_end[i])) continue;
    const Status event_status = run.events->on_event(static_cast<int>(i), t_new, y_data);
    if (event_status == Status::ok) continue;
    run.t = t_new;
    if (event_status == Status::stopped) return run.finish(Status::stopped, {});
    return run.finish(event_status,
                      fmt::format("{}: at the event at t = {}: {}", run.method, run.t, describe(event_status)));
  }
  return std::nullopt;
}

// Up to t_new (a step's end, or a root CVODE returned at inside it, y the state there): the dips
// of the event functions that may dip since they were last looked for, on CVODE's interpolating
// polynomial, before any root CVODE found (its root finding sees sign changes only, and takes any
// of the roots of a gap that dipped and came back before changing sign); each found is handled as
// a root (the outputs before it, then on_event with the state there).
std::optional<IntegrationResult> handle_dips(CvodeRun& run, double t_new) {
  if (!run.dips) return std::nullopt;
  void* mem = run.objects.cvode.get();
  bool dipped = false;
  Status status = run.dips->check_dips(t_new, N_VGetArrayPointer(run.objects.y.get()), dipped);
  if (status == Status::ok && dipped && t_new > run.dips_t) {
    const double t = run.dips_t, h = t_new - run.dips_t;
    N_Vector y_dky = run.objects.y_dky.get();
    bool interpolated = true;
    status = run.dips->locate(
        t, h,
        [&](double theta, double* out) {
          interpolated = interpolated && CVodeGetDky(mem, theta >= 1.0 ? t_new : t + theta * h, 0, y_dky) == CV_SUCCESS;
          std::copy(N_VGetArrayPointer(y_dky), N_VGetArrayPointer(y_dky) + N_VGetLength(y_dky), out);
        },
        run.crossings);
    if (!interpolated)
      return run.finish(Status::integrator_failure, fmt::format("{}: interpolation inside the step from t = {} failed: {}",
                                                                run.method, t, run.state.cvode_message));
    for (const EventTracker::Crossing& crossing : run.crossings) {
      if (auto stop = write_outputs_before(run, crossing.t)) return stop;
      if (CVodeGetDky(mem, crossing.t, 0, y_dky) != CV_SUCCESS)
        return run.finish(Status::integrator_failure, fmt::format("{}: interpolation at t = {} failed: {}", run.method,
                                                                  crossing.t, run.state.cvode_message));
      const Status event_status = run.events->on_event(crossing.index, crossing.t, N_VGetArrayPointer(y_dky));
      if (event_status == Status::ok) continue;
      run.t = crossing.t;
      if (event_status == Status::stopped) return run.finish(Status::stopped, {});
      return run.finish(event_status, fmt::format("{}: at the event at t = {}: {}", run.method, run.t,
                                                  describe(event_status)));
    }
  }
  if (status != Status::ok)
    return run.finish(status, fmt::format("{}: the event functions failed at t = {}: {}", run.method, t_new,
                                          describe(status)));
  run.dips->advance();
  run.dips_t = t_new;
  return std::nullopt;
}

// After after_step changed the state: CVODE starts again from it (its counters banked first,
// since re-initialization resets them).
std::optional<IntegrationResult> restart(CvodeRun& run, double t_end) {
  void* mem = run.objects.cvode.get();
  const Counters before = read_counters(mem);
  run.totals.steps += before.steps;
  run.totals.rejected_steps += before.rejected_steps;
  run.totals.rhs_evaluations += before.rhs_evaluations;
  if (CVodeReInit(mem, run.t, run.objects.y.get()) != CV_SUCCESS || CVodeSetStopTime(mem, t_end) != CV_SUCCESS)
    return run.finish(Status::integrator_failure,
                      fmt::format("{}: re-initializing CVODE at t = {} after after_step changed "
                                  "the state failed: {}",
                                  run.method, run.t, run.state.cvode_message));
  return std::nullopt;
}

}  // namespace

IntegrationResult integrate_cvode(OdeSystem& system, const IntegratorOptions& options, double t0,
                                  const double* y0, std::span<const double> output_times,
                                  const OutputFn& output, EventFunctions* events) {
  const std::string_view method = integrator_name(options.kind);
  const int n = system.size();
  CvodeRun run{method, options, output_times, output, events, {}, {}, {}, {}, {}, t0, 0, {}, {}};
  run.result.t_reached = t0;
  if (output_times.empty()) return run.result;

  if (output_times.front() == t0) {
    if (output(t0, y0) == Status::stopped) {
      run.result.status = Status::stopped;
      return run.result;
    }
    ++run.next;
  }
  if (run.next == output_times.size()) return run.result;
  const double t_end = output_times.back();

  run.state.system = &system;
  run.state.cvode_message.reserve(512);
  if (const char* what = create_cvode(run.objects, run.roots, run.state, options, n, t0, y0, t_end, events)) {
    // A failed setup reports no counters: CVODE may be half made.
    IntegrationResult& result = run.result;
    result.status = Status::integrator_failure;
    result.t_reached = run.t;
    result.message = fmt::format("{}: setting up CVODE failed ({}) {}", method, what, run.state.cvode_message);
    return result;
  }
  void* mem = run.objects.cvode.get();
  double* y_data = N_VGetArrayPointer(run.objects.y.get());
  if (events != nullptr && events->count() > 0) {
    run.dips.emplace(*events, n, options.rtol, options.atol);
    if (!run.dips->any_may_dip()) {
      run.dips.reset();
    } else if (const Status status = run.dips->restart(t0, y0); status != Status::ok) {
      return run.finish(status, fmt::format("{}: the event functions failed at t = {}: {}", method, t0, describe(status)));
    }
    run.dips_t = t0;
  }

  for (;;) {
    const Counters current = read_counters(mem);
    if (run.totals.steps + current.steps + run.totals.rejected_steps + current.rejected_steps >= options.max_steps)
      return run.finish(Status::too_many_steps,
                        fmt::format("{}: the budget of {} steps (accepted + rejected) was used up at "
                                    "t = {}; raise max_steps or loosen the tolerances",
                                    method, options.max_steps, run.t));

    // In CV_ONE_STEP mode tout only bounds the first step after (re)initialization.
    double t_new = run.t;
    const int flag = CVode(mem, t_end, run.objects.y.get(), &t_new, CV_ONE_STEP);
    if (run.state.exception) std::rethrow_exception(run.state.exception);
    if (run.state.rhs_status != Status::ok)
      return run.finish(run.state.rhs_status, fmt::format("{}: the right-hand side failed at t = {}: {}", method,
                                                          run.state.t_fail, describe(run.state.rhs_status)));
    double h_next = 0.0;
    CVodeGetCurrentStep(mem, &h_next);
    if (flag < 0) {
      const Status status = flag == CV_TOO_MUCH_WORK ? Status::too_many_steps
                            : below_floor(h_next, run.t) ? Status::step_size_underflow
                                                         : Status::integrator_failure;
      return run.finish(status, fmt::format("{}: CVODE failed after t = {} ({}, h = {}): {}", method, run.t,
                                            flag_name(flag), h_next, run.state.cvode_message));
    }

    if (flag == CV_ROOT_RETURN) {
      if (auto stop = handle_dips(run, t_new)) return *std::move(stop);
      if (auto stop = handle_roots(run, t_new)) return *std::move(stop);
      continue;
    }

    // Outputs inside the step come from CVODE's interpolating polynomial, valid until the
    // re-initialization below; after_step acts at the step end, so an output there sees the
    // state it leaves.
    if (auto stop = handle_dips(run, t_new)) return *std::move(stop);
    if (auto stop = write_outputs_before(run, t_new)) return *std::move(stop);
    run.t = t_new;
    const StepEnd end = system.after_step(run.t, y_data);
    if (end.status != Status::ok)
      return run.finish(end.status,
                        fmt::format("{}: after the step to t = {}: {}", method, run.t, describe(end.status)));
    if (run.next < output_times.size() && output_times[run.next] == run.t) {
      if (output(run.t, y_data) == Status::stopped) return run.finish(Status::stopped, {});
      ++run.next;
    }
    if (flag == CV_TSTOP_RETURN || run.next == output_times.size()) break;
    // CVODE itself only warns when t + h == t and can go on for thousands of steps that do not
    // advance t; stop where dopri5 would.
    if (below_floor(h_next, run.t))
      return run.finish(Status::step_size_underflow,
                        fmt::format("{}: step size underflow at t = {} (h = {}): the solution may be "
                                    "singular there, or the tolerances too tight",
                                    method, run.t, h_next));
    if (end.changed) {
      if (auto failure = restart(run, t_end)) return *std::move(failure);
      if (run.dips && run.dips->restart(run.t, y_data) != Status::ok)
        return run.finish(Status::integrator_failure,
                          fmt::format("{}: the event functions failed at t = {}", method, run.t));
      run.dips_t = run.t;
    }
  }
  return run.finish(Status::ok, {});
}

}  // namespace nhdyn
