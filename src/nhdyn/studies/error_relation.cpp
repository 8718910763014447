#include "nhdyn/studies/error_relation.hpp"

#include <fmt/format.h>

#include <cmath>

#include "nhdyn/core/error.hpp"
#include "nhdyn/studies/run_times.hpp"

namespace nhdyn {

std::string formulation_label(const StudyFormulation& formulation) {
  if (formulation.method != Formulation::sanh) return std::string(formulation_name(formulation.method));
  return fmt::format("sanh-{}", complement_name(formulation.complement));
}

std::vector<StudyFormulation> calc_study_formulations(const Model& model) {
  std::vector<StudyFormulation> out{{Formulation::sanh, Complement::qr}, {Formulation::sanh, Complement::partition}};
  if (model.evaluator->has_complement()) out.push_back({Formulation::sanh, Complement::analytic});
  for (Formulation m : {Formulation::lagrange, Formulation::udwadia_kalaba, Formulation::nullspace}) out.push_back({m, Complement::qr});
  return out;
}

ErrorRelation study_error_relation(const Model& model, const ErrorRelationOptions& options) {
  if (model.s() == 0)
    throw InputError(fmt::format("model '{}' has no constraints, so it has no residual to set beside the error; "
                                 "the error-relation study needs a constrained model",
                                 model.name));
  if (options.tolerances.empty()) throw InputError("the error-relation study needs at least one tolerance");
  for (double tol : options.tolerances)
    if (!(tol > 0.0 && std::isfinite(tol)))
      throw InputError(fmt::format("tolerance {} is not a positive number; give tolerances such as 1e-3,1e-6", tol));
  if (!(options.atol_factor > 0.0 && std::isfinite(options.atol_factor)))
    throw InputError(fmt::format("the atol factor {} is not a positive number", options.atol_factor));
  if (options.integrators.empty()) throw InputError("the error-relation study needs at least one integrator");
  check_study_run_times(model, options.t_end, options.output_step);
  for (std::size_t i = 0; i < options.tolerances.size(); ++i)
    for (std::size_t j = 0; j < i; ++j)
      if (options.tolerances[i] == options.tolerances[j])
        throw InputError(fmt::format("tolerance {} is given twice; give each once", options.tolerances[i]));
  for (std::size_t i = 0; i < options.integrators.size(); ++i) {
    if (options.integrators[i] == IntegratorKind::rk4)
      throw InputError("rk4 takes a fixed step, so its runs do not depend on the tolerance: leave it out of the "
                       "error-relation study (" + adaptive_integrator_names(", ") + " adapt their step)");
    for (std::size_t j = 0; j < i; ++j)
      if (options.integrators[i] == options.integrators[j])
        throw InputError(fmt::format("integrator {} is given twice; give each once", integrator_name(options.integrators[i])));
  }
  for (std::size_t i = 0; i < options.formulations.size(); ++i)
    for (std::size_t j = 0; j < i; ++j)
      if (options.formulations[i].method == options.formulations[j].method &&
          (options.formulations[i].method != Formulation::sanh ||
           options.formulations[i].complement == options.formulations[j].complement))
        throw InputError(fmt::format("formulation {} is given twice; give each once",
                                     formulation_label(options.formulations[i])));

  ErrorRelation out;
  out.analytic = model.evaluator->has_solution();
  out.tolerances = options.tolerances;
  out.integrators = options.integrators;
  out.formulations = options.formulations;
  if (out.formulations.empty()) out.formulations = calc_study_formulations(model);
  for (const StudyFormulation& f : out.formulations)
    if (f.complement == Complement::analytic && !model.evaluator->has_complement())
      throw InputError(fmt::format("model '{}' gives no analytic complement D, so {} cannot run; leave it out",
                                   model.name, formulation_label(f)));

  // Runs are stored formulation by formulation, integrator by integrator, tolerance by tolerance
  // (ErrorRelation::run); one comparison runs every integrator of a (formulation, tolerance).
  const std::size_t I = out.integrators.size(), K = out.tolerances.size();
  out.runs.resize(out.formulations.size() * I * K);
  for (std::size_t f = 0; f < out.formulations.size(); ++f)
    for (std::size_t k = 0; k < K; ++k) {
      const StudyFormulation& formulation = out.formulations[f];
      ComparisonOptions compare;
      compare.reference = out.analytic ? Reference::analytic : Reference::tight;
      compare.run.t_end = options.t_end > 0.0 ? options.t_end : model.defaults.t_end;
      compare.run.output_step = options.output_step > 0.0 ? options.output_step : model.defaults.output_step;
      compare.run.formulation.method = formulation.method;
      compare.run.formulation.complement = formulation.complement;
      compare.run.integrator.rtol = out.tolerances[k];
      compare.run.integrator.atol = options.atol_factor * out.tolerances[k];
      for (IntegratorKind integrator : out.integrators) compare.cases.push_back({formulation.method, integrator});
      compare.cost_samples = 0;  // the study measures accuracy, not cost
      const Comparison result = compare_formulations(model, compare);
      for (std::size_t i = 0; i < I; ++i) {
        const ComparisonResult& r = result.results[i];
        ErrorRelationRun& run = out.runs[(f * I + i) * K + k];
        run.formulation = formulation;
        run.integrator = out.integrators[i];
        run.tolerance = out.tolerances[k];
        run.summary = r.summary;
        run.max_error_q = r.max_error_q;
        run.max_error_v = r.max_error_v;
        run.max_residual_pos = r.summary.residuals.position;
        run.max_residual_vel = r.summary.residuals.velocity;
      }
    }
  return out;
}

}  // namespace nhdyn
