#include "nhdyn/frontend/provenance.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <map>

#include "nhdyn/core/error.hpp"
#include "nhdyn/core/join.hpp"
#include "nhdyn/formulation/formulation.hpp"
#include "nhdyn/integrators/ode.hpp"

namespace nhdyn {

std::string calc_model_hash(const ModelSource& source) {
  return calc_text_hash(source.is_builtin() ? "builtin:" + source.builtin : source.text);
}

namespace {

// What every provenance says of the model: the run's options come after.
Provenance make_model_provenance(const Model& model, const ModelSource& source) {
  Provenance p;
  p.version = nhdyn_version_text();
  p.model = model.name;
  p.model_file = source.is_builtin() ? "built-in" : source.file_name;
  p.model_hash = calc_model_hash(source);
  for (const Parameter& parameter : model.parameters) p.parameters.emplace_back(parameter.name, parameter.value);
  for (std::size_t i = 0; i < model.coordinates.size(); ++i)
    p.initial.emplace_back(model.coordinates[i], model.q0(static_cast<Eigen::Index>(i)));
  for (std::size_t i = 0; i < model.coordinates.size(); ++i)
    p.initial.emplace_back(model.coordinates[i] + "'", model.v0(static_cast<Eigen::Index>(i)));
  return p;
}

}  // namespace

Provenance make_command_provenance(const Model& model, const ModelSource& source, std::string_view command,
                                   std::vector<std::pair<std::string, std::string>> options) {
  Provenance p = make_model_provenance(model, source);
  p.run.emplace_back("command", std::string(command));
  for (auto& option : options) p.run.push_back(std::move(option));
  return p;
}

Provenance make_provenance(const Model& model, const ModelSource& source, const SimulationOptions& options,
                           std::string_view evaluator) {
  Provenance p = make_model_provenance(model, source);
  const auto add = [&](std::string name, std::string value) { p.run.emplace_back(std::move(name), std::move(value)); };
  add("method", std::string(formulation_name(options.formulation.method)));
  add("complement", std::string(complement_name(options.formulation.complement)));
  add("integrator", std::string(integrator_name(options.integrator.kind)));
  add("rtol", fmt::format("{}", options.integrator.rtol));
  add("atol", fmt::format("{}", options.integrator.atol));
  add("step", fmt::format("{}", options.integrator.step));
  add("max_steps", fmt::format("{}", options.integrator.max_steps));
  add("t0", fmt::format("{}", model.t0));
  add("t_end", fmt::format("{}", options.t_end));
  add("output_step", fmt::format("{}", options.output_step));
  add("stabilize", std::string(stabilization_name(options.stabilization)));
  if (options.stabilization == Stabilization::baumgarte) {
    add("baumgarte_alpha", fmt::format("{}", options.formulation.baumgarte.alpha));
    add("baumgarte_beta", fmt::format("{}", options.formulation.baumgarte.beta));
  }
  if (options.stabilization == Stabilization::projection)
    add("projection_tolerance", fmt::format("{}", options.projection.tolerance));
  add("fix_initial", options.fix_initial ? "true" : "false");
  if (options.formulation.program_feedback.enabled)
    add("program_feedback", fmt::format("{},{}", options.formulation.program_feedback.alpha,
                                        options.formulation.program_feedback.beta));
  add("evaluator", std::string(evaluator));
  std::string events;
  for (const Event& e : options.events)
    events += fmt::format("{}{}:{}", events.empty() ? "" : "; ", e.name, e.expression);
  if (!events.empty()) add("events", events);
  return p;
}

ParameterOverrides check_provenance(const Provenance& provenance, const ModelSource& source, const std::string& csv) {
  const std::string hash = calc_model_hash(source);
  const std::string given = source.is_builtin() ? "the built-in model '" + source.builtin + "'" : source.file_name;
  if (hash != provenance.model_hash) {
    const std::string origin =
        provenance.model_file == "built-in" ? "the built-in model '" + provenance.model + "'" : provenance.model_file;
    std::string why = "it is another model";
    if (!source.is_builtin() && provenance.model_file != "built-in") {
      // What differs in the parameters, when the file can still be read: the likeliest edit.
      std::map<std::string, double> run(provenance.parameters.begin(), provenance.parameters.end());
      std::vector<std::string> differences;
      try {
        for (const auto& [name, value] : model_parameters(source)) {
          const auto it = run.find(name);
          if (it == run.end()) differences.push_back(fmt::format("{} (in the file, not in the run)", name));
          else if (it->second != value)
            differences.push_back(fmt::format("{} = {} in the file, {} in the run", name, value, it->second));
          if (it != run.end()) run.erase(it);
        }
        for (const auto& [name, value] : run) differences.push_back(fmt::format("{} (in the run, not in the file)", name));
      } catch (const Error&) {
        differences.clear();
      }
      why = "the model file changed since the run, or is another model";
      if (!differences.empty()) why += "; parameters that differ: " + join(differences);
    }
    throw InputError(fmt::format("{} was written by a run of '{}' from {} (model hash {}), but {} has hash {}: {}. "
                                 "Give --model the model the run used, or run nhdyn simulate again with this one",
                                 csv, provenance.model, origin, provenance.model_hash, given, hash, why));
  }
  // The parameters line names the model's parameters with finite values; an edited one was named
  // as a --set the user never gave.
  std::vector<std::string> known;
  for (const auto& [name, value] : model_parameters(source)) known.push_back(name);
  ParameterOverrides overrides;
  for (const auto& [name, value] : provenance.parameters) {
    if (std::find(known.begin(), known.end(), name) == known.end())
      throw InputError(fmt::format("{}: its '# parameters:' line names '{}', which is not a parameter of model '{}' ({}): "
                                   "the line was edited; run nhdyn simulate again",
                                   csv, name, provenance.model, join(known)));
    if (!std::isfinite(value))
      throw InputError(fmt::format("{}: its '# parameters:' line gives {} = {}, which is not a finite number: the line "
                                   "was edited; run nhdyn simulate again",
                                   csv, name, value));
    overrides.emplace_back(name, value);
  }
  return overrides;
}

}  // namespace nhdyn
