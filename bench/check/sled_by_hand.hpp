// The sled of examples/sled.toml integrated by hand in one process: its Do Sanh stacked system
// written out (A, Q + G, the blade's row b and b0, the analytic D; a fixed-size 3 x 3 LU, as
// bench/reference_bench.cpp's `stacked_matrix3d`) and two explicit Runge-Kutta pairs written for
// exactly this state of 6 doubles: Dormand-Prince 5(4) and Dormand-Prince 8(5,3) with Hairer's
// step-size control and error estimates (DOPRI5, DOP853), on the coefficients of nhdyn's tableaus
// (the methods' definitions; the loops around them are this file's). No output inside the run, no
// events, no checks: what a user who writes the sled's integration by hand would run. It is the
// yardstick of bench-check's `sled_dopri5_vs_hand_written` and `sled_dop853_vs_hand_written`, which
// time `simulate()` of the model file against it; both start with the same first step and take the
// same steps (the bench compares the step counts, to 1 %: a step whose error estimate is within
// round-off of 1 may go either way, and the final states before timing).
#pragma once

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>

#include "nhdyn/integrators/tableaus.hpp"

namespace nhdyn::bench {

using SledState = std::array<double, 6>;  // x, y, phi, x', y', phi'

// examples/sled.toml: m = 1, a = 0.5, rho = 0.7, alpha = pi/6, g = 9.81, potential of the centre
// of mass, the blade's constraint -sin(phi) x' + cos(phi) y' = 0.
struct SledByHand {
  double m = 1.0, a = 0.5, rho2 = 0.49, gs = 9.81 * std::sin(M_PI / 6);

  // [D A; b] q'' = [D (Q + G); -b0]; dy = (q', q'').
  [[gnu::noinline]] void rhs(const SledState& y, SledState& dy) const {
    const double s = std::sin(y[2]), c = std::cos(y[2]), w = y[5];
    const double ma = m * a;
    Eigen::Matrix3d A;
    A << m, 0.0, -ma * s, 0.0, m, ma * c, -ma * s, ma * c, m * rho2;
    const Eigen::Vector3d h(m * gs + ma * c * w * w, ma * s * w * w, -m * gs * a * s);
    Eigen::Matrix<double, 2, 3> D;
    D << c, s, 0.0, 0.0, 0.0, 1.0;
    Eigen::Matrix3d M;
    M.topRows<2>().noalias() = D * A;
    M.row(2) << -s, c, 0.0;
    Eigen::Vector3d r;
    r.head<2>().noalias() = D * h;
    r(2) = (c * y[3] + s * y[4]) * w;  // -b0
    const Eigen::Vector3d qdd = M.partialPivLu().solve(r);
    dy = {y[3], y[4], y[5], qdd(0), qdd(1), qdd(2)};
  }
};

struct ByHandRun {
  SledState y;
  long steps = 0, rejected = 0;
};

// Error of a step of Dormand-Prince 5(4): the RMS of h sum e_j k_j / (atol + rtol max(|y|, |y1|)).
template <class Tableau>
double by_hand_error(const std::array<SledState, Tableau::stages>& k, const SledState& y, const SledState& y1,
                     double h, double rtol, double atol) {
  double err = 0.0;
  if constexpr (Tableau::order == 5) {
    for (int i = 0; i < 6; ++i) {
      double e = 0.0;
      for (int j = 0; j < Tableau::stages; ++j) e += Tableau::e[j] * k[j][i];
      const double sk = atol + rtol * std::max(std::abs(y[i]), std::abs(y1[i]));
      err += (h * e / sk) * (h * e / sk);
    }
    return std::sqrt(err / 6);
  } else {  // DOP853: the 5th- and 3rd-order estimates together
    double err5 = 0.0, err3 = 0.0;
    for (int i = 0; i < 6; ++i) {
      double e5 = 0.0, e3 = 0.0;
      for (int j = 0; j + 1 < Tableau::stages; ++j) {
        e5 += Tableau::e5[j] * k[j][i];
        e3 += (Tableau::b[j] - Tableau::bhh[j]) * k[j][i];
      }
      const double sk = atol + rtol * std::max(std::abs(y[i]), std::abs(y1[i]));
      err5 += (e5 / sk) * (e5 / sk);
      err3 += (e3 / sk) * (e3 / sk);
    }
    double denominator = err5 + 0.01 * err3;
    if (denominator <= 0.0) denominator = 1.0;
    return std::abs(h) * err5 / std::sqrt(6 * denominator);
  }
}

// From y0 at t = 0 to t_end with the first step h0; Hairer's controller with the tableau's
// constants (dopri5: PI with beta 0.04; dop853: beta 0), the step after a rejection not larger.
template <class Tableau>
ByHandRun integrate_sled_by_hand(const SledByHand& sled, const SledState& y0, double t_end, double h0, double rtol,
                                 double atol) {
  std::array<SledState, Tableau::stages> k{};
  ByHandRun run{y0};
  SledState& y = run.y;
  SledState y1{}, ys{};
  sled.rhs(y, k[0]);
  double t = 0.0, h = h0, err_old = 1e-4;
  bool last_rejected = false;
  for (;;) {
    const bool last = t + 1.01 * h >= t_end;
    if (last) h = t_end - t;
    // Stages 2..s-1; the last row of a is b, so the last stage's state is y1.
    for (int s = 1; s < Tableau::stages; ++s) {
      SledState& target = s == Tableau::stages - 1 ? y1 : ys;
      target = y;
      for (int j = 0; j < s; ++j)
        if (Tableau::a[s][j] != 0.0)
          for (int i = 0; i < 6; ++i) target[i] += h * Tableau::a[s][j] * k[j][i];
      if (s < Tableau::stages - 1 || Tableau::order == 5) sled.rhs(target, k[s]);
    }
    const double err = by_hand_error<Tableau>(k, y, y1, h, rtol, atol);
    const double fac11 = std::pow(err, Tableau::exponent);
    if (err > 1.0) {
      ++run.rejected;
      last_rejected = true;
      h /= std::min(1.0 / Tableau::fac_min, fac11 / Tableau::safety);
      continue;
    }
    const double memory = Tableau::beta == 0.0 ? 1.0 : std::pow(err_old, Tableau::beta);
    const double fac = std::clamp(fac11 / memory / Tableau::safety,
                                  1.0 / Tableau::fac_max, 1.0 / Tableau::fac_min);
    double h_new = h / fac;
    err_old = std::max(err, 1e-4);
    if (last_rejected) h_new = std::min(h_new, h);
    last_rejected = false;
    ++run.steps;
    if constexpr (Tableau::order != 5) sled.rhs(y1, k[Tableau::stages - 1]);  // DOP853's FSAL stage
    y = y1;
    k[0] = k[Tableau::stages - 1];
    t = last ? t_end : t + h;
    if (last) break;
    h = std::min(h_new, t_end);
  }
  return run;
}

}  // namespace nhdyn::bench
