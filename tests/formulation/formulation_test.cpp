// Consistency checks and exams for the four formulations and the three choices of D: at random
// states of the paper's two examples they must agree with each other and with the closed forms
// derived in docs/derivations/, and D must be a complement of b.
#include "nhdyn/formulation/formulation.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <string>

#include "nhdyn/formulation/complement.hpp"
#include "nhdyn/model/appell.hpp"
#include "nhdyn/model/sled.hpp"
#include "nhdyn/model/terms.hpp"

namespace nhdyn {
namespace {

const Formulation kMethods[] = {Formulation::sanh, Formulation::lagrange, Formulation::udwadia_kalaba, Formulation::nullspace};
const Complement kComplements[] = {Complement::qr, Complement::partition, Complement::analytic};

struct Solution {
  Vector qdd, R;
};

Solution solve(const Model& model, Data& data, FormulationOptions options, const Vector& q, const Vector& v) {
  const Status status = compute_dynamics(model, data, options, 0.0, q.data(), v.data());
  EXPECT_EQ(status, Status::ok) << formulation_name(options.method) << " " << complement_name(options.complement);
  return {data.qdd, data.R};
}

// Closed form of the sled with the centre-of-mass potential and the regular constraint, valid
// at any state (docs/derivations/sled.md, "closed-form q''").
Vector sled_closed_form_qdd(const SledParameters& p, const Vector& q, const Vector& v) {
  const double s = std::sin(q(2)), c = std::cos(q(2)), w = v(2);
  const double u = c * v(0) + s * v(1);  // speed along the blade
  const double gs = p.g * std::sin(p.alpha);
  Vector qdd(3);
  qdd(0) = c * (gs * c + p.a * w * w) - s * u * w;
  qdd(1) = s * (gs * c + p.a * w * w) + c * u * w;
  qdd(2) = -(p.a / (p.rho * p.rho)) * (gs * s + u * w);
  return qdd;
}

TEST(SledFormulations, AllMethodsAndComplementsMatchClosedFormAtRandomStates) {
  SledParameters p;
  const Model model = make_sled_model(SledVariant::centre_of_mass, p);
  Data data = make_data(model);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> U(-3.0, 3.0);
  for (int trial = 0; trial < 50; ++trial) {
    Vector q(3), v(3);
    q << U(rng), U(rng), U(rng) * 2.0;  // every heading, including near +-pi/2
    v << U(rng), U(rng), U(rng);        // on or off the constraint: the closed form holds for both
    const Vector expected = sled_closed_form_qdd(p, q, v);
    // R = A q'' - Q - G from the closed form, evaluated independently of any formulation.
    compute_terms(model, data, 0.0, q.data(), v.data());
    const Vector expected_R = data.A * expected - data.Q - data.G;
    for (Formulation m : kMethods)
      for (Complement c : kComplements) {
        if ((m == Formulation::lagrange || m == Formulation::udwadia_kalaba) && c != Complement::qr) continue;
        const Solution sol = solve(model, data, {m, c}, q, v);
        EXPECT_LT((sol.qdd - expected).norm(), 1e-10 * (1.0 + expected.norm()))
            << formulation_name(m) << "/" << complement_name(c) << " trial " << trial;
        EXPECT_LT((sol.R - expected_R).norm(), 1e-10 * (1.0 + expected_R.norm()))
            << formulation_name(m) << "/" << complement_name(c) << " trial " << trial;
      }
  }
}

TEST(SledFormulations, PaperVariantSatisfiesThePapersReducedEquations) {
  SledParameters p;
  const Model model = make_sled_model(SledVariant::paper, p);
  Data data = make_data(model);
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> U(-2.0, 2.0);
  for (int trial = 0; trial < 50; ++trial) {
    Vector q(3), v(3);
    q << U(rng), U(rng), 0.6 * U(rng);  // |phi| < 1.2, away from the paper's singular heading
    v << U(rng), 0.0, U(rng);
    v(1) = std::tan(q(2)) * v(0);  // on the constraint
    const double m = p.m, a = p.a, phi = q(2), w = v(2);
    for (Formulation method : kMethods)
      for (Complement c : kComplements) {
        if ((method == Formulation::lagrange || method == Formulation::udwadia_kalaba) && c != Complement::qr) continue;
        const Solution sol = solve(model, data, {method, c}, q, v);
        const Vector& a_ = sol.qdd;
        // docs/notation.md section 6: the paper's equations with the paper's potential.
        const double eq1 = m * a_(0) + m * std::tan(phi) * a_(1) - (m * p.g * std::sin(p.alpha) + m * a * w * w / std::cos(phi));
        const double eq2 = -m * a * std::sin(phi) * a_(0) + m * a * std::cos(phi) * a_(1) + m * p.rho * p.rho * a_(2);
        // The constraint y' = tan(phi) x' differentiated once.
        const double eq3 = a_(1) - std::tan(phi) * a_(0) - v(0) * w / (std::cos(phi) * std::cos(phi));
        const double scale = 1.0 + a_.norm() + w * w;
        EXPECT_LT(std::abs(eq1), 1e-11 * scale) << formulation_name(method) << "/" << complement_name(c);
        EXPECT_LT(std::abs(eq2), 1e-11 * scale) << formulation_name(method) << "/" << complement_name(c);
        EXPECT_LT(std::abs(eq3), 1e-11 * scale) << formulation_name(method) << "/" << complement_name(c);
      }
  }
}

TEST(AppellFormulations, AllMethodsMatchClosedFormOffTheConstraint) {
  AppellParameters p;
  const Model model = make_appell_model(p);
  Data data = make_data(model);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> U(-2.0, 2.0);
  for (int trial = 0; trial < 50; ++trial) {
    Vector q(3), v(3);
    q << U(rng), U(rng), U(rng);
    v << U(rng), U(rng), 0.5 + std::abs(U(rng));  // z' away from 0, where the paper's b is singular
    // docs/derivations/appell.md: with N = a^4 (x'^2 + y'^2) + z'^2,
    // q'' = g a^2 (x' z', y' z', a^2 (x'^2 + y'^2)) / N, for any state.
    const double a2 = p.a * p.a, h2 = v(0) * v(0) + v(1) * v(1);
    const double N = a2 * a2 * h2 + v(2) * v(2);
    Vector expected(3);
    expected << p.g * a2 * v(0) * v(2) / N, p.g * a2 * v(1) * v(2) / N, p.g * a2 * a2 * h2 / N;
    Vector expected_R = p.m * expected;
    expected_R(2) -= p.m * p.g;
    for (Formulation m : kMethods)
      for (Complement c : kComplements) {
        if ((m == Formulation::lagrange || m == Formulation::udwadia_kalaba) && c != Complement::qr) continue;
        const Solution sol = solve(model, data, {m, c}, q, v);
        EXPECT_LT((sol.qdd - expected).norm(), 1e-12 * (1.0 + expected.norm())) << formulation_name(m) << "/" << complement_name(c);
        EXPECT_LT((sol.R - expected_R).norm(), 1e-12 * (1.0 + expected_R.norm())) << formulation_name(m) << "/" << complement_name(c);
      }
  }
}

TEST(Multipliers, ReactionsAreBTransposeLambdaWhereMultipliersExist) {
  const Model model = make_sled_model();
  Data data = make_data(model);
  Vector q(3), v(3);
  q << 0.3, -0.2, 0.7;
  v << 1.2, 0.4, -0.8;
  for (Formulation m : {Formulation::lagrange, Formulation::udwadia_kalaba}) {
    ASSERT_EQ(compute_dynamics(model, data, {m, Complement::qr}, 0.0, q.data(), v.data()), Status::ok);
    ASSERT_TRUE(data.has_multipliers);
    const Vector bt_lambda = data.b.transpose() * data.lambda;
    EXPECT_LT((data.R - bt_lambda).norm(), 1e-12 * (1.0 + data.R.norm())) << formulation_name(m);
    // The reactions of an ideal constraint do no virtual work on admissible motions: D R = 0 (2.8).
    ASSERT_EQ(compute_complement(model, data, Complement::qr), Status::ok);
    EXPECT_LT((data.D * data.R).norm(), 1e-12 * (1.0 + data.R.norm())) << formulation_name(m);
  }
}

TEST(Complements, EveryChoiceIsAFullRankComplementOfB) {
  for (const Model& model : {make_sled_model(SledVariant::centre_of_mass), make_sled_model(SledVariant::paper),
                             make_appell_model()}) {
    Data data = make_data(model);
    Vector q(3), v(3);
    q << 0.1, 0.2, 0.9;
    v << 0.7, -0.4, 1.3;
    ASSERT_EQ(compute_terms(model, data, 0.0, q.data(), v.data()), Status::ok);
    for (Complement c : kComplements) {
      ASSERT_EQ(compute_complement(model, data, c), Status::ok);
      EXPECT_LT((data.D * data.b.transpose()).norm(), 1e-14 * (1.0 + data.D.norm() * data.b.norm()))
          << model.name << " " << complement_name(c);
      Eigen::JacobiSVD<Matrix> svd(data.D);
      EXPECT_GT(svd.singularValues().minCoeff(), 1e-3) << model.name << " " << complement_name(c);
      if (c == Complement::qr) {
        const Matrix gram = data.D * data.D.transpose();
        EXPECT_LT((gram - Matrix::Identity(model.k(), model.k())).norm(), 1e-14) << model.name;
      }
      if (c == Complement::partition) {
        // The rows of a partitioned D carry an identity on the independent coordinates.
        for (int r = 0; r < model.k(); ++r) EXPECT_EQ(data.D(r, data.independent[static_cast<std::size_t>(r)]), 1.0);
      }
    }
  }
}

TEST(Names, MethodsAndComplementsRoundTripAndRejectUnknownNames) {
  for (Formulation m : kMethods) EXPECT_EQ(parse_formulation(formulation_name(m)), m);
  for (Complement c : kComplements) EXPECT_EQ(parse_complement(complement_name(c)), c);
  try {
    parse_formulation("kane");
    FAIL() << "expected an error";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("udwadia-kalaba"), std::string::npos);
  }
  EXPECT_THROW(parse_complement("svd"), std::exception);
}

TEST(DataFlow, AccelerationBeforeTermsIsRefusedWithAClearMessage) {
  const Model model = make_sled_model();
  Data data = make_data(model);
  try {
    compute_acceleration(model, data, {});
    FAIL() << "expected an error";
  } catch (const std::logic_error& e) {
    EXPECT_NE(std::string(e.what()).find("compute_terms first"), std::string::npos);
  }
}

}  // namespace
}  // namespace nhdyn
