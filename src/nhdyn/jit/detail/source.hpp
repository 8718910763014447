// The C++ source of a model's terms tape for the compiled evaluator (compiled_evaluator.hpp):
// the parametric terms tape (model/tape.hpp) printed as straight-line code behind a C
// interface, so the shared object needs no header of the library and no C++ ABI across dlopen.
// What depends on parameters and constants only (the parameter stage) is a function of its own,
// run once per parameter change; the call reads its results from an array. Operations and their
// order are the tape's, and the source is compiled without contraction into fused
// multiply-adds, so the compiled terms round as the interpreter's do.
// Internal: used by jit/compiled_evaluator.cpp, not part of the public API (nhdyn/nhdyn.hpp).
#pragma once

#include <string>

#include "nhdyn/model/tape.hpp"

namespace nhdyn::jit {

// Bumped whenever the interface below changes: a cached object of another version is rebuilt.
inline constexpr int kInterfaceVersion = 2;

// The functions the source defines (extern "C"):
//   int    nhdyn_jit_version(void)             kInterfaceVersion
//   size_t nhdyn_jit_stage_size(void)          number of doubles the stage writes
//   void   nhdyn_jit_stage(const double* p, double* m)      p: parameter values, m: the stage
//   void   nhdyn_jit_terms(const double* m, double t, const double* q, const double* v,
//                          double* A, double* Q, double* G, double* b, double* b0)
//          A and b as the tape writes them (every entry, or the nonzeros of `sparsity`)
//   void   nhdyn_jit_terms_dense(...)           the same signature, A and b dense (every entry
//          the caller has zeroed); only for a sparse tape
// n, s: the model's dimensions; `sparsity` null for a dense tape.
std::string make_terms_source(const Tape& terms, int n, int s, const TermsSparsity* sparsity);

// Another tape of the model (the contact forces', the derived outputs') to append to the terms'
// source, so that a model's output rows run compiled as its terms do (NativeTape in
// model/tape.hpp). It defines, for NAME:
//   size_t nhdyn_jit_NAME_stage_size(void)
//   void   nhdyn_jit_NAME_stage(const double* p, double* m)
//   void   nhdyn_jit_NAME(const double* m, double t, const double* q, const double* v, double* out)
//          out: the tape's outputs in order (Tape::run's)
std::string make_tape_source(const std::string& name, const Tape& tape);

}  // namespace nhdyn::jit
