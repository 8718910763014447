// The explicit Runge-Kutta integrators: one stepper (explicit_rk.cpp) driven by Butcher tableaus
// given here as data. rk4 is the classic fixed-step method whose steps land exactly on the
// output times; dopri5 is Dormand-Prince 5(4) with FSAL, Hairer's PI step-size control and the
// 4th-order continuous extension for output times inside a step (Hairer, Norsett, Wanner,
// "Solving Ordinary Differential Equations I", II.4-II.6, and their code DOPRI5). integrate()
// (ode.hpp) checks its input and dispatches here; call that rather than these entry points.
#pragma once

#include <array>
#include <span>

#include "nhdyn/integrators/ode.hpp"

namespace nhdyn {
namespace rk {

// A tableau is a struct of constexpr data: stages, order, fsal (the last stage is f at the new
// state, so it is the next step's first stage), c (nodes), a (stage weights, strictly lower
// triangular), b (weights of the solution). Adaptive tableaus add e = b - b_hat (weights of the
// error estimate) and the order of the embedded solution.

struct ClassicRk4 {
  static constexpr int stages = 4;
  static constexpr int order = 4;
  static constexpr bool fsal = false;
  static constexpr std::array<double, stages> c{{0.0, 0.5, 0.5, 1.0}};
  static constexpr std::array<std::array<double, stages>, stages> a{{
      {{0.0, 0.0, 0.0, 0.0}},
      {{0.5, 0.0, 0.0, 0.0}},
      {{0.0, 0.5, 0.0, 0.0}},
      {{0.0, 0.0, 1.0, 0.0}},
  }};
  static constexpr std::array<double, stages> b{{1.0 / 6.0, 1.0 / 3.0, 1.0 / 3.0, 1.0 / 6.0}};
};

// Dormand & Prince (1980), coefficients as in Hairer's DOPRI5.
struct DormandPrince54 {
  static constexpr int stages = 7;
  static constexpr int order = 5;
  static constexpr int embedded_order = 4;
  static constexpr bool fsal = true;
  static constexpr std::array<double, stages> c{{0.0, 0.2, 0.3, 0.8, 8.0 / 9.0, 1.0, 1.0}};
  static constexpr std::array<std::array<double, stages>, stages> a{{
      {{0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0}},
      {{0.2, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0}},
      {{3.0 / 40.0, 9.0 / 40.0, 0.0, 0.0, 0.0, 0.0, 0.0}},
      {{44.0 / 45.0, -56.0 / 15.0, 32.0 / 9.0, 0.0, 0.0, 0.0, 0.0}},
      {{19372.0 / 6561.0, -25360.0 / 2187.0, 64448.0 / 6561.0, -212.0 / 729.0, 0.0, 0.0, 0.0}},
      {{9017.0 / 3168.0, -355.0 / 33.0, 46732.0 / 5247.0, 49.0 / 176.0, -5103.0 / 18656.0, 0.0,
        0.0}},
      {{35.0 / 384.0, 0.0, 500.0 / 1113.0, 125.0 / 192.0, -2187.0 / 6784.0, 11.0 / 84.0, 0.0}},
  }};
  static constexpr std::array<double, stages> b{
      {35.0 / 384.0, 0.0, 500.0 / 1113.0, 125.0 / 192.0, -2187.0 / 6784.0, 11.0 / 84.0, 0.0}};
  static constexpr std::array<double, stages> e{{71.0 / 57600.0, 0.0, -71.0 / 16695.0,
                                                71.0 / 1920.0, -17253.0 / 339200.0, 22.0 / 525.0,
                                                -1.0 / 40.0}};
  // Continuous extension of order 4 (Hairer's CONTD5): a cubic Hermite interpolant through
  // (y0, f0) and (y1, f1) plus theta^2 (1 - theta)^2 times h sum d_i k_i.
  static constexpr std::array<double, stages> d{
      {-12715105075.0 / 11282082432.0, 0.0, 87487479700.0 / 32700410799.0,
       -10690763975.0 / 1880347072.0, 701980252875.0 / 199316789632.0,
       -1453857185.0 / 822651844.0, 69997945.0 / 29380423.0}};
};

}  // namespace rk

// Classic RK4 with fixed steps: h = options.step, or (mean spacing of the output times) / 10 when
// options.step is 0; each interval between consecutive output times (t0 included) is split into
// ceil(interval / h) equal steps, so outputs are step ends. 4 rhs evaluations per step.
IntegrationResult integrate_rk4(OdeSystem& system, const IntegratorOptions& options, double t0,
                                const double* y0, std::span<const double> output_times,
                                const OutputFn& output);

// Dormand-Prince 5(4), 6 rhs evaluations per step (FSAL), plus 1 after each step whose state
// after_step changed. Error test on the RMS norm of the error estimate weighted by
// atol + rtol max(|y0|, |y1|); outputs inside a step come from the continuous extension and never
// shorten a step; only the last step is shortened to end on the last output time, so the rhs is
// never evaluated beyond it.
IntegrationResult integrate_dopri5(OdeSystem& system, const IntegratorOptions& options, double t0,
                                   const double* y0, std::span<const double> output_times,
                                   const OutputFn& output);

}  // namespace nhdyn
