// The double integrator of docs/derivations/optimal-programs.md (section 10.1) transcribed as that
// page states it and solved with IPOPT through its C++ interface (TNLP): a check that the Debian
// toolchain (coinor-libipopt-dev, Ipopt 3.11 with MUMPS) works, not part of the build.
//
//   g++ -std=c++20 -O2 -Wall -Wextra -Wpedantic -Werror -isystem /usr/include/coin -DHAVE_CSTDDEF
//       docs/derivations/checks/ipopt_double_integrator.cpp $(pkg-config --libs ipopt)
//       -o /tmp/ipopt_double_integrator
//   /tmp/ipopt_double_integrator
//
// (pkg-config --cflags ipopt gives -I/usr/include/coin -DHAVE_CSTDDEF; the headers of Ipopt 3.11
// warn under -Wextra (unused parameters), so they are included as system headers.)
//
// A mass m, m x'' = F, from rest at 0 to rest at d in the time T, minimizing the integral of F^2.
// Variables at every point p: z_p = (x, x', x'', F); the points are the N + 1 nodes (trapezoidal)
// or the nodes and the interval midpoints, node j at 2j (Hermite-Simpson). Constraints: the
// collocation defects (C1) or (C2), (C3), and the dynamics defect m x'' - F = 0 at every point
// (D = I, no constraints: (O4) with n = 1, s = 0). Boundary values are fixed through equal bounds.
// Expected optimum: trapezoidal J_N = 12 d^2/T^3 N^3/((N - 1)(N^2 + N - 3)); Hermite-Simpson exact,
// J = 12 d^2/T^3. The program solves both with IPOPT's exact Hessian and with its limited-memory
// quasi-Newton approximation and exits with status 1 if any objective misses its closed form by
// more than 1e-8 (relative).
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "IpIpoptApplication.hpp"
#include "IpSolveStatistics.hpp"
#include "IpTNLP.hpp"

namespace {

using Ipopt::Index;
using Ipopt::Number;

enum class Method { trapezoidal, hermite_simpson };

class DoubleIntegrator final : public Ipopt::TNLP {
 public:
  DoubleIntegrator(Method method, int intervals, double mass, double distance, double duration)
      : method_(method), N_(intervals), m_(mass), d_(distance), T_(duration) {
    P_ = method == Method::trapezoidal ? N_ + 1 : 2 * N_ + 1;
    h_ = T_ / N_;
    // quadrature weights of the objective at the points, (O8)
    weights_.assign(P_, 0.0);
    for (int j = 0; j < N_; ++j) {
      if (method_ == Method::trapezoidal) {
        weights_[j] += h_ / 2;
        weights_[j + 1] += h_ / 2;
      } else {
        weights_[2 * j] += h_ / 6;
        weights_[2 * j + 1] += 4 * h_ / 6;
        weights_[2 * j + 2] += h_ / 6;
      }
    }
    build_jacobian();
  }

  double objective() const { return objective_; }

  bool get_nlp_info(Index& n, Index& m, Index& nnz_jac_g, Index& nnz_h_lag, IndexStyleEnum& index_style) override {
    n = 4 * P_;
    m = rows_;
    nnz_jac_g = static_cast<Index>(jac_rows_.size());
    nnz_h_lag = P_;  // d2/dF2 at each point: the only second derivative
    index_style = C_STYLE;
    return true;
  }

  bool get_bounds_info(Index n, Number* x_l, Number* x_u, Index m, Number* g_l, Number* g_u) override {
    for (Index i = 0; i < n; ++i) {
      x_l[i] = -1e19;  // IPOPT's "no bound" (nlp_lower_bound_inf)
      x_u[i] = 1e19;
    }
    const int last = P_ - 1;
    fix(x_l, x_u, var(0, 0), 0.0);  // x(0) = 0
    fix(x_l, x_u, var(0, 1), 0.0);  // x'(0) = 0
    fix(x_l, x_u, var(last, 0), d_);
    fix(x_l, x_u, var(last, 1), 0.0);
    for (Index r = 0; r < m; ++r) g_l[r] = g_u[r] = 0.0;
    return true;
  }

  bool get_starting_point(Index n, bool init_x, Number* x, bool, Number*, Number*, Index, bool, Number*) override {
    if (!init_x) return false;
    // the straight line between the boundary states, accelerations and force zero
    for (Index i = 0; i < n; ++i) x[i] = 0.0;
    for (int p = 0; p < P_; ++p) x[var(p, 0)] = d_ * p / (P_ - 1);
    return true;
  }

  bool eval_f(Index, const Number* x, bool, Number& f) override {
    f = 0.0;
    for (int p = 0; p < P_; ++p) f += weights_[p] * x[var(p, 3)] * x[var(p, 3)];
    return true;
  }

  bool eval_grad_f(Index n, const Number* x, bool, Number* grad) override {
    for (Index i = 0; i < n; ++i) grad[i] = 0.0;
    for (int p = 0; p < P_; ++p) grad[var(p, 3)] = 2 * weights_[p] * x[var(p, 3)];
    return true;
  }

  bool eval_g(Index, const Number* x, bool, Index m, Number* g) override {
    for (Index r = 0; r < m; ++r) g[r] = 0.0;
    // every constraint is linear: g = J x
    for (std::size_t e = 0; e < jac_rows_.size(); ++e) g[jac_rows_[e]] += jac_values_[e] * x[jac_cols_[e]];
    return true;
  }

