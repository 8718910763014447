#include "nhdyn/integrators/sundials/cvode.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <exception>
#include <limits>
#include <memory>
#include <string>
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

// Owners of SUNDIALS objects, so that every return and every exception frees them. Declared in
// the order they are created; destruction in reverse frees CVODE before the solver, matrix and
// vectors it uses, and the context last.
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

}  // namespace

IntegrationResult integrate_cvode(OdeSystem& system, const IntegratorOptions& options, double t0,
                                  const double* y0, std::span<const double> output_times,
                                  const OutputFn& output, EventFunctions* events) {
  const std::string_view method = integrator_name(options.kind);
  const int n = system.size();
  IntegrationResult result;
  result.t_reached = t0;
  if (output_times.empty()) return result;

  std::size_t next = 0;
  if (output_times.front() == t0) {
    if (output(t0, y0) == Status::stopped) {
      result.status = Status::stopped;
      return result;
    }
    ++next;
  }
  if (next == output_times.size()) return result;
  const double t_end = output_times.back();

  CallbackState state;
  state.system = &system;
  state.cvode_message.reserve(512);
  Counters totals;  // counters of the CVODE runs before the last re-initialization

  double t = t0;
  auto finish = [&](Status status, std::string message, void* cvode) {
    const Counters current = cvode ? read_counters(cvode) : Counters{};
    result.status = status;
    result.t_reached = t;
    result.stats.steps = totals.steps + current.steps;
    result.stats.rejected_steps = totals.rejected_steps + current.rejected_steps;
    result.stats.rhs_evaluations = totals.rhs_evaluations + current.rhs_evaluations;
    result.message = std::move(message);
    return result;
  };
  auto setup_failure = [&](std::string_view what) {
    return finish(Status::integrator_failure,
                  fmt::format("{}: setting up CVODE failed ({}) {}", method, what,
                              state.cvode_message),
                  nullptr);
  };

  SUNContext raw_context = nullptr;
  if (SUNContext_Create(nullptr, &raw_context) != 0) return setup_failure("SUNContext_Create");
  const ContextPtr context(raw_context);
  const VectorPtr y(N_VNew_Serial(n, context.get()));
  const VectorPtr y_dky(N_VNew_Serial(n, context.get()));
  if (!y || !y_dky) return setup_failure("N_VNew_Serial");
  double* y_data = N_VGetArrayPointer(y.get());
  std::copy(y0, y0 + n, y_data);
  const MatrixPtr jacobian(SUNDenseMatrix(n, n, context.get()));
  if (!jacobian) return setup_failure("SUNDenseMatrix");
  const LinearSolverPtr linear_solver(SUNLinSol_Dense(y.get(), jacobian.get(), context.get()));
  if (!linear_solver) return setup_failure("SUNLinSol_Dense");
  const int lmm = options.kind == IntegratorKind::cvode_adams ? CV_ADAMS : CV_BDF;
  const CvodePtr cvode(CVodeCreate(lmm, context.get()));
  if (!cvode) return setup_failure("CVodeCreate");
  void* mem = cvode.get();
  // The handler first, so that the messages of the calls below are kept rather than printed.
  if (CVodeSetErrHandlerFn(mem, cvode_error_handler, &state) != CV_SUCCESS)
    return setup_failure("CVodeSetErrHandlerFn");
  if (CVodeInit(mem, cvode_rhs, t0, y.get()) != CV_SUCCESS) return setup_failure("CVodeInit");
  if (CVodeSetUserData(mem, &state) != CV_SUCCESS) return setup_failure("CVodeSetUserData");
  if (CVodeSStolerances(mem, options.rtol, options.atol) != CV_SUCCESS)
    return setup_failure("CVodeSStolerances");
  // No Jacobian function: CVODE's difference quotients, counted in CVodeGetNumLinRhsEvals.
  if (CVodeSetLinearSolver(mem, linear_solver.get(), jacobian.get()) != CV_SUCCESS)
    return setup_failure("CVodeSetLinearSolver");
  if (options.max_step > 0.0 && CVodeSetMaxStep(mem, options.max_step) != CV_SUCCESS)
    return setup_failure("CVodeSetMaxStep");
  if (options.step > 0.0 && CVodeSetInitStep(mem, options.step) != CV_SUCCESS)
    return setup_failure("CVodeSetInitStep");
  if (CVodeSetStopTime(mem, t_end) != CV_SUCCESS) return setup_failure("CVodeSetStopTime");
  // Events: CVODE's own root finding on its interpolating polynomial (CVodeRootInit), which
  // returns at each root with the state there (CV_ROOT_RETURN) before the step's end.
  std::vector<int> directions, roots;
  std::vector<double> g_root, g_start, g_end;  // g at a root and at the ends of its step (is_jump)
  if (events != nullptr && events->count() > 0) {
    state.events = events;
    const int m = events->count();
    for (int i = 0; i < m; ++i) directions.push_back(static_cast<int>(events->direction(i)));
    roots.assign(static_cast<std::size_t>(m), 0);
    g_root.assign(static_cast<std::size_t>(m), 0.0);
    g_start.assign(static_cast<std::size_t>(m), 0.0);
    g_end.assign(static_cast<std::size_t>(m), 0.0);
    if (CVodeRootInit(mem, m, cvode_roots) != CV_SUCCESS) return setup_failure("CVodeRootInit");
    if (CVodeSetRootDirection(mem, directions.data()) != CV_SUCCESS) return setup_failure("CVodeSetRootDirection");
  }

  for (;;) {
    const Counters current = read_counters(mem);
    if (totals.steps + current.steps + totals.rejected_steps + current.rejected_steps >=
        options.max_steps)
      return finish(Status::too_many_steps,
                    fmt::format("{}: the budget of {} steps (accepted + rejected) was used up at "
                                "t = {}; raise max_steps or loosen the tolerances",
                                method, options.max_steps, t),
                    mem);

    // In CV_ONE_STEP mode tout only bounds the first step after (re)initialization.
    double t_new = t;
    const int flag = CVode(mem, t_end, y.get(), &t_new, CV_ONE_STEP);
    if (state.exception) std::rethrow_exception(state.exception);
    if (state.rhs_status != Status::ok)
      return finish(state.rhs_status,
                    fmt::format("{}: the right-hand side failed at t = {}: {}", method,
                                state.t_fail, describe(state.rhs_status)),
                    mem);
    double h_next = 0.0;
    CVodeGetCurrentStep(mem, &h_next);
    if (flag < 0) {
      const Status status = flag == CV_TOO_MUCH_WORK ? Status::too_many_steps
                            : below_floor(h_next, t) ? Status::step_size_underflow
                                                     : Status::integrator_failure;
      return finish(status,
                    fmt::format("{}: CVODE failed after t = {} ({}, h = {}): {}", method, t,
                                flag_name(flag), h_next, state.cvode_message),
                    mem);
    }

    if (flag == CV_ROOT_RETURN) {
      // t_new is a root inside the step and y the state there; the next call returns the step's
      // end (CV_ONE_STEP), where after_step acts.
      for (; next < output_times.size() && output_times[next] < t_new; ++next) {
        const double t_out = output_times[next];
        const int dky_flag = CVodeGetDky(mem, t_out, 0, y_dky.get());
        if (dky_flag != CV_SUCCESS)
          return finish(Status::integrator_failure,
                        fmt::format("{}: interpolation at output time {} failed ({}): {}", method,
                                    t_out, flag_name(dky_flag), state.cvode_message),
                        mem);
        if (output(t_out, N_VGetArrayPointer(y_dky.get())) == Status::stopped) {
          t = t_out;
          return finish(Status::stopped, {}, mem);
        }
      }
      CVodeGetRootInfo(mem, roots.data());
      const bool judged = evaluate_around_root(mem, *events, t_new, y_data, y_dky.get(), g_root, g_start, g_end);
      for (std::size_t i = 0; i < roots.size(); ++i) {
        if (roots[i] == 0) continue;
        if (judged && is_jump(g_root[i], g_start[i], g_end[i])) continue;
        const Status event_status = events->on_event(static_cast<int>(i), t_new, y_data);
        if (event_status == Status::ok) continue;
        t = t_new;
        if (event_status == Status::stopped) return finish(Status::stopped, {}, mem);
        return finish(event_status, fmt::format("{}: at the event at t = {}: {}", method, t, describe(event_status)), mem);
      }
      continue;
    }

    // Outputs inside the step come from CVODE's interpolating polynomial, valid until the
    // re-initialization below; after_step acts at the step end, so an output there sees the
    // state it leaves.
    for (; next < output_times.size() && output_times[next] < t_new; ++next) {
      const double t_out = output_times[next];
      const int dky_flag = CVodeGetDky(mem, t_out, 0, y_dky.get());
      if (dky_flag != CV_SUCCESS)
        return finish(Status::integrator_failure,
                      fmt::format("{}: interpolation at output time {} failed ({}): {}", method,
                                  t_out, flag_name(dky_flag), state.cvode_message),
                      mem);
      if (output(t_out, N_VGetArrayPointer(y_dky.get())) == Status::stopped) {
        t = t_out;
        return finish(Status::stopped, {}, mem);
      }
    }
    t = t_new;
    const StepEnd end = system.after_step(t, y_data);
    if (end.status != Status::ok)
      return finish(end.status, fmt::format("{}: after the step to t = {}: {}", method, t, describe(end.status)), mem);
    const bool changed = end.changed;
    if (next < output_times.size() && output_times[next] == t) {
      if (output(t, y_data) == Status::stopped) return finish(Status::stopped, {}, mem);
      ++next;
    }
    if (flag == CV_TSTOP_RETURN || next == output_times.size()) break;
    // CVODE itself only warns when t + h == t and can go on for thousands of steps that do not
    // advance t; stop where dopri5 would.
    if (below_floor(h_next, t))
      return finish(Status::step_size_underflow,
                    fmt::format("{}: step size underflow at t = {} (h = {}): the solution may be "
                                "singular there, or the tolerances too tight",
                                method, t, h_next),
                    mem);

    if (changed) {
      // Re-initialization resets CVODE's counters: bank them first.
      const Counters before = read_counters(mem);
      totals.steps += before.steps;
      totals.rejected_steps += before.rejected_steps;
      totals.rhs_evaluations += before.rhs_evaluations;
      if (CVodeReInit(mem, t, y.get()) != CV_SUCCESS || CVodeSetStopTime(mem, t_end) != CV_SUCCESS)
        return finish(Status::integrator_failure,
                      fmt::format("{}: re-initializing CVODE at t = {} after after_step changed "
                                  "the state failed: {}",
                                  method, t, state.cvode_message),
                      mem);
    }
  }
  return finish(Status::ok, {}, mem);
}

}  // namespace nhdyn
