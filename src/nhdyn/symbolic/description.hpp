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

#include <memory>
#include <mutex>
#include <optional>
#include <string>

#include "nhdyn/model/model.hpp"
#include "nhdyn/symbolic/compile.hpp"
#include "nhdyn/symbolic/derivation.hpp"
#include "nhdyn/symbolic/spec.hpp"
#include "nhdyn/symbolic/visual.hpp"

namespace nhdyn::symbolic {

// Where a derivation is kept between loads of the same model (frontend/detail/derivation_cache.hpp:
// a file in the user's cache). Without one, every load derives.
class DerivationStore {
 public:
  virtual ~DerivationStore() = default;
  // The bytes kept for this model (archive_derivation), if any.
  virtual std::optional<std::string> read() const = 0;
  // Whether a derivation that took `seconds` for `coordinates` coordinates is worth keeping
  // (asked before it is archived: the archive costs time too).
  virtual bool wants(double seconds, int coordinates) const = 0;
  // Keeps them for the next load; a store that cannot write keeps nothing and says nothing.
  virtual void write(const std::string& bytes) const = 0;
};

class ModelDescription {
 public:
  explicit ModelDescription(Spec spec, std::shared_ptr<const DerivationStore> store = nullptr)
      : spec_(std::move(spec)), store_(std::move(store)) {}
  ModelDescription(const ModelDescription&) = delete;
  ModelDescription& operator=(const ModelDescription&) = delete;

  const Spec& spec() const { return spec_; }
  // derive(spec()), the first call derives (its cost: docs/performance.md), later ones return it.
  // With a store, the first call reads the derivation kept there instead when the store has one
  // that reads back (derivation_archive.hpp), and keeps the one it derives otherwise.
  const Derivation& derivation() const;
  // Whether derivation() read its derivation from the store (false before the first call).
  bool derivation_was_stored() const { return read_from_store_; }
  // compile_visual(spec()), compiled on first use; throws as compile_visual.
  const VisualScene& scene() const;
  // compile_model(spec(), derivation(), options): the derivation is the one kept here.
  Model compile(const CompileOptions& options = {}) const;

 private:
  Spec spec_;
  std::shared_ptr<const DerivationStore> store_;
  mutable bool read_from_store_ = false;
  mutable std::once_flag derived_;
  mutable std::optional<Derivation> derivation_;
  mutable std::once_flag drawn_;
  mutable std::optional<VisualScene> scene_;
};

}  // namespace nhdyn::symbolic
