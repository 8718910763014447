// The check of a model's analytic complement D: complement_residual against hand-computed values,
// and, with the check on (debug builds), a D that stops being a complement along the run is refused at the
// evaluation where it fails, with the residual in the message.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <string>

#include "nhdyn/formulation/complement.hpp"
#include "nhdyn/formulation/diagnosis.hpp"
#include "nhdyn/formulation/formulation.hpp"
#include "nhdyn/model/data.hpp"
#include "nhdyn/model/terms.hpp"
#include "support/test_models.hpp"

namespace nhdyn {
namespace {

// A particle in the plane on the line y = x (b = [-1, 1]) whose "complement" D = [1, 1 + t] is
// one only at t = 0: D b^T = t. Its residual is t / (|D| |b|) = t / (sqrt(1 + (1 + t)^2) sqrt 2).
class DriftingComplement final : public Evaluator {
 public:
  void terms(double, const double*, const double*, double*, const TermsOut& out) const override {
    Eigen::Map<Matrix>(out.A, 2, 2).setIdentity();
    out.Q[0] = 0.0;
    out.Q[1] = -1.0;
    out.G[0] = out.G[1] = 0.0;
    out.b[0] = -1.0;
    out.b[1] = 1.0;
    out.b0[0] = 0.0;
  }
  bool has_complement() const override { return true; }
  void complement(double t, const double*, const double*, double*, double* D) const override {
    D[0] = 1.0;
    D[1] = 1.0 + t;
  }
};

Model drifting_model() {
  Model m = testing::make_constant_model(Matrix::Identity(2, 2), Vector::Zero(2), Matrix::Ones(1, 2), Vector::Zero(1));
  m.name = "drifting";
  m.evaluator = std::make_shared<DriftingComplement>();
  return m;
}

double expected_residual(double t) { return t / (std::sqrt(1.0 + (1.0 + t) * (1.0 + t)) * std::sqrt(2.0)); }

TEST(ComplementCheck, ResidualIsTheLargestNormalizedEntryOfDbT) {
  const Model model = drifting_model();
  Data data = make_data(model);
  const Vector q = Vector::Zero(2), v = Vector::Zero(2);
  for (double t : {0.0, 1e-12, 0.25, 3.0}) {
    ASSERT_EQ(compute_terms(model, data, t, q.data(), v.data()), Status::ok);
    model.evaluator->complement(t, q.data(), v.data(), data.scratch.data(), data.D.data());
    EXPECT_NEAR(complement_residual(data), expected_residual(t), 1e-15) << "t = " << t;
  }
  // Two rows of D against two constraints: the worst pair counts.
  Data two;
  two.b = Matrix{{1.0, 0.0, 0.0}, {0.0, 1.0, 0.0}};
  two.D = Matrix{{0.0, 0.0, 2.0}, {0.0, 1e-3, 1.0}};
  EXPECT_NEAR(complement_residual(two), 1e-3 / std::sqrt(1.0 + 1e-6), 1e-15);
}

TEST(ComplementCheck, ADriftingComplementIsRefusedWhereItFailsWhenChecked) {
  const Model model = drifting_model();
  Data data = make_data(model);
#ifdef NDEBUG
  EXPECT_FALSE(data.check_complement);
#else
  EXPECT_TRUE(data.check_complement);
#endif
  data.check_complement = true;  // what a debug build does
  const Vector q = Vector::Zero(2), v = Vector::Zero(2);
  const FormulationOptions options(Formulation::sanh, Complement::analytic);
  EXPECT_EQ(compute_dynamics(model, data, options, 0.0, q.data(), v.data()), Status::ok);
  // Still within the tolerance just after t = 0, refused once D b^T is far from zero.
  EXPECT_EQ(compute_dynamics(model, data, options, 1e-10, q.data(), v.data()), Status::ok);
  ASSERT_EQ(compute_dynamics(model, data, options, 0.5, q.data(), v.data()), Status::singular_system);
  EXPECT_NEAR(data.failed_value, expected_residual(0.5), 1e-15);
  const std::string message = explain_failure(model, data);
  EXPECT_NE(message.find("complement D is not a complement of b at t = 0.5"), std::string::npos) << message;
  EXPECT_NE(message.find("--complement qr"), std::string::npos) << message;
  // Unchecked (a release build), the same evaluation goes through: the check is what refuses it.
  data.check_complement = false;
  EXPECT_EQ(compute_dynamics(model, data, options, 0.5, q.data(), v.data()), Status::ok);
}

}  // namespace
}  // namespace nhdyn
