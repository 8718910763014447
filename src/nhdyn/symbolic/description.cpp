#include "nhdyn/symbolic/description.hpp"

#include <chrono>

#include "nhdyn/symbolic/derivation_archive.hpp"

namespace nhdyn::symbolic {

const Derivation& ModelDescription::derivation() const {
  std::call_once(derived_, [this] {
    if (store_)
      if (const std::optional<std::string> bytes = store_->read())
        if (std::optional<Derivation> kept = unarchive_derivation(*bytes, spec_)) {
          derivation_ = std::move(kept);
          read_from_store_ = true;
          return;
        }
    // Derived here (a derivation that fails throws, and nothing is kept).
    const auto start = std::chrono::steady_clock::now();
    derivation_ = derive(spec_);
    const std::chrono::duration<double> took = std::chrono::steady_clock::now() - start;
    if (store_ && store_->wants(took.count(), spec_.n()))
      if (const std::string bytes = archive_derivation(*derivation_); !bytes.empty()) store_->write(bytes);
  });
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
