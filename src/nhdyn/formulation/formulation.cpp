#include "nhdyn/formulation/formulation.hpp"

#include <stdexcept>
#include <string>

#include "nhdyn/core/error.hpp"
#include "nhdyn/core/detail/finite.hpp"
#include "nhdyn/formulation/complement.hpp"
#include "nhdyn/formulation/contact_modes.hpp"
#include "nhdyn/formulation/detail/small_dense.hpp"
#include "nhdyn/formulation/lagrange.hpp"
#include "nhdyn/formulation/nullspace.hpp"
#include "nhdyn/formulation/program_motion.hpp"
#include "nhdyn/formulation/sanh.hpp"
#include "nhdyn/formulation/sparse_lagrange.hpp"
#include "nhdyn/formulation/sparse_sanh.hpp"
#include "nhdyn/formulation/udwadia_kalaba.hpp"
#include "nhdyn/model/terms.hpp"

namespace nhdyn {

std::string_view formulation_name(Formulation method) { return name_of(kFormulations, method); }

Formulation parse_formulation(std::string_view name) {
  if (const FormulationInfo* info = find_named(kFormulations, name)) return info->value;
  throw InputError("unknown method '" + std::string(name) + "'; choose one of: " + list_names(kFormulations));
}

std::string_view complement_name(Complement complement) { return name_of(kComplements, complement); }

Complement parse_complement(std::string_view name) {
  if (const ComplementInfo* info = find_named(kComplements, name)) return info->value;
  throw InputError("unknown choice of D '" + std::string(name) + "'; choose one of: " + list_names(kComplements));
}

namespace {

// The kernels of the common small case, sanh with the QR complement on a small dense model
// without programs, contact modes or Baumgarte terms, in one fused call (small_dense.hpp's
// sanh_qr); null for every other case.
const small::Kernels* fused_kernels(const Model& model, const Data& data, const FormulationOptions& options) {
  if (options.method != Formulation::sanh || options.complement != Complement::qr || options.baumgarte.enabled ||
      data.modes.active || data.sparse || !data.small_kernels || model.m() != 0)
    return nullptr;
  return small::find_kernels(model.n(), model.s());
}

}  // namespace

Status compute_acceleration(const Model& model, Data& data, const FormulationOptions& options) {
  if (data.stage < Stage::terms)
    throw std::logic_error("compute_acceleration: call compute_terms first for the current state");
  if (data.method && *data.method != options.method)
    throw std::logic_error("compute_acceleration: this Data was made for the " + std::string(formulation_name(*data.method)) +
                           " formulation; make one for " + std::string(formulation_name(options.method)) +
                           " (make_data with DataOptions::method)");
  if (data.sparse && !find_value(kFormulations, options.method)->sparse)
    throw std::logic_error("compute_acceleration: the " + std::string(formulation_name(options.method)) +
                           " formulation has no sparse kernels; use sanh or lagrange on the sparse path, or make "
                           "the Data with DataOptions::method = " + std::string(formulation_name(options.method)) +
                           " (the dense path)");
  if (model.m() > 0 && (options.method != Formulation::sanh || data.sparse))
    throw InputError("model '" + model.name + "' has programs ([[programs]]), which only the sanh formulation solves, "
                     "on the dense path (docs/derivations/program-motion.md); choose --method sanh");
  data.has_multipliers = false;
  // The common small case in one fused kernel (small_dense.hpp's sanh_qr): the same operations
  // and checks, in the same order, as the general path below.
  if (const small::Kernels* kernels = fused_kernels(model, data, options)) {
    switch (kernels->sanh_qr(data.A.data(), data.Q.data(), data.G.data(), data.b.data(), data.b0.data(),
                             coordinate_order(data), data.D.data(), data.h.data(), data.qdd.data(), data.R.data())) {
      case small::SanhResult::ok: break;
      case small::SanhResult::dependent_constraints:
        return record_failure(data, Status::dependent_constraints, "constraint matrix b");
      case small::SanhResult::singular:
        return record_failure(data, Status::singular_system, "stacked matrix [D A; b]");
      case small::SanhResult::non_finite_qdd: return record_failure(data, Status::non_finite, "accelerations q''");
      case small::SanhResult::non_finite_R: return record_failure(data, Status::non_finite, "reactions R");
    }
    data.stage = Stage::acceleration;
    ++data.acceleration_solves;
    return Status::ok;
  }
  if (options.baumgarte.enabled) {
    compute_baumgarte_terms(model, data, options.baumgarte);
    data.b0_model = data.b0;
    data.b0 += data.stabilization;
  }
  Status status = Status::ok;
  if (data.modes.active && !data.sparse)
    status = compute_mode_acceleration(model, data);  // contacts that may slide or lift off (contact_modes.hpp)
  else if (data.sparse)
    status = options.method == Formulation::sanh ? compute_sparse_sanh_acceleration(model, data)
                                            : compute_sparse_lagrange_acceleration(model, data);
  else switch (options.method) {
    case Formulation::sanh:
      status = model.m() > 0 ? compute_program_motion(model, data, options.complement, options.program_feedback)
                             : compute_sanh_acceleration(model, data, options.complement);
      break;
    case Formulation::lagrange: status = compute_lagrange_acceleration(model, data); break;
    case Formulation::udwadia_kalaba: status = compute_udwadia_kalaba_acceleration(model, data); break;
    case Formulation::nullspace: status = compute_nullspace_acceleration(model, data, options.complement); break;
  }
  if (options.baumgarte.enabled) data.b0 = data.b0_model;
  if (status != Status::ok) return status;
  const double acc = data.pair_non_finite ? data.pair_non_finite(data.qdd.data(), data.R.data())
                                           : accumulate_non_finite(accumulate_non_finite(0.0, data.qdd), data.R);
  if (acc != 0.0) {
    if (!data.qdd.allFinite()) return record_failure(data, Status::non_finite, "accelerations q''");
    return record_failure(data, Status::non_finite, "reactions R");
  }
  data.stage = Stage::acceleration;
  ++data.acceleration_solves;
  return Status::ok;
}

Status compute_dynamics(const Model& model, Data& data, const FormulationOptions& options, double t,
                        const double* q, const double* v) {
  // The common small case, a right-hand side of an integration, in one pass: the terms from the
  // caller's state, the state stored in Data as it is tested, then the fused kernel. The terms
  // are not tested apart: a NaN or an infinity in A, Q, G, b or b0 always reaches q'' or R, which
  // the kernel tests (IEEE arithmetic, no entry skipped: tests/formulation/small_dense_test.cpp
  // tries every entry), so that finite q'' and R vouch for the terms. A failure of any kind is
  // evaluated again by the separate kernels below, which name it as they always do (the state,
  // then the terms, then the solve).
  if (const small::Kernels* kernels = fused_kernels(model, data, options);
      kernels && (!data.method || *data.method == Formulation::sanh)) {
    const int n = model.n();
    data.t = t;  // as compute_terms: an evaluator that throws leaves no stage claimed
    data.stage = Stage::empty;
    model.evaluator->terms(t, q, v, data.scratch.data(),
                           TermsOut{data.A.data(), data.Q.data(), data.G.data(), data.b.data(), data.b0.data()});
    double* q_data = data.q.data();
    double* v_data = data.v.data();
    double acc = 0.0;
    for (int i = 0; i < n; ++i) {
      acc += q[i] * 0.0 + v[i] * 0.0;  // 0 while both are finite (core/detail/finite.hpp)
      q_data[i] = q[i];
      v_data[i] = v[i];
    }
    if (acc == 0.0 && kernels->sanh_qr(data.A.data(), data.Q.data(), data.G.data(), data.b.data(), data.b0.data(),
                                       coordinate_order(data), data.D.data(), data.h.data(), data.qdd.data(),
                                       data.R.data()) == small::SanhResult::ok) {
      data.status = Status::ok;
      data.has_multipliers = false;
      data.stage = Stage::acceleration;
      ++data.term_evaluations;
      ++data.acceleration_solves;
      return Status::ok;
    }
  }
  const Status status = compute_terms(model, data, t, q, v);
  if (status != Status::ok) return status;
  return compute_acceleration(model, data, options);
}

}  // namespace nhdyn
