#include "nhdyn/model/initial_values.hpp"

#include <fmt/format.h>

#include <cmath>

#include "nhdyn/core/error.hpp"
#include "nhdyn/core/join.hpp"
#include "nhdyn/core/detail/suggest.hpp"
#include "nhdyn/model/parameters.hpp"

namespace nhdyn {

void set_initial_value(Model& model, std::string_view set, std::string_view option) {
  const std::string text(set);
  const std::size_t eq = text.find('=');
  std::string name = eq == std::string::npos ? std::string() : text.substr(0, eq);
  while (!name.empty() && name.back() == ' ') name.pop_back();
  while (!name.empty() && name.front() == ' ') name.erase(0, 1);
  if (eq == std::string::npos || name.empty())
    throw InputError(fmt::format("{} '{}': write it as NAME=VALUE, NAME a coordinate (its initial value) or a "
                                 "coordinate with a prime (its initial velocity), e.g. {} \"phi'=0.5\"",
                                 option, text, option));
  if (name.ends_with("(0)")) name.resize(name.size() - 3);  // batch's x(0), x'(0)
  const bool velocity = name.ends_with("'");
  const std::string coordinate = velocity ? name.substr(0, name.size() - 1) : name;
  int index = -1;
  for (int i = 0; i < model.n(); ++i)
    if (model.coordinates[static_cast<std::size_t>(i)] == coordinate) index = i;
  if (index < 0) {
    std::vector<std::string> known;
    for (const std::string& c : model.coordinates) {
      known.push_back(c);
      known.push_back(c + "'");
    }
    const std::string nearest = nearest_name(name, known);
    throw InputError(fmt::format("{} '{}': '{}' is not a coordinate of model '{}'{}; its coordinates are {} (add a "
                                 "prime for a velocity: {}')",
                                 option, text, coordinate, model.name,
                                 nearest.empty() ? "" : fmt::format(" (did you mean '{}'?)", nearest),
                                 join(model.coordinates), model.coordinates.front()));
  }
  double value = 0.0;
  try {
    value = calc_parameter_expression(std::string_view(text).substr(eq + 1), model.parameters);
  } catch (const InputError& e) {
    throw InputError(fmt::format("{} '{}': {}", option, text, e.what()));
  }
  if (!std::isfinite(value))
    throw InputError(fmt::format("{} '{}': the value is {}; give a finite number", option, text, value));
  (velocity ? model.v0 : model.q0)(index) = value;
}

void apply_initial_values(Model& model, const std::vector<std::string>& sets, std::string_view option) {
  for (const std::string& set : sets) set_initial_value(model, set, option);
}

}  // namespace nhdyn
