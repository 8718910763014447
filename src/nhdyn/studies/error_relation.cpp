#include "nhdyn/studies/error_relation.hpp"

#include <fmt/format.h>

#include <cmath>

#include "nhdyn/core/error.hpp"

namespace nhdyn {

std::string formulation_label(const StudyFormulation& formulation) {
  if (formulation.method != Method::sanh) return std::string(method_name(formulation.method));
  return fmt::format("sanh-{}", complement_name(formulation.complement));
}

ErrorRelation study_error_relation(const Model& model, const ErrorRelationOptions& options) {
  if (options.tolerances.empty()) throw InputError("the error-relation study needs at least one tolerance");
  for (double tol : options.tolerances)
    if (!(tol > 0.0 && std::isfinite(tol)))
      throw InputError(fmt::format("tolerance {} is not a positive number; give tolerances such as 1e-3,1e-6", tol));
  if (!(options.atol_factor > 0.0 && std::isfinite(options.atol_factor)))
    throw InputError(fmt::format("the atol factor {} is not a positive number", options.atol_factor));
  if (options.integrators.empty()) throw InputError("the error-relation study needs at least one integrator");

  ErrorRelation out;
  out.analytic = model.evaluator->has_solution();
  out.tolerances = options.tolerances;
  out.integrators = options.integrators;
  out.formulations = options.formulations;
  if (out.formulations.empty()) {
    out.formulations = {{Method::sanh, Complement::qr}, {Method::sanh, Complement::partition}};
    if (model.evaluator->has_complement()) out.formulations.push_back({Method::sanh, Complement::analytic});
    for (Method m : {Method::lagrange, Method::udwadia_kalaba, Method::nullspace}) out.formulations.push_back({m, Complement::qr});
  }
  for (const StudyFormulation& f : out.formulations)
    if (f.complement == Complement::analytic && !model.evaluator->has_complement())
      throw InputError(fmt::format("model '{}' gives no analytic complement D, so {} cannot run; leave it out",
                                   model.name, formulation_label(f)));

  for (const StudyFormulation& f : out.formulations)
    for (IntegratorKind integrator : out.integrators)
      for (double tol : out.tolerances) {
        ComparisonOptions compare;
        compare.reference = out.analytic ? Reference::analytic : Reference::tight;
        compare.run.t_end = options.t_end > 0.0 ? options.t_end : model.defaults.t_end;
        compare.run.output_step = options.output_step > 0.0 ? options.output_step : model.defaults.output_step;
        compare.run.formulation.method = f.method;
        compare.run.formulation.complement = f.complement;
        compare.run.integrator.rtol = tol;
        compare.run.integrator.atol = options.atol_factor * tol;
        compare.cases = {{f.method, integrator}};
        compare.cost_samples = 0;  // the study measures accuracy, not cost
        const Comparison result = compare_formulations(model, compare);
        const ComparisonResult& r = result.results.front();
        ErrorRelationRun run;
        run.formulation = f;
        run.integrator = integrator;
        run.tolerance = tol;
        run.summary = r.summary;
        run.max_error_q = r.max_error_q;
        run.max_error_v = r.max_error_v;
        run.max_residual_pos = r.summary.max_position_residual;
        run.max_residual_vel = r.summary.max_velocity_residual;
        out.runs.push_back(std::move(run));
      }
  return out;
}

}  // namespace nhdyn
