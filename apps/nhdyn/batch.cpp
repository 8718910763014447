// `nhdyn batch MODEL --grid NAME=FROM:TO:COUNT ... | --runs runs.csv`: many runs of one model on a
// pool of threads (analysis/batch.hpp), one summary row per run (its parameters and initial
// values, status, final state, largest residuals, message) and optionally every run's CSV.
// A NAME is a parameter of the model file, or an initial value: x(0) for a coordinate, x'(0) for
// a velocity. Runs that fail are reported in the summary; the others are kept (exit 1 if any failed).
#include <fmt/format.h>
#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <cerrno>
#include <cfloat>
#include <cmath>
#include <csignal>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "commands.hpp"
#include "nhdyn/core/shown_text.hpp"
#include "run_files.hpp"
#include "run_overrides.hpp"
#include "nhdyn/analysis/batch.hpp"
#include "nhdyn/analysis/run_options.hpp"
#include "nhdyn/core/error.hpp"
#include "nhdyn/core/join.hpp"
#include "nhdyn/io/atomic_file.hpp"
#include "nhdyn/io/csv.hpp"
#include "nhdyn/frontend/load_model.hpp"
#include "nhdyn/frontend/provenance.hpp"
#include "nhdyn/io/results.hpp"
#include "nhdyn/jit/compiled_evaluator.hpp"