  bool eval_jac_g(Index, const Number*, bool, Index, Index nele, Index* iRow, Index* jCol, Number* values) override {
    for (Index e = 0; e < nele; ++e) {
      if (values == nullptr) {
        iRow[e] = jac_rows_[e];
        jCol[e] = jac_cols_[e];
      } else {
        values[e] = jac_values_[e];
      }
    }
    return true;
  }

  bool eval_h(Index, const Number*, bool, Number obj_factor, Index, const Number*, bool, Index nele, Index* iRow,
              Index* jCol, Number* values) override {
    for (Index e = 0; e < nele; ++e) {
      if (values == nullptr) {
        iRow[e] = jCol[e] = var(e, 3);
      } else {
        values[e] = obj_factor * 2 * weights_[e];  // the constraints are linear
      }
    }
    return true;
  }

  void finalize_solution(Ipopt::SolverReturn, Index, const Number*, const Number*, const Number*, Index,
                         const Number*, const Number*, Number obj_value, const Ipopt::IpoptData*,
                         Ipopt::IpoptCalculatedQuantities*) override {
    objective_ = obj_value;
  }

 private:
  static Index var(int point, int component) { return 4 * point + component; }  // (x, x', x'', F)
  static void fix(Number* lo, Number* hi, Index i, double value) { lo[i] = hi[i] = value; }

  void add(int row, Index col, double value) {
    jac_rows_.push_back(row);
    jac_cols_.push_back(col);
    jac_values_.push_back(value);
  }

  void build_jacobian() {
    int row = 0;
    for (int j = 0; j < N_; ++j) {
      if (method_ == Method::trapezoidal) {
        const int a = j, b = j + 1;
        for (int c = 0; c < 2; ++c) {  // c = 0: q rows (with v); c = 1: v rows (with a)
          add(row, var(b, c), 1.0);
          add(row, var(a, c), -1.0);
          add(row, var(a, c + 1), -h_ / 2);
          add(row, var(b, c + 1), -h_ / 2);
          ++row;
        }
      } else {
        const int a = 2 * j, mid = 2 * j + 1, b = 2 * j + 2;
        for (int c = 0; c < 2; ++c) {  // Simpson (C2)
          add(row, var(b, c), 1.0);
          add(row, var(a, c), -1.0);
          add(row, var(a, c + 1), -h_ / 6);
          add(row, var(mid, c + 1), -4 * h_ / 6);
          add(row, var(b, c + 1), -h_ / 6);
          ++row;
        }
        for (int c = 0; c < 2; ++c) {  // Hermite interpolation (C3)
          add(row, var(mid, c), 1.0);
          add(row, var(a, c), -0.5);
          add(row, var(b, c), -0.5);
          add(row, var(a, c + 1), -h_ / 8);
          add(row, var(b, c + 1), h_ / 8);
          ++row;
        }
      }
    }
    for (int p = 0; p < P_; ++p) {  // dynamics (O4): m x'' - F = 0
      add(row, var(p, 2), m_);
      add(row, var(p, 3), -1.0);
      ++row;
    }
    rows_ = row;
  }

  Method method_;
  int N_ = 0, P_ = 0, rows_ = 0;
  double m_, d_, T_, h_;
  std::vector<double> weights_;
  std::vector<Index> jac_rows_, jac_cols_;
  std::vector<double> jac_values_;
  double objective_ = 0.0;
};

}  // namespace

int main() {
  const double m = 1.0, d = 1.0, T = 2.0;
  const double J = 12 * d * d / (T * T * T);
  int failures = 0;
  std::printf("%-16s %-14s %5s %6s %22s %22s %10s\n", "method", "hessian", "N", "iters", "objective",
              "closed form", "rel. error");
  for (const char* hessian : {"exact", "limited-memory"}) {
    for (Method method : {Method::trapezoidal, Method::hermite_simpson}) {
      for (int N : {4, 16, 64, 250}) {
        Ipopt::SmartPtr<DoubleIntegrator> nlp = new DoubleIntegrator(method, N, m, d, T);
        Ipopt::SmartPtr<Ipopt::IpoptApplication> app = IpoptApplicationFactory();
        app->Options()->SetIntegerValue("print_level", 0);
        app->Options()->SetStringValue("sb", "yes");  // no banner: a library does not print
        app->Options()->SetNumericValue("tol", 1e-12);
        app->Options()->SetStringValue("hessian_approximation", hessian);
        if (app->Initialize() != Ipopt::Solve_Succeeded) {
          std::printf("IPOPT failed to initialize\n");
          return 1;
        }
        const Ipopt::ApplicationReturnStatus status = app->OptimizeTNLP(Ipopt::GetRawPtr(nlp));
        const int iterations = Ipopt::IsValid(app->Statistics()) ? app->Statistics()->IterationCount() : -1;
        const double expected = method == Method::trapezoidal
                                    ? J * N * N * N / ((N - 1.0) * (1.0 * N * N + N - 3.0))
                                    : J;
        const double error = std::abs(nlp->objective() - expected) / expected;
        const bool ok = status == Ipopt::Solve_Succeeded && error < 1e-8;
        failures += ok ? 0 : 1;
        std::printf("%-16s %-14s %5d %6d %22.15f %22.15f %10.1e%s\n",
                    method == Method::trapezoidal ? "trapezoidal" : "hermite-simpson", hessian, N, iterations,
                    nlp->objective(), expected, error, ok ? "" : "  FAIL");
      }
    }
  }
  std::printf(failures ? "%d failed\n" : "all match their closed forms\n", failures);
  return failures ? 1 : 0;
}
