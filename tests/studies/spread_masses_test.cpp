// The spread-masses study at a small size (ratios 1, 1e6, 1e12; two states), asserting what the
// full study found (docs/studies/spread-masses.md), with margins: every formulation is accurate to
// round-off at ratio 1; the error of every one grows with the ratio, sanh's included, and stays
// within a bound at 1e12; no formulation is more than a factor 100 better than another; the
// acceleration-level residual stays at round-off; Lagrange is either refused or within the same
// bound. Also: the sample states lie on the constraints, and bad input is refused by name.
#include "nhdyn/studies/spread_masses.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "nhdyn/analysis/initial_state.hpp"
#include "nhdyn/core/error.hpp"
#include "nhdyn/frontend/model_file.hpp"
#include "nhdyn/model/data.hpp"
#include "nhdyn/symbolic/compile.hpp"

namespace nhdyn {
namespace {

symbolic::Spec spread_masses_spec() { return load_model_file(NHDYN_SOURCE_DIR "/examples/spread_masses.toml"); }

const SpreadMasses& small_study() {
  static const SpreadMasses study = [] {
    SpreadMassesOptions options;
    options.ratios = {1.0, 1e6, 1e12};
    options.samples = 2;
    return study_spread_masses(spread_masses_spec(), options);
  }();
  return study;
}

bool is_lagrange(const StudyFormulation& f) { return f.method == Formulation::lagrange; }

TEST(SpreadMasses, EveryFormulationTheModelAllowsIsRun) {
  const SpreadMasses& study = small_study();
  ASSERT_EQ(study.formulations.size(), 6u);  // sanh qr, partition, analytic; lagrange; udwadia-kalaba; nullspace
  ASSERT_EQ(study.ratios.size(), 3u);
  ASSERT_EQ(study.states.size(), 2u);
  EXPECT_EQ(study.digits, 50);
  for (const SpreadMassesRatio& r : study.ratios) EXPECT_LT(r.reference_error, 1e-40) << "ratio " << r.ratio;
  // cond(A) grows like the ratio (measured 18, 5e6, 5e12).
  EXPECT_LT(study.ratios[0].cond_A, 1e3);
  EXPECT_GT(study.ratios[2].cond_A, 1e11);
}

TEST(SpreadMasses, AllFormulationsAreAccurateAtEqualMasses) {
  const SpreadMasses& study = small_study();
  for (std::size_t f = 0; f < study.formulations.size(); ++f) {
    const SpreadMassesPoint& p = study.point(0, f);
    const std::string label = formulation_label(study.formulations[f]);
    ASSERT_EQ(p.failures, 0) << label;
    EXPECT_LT(p.error_qdd, 1e-14) << label;  // measured <= 1.1e-15
    EXPECT_LT(p.error_R, 2e-14) << label;    // measured <= 2.1e-15
  }
}

TEST(SpreadMasses, ErrorsGrowWithTheRatioForEveryFormulationAlike) {
  // The finding: not inverting A does not buy accuracy here. At ratio 1e12, sanh's error has grown
  // like everyone's (measured 1e-10 .. 5e-10 for q'', 1e-8 .. 5e-8 for R), and the spread between
  // the formulations that run stays within a factor of about 5 (asserted: 100).
  const SpreadMasses& study = small_study();
  double smallest = std::numeric_limits<double>::infinity(), largest = 0.0;
  for (std::size_t f = 0; f < study.formulations.size(); ++f) {
    const SpreadMassesPoint& p = study.point(2, f);
    const std::string label = formulation_label(study.formulations[f]);
    if (is_lagrange(study.formulations[f]) && p.failures > 0) {
      // The KKT matrix [A b^T; b 0] at 1e12: the library's pivot test calls it singular (it is
      // not; the 50-digit solve of the same system is the reference).
      EXPECT_EQ(p.failure, Status::singular_system);
      continue;
    }
    ASSERT_EQ(p.failures, 0) << label;
    EXPECT_LT(p.error_qdd, 1e-8) << label;
    EXPECT_LT(p.error_R, 1e-6) << label;
    EXPECT_GT(p.error_qdd, 1e-13) << label << ": more accurate than any formulation was found to be";
    EXPECT_GT(p.error_qdd, 100 * study.point(0, f).error_qdd) << label;
    // The solve alone (against the exact solution of the rounded terms) is as inaccurate: the
    // error is not the rounding of the terms.
    EXPECT_GT(p.solve_error_qdd, 1e-13) << label;
    smallest = std::min(smallest, p.error_qdd);
    largest = std::max(largest, p.error_qdd);
  }
  EXPECT_LT(largest / smallest, 100.0);
}

TEST(SpreadMasses, AccelerationResidualStaysAtRoundOff) {
  const SpreadMasses& study = small_study();
  for (std::size_t r = 0; r < study.ratios.size(); ++r)
    for (std::size_t f = 0; f < study.formulations.size(); ++f) {
      const SpreadMassesPoint& p = study.point(r, f);
      if (p.failures > 0) continue;
      EXPECT_LT(p.residual, 1e-13) << formulation_label(study.formulations[f]) << " at ratio " << study.ratios[r].ratio;
    }
}

TEST(SpreadMasses, SampleStatesLieOnTheConstraints) {
  const symbolic::Spec spec = spread_masses_spec();
  const std::vector<SpreadMassesState> states = make_spread_masses_states(spec, "ratio", 4);
  ASSERT_EQ(states.size(), 4u);
  const Model model = symbolic::compile_model(spec);
  Data data = make_data(model);
  for (const SpreadMassesState& state : states)
    for (const ConstraintResidual& r : calc_initial_residuals(model, data, state.t, state.q, state.v))
      EXPECT_LT(std::abs(r.value), 1e-12) << r.constraint;
  // The states differ from one another (not the same state four times).
  EXPECT_GT((states[1].q - states[2].q).norm(), 1e-3);
  EXPECT_GT((states[1].v - states[2].v).norm(), 1e-3);
}

void expect_input_error(const symbolic::Spec& spec, const SpreadMassesOptions& options, const std::string& needle) {
  try {
    study_spread_masses(spec, options);
    ADD_FAILURE() << "no InputError; expected one naming '" << needle << "'";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
  }
}

TEST(SpreadMasses, RefusesBadInputNamingTheValue) {
  const symbolic::Spec spec = spread_masses_spec();
  SpreadMassesOptions options;
  options.ratios = {};
  expect_input_error(spec, options, "at least one mass ratio");
  options.ratios = {1.0, -5.0};
  expect_input_error(spec, options, "-5");
  options.ratios = {0.0};
  expect_input_error(spec, options, "mass ratio 0");
  options.ratios = {std::numeric_limits<double>::infinity()};
  expect_input_error(spec, options, "inf");
  options.ratios = {std::nan("")};
  expect_input_error(spec, options, "nan");
  options.ratios = {1.0};
  options.samples = 0;
  expect_input_error(spec, options, "0 samples");
  // 1e8 samples grew the memory for days of work before the first result.
  options.samples = kMaxSpreadMassesSamples + 1;
  expect_input_error(spec, options, "--samples 100001: at most 100000 states per ratio");
  options.samples = 1;
  options.digits = 19;
  expect_input_error(spec, options, "19 digits");
  options.digits = kMaxSpreadMassesDigits + 1;
  expect_input_error(spec, options, "--digits 1001: at most 1000 digits");
  options.digits = 50;
  options.parameter = "mass_ratio";
  expect_input_error(spec, options, "no parameter 'mass_ratio'");
  const symbolic::Spec appell = load_model_file(NHDYN_SOURCE_DIR "/examples/appell.toml");
  options.parameter = "ratio";
  expect_input_error(appell, options, "model 'appell' has no parameter 'ratio'");
}

}  // namespace
}  // namespace nhdyn
