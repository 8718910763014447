#include "nhdyn/analysis/residuals.hpp"

#include <stdexcept>

namespace nhdyn {

void compute_residuals(const Model& model, Data& data) {
  if (data.stage < Stage::acceleration)
    throw std::logic_error("compute_residuals: call compute_acceleration first for the current state");
  const Evaluator& ev = *model.evaluator;
  if (data.phi.size() > 0) ev.position_residual(data.t, data.q.data(), data.scratch.data(), data.phi.data());
  if (data.f.size() > 0)
    ev.velocity_residual(data.t, data.q.data(), data.v.data(), data.scratch.data(), data.f.data());
  if (data.sparse)
    data.e.noalias() = data.b_sparse * data.qdd;
  else
    data.e.noalias() = data.b * data.qdd;
  data.e += data.b0;
}

void compute_energy(const Model& model, Data& data) {
  if (data.stage < Stage::terms) throw std::logic_error("compute_energy: call compute_terms first for the current state");
  const Evaluator& ev = *model.evaluator;
  if (ev.has_energy()) data.energy = ev.energy(data.t, data.q.data(), data.v.data(), data.scratch.data());
  if (ev.has_energy_balance())
    data.energy_function = ev.energy_function(data.t, data.q.data(), data.v.data(), data.scratch.data());
}

void fill_energy_balance(const Data& data, double* out) {
  out[0] = data.energy_function;
  out[1] = data.power_forces + data.power_reactions + data.power_time + data.power_friction;
  out[2] = data.work_forces;
  out[3] = data.work_reactions;
  out[4] = data.work_time;
  out[5] = data.work_forces + data.work_reactions + data.work_time + data.work_friction - data.impact_loss;
  out[6] = data.balance_error;
}

void compute_power(const Model& model, Data& data) {
  if (data.stage < Stage::acceleration)
    throw std::logic_error("compute_power: call compute_acceleration first for the current state");
  double out[2] = {0.0, 0.0};
  if (!data.power_is_zero) model.evaluator->power(data.t, data.q.data(), data.v.data(), data.scratch.data(), out);
  data.power_forces = out[0];
  data.power_time = out[1];
  // A sliding contact's friction is booked apart (power_friction, contact_modes.hpp; 0 without).
  data.power_reactions = data.R.dot(data.v) - data.power_friction;
  // A model with programs: R is the physical reactions, and the actuators' forces B u are applied
  // forces doing work like Q_nc (docs/derivations/program-motion.md (P3)): booked with the forces.
  // A loop, not (B u) . v, so that nothing is allocated.
  if (model.m() > 0)
    for (int j = 0; j < model.m(); ++j) data.power_forces += data.motion.u(j) * data.motion.B.col(j).dot(data.v);
}

}  // namespace nhdyn
