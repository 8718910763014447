#include "nhdyn/symbolic/spec.hpp"

#include <fmt/format.h>

#include <stdexcept>

#include "nhdyn/core/error.hpp"
#include "nhdyn/model/parameters.hpp"
#include "nhdyn/core/detail/suggest.hpp"
#include "nhdyn/symbolic/detail/chain_rule.hpp"

namespace nhdyn::symbolic {

std::string SourceLocation::describe() const {
  if (file.empty() && line == 0) return "";
  std::string out = file.empty() ? std::string("<model>") : file;
  if (line > 0) out += fmt::format(":{}", line);
  if (line > 0 && column > 0) out += fmt::format(":{}", column);
  return out;
}

void throw_model_error(const SourceLocation& where, const std::string& context, const std::string& problem) {
  const std::string location = where.describe();
  throw ModelError((location.empty() ? "" : location + ": ") + (context.empty() ? "" : context + ": ") + problem);
}

SymbolTable::SymbolTable() : t_(GiNaC::symbol("t")) {
  // Before any expression of the model is built: GiNaC then differentiates its functions without
  // an exception per call (detail/chain_rule.hpp).
  detail::install_chain_rule();
  by_name_.emplace("t", t_);
}

int SymbolTable::add_coordinate(const std::string& name) {
  q_.emplace_back(GiNaC::symbol(name));
  v_.emplace_back(GiNaC::symbol(name + "'"));
  a_.emplace_back(GiNaC::symbol(name + "''"));
  r_.emplace_back(GiNaC::symbol("R_" + name));
  by_name_.emplace(name, q_.back());
  by_name_.emplace(name + "'", v_.back());
  by_name_.emplace(name + "''", a_.back());
  return static_cast<int>(q_.size()) - 1;
}

void SymbolTable::add_parameter(const std::string& name) { by_name_.emplace(name, GiNaC::symbol(name)); }

const GiNaC::symbol& SymbolTable::parameter(const std::string& name) const { return symbol_of(by_name_.at(name)); }

std::optional<GiNaC::symbol> SymbolTable::find(const std::string& name) const {
  const auto it = by_name_.find(name);
  if (it == by_name_.end()) return std::nullopt;
  return symbol_of(it->second);
}

const GiNaC::ex* SymbolTable::expression_of(const std::string& name) const {
  const auto it = by_name_.find(name);
  return it == by_name_.end() ? nullptr : &it->second;
}

std::vector<std::string> SymbolTable::names() const {
  std::vector<std::string> out;
  for (const auto& [name, symbol] : by_name_) out.push_back(name);
  return out;
}

GiNaC::symtab SymbolTable::parser_table() const {
  GiNaC::symtab table;
  for (const auto& [name, symbol] : by_name_) table[name] = symbol;
  table["pi"] = GiNaC::Pi;
  return table;
}

GiNaC::lst Spec::parameter_values() const {
  GiNaC::lst values;
  for (const SpecParameter& p : parameters) values.append(symbols.parameter(p.name) == GiNaC::numeric(p.value));
  return values;
}

namespace {

std::vector<Parameter> model_parameters(const std::vector<SpecParameter>& parameters) {
  std::vector<Parameter> out;
  for (const SpecParameter& p : parameters) out.push_back({p.name, p.value, p.unit, p.expression});
  return out;
}

void copy_back(const std::vector<Parameter>& from, std::vector<SpecParameter>& to) {
  for (std::size_t i = 0; i < to.size(); ++i) {
    to[i].value = from[i].value;
    to[i].expression = from[i].expression;
  }
}

}  // namespace

void Spec::set_parameter(const std::string& name, double value) {
  std::vector<Parameter> values = model_parameters(parameters);
  bool found = false;
  for (Parameter& p : values)
    if (p.name == name) {
      check_parameter_value(name, value);
      p.value = value;
      p.expression.clear();
      found = true;
    }
  if (!found) {
    std::vector<std::string> names;
    for (const SpecParameter& p : parameters) names.push_back(p.name);
    const std::string nearest = nearest_name(name, names);
    throw InputError(fmt::format("model '{}' has no parameter '{}'{}", this->name, name,
                                 nearest.empty() ? "" : fmt::format("; did you mean '{}'?", nearest)));
  }
  update_parameters(values, this->name);
  copy_back(values, parameters);
}

void Spec::apply_parameter_sets(const std::vector<std::string>& sets) {
  std::vector<Parameter> values = model_parameters(parameters);
  nhdyn::apply_parameter_sets(values, sets, name);
  copy_back(values, parameters);
}

}  // namespace nhdyn::symbolic
