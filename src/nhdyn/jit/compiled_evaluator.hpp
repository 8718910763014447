// The compiled evaluator: a model's terms tape (the hot path of every right-hand side) turned
// into machine code by the system's C++ compiler, loaded with dlopen and used in place of the
// interpreter. This folder is the only place that runs a compiler or calls dlopen.
//
// The source (jit/detail/source.hpp) is compiled into a shared object cached under
// $XDG_CACHE_HOME/nhdyn (else ~/.cache/nhdyn), named by a hash of the source, the compiler (its
// command and its --version) and the flags, so a second run of the same model loads it without
// compiling, and a parameter change reuses it (parameters are data: the stage is recomputed).
// An object is compiled under a temporary name and renamed into place, so a concurrent process
// never loads a half-written file. Beside it, NAME.so.check holds the key, the size and a hash of
// the object, checked before every dlopen, and the object itself returns its key: a truncated,
// altered or misplaced entry is removed and compiled again with a note (JitReport::note), never
// loaded. An interrupted compile (SIGINT, SIGTERM, SIGHUP, SIGQUIT, SIGUSR1, SIGUSR2) stops the
// compiler's whole process group, removes its source, log and temporary object, and then lets the
// signal take its course. The tapes of an output row go into the same object, so a compiled
// model computes its rows compiled too: the residuals, the energy, h and the power (the
// evaluator's), the contact forces' and the derived outputs' tapes (NativeTape, set on the
// Model's ContactForceModel and ModelOutputs). The other tapes (complement, solution, initial
// state, program constraints) and the parameter handling stay with the interpreter, whose
// TapeEvaluator the compiled evaluator wraps; so every formulation, the sparse path and
// linearization's finite differences work unchanged.
#pragma once

#include <array>
#include <memory>
#include <string>

#include "nhdyn/core/error.hpp"
#include "nhdyn/core/names.hpp"
#include "nhdyn/model/model.hpp"

namespace nhdyn::jit {

// The compiled evaluator could not be made; the message says why.
class JitError : public Error {
 public:
  using Error::Error;
};

enum class EvaluatorChoice { interpreted, compiled, automatic };

// The evaluator choices, once (core/names.hpp): `--evaluator NAME`.
using EvaluatorChoiceInfo = Named<EvaluatorChoice>;
inline constexpr std::array<EvaluatorChoiceInfo, 3> kEvaluatorChoices{
    {{EvaluatorChoice::interpreted, "interpreted"}, {EvaluatorChoice::compiled, "compiled"}, {EvaluatorChoice::automatic, "auto"}}};

// "interpreted" | "compiled" | "auto"; throws InputError naming the value otherwise.
EvaluatorChoice parse_evaluator_choice(const std::string& text);

// `auto` compiles a model whose terms tape has at least this many operations (docs/design.md,
// "Compiled evaluator": below it the compile time is not won back in a typical run).
inline constexpr int kAutoCompileFrom = 1000;

struct JitOptions {
  std::string compiler;  // "" = $NHDYN_CXX, else "c++"
  std::string cache_dir;  // "" = $XDG_CACHE_HOME/nhdyn, else $HOME/.cache/nhdyn
  // `auto` compiles a model the cache lacks in the background (with_evaluator); false: it waits
  // for the compile, as a batch of many runs does, which repays it.
  bool background = true;
};

// What make_compiled happened to do.
struct JitReport {
  bool compiled = false;       // a compiler ran (false: the cached object was loaded)
  double compile_seconds = 0;  // its wall time
  std::string object;          // the shared object's path
  std::string note;            // a cached object found damaged and compiled again, for the user
};

// The model with its terms compiled, sharing everything else. Throws JitError naming the reason
// (no compiler, a failed compile with its first error line, a failed dlopen, a model whose
// evaluator is not a compiled tape, e.g. a hand-written built-in).
Model make_compiled(const Model& model, const JitOptions& options = {}, JitReport* report = nullptr);

// The model with the evaluator `choice` asks for: interpreted returns it unchanged; compiled
// compiles it; automatic, for a terms tape of kAutoCompileFrom operations or more, loads the cached
// object, or else starts compiling it in the background and returns at once, the model running on
// the interpreter until the compiled object is loaded (BackgroundState), with the same results to
// the bit; the compile is stopped, not waited for, when the model goes before it is done.
// A compile that fails (no compiler, a compile error, a failed dlopen, a hand-written model) never
// fails the run: the interpreter is kept and a one-line notice written to `notice` (not printed:
// the caller prints). make_compiled is the call that throws.
Model with_evaluator(const Model& model, EvaluatorChoice choice, std::string* notice = nullptr,
                     const JitOptions& options = {}, JitReport* report = nullptr);

// Whether the model's evaluator is a compiled one.
bool is_compiled(const Model& model);

// `auto` on a model the cache does not hold yet (with_evaluator): where its background compile
// stands. none: the model's evaluator is not such a one (interpreted, compiled, or a model too
// small to compile); compiling: the interpreter runs the model meanwhile; switched: the compiled
// evaluator runs its terms and rows from now on; failed: the interpreter stays.
enum class BackgroundState { none, compiling, switched, failed };
BackgroundState background_state(const Model& model);

// Ends the process groups of the background compiles still running (SIGKILL), for a process about
// to end on a signal: async-signal-safe, so a signal handler may call it (the CLI's do). Their
// files are removed by the next compile in the same cache (a file of a process gone is an orphan).
void stop_background_compiles() noexcept;

// Once the background compile failed (not stopped): the one-line notice the caller prints, as
// with_evaluator's for a failed compile ("nhdyn: notice: using the interpreter (...)"); else "".
std::string background_notice(const Model& model);

}  // namespace nhdyn::jit
