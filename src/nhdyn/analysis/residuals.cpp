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
  if (model.evaluator->has_energy())
    data.energy = model.evaluator->energy(data.t, data.q.data(), data.v.data(), data.scratch.data());
}

}  // namespace nhdyn
