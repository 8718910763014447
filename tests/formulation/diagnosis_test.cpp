// The failure modes of the kernel: dependent or conflicting constraints, an inertia matrix that
// is not positive definite, and non-finite values must each come back as a status with words
// that name the constraints, the eigenvalue or the quantity and t.
#include "nhdyn/formulation/diagnosis.hpp"

#include <gtest/gtest.h>

#include <limits>
#include <string>

#include "nhdyn/core/error.hpp"
#include "nhdyn/formulation/formulation.hpp"
#include "nhdyn/model/appell.hpp"
#include "support/test_models.hpp"
#include "support/text.hpp"

namespace nhdyn {
namespace {

const Formulation kDiagnosedMethods[] = {Formulation::sanh, Formulation::lagrange, Formulation::udwadia_kalaba, Formulation::nullspace};

using nhdyn::test::contains;

TEST(Diagnosis, DependentConstraintsAreNamedWithAConditionEstimate) {
  Matrix b(3, 4);
  b << 1, 0, 0, 0,
       0, 1, 1, 0,
       2, 0, 0, 0;  // c3 = 2 c1
  const Model model = testing::make_constant_model(Matrix::Identity(4, 4), Vector::Ones(4), b, Vector::Zero(3));
  for (Formulation m : kDiagnosedMethods) {
    Data data = make_data(model);
    const Status status = compute_dynamics(model, data, {m, Complement::qr}, 0.0, model.q0.data(), model.v0.data());
    ASSERT_NE(status, Status::ok) << formulation_name(m);
    const std::string message = explain_failure(model, data);
    EXPECT_TRUE(contains(message, "'c1'") && contains(message, "'c3'")) << formulation_name(m) << ": " << message;
    EXPECT_FALSE(contains(message, "'c2'")) << message;
    EXPECT_TRUE(contains(message, "condition estimate")) << message;
  }
  Data data = make_data(model);
  EXPECT_EQ(compute_dynamics(model, data, {Formulation::sanh, Complement::partition}, 0.0, model.q0.data(), model.v0.data()),
            Status::dependent_constraints);
  try {
    check_state_or_throw(model, data, 0.0, model.q0.data(), model.v0.data());
    FAIL() << "expected ModelError";
  } catch (const ModelError& e) {
    EXPECT_TRUE(contains(e.what(), "dependent")) << e.what();
  }
}

// A b that is singular in double precision only through the scale of a column (a coordinate in
// units out of proportion with the others) is said to be so, naming the columns; a true
// dependency among the same columns is still called one.
TEST(Diagnosis, ColumnsOutOfProportionAreNotCalledDependentConstraints) {
  Matrix b(2, 3);
  b << 1, 0, 1e20,
       0, 1, 0;
  const Model model = testing::make_constant_model(Matrix::Identity(3, 3), Vector::Ones(3), b, Vector::Zero(2));
  Data data = make_data(model);
  ASSERT_EQ(compute_dynamics(model, data, {Formulation::sanh, Complement::qr}, 0.0, model.q0.data(), model.v0.data()),
            Status::dependent_constraints);
  const std::string message = explain_failure(model, data);
  EXPECT_TRUE(contains(message, "only through the units of the coordinates")) << message;
  EXPECT_TRUE(contains(message, "in the rows of the constraint 'c1'")) << message;
  EXPECT_TRUE(contains(message, "its column of 'q3' is 1e+20 times its column of ")) << message;
  EXPECT_TRUE(contains(message, "'c1'") && !contains(message, "'c2'")) << message;

  Matrix dependent(2, 3);
  dependent << 1, 0, 1e20,
               2, 0, 2e20;  // c2 = 2 c1
  const Model truly = testing::make_constant_model(Matrix::Identity(3, 3), Vector::Ones(3), dependent, Vector::Zero(2));
  Data truly_data = make_data(truly);
  ASSERT_NE(compute_dynamics(truly, truly_data, {Formulation::sanh, Complement::qr}, 0.0, truly.q0.data(),
                             truly.v0.data()),
            Status::ok);
  const std::string said = explain_failure(truly, truly_data);
  EXPECT_TRUE(contains(said, "dependent or conflicting")) << said;
  EXPECT_FALSE(contains(said, "units of the coordinates")) << said;
}

// A constraint whose row of b vanishes (x'^2 + y'^2 = 1 at rest) is named alone for that, not
// called dependent on the others.
TEST(Diagnosis, AZeroRowOfBIsNamedAsSuch) {
  Matrix b(2, 3);
  b << 1, 0, 0,
       0, 0, 0;
  const Model model = testing::make_constant_model(Matrix::Identity(3, 3), Vector::Ones(3), b, Vector::Zero(2));
  Data data = make_data(model);
  ASSERT_EQ(compute_dynamics(model, data, {Formulation::sanh, Complement::qr}, 0.0, model.q0.data(), model.v0.data()),
            Status::dependent_constraints);
  const std::string message = explain_failure(model, data);
  EXPECT_TRUE(contains(message, "the constraint 'c2' has a zero row of b at t = 0")) << message;
  EXPECT_FALSE(contains(message, "'c1'") || contains(message, "dependent")) << message;
}

TEST(Diagnosis, IndefiniteInertiaIsReportedWithItsSmallestEigenvalue) {
  Matrix A = Matrix::Identity(3, 3);
  A(2, 2) = -2.0;
  Matrix b(1, 3);
  b << 1, 0, 0;
  const Model model = testing::make_constant_model(A, Vector::Ones(3), b, Vector::Zero(1));
  Data data = make_data(model);
  EXPECT_EQ(compute_dynamics(model, data, {Formulation::udwadia_kalaba, Complement::qr}, 0.0, model.q0.data(),
                             model.v0.data()),
            Status::inertia_not_positive_definite);
  EXPECT_EQ(compute_dynamics(model, data, {Formulation::nullspace, Complement::qr}, 0.0, model.q0.data(), model.v0.data()),
            Status::inertia_not_positive_definite);
  try {
    check_state_or_throw(model, data, 0.0, model.q0.data(), model.v0.data());
    FAIL() << "expected ModelError";
  } catch (const ModelError& e) {
    EXPECT_TRUE(contains(e.what(), "not positive definite")) << e.what();
    EXPECT_TRUE(contains(e.what(), "-2")) << e.what();
  }
}

TEST(Diagnosis, NonFiniteTermsNameTheQuantityAndTime) {
  // Appell's constraint in the paper's form divides by z': at z' = 0 the term b is infinite.
  const Model model = make_appell_model();
  Data data = make_data(model);
  Vector q = Vector::Zero(3), v(3);
  v << 1.0, 0.0, 0.0;
  for (Formulation m : kDiagnosedMethods) {
    const Status status = compute_dynamics(model, data, {m, Complement::qr}, 2.5, q.data(), v.data());
    ASSERT_EQ(status, Status::non_finite) << formulation_name(m);
    const std::string message = explain_failure(model, data);
    EXPECT_TRUE(contains(message, "constraint matrix b")) << message;
    EXPECT_TRUE(contains(message, "t = 2.5")) << message;
    // The entry and the state: b(appell, x) = -a^2 x' / z' at z' = 0.
    EXPECT_TRUE(contains(message, "(b(appell, x) = -inf, ")) << message;
    EXPECT_TRUE(contains(message, "where x = 0, y = 0, z = 0, x' = 1, y' = 0, z' = 0)")) << message;
  }
  // A NaN in the state itself is named as such.
  q(0) = std::numeric_limits<double>::quiet_NaN();
  v(2) = 1.0;
  EXPECT_EQ(compute_dynamics(model, data, {}, 0.0, q.data(), v.data()), Status::non_finite);
  EXPECT_TRUE(contains(explain_failure(model, data), "coordinates q"));
}

TEST(Diagnosis, AnalyticComplementOfAModelWithoutOneIsAnInputError) {
  Matrix b(1, 2);
  b << 1, 1;
  const Model model = testing::make_constant_model(Matrix::Identity(2, 2), Vector::Ones(2), b, Vector::Zero(1));
  Data data = make_data(model);
  EXPECT_THROW(compute_dynamics(model, data, {Formulation::sanh, Complement::analytic}, 0.0, model.q0.data(), model.v0.data()),
               InputError);
}

}  // namespace
}  // namespace nhdyn