namespace nhdyn::cli {
namespace {

struct BatchArgs {
  std::string model;
  std::vector<std::string> grids;
  std::string runs_csv;
  std::vector<std::string> sets;
  int threads = 0;
  std::string output = "batch";
  bool write_runs = false;
  std::optional<double> t_end, output_step, rtol, atol;
  std::optional<std::string> method, complement, integrator;
  bool quiet = false;
  std::string evaluator = "interpreted";  // interpreted | compiled | auto (jit/compiled_evaluator.hpp)
};

// What a column of the batch sets: a parameter, or the initial coordinate / velocity `index`.
struct Varied {
  std::string name;
  enum Kind { parameter, coordinate, velocity } kind = parameter;
  int index = -1;
};

Varied classify(const std::string& name, const Model& model) {
  Varied v{name};
  const bool velocity = name.ends_with("'(0)");
  if (velocity || name.ends_with("(0)")) {
    const std::string coordinate = name.substr(0, name.size() - (velocity ? 4 : 3));
    for (int i = 0; i < model.n(); ++i)
      if (model.coordinates[static_cast<std::size_t>(i)] == coordinate) {
        v.kind = velocity ? Varied::velocity : Varied::coordinate;
        v.index = i;
        return v;
      }
    std::string names;
    for (const std::string& c : model.coordinates) names += (names.empty() ? "" : ", ") + c;
    throw InputError(fmt::format("'{}': '{}' is not a coordinate of model '{}'; its coordinates are {}", name,
                                 coordinate, model.name, names));
  }
  return v;  // a parameter: load_model_variants checks the name
}

double parse_number(const std::string& text, const std::string& what) {
  char* end = nullptr;
  errno = 0;
  const double value = std::strtod(text.c_str(), &end);
  const bool whole = end != text.c_str() && end == text.c_str() + text.size();
  // Below the normal range (1e-320), as the parameters' own reader says it (model/parameters.cpp).
  if (whole && (value != 0.0 || errno == ERANGE) && std::abs(value) < DBL_MIN)
    throw InputError(fmt::format("{}: the number {} is subnormal: below 2.2e-308 a double loses precision; write 0 or "
                                 "a normal number",
                                 what, text));
  if (!whole || !std::isfinite(value) || errno == ERANGE)
    throw InputError(fmt::format("{}: '{}' is not a finite number", what, text));
  return value;
}

// NAME=FROM:TO:COUNT -> COUNT values, both ends included.
std::pair<std::string, std::vector<double>> parse_grid(const std::string& grid) {
  const std::size_t eq = grid.find('=');
  const std::string hint = "write it as NAME=FROM:TO:COUNT, e.g. --grid v=0:10:101";
  if (eq == std::string::npos || eq == 0) throw InputError(fmt::format("--grid '{}': {}", grid, hint));
  const std::string name = grid.substr(0, eq);
  std::vector<std::string> parts;
  std::string rest = grid.substr(eq + 1);
  for (std::size_t at = rest.find(':'); at != std::string::npos; at = rest.find(':')) {
    parts.push_back(rest.substr(0, at));
    rest = rest.substr(at + 1);
  }
  parts.push_back(rest);
  if (parts.size() != 3) throw InputError(fmt::format("--grid '{}': {}", grid, hint));
  const double from = parse_number(parts[0], "--grid " + name + " FROM");
  const double to = parse_number(parts[1], "--grid " + name + " TO");
  const double count = parse_number(parts[2], "--grid " + name + " COUNT");
  if (count < 1 || count > 1e7 || count != std::floor(count))
    throw InputError(fmt::format("--grid '{}': COUNT = {} must be a whole number from 1 to 10000000", grid, parts[2]));
  if (count == 1 && from != to)
    throw InputError(fmt::format("--grid '{}': one value needs FROM = TO", grid));
  std::vector<double> values(static_cast<std::size_t>(count));
  for (std::size_t i = 0; i < values.size(); ++i)
    values[i] = values.size() == 1 ? from
                                   : from + (to - from) * static_cast<double>(i) / static_cast<double>(values.size() - 1);
  return {name, values};
}

std::string csv_text(const std::string& text) {
  if (text.find_first_of(",\"\n") == std::string::npos) return text;
  std::string out = "\"";
  for (char c : text) {
    if (c == '"') out += '"';
    out += c == '\n' ? ' ' : c;
  }
  return out + "\"";
}

// A folder that held an earlier batch's run files keeps those this batch does not replace (they are
// not its own to remove): said once, so that they are not read as this batch's.
void note_other_run_files(const std::filesystem::path& dir, std::size_t runs, int digits) {
  std::vector<std::string> others;
  std::error_code ec;
  for (const auto& entry : std::filesystem::directory_iterator(dir, ec)) {
    const std::string name = entry.path().filename().string();
    if (!name.starts_with("run_") || !name.ends_with(".csv")) continue;
    const std::string number = name.substr(4, name.size() - 8);
    const bool ours = !number.empty() && std::all_of(number.begin(), number.end(), [](unsigned char c) { return std::isdigit(c) != 0; }) &&
                      number.size() == static_cast<std::size_t>(digits) && std::stoull(number) < runs;
    if (!ours) others.push_back(name);
  }
  if (others.empty()) return;
  std::sort(others.begin(), others.end());
  fmt::print(stderr, "nhdyn: note: {} also holds {} run file{} not of this batch of {} runs ({}{}); they were left as they were\n",
             dir.string(), others.size(), others.size() == 1 ? "" : "s", runs, others.front(),
             others.size() > 1 ? ", ..., " + others.back() : std::string());
}

void print_batch_outcome(const BatchArgs& args, const Model& base, const std::vector<BatchResult>& results, long failed,
                         const std::filesystem::path& dir) {
  // The constraint watch (analysis/constraint_watch.hpp): the first run's warnings that has any,
  // and how many runs warned, whatever -q says.
  std::size_t warned = 0;
  for (std::size_t r = 0; r < results.size(); ++r) {
    if (results[r].summary.warnings.empty()) continue;
    if (warned++ == 0)
      for (const std::string& w : results[r].summary.warnings) fmt::print(stderr, "nhdyn: warning: run {}: {}\n", r, w);
  }
  if (warned > 1) fmt::print(stderr, "nhdyn: warning: {} of {} runs had warnings\n", warned, results.size());
  // A stiff stretch (analysis/simulation_summary.hpp): the first run's words and how many runs had one.
  std::size_t stiff = 0;
  for (std::size_t r = 0; r < results.size(); ++r)
    if (!results[r].summary.stiffness.empty() && stiff++ == 0)
      fmt::print(stderr, "nhdyn: warning: run {}: {}\n", r, results[r].summary.stiffness);
  if (stiff > 1) fmt::print(stderr, "nhdyn: warning: {} of {} runs were stiff\n", stiff, results.size());
  // A stop condition that never held, in simulate's words, once with the runs it names.
  std::vector<std::vector<std::string>> unmet(results.size());
  for (std::size_t r = 0; r < results.size(); ++r) unmet[r] = results[r].summary.events.unmet_stops;
  for (const std::string& w : format_batch_unmet_stops(unmet)) fmt::print(stderr, "nhdyn: warning: {}\n", w);
  if (!args.quiet) {
    fmt::print("nhdyn batch {}: {} runs on {} threads, {} failed -> {}\n", base.name, results.size(),
               batch_threads(args.threads, results.size()), failed, shown_text((dir / "summary.csv").string()));
    for (std::size_t r = 0; r < results.size() && failed > 0; ++r)
      if (!results[r].ok) {
        fmt::print(stderr, "nhdyn: run {} failed: {}\n", r, results[r].message);
        break;
      }
  }
}

// The table of runs: one column per name, one row per run, from the grids (every combination, the
// first grid varying slowest) or the --runs CSV.
void make_run_table(const BatchArgs& args, std::vector<std::string>& names, std::vector<std::vector<double>>& table) {
  if (!args.grids.empty()) {
    std::vector<std::vector<double>> grids;
    double product = 1.0;  // checked before any combination is built
    for (const std::string& grid : args.grids) {
      auto [name, values] = parse_grid(grid);
      for (const std::string& known : names)
        if (known == name) throw InputError(fmt::format("--grid {}: given twice", name));
      names.push_back(name);
      product *= static_cast<double>(values.size());
      if (product > 1e7)
        throw InputError(fmt::format("--grid: the grids make more than 10000000 runs ({:.3g} so far, at --grid {}); "
                                     "use fewer values",
                                     product, name));
      grids.push_back(std::move(values));
    }
    table.assign(1, {});
    for (const std::vector<double>& values : grids) {
      std::vector<std::vector<double>> next;
      next.reserve(table.size() * values.size());
      for (const std::vector<double>& row : table)
        for (double value : values) {
          next.push_back(row);
          next.back().push_back(value);
        }
      table = std::move(next);
    }
    return;
  }
  const CsvTable csv = load_csv(args.runs_csv);
  if (csv.header.empty()) throw InputError(fmt::format("{}: no header naming the columns", args.runs_csv));
  for (std::size_t j = 0; j < csv.header.size(); ++j)
    for (std::size_t k = 0; k < j; ++k)
      if (csv.header[j] == csv.header[k])
        throw InputError(fmt::format("{}: the column '{}' is given twice (columns {} and {}); keep one", args.runs_csv,
                                     csv.header[j], k + 1, j + 1));
  names = csv.header;
  table = csv.rows;
  if (table.empty()) throw InputError(fmt::format("{}: no runs (the file has a header and no rows)", args.runs_csv));
}

// One run's rows as CSV, in the columns of `nhdyn simulate`.
void write_run_file(const std::filesystem::path& path, const Model& model, const Trajectory& tr,
                    const std::string& provenance) {
  // Written on the batch's worker thread, every row there: the other workers have the other cores.
  CsvWriter writer(path, make_result_columns(model).all, provenance, false);
  std::vector<double> row;
  const auto slice = [&row](const std::vector<double>& column, std::size_t k, std::size_t width) {
    row.insert(row.end(), column.begin() + static_cast<std::ptrdiff_t>(k * width),
               column.begin() + static_cast<std::ptrdiff_t>((k + 1) * width));
  };
  const auto n = static_cast<std::size_t>(tr.n);
  for (std::size_t k = 0; k < static_cast<std::size_t>(tr.rows()); ++k) {
    row.clear();
    row.push_back(tr.t[k]);
    for (const std::vector<double>* column : {&tr.q, &tr.v, &tr.qdd, &tr.R}) slice(*column, k, n);
    slice(tr.residuals, k, static_cast<std::size_t>(tr.residual_columns));
    if (tr.has_energy) row.push_back(tr.energy[k]);
    slice(tr.balance, k, static_cast<std::size_t>(tr.balance_columns));
    slice(tr.u, k, static_cast<std::size_t>(tr.actuator_columns));
    slice(tr.program_residuals, k, static_cast<std::size_t>(tr.program_residual_columns));
    slice(tr.contact_forces, k, static_cast<std::size_t>(tr.contact_columns));
    slice(tr.outputs, k, static_cast<std::size_t>(tr.output_columns));
    writer.write_row(row);
  }
  writer.commit();
}

// The batch's signals: a stopping signal only sets a flag, so that the batch stops handing out
// runs, the staging directory is removed whole and the process then exits 128 + the signal.
std::atomic<int> batch_signal{0};
extern "C" void on_batch_signal(int sig) { batch_signal.store(sig); }
constexpr int kBatchSignals[] = {SIGINT, SIGTERM, SIGHUP, SIGQUIT, SIGUSR1, SIGUSR2};

void install_batch_signal_handlers() {
  struct sigaction action{};
  action.sa_handler = on_batch_signal;
  sigemptyset(&action.sa_mask);
  for (int sig : kBatchSignals) ::sigaction(sig, &action, nullptr);
}

const char* signal_name(int sig) {
  switch (sig) {
    case SIGINT: return "SIGINT";
    case SIGTERM: return "SIGTERM";
    case SIGHUP: return "SIGHUP";
    case SIGQUIT: return "SIGQUIT";
    case SIGUSR1: return "SIGUSR1";
    default: return "SIGUSR2";
  }
}

std::string summary_line(std::size_t r, const std::vector<double>& values, const BatchResult& res, const Model& base) {
  std::string line = std::to_string(r);
  for (double value : values) line += fmt::format(",{}", value);
  line += res.ok ? ",ok" : ",failed";
  line += fmt::format(",{}", res.summary.t_reached);
  for (int i = 0; i < base.n(); ++i) line += res.q_end.size() == base.n() ? fmt::format(",{}", res.q_end(i)) : ",";
  for (int i = 0; i < base.n(); ++i) line += res.v_end.size() == base.n() ? fmt::format(",{}", res.v_end(i)) : ",";
  line += fmt::format(",{},{},{},{}\n", res.summary.residuals.position, res.summary.residuals.velocity,
                      res.summary.residuals.acceleration, csv_text(res.message));
  return line;
}

// The runs' models: one per run when parameters vary, else the base shared; initial values set.
std::vector<BatchRun> make_runs(const BatchArgs& args, const ModelSource& source, const ParameterOverrides& overrides,
                                const Model& base, const std::vector<std::string>& names,
                                const std::vector<std::vector<double>>& table) {
  std::vector<Varied> varied;
  std::vector<std::string> parameter_names;
  for (const std::string& name : names) {
    varied.push_back(classify(name, base));
    if (varied.back().kind == Varied::parameter) parameter_names.push_back(name);
  }
  std::vector<std::vector<double>> parameter_values(table.size());
  for (std::size_t r = 0; r < table.size(); ++r)
    for (std::size_t j = 0; j < names.size(); ++j)
      if (varied[j].kind == Varied::parameter) parameter_values[r].push_back(table[r][j]);
  std::vector<BatchRun> runs(table.size());
  std::vector<Model> models;
  if (!parameter_names.empty()) models = load_model_variants(source, overrides, parameter_names, parameter_values);
  // The compiled evaluator is made once; each variant rebinds it to its parameter values.
  // `auto` waits for the compile here: a batch's many runs repay it, and its variants are rebound
  // to the compiled object below.
  std::string notice;
  jit::JitOptions jit_options;
  jit_options.background = false;
  const Model chosen = jit::with_evaluator(base, jit::parse_evaluator_choice(args.evaluator), &notice, jit_options);
  if (!notice.empty()) fmt::print(stderr, "{}\n", notice);
  if (jit::is_compiled(chosen))
    for (Model& m : models) {
      std::vector<double> values;
      for (const Parameter& p : m.parameters) values.push_back(p.value);
      m.evaluator = chosen.evaluator->with_parameters(values.data(), values.size());
    }
  std::shared_ptr<const Model> shared = parameter_names.empty() ? std::make_shared<const Model>(chosen) : nullptr;
  for (std::size_t r = 0; r < table.size(); ++r) {
    runs[r].model = shared ? shared : std::make_shared<const Model>(std::move(models[r]));
    for (std::size_t j = 0; j < names.size(); ++j) {
      if (varied[j].kind == Varied::coordinate) {
        if (!runs[r].q0) runs[r].q0 = runs[r].model->q0;
        (*runs[r].q0)(varied[j].index) = table[r][j];
      } else if (varied[j].kind == Varied::velocity) {
        if (!runs[r].v0) runs[r].v0 = runs[r].model->v0;
        (*runs[r].v0)(varied[j].index) = table[r][j];
      }
    }
  }
  return runs;
}

// Every input (the model file, the --runs table) checked against every output the batch may write
// (summary.csv, run_N.csv), by name, link or inode, before any run (run_files.hpp); the output
// folder made, and the summary opened in it.
AtomicFile& open_batch_files(RunFiles& files, const BatchArgs& args, const std::filesystem::path& dir,
                             std::size_t runs, int digits) {
  files.input(args.runs_csv, "--runs");
  files.output(dir / "summary.csv", "the summary", Folder::make);
  if (args.write_runs)
    files.numbered_outputs(runs, [dir, digits](std::size_t r) { return dir / fmt::format("run_{:0{}}.csv", r, digits); },
                           "--write-runs");
  files.check();
  return files.open(dir / "summary.csv");  // checks the directory is writable before any run
}

// --threads: 0 is every core (checked by the library); more than the machine runs is capped, with a note.
void note_batch_threads(int threads) {
  check_batch_threads(threads);
  if (threads > max_batch_threads())
    fmt::print(stderr, "nhdyn: note: --threads {}: this machine has {} cores; using at most {} threads\n", threads,
               std::max(1U, std::thread::hardware_concurrency()), max_batch_threads());
}

// The summary's provenance and column names: the run, its varied names, its outcome, its final
// state and residuals.
std::string summary_header(const std::string& provenance, const std::vector<std::string>& names, const Model& base) {
  std::string header = provenance + "run";
  for (const std::string& name : names) header += "," + csv_text(name);
  header += ",status,t_reached";
  for (const std::string& c : base.coordinates) header += "," + csv_text(c);
  for (const std::string& c : base.coordinates) header += "," + csv_text(c + "'");
  header += ",max_residual_pos,max_residual_vel,max_residual_acc,message\n";
  return header;
}

// The options of every run: the model's, the command line's overrides, the file's [[events]];
// checked whole before any file is made.
BatchOptions make_batch_options(const Model& base, const BatchArgs& args) {
  BatchOptions options;
  options.simulation = make_simulation_options(run_options_with(base, args));
  options.simulation.events = base.events;  // the file's [[events]], as simulate and Python's batch honour them
  options.threads = args.threads;
  options.keep_trajectories = args.write_runs;
  check_simulation_options(base, options.simulation);
  return options;
}

// summary.csv: its provenance and header, then one line per run. Returns how many runs failed.
long write_summary(AtomicFile& summary, const std::string& provenance, const std::vector<std::string>& names,
                   const std::vector<std::vector<double>>& table, const std::vector<BatchResult>& results,
                   const Model& base) {
  summary.write(summary_header(provenance, names, base));
  long failed = 0;
  for (std::size_t r = 0; r < results.size(); ++r) {
    failed += results[r].ok ? 0 : 1;
    summary.write(summary_line(r, table[r], results[r], base));
  }
  return failed;
}

// An interrupted batch writes nothing: the staged run files and the summary's temporary go, and
// the process ends as the signal would have ended it.
[[noreturn]] void exit_interrupted(int sig, RunFiles& files) {
  files.discard();           // the staged run files and the summary's temporary (_exit runs no destructor)
  remove_temporary_files();  // and any other file under way
  fmt::print(stderr, "\nnhdyn: batch interrupted by {}; nothing was written (no summary, no run files)\n",
             signal_name(sig));
  std::signal(sig, SIG_DFL);
  ::_exit(128 + sig);
}

int run_batch(const BatchArgs& args) {
  if (args.grids.empty() == args.runs_csv.empty())
    throw InputError("give the runs either as --grid NAME=FROM:TO:COUNT (repeatable) or as --runs FILE.csv");
  note_batch_threads(args.threads);
  RunFiles files(args.model);
  const ParameterOverrides overrides = parse_parameter_sets(args.sets);  // each given to every run
  const ModelSource source = read_model_source(args.model);
  const Model base = load_model(source, overrides);
  std::vector<std::string> names;
  std::vector<std::vector<double>> table;
  make_run_table(args, names, table);

  BatchOptions options = make_batch_options(base, args);

  namespace fs = std::filesystem;
  const fs::path dir(args.output);
  const int digits = static_cast<int>(std::to_string(std::max<std::size_t>(table.size(), 1) - 1).size());
  // From the first file made in the output folder on, a signal ends the batch through its own
  // handlers (every signal of kBatchSignals, all files removed, "nothing was written").
  install_batch_signal_handlers();
  AtomicFile& summary = open_batch_files(files, args, dir, table.size(), digits);
  const std::vector<BatchRun> runs = make_runs(args, source, overrides, base, names, table);
  if (const int sig = batch_signal.load()) exit_interrupted(sig, files);
  // Every file says what made it (io/provenance.hpp): the summary the batch's model and options
  // and its table of runs; each run's file that run's parameters and initial state, as simulate's.
  const auto batch_provenance = [&](const Model& model) {
    Provenance p = make_provenance(model, source, options.simulation, args.evaluator);
    p.run.emplace_back("runs", args.runs_csv.empty() ? join(args.grids, " ") : args.runs_csv);
    return p;
  };
  const std::string summary_provenance = format_provenance(batch_provenance(base));
  const auto run_provenance = [&](std::size_t r) {
    Provenance p = batch_provenance(*runs[r].model);
    const std::size_t n = base.coordinates.size();
    for (std::size_t i = 0; i < n; ++i) {
      if (runs[r].q0) p.initial[i].second = (*runs[r].q0)(static_cast<Eigen::Index>(i));
      if (runs[r].v0) p.initial[n + i].second = (*runs[r].v0)(static_cast<Eigen::Index>(i));
    }
    p.run.emplace_back("batch_run", std::to_string(r));
    return format_provenance(p);
  };

  // Each run's file is written as soon as the run ends (not kept in memory), into a staging
  // directory; the files are moved into place when every run has ended and been written.
  if (args.write_runs) {
    const fs::path staging = files.staging_folder(dir, "-o");
    options.on_result = [&, staging](std::size_t r, BatchResult& result) {
      if (result.trajectory.rows() > 0)
        write_run_file(staging / fmt::format("run_{:0{}}.csv", r, digits), *runs[r].model, result.trajectory,
                       run_provenance(r));
      result.trajectory = Trajectory{};
    };
  }
  options.keep_going = [] { return batch_signal.load() == 0; };
  const std::vector<BatchResult> results = simulate_batch(runs, options);
  if (const int sig = batch_signal.load()) exit_interrupted(sig, files);

  const long failed = write_summary(summary, summary_provenance, names, table, results, base);
  files.commit();  // the run files moved into place, then the summary
  if (args.write_runs) note_other_run_files(dir, table.size(), digits);
  print_batch_outcome(args, base, results, failed, dir);
  return failed > 0 ? 1 : 0;
}

}  // namespace

std::function<int()> add_batch_command(CLI::App& app) {
  auto args = std::make_shared<BatchArgs>();
  CLI::App* cmd = app.add_subcommand("batch", "Run a model for many parameter values or initial states on every core");
  cmd->add_option("MODEL", args->model, "A model file (.toml) or a built-in model (initial states only)")->required();
  cmd->add_option("--grid", args->grids,
                  "NAME=FROM:TO:COUNT, COUNT values from FROM to TO (repeatable: every combination). NAME is a "
                  "parameter, or x(0) / x'(0) for an initial coordinate / velocity");
  cmd->add_option("--runs", args->runs_csv, "A CSV file: a header of NAMEs, one row of values per run");
  cmd->add_option("--set", args->sets, "Override a model file's parameter for every run, NAME=VALUE (repeatable)");
  cmd->add_option("--threads", args->threads, "Threads (default 0: every core)");
  cmd->add_option("--evaluator", args->evaluator, "interpreted (default) | compiled | auto, as for simulate");
  cmd->add_option("-o,--output", args->output, "Directory for summary.csv (and run_*.csv)")->capture_default_str();
  cmd->add_flag("--write-runs", args->write_runs, "Also write every run's results as run_NNN.csv");
  cmd->add_option("--t-end", args->t_end, "End time [s] (default: the model's)");
  cmd->add_option("--output-step", args->output_step, "Time between output rows [s] (default: the model's)");
  cmd->add_option("--method", args->method, "Formulation (default: the model's, else sanh)");
  cmd->add_option("--complement", args->complement, "qr (default) | partition | analytic");
  cmd->add_option("--integrator", args->integrator, "Integrator (default: the model's, else dopri5)");
  cmd->add_option("--rtol", args->rtol, "Relative tolerance (default: the model's, else 1e-8)");
  cmd->add_option("--atol", args->atol, "Absolute tolerance (default: the model's, else 1e-10)");
  cmd->add_flag("-q,--quiet", args->quiet, "Print no summary");
  return [args] { return run_batch(*args); };
}

}  // namespace nhdyn::cli
