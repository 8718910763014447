#include "nhdyn/frontend/load_model.hpp"

#include <fmt/format.h>

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "nhdyn/core/error.hpp"
#include "nhdyn/frontend/detail/derivation_cache.hpp"
#include "nhdyn/frontend/model_file.hpp"
#include "nhdyn/io/results.hpp"
#include "nhdyn/model/builtin.hpp"
#include "nhdyn/model/parameters.hpp"
#include "nhdyn/frontend/describe.hpp"
#include "nhdyn/symbolic/description.hpp"
#include "nhdyn/symbolic/rolling_contact.hpp"
#include "nhdyn/symbolic/spec.hpp"

namespace nhdyn {
namespace {

bool looks_like_file(const std::string& source) {
  return source.find('/') != std::string::npos || source.ends_with(".toml") || std::filesystem::exists(source);
}

// The overrides as the command line's --set NAME=EXPR writes them: a number keeps every bit
// (17 significant digits), a string is an expression in numbers, constants and the other
// parameters (model/parameters.hpp).
std::vector<std::string> override_sets(const ParameterOverrides& overrides) {
  std::vector<std::string> sets;
  for (const auto& [name, value] : overrides) {
    if (const double* number = std::get_if<double>(&value))
      sets.push_back(fmt::format("{}={:.17g}", name, *number));
    else
      sets.push_back(fmt::format("{}={}", name, std::get<std::string>(value)));
  }
  return sets;
}

symbolic::Spec load_spec(const ModelSource& source, const ParameterOverrides& overrides) {
  symbolic::Spec spec = load_model_string(source.text, source.file_name);
  spec.apply_parameter_sets(override_sets(overrides));
  // The contact points nhdyn added, found again at the parameters set here.
  if (!overrides.empty()) symbolic::solve_contact_coordinates(spec);
  return spec;
}

// The description of a model file's model, with the store that keeps its derivation between
// processes (detail/derivation_cache.hpp).
std::shared_ptr<const symbolic::ModelDescription> describe(const ModelSource& source,
                                                           const ParameterOverrides& overrides) {
  return std::make_shared<const symbolic::ModelDescription>(
      load_spec(source, overrides), detail::make_derivation_store(source.text, override_sets(overrides)));
}

// A built-in model has no Spec: refused with the path of its model file (and, when `what` is
// given, what it therefore lacks).
void require_file(const ModelSource& source, const char* what = nullptr) {
  if (source.is_builtin()) {
    const std::string file = source.builtin == "sled-paper" ? "sled_paper" : source.builtin;
    throw InputError(fmt::format("'{}' is a built-in model written in C++, with no symbolic form{}; use its model "
                                 "file instead: examples/{}.toml",
                                 source.builtin, what ? fmt::format(", so it has no {}", what) : "", file));
  }
}

}  // namespace

ParameterOverrides parse_parameter_sets(const std::vector<std::string>& sets) {
  ParameterOverrides overrides;
  for (const std::string& set : sets) {
    auto [name, expression] = split_parameter_set(set);
    overrides.emplace_back(std::move(name), std::move(expression));
  }
  return overrides;
}

ModelSource read_model_source(const std::string& source) {
  if (is_builtin_model(source) && !looks_like_file(source)) return ModelSource{source, "", source};
  if (!looks_like_file(source)) make_builtin_model(source);  // throws, listing the built-in models
  return ModelSource{"", read_model_text(source), source};
}

ModelSource model_source_from_text(std::string text, std::string file_name) {
  return ModelSource{"", std::move(text), std::move(file_name)};
}

LoadedModel load_model_described(const ModelSource& source, const ParameterOverrides& overrides) {
  if (source.is_builtin()) {
    Model model = make_builtin_model(source.builtin);
    apply_parameter_sets(model, override_sets(overrides));  // parameters are data: no recompilation
    return {std::move(model), nullptr};
  }
  auto description = describe(source, overrides);
  Model model = description->compile();
  make_result_columns(model);  // refuses a derived output named like another column, at load time
  return {std::move(model), std::move(description)};
}

LoadedModel load_model_argument(const std::string& source, const std::vector<std::string>& sets) {
  return load_model_described(read_model_source(source), parse_parameter_sets(sets));
}

std::shared_ptr<const symbolic::ModelDescription> load_description(const ModelSource& source,
                                                                   const ParameterOverrides& overrides) {
  require_file(source);
  return describe(source, overrides);
}

Model load_model(const ModelSource& source, const ParameterOverrides& overrides) {
  return load_model_described(source, overrides).model;
}

Model load_model(const std::string& source, const ParameterOverrides& overrides) {
  return load_model(read_model_source(source), overrides);
}

Model load_model_text(std::string_view text, const std::string& file_name, const ParameterOverrides& overrides) {
  return load_model(model_source_from_text(std::string(text), file_name), overrides);
}

std::vector<Model> load_model_variants(const ModelSource& source, const ParameterOverrides& overrides,
                                       const std::vector<std::string>& names,
                                       const std::vector<std::vector<double>>& values) {
  // One load (derivation and compilation), then a copy per run with its parameters set: the
  // parameters are data (model/parameters.hpp), so no run recompiles.
  const Model base = load_model(source, overrides);
  for (const std::string& name : names) find_parameter(base, name);  // throws, naming the nearest
  std::vector<Model> models;
  models.reserve(values.size());
  for (std::size_t row = 0; row < values.size(); ++row) {
    if (values[row].size() != names.size())
      throw InputError(fmt::format("run {}: {} parameter values for {} names", row, values[row].size(), names.size()));
    Model model = base;
    for (std::size_t j = 0; j < names.size(); ++j) {
      if (!std::isfinite(values[row][j]))
        throw InputError(fmt::format("run {}: parameter {} = {} is not a finite number", row, names[j], values[row][j]));
      set_parameter(model, names[j], values[row][j]);
    }
    models.push_back(std::move(model));
  }
  return models;
}

std::vector<std::pair<std::string, double>> model_parameters(const ModelSource& source,
                                                             const ParameterOverrides& overrides) {
  std::vector<std::pair<std::string, double>> out;
  if (source.is_builtin()) {
    for (const Parameter& p : load_model(source, overrides).parameters) out.emplace_back(p.name, p.value);
    return out;
  }
  const symbolic::Spec spec = load_spec(source, overrides);
  for (const symbolic::SpecParameter& p : spec.parameters) out.emplace_back(p.name, p.value);
  return out;
}

std::string model_equations(const ModelSource& source, const ParameterOverrides& overrides, EquationsFormat format) {
  require_file(source, "equations to show");
  return format_model_equations(*load_description(source, overrides), format);
}

Sweep sweep_model_parameter(const ModelSource& source, const ParameterOverrides& overrides,
                            const SweepOptions& options) {
  check_sweep_options(options);
  return calc_parameter_sweep(load_model(source, overrides), options);
}

}  // namespace nhdyn
