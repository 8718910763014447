// Batch runs: many simulations of one system (other parameter values, other initial states) on a
// pool of threads, each run's output kept as a Trajectory (one row per output time). Models are
// read-only and their evaluators stateless, so runs share them; every run makes its own Data
// inside simulate(), which is the whole thread-safety story (model/data.hpp). Runs are handed out
// one at a time from a shared counter, so a slow run does not hold up a fixed share of the others.
// A run that fails (bad initial state, numerical trouble) reports its status and message in its
// own result and never stops the others. Used by `nhdyn batch` and nhdyn.simulate_batch (Python).
#pragma once

#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "nhdyn/analysis/simulation.hpp"
#include "nhdyn/core/types.hpp"
#include "nhdyn/model/model.hpp"

namespace nhdyn {

// The outputs of one run, each row-major with one row per output time (rows() of them):
// the same quantities, in the same order, as a results CSV (io/results.hpp).
struct Trajectory {
  int n = 0;                        // coordinates
  int residual_columns = 0;         // position + velocity + acceleration residuals
  bool has_energy = false;
  std::vector<double> t;            // rows
  std::vector<double> q, v, qdd, R; // rows x n each
  std::vector<double> residuals;    // rows x residual_columns: phi, then f, then e (Data)
  std::vector<double> energy;       // rows (empty without an energy)
  int balance_columns = 0;          // kEnergyBalanceColumns with an energy balance, else 0
  std::vector<double> balance;      // rows x balance_columns (analysis/residuals.hpp fill_energy_balance)
  // Program motion (docs/derivations/program-motion.md), empty without programs:
  int actuator_columns = 0;            // m
  std::vector<double> u;               // rows x m: the actuator forces (Data::motion.u)
  int program_residual_columns = 0;    // position + velocity + acceleration level program residuals
  std::vector<double> program_residuals;  // rows x program_residual_columns: phi_p, then f_p, then e_p
  // The contact forces and contact_residual (model/contact_forces.hpp), 0 columns without contacts.
  int contact_columns = 0;
  std::vector<double> contact_forces;  // rows x contact_columns
  int output_columns = 0;           // derived outputs, Model::outputs (model/output.hpp)
  std::vector<double> outputs;      // rows x output_columns, in Model::outputs.list order

  long rows() const { return static_cast<long>(t.size()); }
  // Sizes the columns for `model` and drops every row; reserves `expected_rows`.
  void reset(const Model& model, long expected_rows = 0);
  // Appends the row of Data after an output (simulate's RowFn): t, q, q', q'', R, residuals,
  // energy, energy balance, actuator forces, program residuals, contact forces, derived outputs.
  void append(const Data& data);
};

struct BatchRun {
  std::shared_ptr<const Model> model;  // this run's model; runs may share one
  std::optional<Vector> q0, v0;        // n each: initial state replacing the model's
};

struct BatchResult;

struct BatchOptions {
  SimulationOptions simulation;  // the same for every run
  int threads = 0;               // 0: every core (std::thread::hardware_concurrency)
  bool keep_trajectories = true; // false: keep the summaries only (less memory)
  // Called by the calling thread about every 20 ms while the workers run (the calling thread then
  // runs none itself); false stops the batch: no further run starts, the running ones finish, and
  // simulate_batch returns with `interrupted` set in every result not run. For Ctrl-C in Python
  // and the CLI's signals. Empty: the calling thread is one of the workers.
  std::function<bool()> keep_going;
  // Called in the worker thread as soon as run i has finished (from several threads at once: the
  // callee synchronizes). It may take the trajectory away (the CLI streams runs to disk with it);
  // an exception it throws stops the batch as keep_going does and is rethrown by simulate_batch.
  std::function<void(std::size_t, BatchResult&)> on_result;
};

struct BatchResult {
  bool ok = false;               // the run reached t_end
  std::string message;           // empty when ok: the error or the numerical trouble, with t
  SimulationSummary summary;     // steps, residuals, ... (status set when the run started)
  Trajectory trajectory;         // the rows up to where the run ended
  Vector q_end, v_end;           // n, the last output's state (empty when no row was made)
  bool interrupted = false;      // not run: the batch was stopped first (BatchOptions::keep_going)
};

// The most threads a batch uses: four per core (at least 8). A CPU-bound run gains nothing from
// more, and tens of thousands of threads exhaust the system's limits.
int max_batch_threads();
// The one check of a batch's thread count, for the command line (--threads) and Python (threads=)
// alike: throws InputError unless `threads` is 0 (every core) or positive. simulate_batch calls it;
// a caller may call it first to refuse the value before any work.
void check_batch_threads(int threads);
// The number of threads a batch of `runs` runs uses for `threads` (0 = every core), at least 1,
// at most max_batch_threads() and `runs`. Fewer run when the system refuses to create a thread.
int batch_threads(int threads, std::size_t runs);

// The stop conditions that never held in a batch (SimulationSummary::unmet_stops, the sentence
// simulate warns with), each once with the runs it names: "SENTENCE (runs 0, 2 and 5 of 10)", or
// "(every run of 10)"; at most 20 runs are listed, then how many more. `unmet_stops[i]` is run i's.
std::vector<std::string> format_batch_unmet_stops(const std::vector<std::vector<std::string>>& unmet_stops);

// Runs every member; result i belongs to runs[i], whatever the number of threads (the results do
// not depend on it: each run is the same sequential computation). Throws InputError only for
// options that no run could use (a run without a model, an initial state of the wrong size, a
// negative thread count);
// everything specific to a run ends up in its result.
std::vector<BatchResult> simulate_batch(const std::vector<BatchRun>& runs, const BatchOptions& options);

}  // namespace nhdyn
