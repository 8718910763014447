// The derived model kept between processes: a model file loaded again (the same text, the same
// --set values, the same nhdyn build) reads its derivation instead of deriving it, which is most of
// a large model's start-up (docs/performance.md, "Start-up"). One file per model under
// $XDG_CACHE_HOME/nhdyn/derivations (else ~/.cache/nhdyn/derivations), named by a hash of its key
// and holding the whole key (the build's identity, the --set values and the model text), compared
// in full before the derivation is read, so that a hash collision or another build's file is never
// used. Written to a temporary file and renamed into place: a reader never sees half a file. A
// file that does not read back is derived again and replaced. Only derivations that cost more than
// reading them back are kept (FileStore::wants: at least 1 ms per coordinate), and only from their
// second load (the first leaves a mark, NAME.seen): a model loaded once pays no archive.
// NHDYN_DERIVATION_CACHE=off turns it off, =always keeps every derivation; a build without a GNU
// build-id (its identity) or without a cache directory has none.
// Internal: frontend/load_model.cpp (and tests/io/derivation_cache_test.cpp).
#pragma once

#include <memory>
#include <string>
#include <vector>

namespace nhdyn::symbolic {
class DerivationStore;  // symbolic/description.hpp
}

namespace nhdyn::detail {

// The store for a model file's text and its overrides (as --set writes them), or nullptr when
// the cache is off or unavailable.
std::shared_ptr<const symbolic::DerivationStore> make_derivation_store(const std::string& text,
                                                                       const std::vector<std::string>& sets);

// The GNU build-id of the object (executable or shared library) that holds nhdyn's code, as hex;
// "" when it has none.
std::string build_identity();

}  // namespace nhdyn::detail
