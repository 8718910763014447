// libFuzzer target for the model-file loader: any bytes go through the front door the CLI uses
// (frontend/load_model.hpp: parse, parameter values and their expressions, derivation,
// compilation of the terms, [outputs], [[events]], [[programs]] and contacts, the result columns).
// A file that loads is then run the way `nhdyn simulate` starts a run, over one short output step
// (a few steps at most): the initial-state checks, the events at the start, the dynamics (with the
// programs' actuators), the outputs and contact forces at each row. A small model also gets its
// equations printed as `nhdyn equations` does.
//
// Every rejection must be an nhdyn::Error (the CLI's exit 2); any other exception is what the CLI
// reports as "internal error" with exit 3, and aborts here, as do a crash, a leak and undefined
// behaviour. An input that takes more than 10 s is a bug too (fuzz/run: -timeout=10).
// Built and run by fuzz/run (see fuzz/CMakeLists.txt).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <string>
#include <string_view>

#include "nhdyn/analysis/run_options.hpp"
#include "nhdyn/analysis/simulation.hpp"
#include "nhdyn/core/error.hpp"
#include "nhdyn/frontend/describe.hpp"
#include "nhdyn/frontend/load_model.hpp"
#include "nhdyn/model/data.hpp"

namespace {

// Models up to this many coordinates get their equations printed: the printed matrices grow as
// n^2 and the CLI's own limit (1000) is far beyond what one fuzz input may spend.
constexpr int kEquationsUpTo = 24;

void run_briefly(const nhdyn::Model& model) {
  nhdyn::SimulationOptions options = nhdyn::make_simulation_options(model);
  options.events = model.events;
  // One output step, short enough that a stiff or fast model takes few steps, and a step budget
  // that bounds the work whatever the model does.
  const double span = std::isfinite(model.defaults.output_step) && model.defaults.output_step > 0
                          ? std::min(model.defaults.output_step, 1e-3)
                          : 1e-3;
  options.t_end = model.t0 + span;
  options.output_step = span;
  options.integrator.max_steps = 200;
  // The rows (outputs and contact forces computed for each, as for a CSV row) are not kept.
  nhdyn::simulate(model, options, [](const nhdyn::Data&) {});
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  // NHDYN_FUZZ_VERBOSE=1: why an input was refused, and the time of each stage (for a replay).
  const bool verbose = std::getenv("NHDYN_FUZZ_VERBOSE") != nullptr;
  auto start = std::chrono::steady_clock::now();
  const auto stage = [&](const char* what) {
    const auto now = std::chrono::steady_clock::now();
    if (verbose) std::fprintf(stderr, "%s: %.3f s\n", what, std::chrono::duration<double>(now - start).count());
    start = now;
  };
  try {
    const nhdyn::LoadedModel loaded =
        nhdyn::load_model_described(nhdyn::model_source_from_text(std::string(text), "fuzz.toml"));
    stage("load (parse, derive, compile)");
    if (loaded.description && loaded.model.n() <= kEquationsUpTo) {
      (void)nhdyn::format_model_equations(*loaded.description, nhdyn::EquationsFormat::text);
      stage("equations");
    }
    run_briefly(loaded.model);
    stage("short run");
  } catch (const nhdyn::Error& e) {
    if (verbose) std::fprintf(stderr, "refused: %s\n", e.what());
    // A clear rejection: what the loader and the run's checks are for.
  } catch (const std::exception& e) {
    std::fprintf(stderr, "internal error (the CLI would exit 3): %s\n", e.what());
    std::abort();
  }
  return 0;
}
