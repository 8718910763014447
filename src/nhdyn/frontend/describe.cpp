#include "nhdyn/frontend/describe.hpp"

#include "nhdyn/symbolic/codegen.hpp"
#include "nhdyn/symbolic/description.hpp"
#include "nhdyn/symbolic/equations.hpp"

namespace nhdyn {

const std::string& description_name(const symbolic::ModelDescription& description) {
  return description.spec().name;
}

int description_coordinates(const symbolic::ModelDescription& description) { return description.spec().n(); }

bool description_gives_complement(const symbolic::ModelDescription& description) {
  return !description.spec().independent.empty() || description.spec().complement.has_value();
}

const symbolic::Spec& description_spec(const symbolic::ModelDescription& description) { return description.spec(); }

std::string format_model_equations(const symbolic::ModelDescription& description, EquationsFormat format) {
  return symbolic::format_equations(description.spec(), description.derivation(),
                                    format == EquationsFormat::latex ? symbolic::EquationFormat::latex
                                                                     : symbolic::EquationFormat::text);
}

std::string generate_model_code(const symbolic::ModelDescription& description, const std::string& namespace_name) {
  symbolic::CodegenOptions options;
  options.namespace_name = namespace_name;
  return symbolic::generate_code(description.spec(), description.derivation(), options);
}

std::string model_code_identifier(const symbolic::ModelDescription& description) {
  return symbolic::make_identifier(description.spec().name);
}

const std::vector<bool>& description_angles(const symbolic::ModelDescription& description) {
  return description.scene().angles;
}

}  // namespace nhdyn
