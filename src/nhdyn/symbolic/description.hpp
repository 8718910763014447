// What the symbolic front end knows of a model file's model, kept beside its Model so that nothing
// is derived twice: the Spec (with the parameter overrides applied), its derivation (the
// matrices A, Q, G, b, b0 that compile_model compiled) and the 3-D scene of its [visual] items.
// frontend/load_model.hpp makes one per load and hands it out as a shared pointer to a const
// object; `nhdyn equations`, `codegen`, `report`, `simulate --html` and the plot's angles read it.
//
//     model file --parse--> Spec --derive--> Derivation --compile_model--> Model
//                           \____________ ModelDescription ____________/
//
// The derivation and the scene are computed on first use, once (std::call_once: one description
// may be read by several threads), so that a command that needs only the Spec (the size check of
// `nhdyn equations`) derives nothing, and one that never draws compiles no scene. A call that
// throws (a [visual] size that depends on q) leaves nothing cached and throws again next time.
#pragma once

#include <mutex>
#include <optional>

#include "nhdyn/model/model.hpp"
#include "nhdyn/symbolic/compile.hpp"
#include "nhdyn/symbolic/derivation.hpp"
#include "nhdyn/symbolic/spec.hpp"
#include "nhdyn/symbolic/visual.hpp"

namespace nhdyn::symbolic {

class ModelDescription {
 public:
  explicit ModelDescription(Spec spec) : spec_(std::move(spec)) {}
  ModelDescription(const ModelDescription&) = delete;
  ModelDescription& operator=(const ModelDescription&) = delete;

  const Spec& spec() const { return spec_; }
  // derive(spec()), the first call derives (its cost: docs/performance.md), later ones return it.
  const Derivation& derivation() const;
  // compile_visual(spec()), compiled on first use; throws as compile_visual.
  const VisualScene& scene() const;
  // compile_model(spec(), derivation(), options): the derivation is the one kept here.
  Model compile(const CompileOptions& options = {}) const;

 private:
  Spec spec_;
  mutable std::once_flag derived_;
  mutable std::optional<Derivation> derivation_;
  mutable std::once_flag drawn_;
  mutable std::optional<VisualScene> scene_;
};

}  // namespace nhdyn::symbolic
