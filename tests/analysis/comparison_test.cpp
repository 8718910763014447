// compare_formulations: every case is measured against the tight reference, and the errors it
// reports behave as the integrators' orders say they must.
#include <gtest/gtest.h>

#include <cmath>

#include "nhdyn/analysis/comparison.hpp"
#include "nhdyn/model/sled.hpp"

namespace nhdyn {
namespace {

Comparison run(IntegratorKind kind, double rtol, double step) {
  const Model model = make_sled_model();
  ComparisonOptions options;
  options.run.t_end = 2.0;
  options.run.output_step = 0.1;
  options.run.integrator.rtol = rtol;
  options.run.integrator.atol = rtol * 1e-2;
  options.run.integrator.step = step;
  options.cost_samples = 10;
  options.cases = {{Formulation::sanh, kind}, {Formulation::lagrange, kind}};
  return compare_formulations(model, options);
}

TEST(Comparison, Rk4ErrorFallsWithTheFourthPowerOfTheStep) {
  const Comparison coarse = run(IntegratorKind::rk4, 1e-8, 0.02);
  const Comparison fine = run(IntegratorKind::rk4, 1e-8, 0.01);
  for (std::size_t i = 0; i < coarse.results.size(); ++i) {
    ASSERT_EQ(coarse.results[i].summary.status, Status::ok);
    ASSERT_EQ(fine.results[i].summary.status, Status::ok);
    const double ratio = coarse.results[i].max_error_q / fine.results[i].max_error_q;
    EXPECT_GT(ratio, 12.0) << "order 4 halves the error 16 times";
    EXPECT_LT(ratio, 20.0);
  }
}

TEST(Comparison, Dopri5ErrorShrinksWithTheTolerance) {
  double previous = INFINITY;
  for (double rtol : {1e-4, 1e-6, 1e-8, 1e-10}) {
    const Comparison c = run(IntegratorKind::dopri5, rtol, 0.0);
    for (const ComparisonResult& r : c.results) {
      ASSERT_EQ(r.summary.status, Status::ok);
      EXPECT_LT(r.max_error_q, 1e3 * rtol) << "rtol " << rtol;
      EXPECT_GT(r.solve_ns, 0.0);
    }
    EXPECT_LT(c.results[0].max_error_q, 0.5 * previous) << "rtol " << rtol;
    previous = c.results[0].max_error_q;
    // Both formulations integrate the same equations: their errors agree to the reference's level.
    EXPECT_NEAR(c.results[0].max_error_q, c.results[1].max_error_q, 1e-3 * c.results[0].max_error_q + 1e-11);
  }
}

}  // namespace
}  // namespace nhdyn
