// The entry points of nhdyn's IPOPT module, libnhdyn_ipopt.so (built from ipopt_solver.cpp), as its
// loader (solver_module.cpp) finds and checks them. IPOPT is loaded at run time, the first time a
// program is solved, so that nhdyn's other commands and `import nhdyn` do not map IPOPT and the
// dozen shared libraries it brings (MUMPS, BLAS, LAPACK, the Fortran runtime, ...), which were
// about a third of a small model's whole run (docs/performance.md).
#pragma once

#include "nhdyn/core/version.hpp"
#include "nhdyn/optimize/nlp.hpp"

namespace nhdyn::ipopt_module {

// The module's file: next to the executable or shared object that loads it (the Python package's
// folder), in <prefix>/lib/nhdyn for the installed command, or in the build tree.
inline constexpr const char* kFileName = "libnhdyn_ipopt.so";

// What the module says it implements. The loader refuses a module that says anything else (one of
// another nhdyn, whose Nlp, NlpOptions or NlpResult may be laid out otherwise): raise the number
// whenever this file or nlp.hpp changes their layout.
inline constexpr const char* kInterface = "nhdyn-ipopt-1 " NHDYN_VERSION;

// extern "C" const char* nhdyn_ipopt_interface(): kInterface, as the module was built.
inline constexpr const char* kInterfaceSymbol = "nhdyn_ipopt_interface";
using InterfaceFunction = const char* (*)();

// extern "C" void nhdyn_ipopt_solve(Nlp&, const NlpOptions&, NlpResult&): solve_nlp (nlp.hpp).
inline constexpr const char* kSolveSymbol = "nhdyn_ipopt_solve";
using SolveFunction = void (*)(Nlp&, const NlpOptions&, NlpResult&);

}  // namespace nhdyn::ipopt_module
