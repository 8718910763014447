#include "nhdyn/symbolic/description.hpp"

namespace nhdyn::symbolic {

const Derivation& ModelDescription::derivation() const {
  std::call_once(derived_, [this] { derivation_ = derive(spec_); });
  return *derivation_;
}

const VisualScene& ModelDescription::scene() const {
  std::call_once(drawn_, [this] { scene_ = compile_visual(spec_); });
  return *scene_;
}

Model ModelDescription::compile(const CompileOptions& options) const {
  return compile_model(spec_, derivation(), options);
}

}  // namespace nhdyn::symbolic
