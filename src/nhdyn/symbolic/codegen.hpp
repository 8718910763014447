// Code generation: a Spec and its Derivation printed as standalone C++ — a header that implements
// nhdyn::Evaluator with straight-line code and a `make_<identifier>_model()` that fills the Model
// as compile_model() does. The code is the compiled tapes (model/tape.hpp) written out, one
// `const double rN = ...;` per instruction, so common subexpressions are shared exactly as in the
// interpreted model and both round alike. The header includes "nhdyn/model/evaluator.hpp",
// "nhdyn/model/model.hpp" and the standard library only (no GiNaC). The output is deterministic:
// it depends on names, values and expressions only, never on GiNaC's term order.
#pragma once

#include <string>

#include "nhdyn/symbolic/derivation.hpp"
#include "nhdyn/symbolic/spec.hpp"

namespace nhdyn::symbolic {

struct CodegenOptions {
  // Namespace of the generated code, "::"-separated identifiers; "" = the global namespace.
  std::string namespace_name = "nhdyn::generated";
  // Base of the generated names (make_<identifier>_model, <Identifier>Evaluator);
  // "" = make_identifier(spec.name).
  std::string identifier;
};

// Turns a model name into a C++ identifier: every run of characters other than letters, digits
// and '_' becomes one '_', leading and trailing '_' go, a leading digit gets "model_" before it,
// a C++ keyword gets a trailing '_'; "" becomes "model". "sled-paper" -> "sled_paper".
std::string make_identifier(const std::string& name);

// The C++ source of a header implementing the model. Throws ModelError as compile_model() does
// (the same checks run), InputError for an invalid namespace or identifier in `options`.
std::string generate_code(const Spec& spec, const Derivation& derivation, const CodegenOptions& options = {});

}  // namespace nhdyn::symbolic
