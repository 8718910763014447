// A hand-built model with a program, for the formulation tests (which link no symbolic compiler):
// the built-in sled (model/sled.hpp) with its heading prescribed, phi - omega t = 0, realized by a
// torque about the normal to the plane (B = e_phi). Its program terms are written by hand here:
// b_p = (0, 0, 1), b_p0 = 0 (phi'' = 0), residuals phi - omega t and phi' - omega
// (docs/derivations/program-motion.md section 6).
#pragma once

#include <memory>
#include <utility>

#include "nhdyn/model/model.hpp"
#include "nhdyn/model/sled.hpp"

namespace nhdyn::testing {

class SledHeadingEvaluator final : public Evaluator {
 public:
  SledHeadingEvaluator(std::shared_ptr<const Evaluator> sled, double omega) : sled_(std::move(sled)), omega_(omega) {}
  std::size_t scratch_size() const override { return sled_->scratch_size(); }
  void terms(double t, const double* q, const double* v, double* scratch, const TermsOut& out) const override {
    sled_->terms(t, q, v, scratch, out);
  }
  bool has_complement() const override { return sled_->has_complement(); }
  void complement(double t, const double* q, const double* v, double* scratch, double* D) const override {
    sled_->complement(t, q, v, scratch, D);
  }
  void velocity_residual(double t, const double* q, const double* v, double* scratch, double* f) const override {
    sled_->velocity_residual(t, q, v, scratch, f);
  }
  bool has_program_constraints() const override { return true; }
  void program_constraint_terms(double, const double*, const double*, double*, double* b_p, double* b_p0,
                                double* B) const override {
    b_p[0] = 0.0, b_p[1] = 0.0, b_p[2] = 1.0;
    b_p0[0] = 0.0;
    B[0] = 0.0, B[1] = 0.0, B[2] = 1.0;
  }
  void program_constraint_position_residual(double t, const double* q, double*, double* phi) const override {
    phi[0] = q[2] - omega_ * t;
  }
  void program_constraint_velocity_residual(double, const double*, const double* v, double*, double* f) const override {
    f[0] = v[2] - omega_;
  }

 private:
  std::shared_ptr<const Evaluator> sled_;
  double omega_;
};

inline Model make_sled_heading_model(double omega = 1.0, const SledParameters& p = {}) {
  Model model = make_sled_model(SledVariant::centre_of_mass, p);
  model.name = "sled_heading";
  model.program_constraints.push_back({"heading", ConstraintLevel::position, "phi - omega*t", "phi"});
  model.evaluator = std::make_shared<SledHeadingEvaluator>(model.evaluator, omega);
  model.q0 << 0.0, 0.0, 0.0;
  model.v0 << 1.0, 0.0, omega;
  return model;
}

}  // namespace nhdyn::testing
