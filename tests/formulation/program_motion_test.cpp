// The program-motion kernel (formulation/program_motion.hpp) on a model whose program terms are
// written by hand (formulation/sled_heading.hpp), independently of the symbolic compiler: the
// sled's torque and S against the closed forms of docs/derivations/program-motion.md section 6,
// the same result for every choice of D, the refusal of the other formulations, and a zero
// actuator reported as absorbed.
#include <gtest/gtest.h>

#include <cmath>

#include "formulation/sled_heading.hpp"
#include "nhdyn/core/error.hpp"
#include "nhdyn/formulation/diagnosis.hpp"
#include "nhdyn/formulation/program_motion.hpp"
#include "nhdyn/model/terms.hpp"

namespace nhdyn {
namespace {

TEST(ProgramMotionKernel, SledTorqueIsTheClosedFormForEveryComplement) {
  const SledParameters p;
  const double omega = 1.0;
  const Model model = testing::make_sled_heading_model(omega, p);
  Data data = make_data(model);
  // On the program (phi = omega t, phi' = omega) with the blade met: u = m a omega v + m g a sin(alpha) sin(phi).
  const double t = 0.8, phi = omega * t, speed = 1.7;
  const double q[3] = {0.3, 0.4, phi}, v[3] = {speed * std::cos(phi), speed * std::sin(phi), omega};
  const double expected = p.m * p.a * omega * speed + p.m * p.g * p.a * std::sin(p.alpha) * std::sin(phi);
  for (Complement c : {Complement::qr, Complement::partition, Complement::analytic}) {
    ASSERT_EQ(compute_dynamics(model, data, {Formulation::sanh, c}, t, q, v), Status::ok) << complement_name(c);
    EXPECT_NEAR(data.motion.u(0), expected, 1e-13) << complement_name(c);
    EXPECT_NEAR(data.motion.S(0, 0), 1.0 / (p.m * p.rho * p.rho), 1e-14) << complement_name(c);
    // v' = g sin(alpha) cos(phi) + a omega^2 along the blade, phi'' = 0.
    const double along = std::cos(phi) * data.qdd(0) + std::sin(phi) * data.qdd(1);
    EXPECT_NEAR(along, p.g * std::sin(p.alpha) * std::cos(phi) + p.a * omega * omega, 1e-12) << complement_name(c);
    EXPECT_NEAR(data.qdd(2), 0.0, 1e-14);
  }
}

TEST(ProgramMotionKernel, OtherFormulationsRefuseAModelWithPrograms) {
  const Model model = testing::make_sled_heading_model();
  Data data = make_data(model);
  ASSERT_EQ(compute_terms(model, data, 0.0, model.q0.data(), model.v0.data()), Status::ok);
  EXPECT_THROW(compute_acceleration(model, data, {Formulation::lagrange}), InputError);
}

TEST(ProgramMotionKernel, AZeroActuatorIsReportedAsAbsorbed) {
  // An actuator along the blade's normal, (-sin(phi), cos(phi), 0), pushes into the constraint.
  class Normal final : public Evaluator {
   public:
    explicit Normal(std::shared_ptr<const Evaluator> sled) : sled_(std::move(sled)) {}
    void terms(double t, const double* q, const double* v, double* s, const TermsOut& out) const override {
      sled_->terms(t, q, v, s, out);
    }
    bool has_program_constraints() const override { return true; }
    void program_constraint_terms(double, const double* q, const double*, double*, double* b_p, double* b_p0,
                                  double* B) const override {
      b_p[0] = 1.0, b_p[1] = 0.0, b_p[2] = 0.0;
      b_p0[0] = 0.0;
      B[0] = -std::sin(q[2]), B[1] = std::cos(q[2]), B[2] = 0.0;
    }
    void program_constraint_position_residual(double, const double*, double*, double* phi) const override { phi[0] = 0; }
    void program_constraint_velocity_residual(double, const double*, const double*, double*, double* f) const override {
      f[0] = 0;
    }

   private:
    std::shared_ptr<const Evaluator> sled_;
  };
  Model model = make_sled_model();
  model.program_constraints.push_back({"push", ConstraintLevel::position, "x", "[-sin(phi), cos(phi), 0]"});
  model.evaluator = std::make_shared<Normal>(model.evaluator);
  Data data = make_data(model);
  const double q[3] = {0.0, 0.0, 0.7}, v[3] = {0.0, 0.0, 0.0};
  ASSERT_EQ(compute_terms(model, data, 0.0, q, v), Status::ok);
  ASSERT_EQ(compute_program_motion(model, data, Complement::qr, {}), Status::singular_system);
  EXPECT_EQ(data.motion.absorbed, 0);
  const std::string message = explain_failure(model, data);
  EXPECT_NE(message.find("program 'push'"), std::string::npos) << message;
  EXPECT_NE(message.find("D B = 0"), std::string::npos) << message;
}

}  // namespace
}  // namespace nhdyn
