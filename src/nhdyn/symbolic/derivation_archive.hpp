// A Derivation as bytes and back (GiNaC's archive format), so that a model loaded again need not
// be derived again (frontend/derivation_cache.hpp keeps the bytes between processes). Reading
// links every symbol to the one of the Spec's SymbolTable with its name, so that the expressions
// read are the ones derive() made: compile_model turns them into the same tapes, and a run from a
// derivation read back gives the same bytes as one from a derivation just made.
#pragma once

#include <optional>
#include <string>

#include "nhdyn/symbolic/derivation.hpp"
#include "nhdyn/symbolic/spec.hpp"

namespace nhdyn::symbolic {

// The bytes of `derivation`: a checksum, the names of the symbols it uses, then GiNaC's archive
// of its fields, each shared subexpression once. Empty when it cannot be stored: an expression
// that would not read back as it is, or deeper or larger than reading accepts (1024 levels, ten
// million nodes counted as a tree; the examples' are 20 and 50 000).
std::string archive_derivation(const Derivation& derivation);

// The libraries that make and read a derivation, as they are loaded: "GiNaC 1.8.6, CLN 1.3.6".
std::string derivation_engine();

// The derivation of `bytes`, its symbols those of `symbols`; std::nullopt when the bytes are not
// a whole derivation archive (damaged or cut short: the checksum), use a symbol `symbols` does
// not know or have other sizes (a derivation of another model), or hold what archive_derivation
// never writes (a definition used before it is made, a matrix inside an expression, an
// expression beyond the limits above): bytes made on purpose to pass the checksum are not trusted.
// Its matrices must have the sizes of `spec` (n coordinates, s constraints, m programs), whose
// symbol table it reads with.
std::optional<Derivation> unarchive_derivation(const std::string& bytes, const Spec& spec);

}  // namespace nhdyn::symbolic
