// The error-relation study at a small size (docs/studies/error-relation.md). What the study found,
// asserted with margin:
// - knife edge (its error leaves the constraint): the velocity residual tracks the global error,
//   error / residual between 3.2 and 9.9 over rtol 1e-3 .. 1e-12 for every formulation and
//   integrator (asserted: between 1 and 30), and the formulations agree to 6 % (asserted: 50 %);
// - Appell's particle (its error stays on the constraint): BDF's error follows its tolerance while
//   the residual stays at round-off (error / residual up to 7e9; asserted: > 1e4 at rtol 1e-3 and
//   1e-6), and dopri5 reproduces the exact motion to round-off at every tolerance.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>

#include "nhdyn/core/error.hpp"
#include "nhdyn/frontend/model_file.hpp"
#include "nhdyn/model/appell.hpp"
#include "nhdyn/model/sled.hpp"
#include "nhdyn/studies/error_relation.hpp"
#include "nhdyn/symbolic/compile.hpp"

namespace nhdyn {
namespace {

double error_of(const ErrorRelationRun& r) { return std::max(r.max_error_q, r.max_error_v); }

TEST(ErrorRelation, KnifeEdgeResidualTracksTheError) {
  const Model model = symbolic::compile_model(load_model_file(std::filesystem::path(NHDYN_SOURCE_DIR) /
                                                              "examples/knife_edge.toml"));
  ErrorRelationOptions options;
  options.tolerances = {1e-4, 1e-8};
  options.formulations = {{Formulation::sanh, Complement::qr}, {Formulation::lagrange, Complement::qr},
                          {Formulation::udwadia_kalaba, Complement::qr}};
  options.integrators = {IntegratorKind::dopri5, IntegratorKind::cvode_bdf};
  const ErrorRelation study = study_error_relation(model, options);
  ASSERT_TRUE(study.analytic);
  ASSERT_EQ(study.runs.size(), 12u);
  for (const ErrorRelationRun& r : study.runs) {
    ASSERT_EQ(r.summary.status, Status::ok);
    EXPECT_GT(error_of(r), 1.0 * r.max_residual_vel) << formulation_label(r.formulation) << " " << r.tolerance;
    EXPECT_LT(error_of(r), 30.0 * r.max_residual_vel) << formulation_label(r.formulation) << " " << r.tolerance;
  }
  for (std::size_t f = 0; f < study.formulations.size(); ++f)
    for (std::size_t i = 0; i < study.integrators.size(); ++i) {
      // Both error and residual fall with the tolerance (by 1e4 for a 1e4 tighter rtol; asserted 100).
      EXPECT_LT(error_of(study.run(f, i, 1)), error_of(study.run(f, i, 0)) / 100.0);
      EXPECT_LT(study.run(f, i, 1).max_residual_vel, study.run(f, i, 0).max_residual_vel / 100.0);
      // Every formulation integrates the same equations: same error, at every tolerance.
      for (std::size_t k = 0; f > 0 && k < study.tolerances.size(); ++k) {
        EXPECT_NEAR(error_of(study.run(f, i, k)), error_of(study.run(0, i, k)), 0.5 * error_of(study.run(0, i, k)))
            << formulation_label(study.formulations[f]) << " " << study.tolerances[k];
      }
    }
}

TEST(ErrorRelation, AppellErrorStaysOnTheConstraintWhereTheResidualCannotSeeIt) {
  const Model model = make_appell_model();
  ErrorRelationOptions options;
  options.tolerances = {1e-3, 1e-6};
  options.formulations = {{Formulation::sanh, Complement::qr}, {Formulation::sanh, Complement::analytic},
                          {Formulation::lagrange, Complement::qr}};
  options.integrators = {IntegratorKind::dopri5, IntegratorKind::cvode_bdf};
  const ErrorRelation study = study_error_relation(model, options);
  ASSERT_TRUE(study.analytic);
  for (const ErrorRelationRun& r : study.runs) {
    ASSERT_EQ(r.summary.status, Status::ok);
    EXPECT_LT(r.max_residual_vel, 1e-10) << formulation_label(r.formulation);  // measured <= 2.2e-12
    if (r.integrator == IntegratorKind::dopri5) {
      EXPECT_LT(error_of(r), 1e-11) << formulation_label(r.formulation);  // measured <= 3.7e-13
    } else {
      EXPECT_GT(error_of(r), 0.1 * r.tolerance) << formulation_label(r.formulation);  // measured ~2.5 rtol
      EXPECT_GT(error_of(r), 1e4 * r.max_residual_vel) << formulation_label(r.formulation);
    }
  }
}

TEST(ErrorRelation, WithoutAnExactSolutionATightRunIsTheReference) {
  const Model model = make_sled_model();
  ErrorRelationOptions options;
  options.tolerances = {1e-5};
  options.formulations = {{Formulation::sanh, Complement::qr}};
  options.integrators = {IntegratorKind::dopri5};
  options.t_end = 2.0;
  const ErrorRelation study = study_error_relation(model, options);
  EXPECT_FALSE(study.analytic);
  ASSERT_EQ(study.runs.size(), 1u);
  EXPECT_GT(error_of(study.runs[0]), 0.0);
  EXPECT_LT(error_of(study.runs[0]), 1e-3);
}

TEST(ErrorRelation, BadOptionsAreRefused) {
  const Model appell = make_appell_model();
  ErrorRelationOptions options;
  EXPECT_THROW(study_error_relation(appell, options), InputError);  // no tolerance
  options.tolerances = {1e-3, -1e-6};
  try {
    study_error_relation(appell, options);
    ADD_FAILURE() << "a negative tolerance was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("-1e-06"), std::string::npos) << e.what();
  }
  options.tolerances = {1e-3, std::nan("")};
  EXPECT_THROW(study_error_relation(appell, options), InputError);
  options.tolerances = {1e-3};
  options.atol_factor = 0.0;
  EXPECT_THROW(study_error_relation(appell, options), InputError);
  options.atol_factor = 1.0;
  options.integrators.clear();
  EXPECT_THROW(study_error_relation(appell, options), InputError);
  options.integrators = {IntegratorKind::dopri5, IntegratorKind::rk4};
  EXPECT_THROW(study_error_relation(appell, options), InputError);  // a fixed step ignores the tolerance
  options.integrators = {IntegratorKind::dopri5, IntegratorKind::dopri5};
  EXPECT_THROW(study_error_relation(appell, options), InputError);
  options.integrators = {IntegratorKind::dopri5};
  options.tolerances = {1e-3, 1e-3};
  EXPECT_THROW(study_error_relation(appell, options), InputError);
  options.tolerances = {1e-3};
  options.formulations = {{Formulation::lagrange, Complement::qr}, {Formulation::lagrange, Complement::partition}};
  EXPECT_THROW(study_error_relation(appell, options), InputError);  // the same formulation: lagrange has no D
  options.formulations = {{Formulation::sanh, Complement::qr}};
  options.t_end = -1.0;
  EXPECT_THROW(study_error_relation(appell, options), InputError);
  options.t_end = 0.0;
  options.output_step = -0.1;
  EXPECT_THROW(study_error_relation(appell, options), InputError);
  options.output_step = 0.0;
  const Model free_fall = symbolic::compile_model(load_model_string(
      "name = \"fall\"\ncoordinates = [\"z\"]\nkinetic_energy = \"z'^2/2\"\npotential_energy = \"-9.81*z\"\n", "f.toml"));
  try {
    study_error_relation(free_fall, options);
    ADD_FAILURE() << "a model without constraints was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("no constraints"), std::string::npos) << e.what();
  }
  options.formulations = {{Formulation::sanh, Complement::analytic}};
  const Model knife = symbolic::compile_model(load_model_file(std::filesystem::path(NHDYN_SOURCE_DIR) /
                                                              "examples/knife_edge.toml"));
  ASSERT_FALSE(knife.evaluator->has_complement());  // the file gives neither D nor independent coordinates
  try {
    study_error_relation(knife, options);
    ADD_FAILURE() << "sanh-analytic was accepted for a model without D";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("sanh-analytic"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace nhdyn
