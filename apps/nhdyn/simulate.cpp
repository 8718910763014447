// `nhdyn simulate MODEL`: integrate a model, write one CSV row per output time, optionally plot,
// and print a short summary. Every check of the user's input (model, times, tolerances, output
// paths) happens before the first step, so a bad option never costs a run.
#include <fmt/format.h>

#include <cctype>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <iterator>
#include <memory>
#include <optional>
#include <string>
#include <system_error>
#include <vector>

#include "commands.hpp"
#include "nhdyn/analysis/run_options.hpp"
#include "nhdyn/analysis/simulation.hpp"
#include "nhdyn/core/error.hpp"
#include "nhdyn/core/shown_text.hpp"
#include "nhdyn/frontend/describe.hpp"
#include "nhdyn/frontend/events.hpp"
#include "nhdyn/frontend/load_model.hpp"
#include "nhdyn/frontend/provenance.hpp"
#include "nhdyn/io/csv.hpp"
#include "nhdyn/io/plot.hpp"
#include "nhdyn/io/report.hpp"
#include "nhdyn/io/results.hpp"
#include "nhdyn/jit/compiled_evaluator.hpp"
#include "nhdyn/model/contact_modes.hpp"
#include "nhdyn/model/initial_values.hpp"
#include "progress.hpp"
#include "run_files.hpp"
#include "run_overrides.hpp"

namespace nhdyn::cli {
namespace {

struct SimulateArgs {
  std::string model;
  std::optional<double> t_end;
  std::optional<double> output_step;
  std::optional<std::string> method;      // default: the model file's, else sanh
  std::optional<std::string> complement;  // default: the model's (RunOptions)
  std::optional<std::string> integrator;  // default: the model file's, else RunOptions
  std::optional<double> rtol;             // default: the model file's, else RunOptions
  std::optional<double> atol;             // default: the model file's, else RunOptions
  std::vector<std::string> sets;
  std::vector<std::string> initial;  // NAME=EXPR: initial values replacing the model's (model/initial_values.hpp)
  bool fix_initial = false;
  std::string stabilize = "none";
  double baumgarte_alpha = BaumgarteGains{}.alpha;
  double baumgarte_beta = BaumgarteGains{}.beta;
  double projection_tolerance = ProjectionOptions{}.tolerance;
  double step = 0.0;
  std::string output;
  std::string plot;
  std::vector<std::string> plot_columns;  // the columns --plot draws (empty: calc_plot_panels' choice)
  std::string html;  // the HTML report (io/report.hpp), written from the CSV after the run
  std::string program_feedback;  // "alpha,beta" (docs/cli.md); empty: no feedback
  bool quiet = false;
  std::string evaluator = "interpreted";  // interpreted | compiled | auto (jit/compiled_evaluator.hpp)
  std::vector<std::string> stop_when;  // conditions that end the run when they become true
  std::vector<std::string> events;     // NAME=EXPR: crossings of zero to record
  std::optional<long> max_steps;       // the integrator's step budget (default IntegratorOptions)
};

// --program-feedback alpha,beta: two plain decimal numbers (no hexadecimal, no nan or inf, no
// spaces); check_simulation_options checks them as rates [1/s], >= 0 and at most kMaxProgramFeedback.
ProgramFeedback parse_program_feedback(const std::string& text) {
  ProgramFeedback out;
  if (text.empty()) return out;
  const std::size_t comma = text.find(',');
  const auto number = [&](const std::string& part, const char* name) {
    const auto fail = [&](const std::string& why) -> double {
      throw InputError(fmt::format("--program-feedback {}: the gain {} '{}' {}; give two rates in 1/s as alpha,beta "
                                   "(e.g. --program-feedback 10,10)",
                                   text, name, part, why));
    };
    // Digits, one point, one exponent: std::from_chars alone would read 0x10 as 0 and take nan and inf.
    const bool plain = !part.empty() && part.find_first_not_of("0123456789.eE+-") == std::string::npos &&
                       (std::isdigit(static_cast<unsigned char>(part[0])) || part[0] == '.' || part[0] == '+' ||
                        part[0] == '-');
    if (!plain) return fail("is not a decimal number");
    const char* begin = part.data() + (part[0] == '+' ? 1 : 0);
    double value = 0.0;
    const std::from_chars_result read = std::from_chars(begin, part.data() + part.size(), value);
    if (read.ec == std::errc::result_out_of_range)
      return fail(part.find("e-") != std::string::npos || part.find("E-") != std::string::npos
                      ? "is below the smallest double (about 1e-308): give 0 for no feedback on that level"
                      : "is beyond the largest double");
    if (read.ec != std::errc() || read.ptr != part.data() + part.size()) return fail("is not a decimal number");
    return value;
  };
  if (comma == std::string::npos || text.find(',', comma + 1) != std::string::npos)
    throw InputError(fmt::format("--program-feedback {}: give two rates in 1/s as alpha,beta (e.g. "
                                 "--program-feedback 10,10)",
                                 text));
  out.enabled = true;
  out.alpha = number(text.substr(0, comma), "alpha");
  out.beta = number(text.substr(comma + 1), "beta");
  return out;  // the gains' range is checked with the other options, by check_simulation_options
}

// Where a run's companion files go: FILE.csv -> FILE-events.csv and FILE.partial.csv (the
// extension .csv, if any, replaced).
std::filesystem::path companion(const std::filesystem::path& csv, const std::string& suffix) {
  std::string base = csv.string();
  if (csv.extension() == ".csv") base.resize(base.size() - 4);
  return base + suffix;
}

std::string csv_cell(const std::string& text) {
  if (text.find_first_of(",\"\n") == std::string::npos) return text;
  std::string out = "\"";
  for (char c : text) {
    if (c == '"') out += '"';
    out += c;
  }
  return out + "\"";
}

std::string csv_line(const std::vector<std::string>& cells) {
  std::string line;
  for (std::size_t i = 0; i < cells.size(); ++i) line += (i ? "," : "") + csv_cell(cells[i]);
  return line + "\n";
}

// FILE-events.csv: the run's provenance, then one row per located crossing, name, t, q, q'.
void write_events_file(AtomicFile& file, const Model& model, const SimulationSummary& summary,
                       const std::string& provenance) {
  std::vector<std::string> header = {"event", "t"};
  for (const std::string& q : model.coordinates) header.push_back(q);
  for (const std::string& q : model.coordinates) header.push_back(q + "'");
  std::string text = provenance + csv_line(header);
  for (const EventRecord& e : summary.events.crossings) {
    text += csv_cell(e.name);
    fmt::format_to(std::back_inserter(text), ",{}", e.t);
    for (double x : e.q) fmt::format_to(std::back_inserter(text), ",{}", x);
    for (double x : e.v) fmt::format_to(std::back_inserter(text), ",{}", x);
    text += '\n';
  }
  file.write(text);
}

// A device or pipe as the CSV (/dev/stdout) has no place beside it for companion files.
bool is_regular_target(const std::filesystem::path& csv) {
  std::error_code ec;
  const std::filesystem::file_status status = std::filesystem::status(csv, ec);
  return ec || !std::filesystem::exists(status) || std::filesystem::is_regular_file(status);
}

// The model as the run uses it: its evaluator chosen and its initial values set, with what loading
// and choosing found said on stderr.
Model prepare_model(const LoadedModel& resolved, const SimulateArgs& args) {
  std::string notice;
  Model model = jit::with_evaluator(resolved.model, jit::parse_evaluator_choice(args.evaluator), &notice);
  apply_initial_values(model, args.initial);
  if (!notice.empty()) fmt::print(stderr, "{}\n", notice);
  fmt::print(stderr, "{}", format_contact_force_notes(model));
  return model;
}

// The run's options: the model's, the command line's overrides, the file's [[events]] then the
// command line's (read against the loaded model's description, frontend/events.hpp); checked
// whole before any file is opened.
SimulationOptions make_run_options(const LoadedModel& resolved, const Model& model, const SimulateArgs& args) {
  SimulationOptions options = make_simulation_options(run_options_with(model, args));
  options.integrator.step = args.step;
  options.fix_initial = args.fix_initial;
  options.stabilization = parse_stabilization(args.stabilize);
  options.formulation.baumgarte.alpha = args.baumgarte_alpha;
  options.formulation.baumgarte.beta = args.baumgarte_beta;
  options.projection.tolerance = args.projection_tolerance;
  if (args.max_steps) options.integrator.max_steps = *args.max_steps;  // checked by check_simulation_options
  options.events = model.events;
  for (const std::string& condition : args.stop_when)
    options.events.push_back(make_stop_condition(resolved, condition));
  for (const std::string& definition : args.events)
    options.events.push_back(make_record_event(resolved, definition));
  options.formulation.program_feedback = parse_program_feedback(args.program_feedback);
  check_simulation_options(model, options);
  return options;
}

// Where a run's rows go: the CSV and its companions (FILE-events.csv, FILE.partial.csv), with
// the files of the run (run_files.hpp) that hold them until the run has succeeded.
struct RunOutput {
  std::filesystem::path csv, events, partial;
  bool companions = false;  // the CSV is a regular file, with a place beside it
  CsvWriter* writer = nullptr;
  AtomicFile* events_file = nullptr;  // opened when the run has events or contact modes
};

// Every file of the run listed and checked together (run_files.hpp), then opened, before any
// work: a bad path never costs a run.
RunOutput open_run_files(RunFiles& files, const SimulateArgs& args, const Model& model,
                         const SimulationOptions& options, const ResultColumns& columns,
                         const std::string& provenance) {
  namespace fs = std::filesystem;
  check_plot_columns(args.plot, columns.all, args.plot_columns);
  RunOutput out;
  const bool default_csv = args.output.empty();
  out.csv = default_csv ? fs::path("results") / (make_file_name(model.name) + ".csv") : fs::path(args.output);
  out.events = companion(out.csv, "-events.csv");
  out.partial = companion(out.csv, ".partial.csv");
  out.companions = is_regular_target(out.csv);
  // Contacts with modes write their switches in the events file too (docs/contact-modes.md).
  const bool events_file = out.companions && (!options.events.empty() || model.contact_modes);
  // The default place is ours to create; a path the user names must already be writable.
  files.output(out.csv, "the CSV output", default_csv ? Folder::make : Folder::must_exist);
  if (events_file) files.output(out.events, "the events file");
  if (out.companions) files.output(out.partial, "the partial-results file");
  files.plot(args.plot);
  files.page(args.html, "--html");
  files.check();
  out.writer = &files.open_csv(out.csv, columns.all, provenance);  // refuses an unwritable path before any step
  if (events_file) out.events_file = &files.open(out.events);
  return out;
}

// Integrates, writing each row to the CSV as it comes (a failed run's FILE.partial.csv is read back
// from the CSV's temporary: no copy of the rows is kept).
SimulationSummary run_to_files(const Model& model, const SimulationOptions& options, const ResultColumns& columns,
                               RunOutput& files) {
  std::vector<double> row;
  row.reserve(columns.all.size());
  ProgressBar progress(model.t0, options.t_end);
  const SimulationSummary summary = simulate(model, options, [&](const Data& data) {
    fill_result_row(model, data, row);
    files.writer->write_row(row);
    progress.update(data.t);
  });
  progress.finish();
  return summary;
}

// A failed run: the reason, and the rows up to the failure in FILE.partial.csv (the CSV itself is
// never committed). Returns the exit code.
int report_failure(const Model& model, const SimulationSummary& summary, const RunOutput& out, RunFiles& files) {
  fmt::print(stderr, "nhdyn: simulation of '{}' failed at t = {:.6g}: {}\n", model.name, summary.t_reached,
             summary.message);
  if (!out.companions) {
    fmt::print(stderr, "nhdyn: no results written ({} is left as it was)\n", shown_text(out.csv.string()));
    return 1;
  }
  std::string reason = fmt::format("# nhdyn: simulation of '{}' failed at t = {:.6g}: {}", model.name,
                                   summary.t_reached, summary.message);
  for (char& c : reason)
    if (c == '\n' || c == '\r') c = ' ';
  files.write_now(out.partial, reason + "\n" + out.writer->written());
  fmt::print(stderr, "nhdyn: the {} rows up to the failure are in {} ({} is left as it was)\n", summary.outputs,
             shown_text(out.partial.string()), shown_text(out.csv.string()));
  return 1;
}

std::string run_title(const Model& model, const SimulationOptions& options) {
  return fmt::format("{}: {}, {}", model.name, formulation_name(options.formulation.method),
                     integrator_name(options.integrator.kind));
}

// --plot: the run's panels (docs/cli.md), drawn from the committed CSV.
void plot_run(const SimulateArgs& args, const LoadedModel& resolved, const Model& model,
              const SimulationOptions& options, const ResultColumns& columns, const SimulationSummary& summary,
              const std::filesystem::path& csv) {
  PlotRequest request;
  request.title = run_title(model, options);
  request.csv = csv;
  request.coordinates = columns.coordinates;
  for (const std::string& q : model.coordinates) request.velocities.push_back(q + "'");
  request.reactions = columns.reactions;
  request.residuals = columns.residuals;
  request.actuators = columns.actuators;
  // Drawn without asking: the file's own [outputs] and each contact's normal force (the load,
  // whose sign says whether the wheel would lift off); the rest of the contact columns and the
  // multibody points' coordinates through --plot-columns.
  for (const DerivedOutput& o : model.outputs.list)
    if (!o.automatic) request.others.push_back(o.name);
  for (const std::string& c : columns.contact_forces)
    if (c.size() > 2 && c.compare(c.size() - 2, 2, "_N") == 0) request.others.push_back(c);
  // Contacts with modes: their mode columns as steps (docs/contact-modes.md); the switches are
  // among the events marked on every panel.
  for (const std::string& c : contact_mode_columns(model))
    if (c.size() > 5 && c.compare(c.size() - 5, 5, "_mode") == 0) request.modes.push_back(c);
  if (model.path)
    request.path = std::make_pair(model.coordinates[static_cast<std::size_t>(model.path->x)],
                                  model.coordinates[static_cast<std::size_t>(model.path->y)]);
  // With an energy balance the drawn error is h - h(t0) - W (the change of E may be physics).
  if (!columns.energy.empty())
    request.energy = columns.energy_balance.empty() ? columns.energy : columns.energy_balance.back();
  for (const EventRecord& e : summary.events.crossings) {
    PlotEvent& mark = request.events.emplace_back(PlotEvent{e.name, e.t});
    for (std::size_t i = 0; i < model.coordinates.size(); ++i) {
      mark.state.emplace_back(model.coordinates[i], e.q[i]);
      mark.state.emplace_back(model.coordinates[i] + "'", e.v[i]);
    }
  }
  // A model file also tells its angles by use: the coordinates inside sin, cos or tan.
  if (resolved.description) {
    try {
      const std::vector<bool>& angles = description_angles(*resolved.description);
      for (std::size_t i = 0; i < angles.size() && i < model.coordinates.size(); ++i)
        if (angles[i]) request.angles.push_back(model.coordinates[i]);
    } catch (const Error&) {
      // A [visual] item that does not compile costs the plot only this hint; the names remain.
    }
  }
  select_plot_columns(request, columns.all, args.plot_columns);
  write_plot(request, args.plot);
}

// After a run that succeeded: the CSV and the events file committed, then the plot and the report
// drawn from them. Returns the report's notice, if any.
std::string commit_run(const SimulateArgs& args, const LoadedModel& resolved, const Model& model,
                       const SimulationOptions& options, const ResultColumns& columns,
                       const SimulationSummary& summary, const std::string& provenance, const RunOutput& out,
                       RunFiles& files) {
  if (out.events_file) write_events_file(*out.events_file, model, summary, provenance);
  files.commit();
  if (!args.plot.empty()) plot_run(args, resolved, model, options, columns, summary, out.csv);
  if (args.html.empty()) return {};
  return write_model_report(
      model, resolved.description.get(), load_csv(out.csv), run_title(model, options),
      {{"steps", fmt::format("{} (rejected {})", summary.stats.steps, summary.stats.rejected_steps)},
       {"right-hand sides", fmt::format("{}", summary.stats.rhs_evaluations)},
       {"results", out.csv.string()}},
      args.html);
}

// The summary on standard output: the run's choices, then each group's lines (analysis/simulation_summary.hpp).
void print_summary(const SimulateArgs& args, const Model& model, const SimulationOptions& options,
                   const SimulationSummary& summary, const RunOutput& files, const std::string& html_notice) {
  const bool adaptive = options.integrator.kind != IntegratorKind::rk4;
  fmt::print("nhdyn simulate {}: method {} ({}), integrator {}{}\n", model.name,
             formulation_name(options.formulation.method),
             summary.sparse ? std::string(options.formulation.method == Formulation::sanh ? "sparse path, D: partition"
                                                                                      : "sparse path")
                            : fmt::format("D: {}", complement_name(options.formulation.complement)),
             integrator_name(options.integrator.kind),
             adaptive ? fmt::format(" (rtol {:g}, atol {:g})", options.integrator.rtol, options.integrator.atol) : "");
  fmt::print("{}", format_stabilization(options, summary.projection));
  if (summary.events.stopped_by >= 0)
    fmt::print("  t = {:g} .. {:.10g} s: stopped by event '{}', {} rows -> {}\n", model.t0, summary.t_reached,
               summary.events.names[static_cast<std::size_t>(summary.events.stopped_by)], summary.outputs,
               shown_text(files.csv.string()));
  else
    fmt::print("  t = {:g} .. {:g} s, {} rows -> {}\n", model.t0, options.t_end, summary.outputs, shown_text(files.csv.string()));
  fmt::print("{}", format_events(summary.events, files.events_file ? shown_text(files.events.string()) : std::string()));
  fmt::print("{}", format_steps(summary));
  fmt::print("{}", format_residuals(model, summary.residuals));
  fmt::print("{}", format_program(model, summary.program, options.formulation.program_feedback));
  if (summary.initial_fix) fmt::print("{}", format_initial_fix(model, *summary.initial_fix));
  fmt::print("{}", format_energy(model, summary.energy));
  fmt::print("{}", format_constraint_watch(model, summary.watch, summary.watch.warnings.size(), summary.sparse));
  if (!args.plot.empty()) fmt::print("  plot -> {}\n", shown_text(args.plot));
  if (!args.html.empty()) fmt::print("  report -> {}{}\n", shown_text(args.html), html_notice.empty() ? "" : "\n  note: " + html_notice);
}

// The command is the process's last work: the symbolic description of the model (every derived
// term as GiNaC objects, 10^5 of them for a large model, a twentieth of the 1000-body chain's
// start-up to free one by one) is left for the operating system to take back at exit. Held from
// a pointer that lives to the end, it is not a leak to a leak checker.
void keep_until_exit(std::shared_ptr<const symbolic::ModelDescription> description) {
  static auto* const kept = new std::vector<std::shared_ptr<const symbolic::ModelDescription>>;
  kept->push_back(std::move(description));
}

int run_simulate(const SimulateArgs& args) {
  RunFiles files(args.model);
  const ModelSource source = read_model_source(args.model);
  const LoadedModel resolved = load_model_described(source, parse_parameter_sets(args.sets));
  keep_until_exit(resolved.description);
  const Model model = prepare_model(resolved, args);
  const SimulationOptions options = make_run_options(resolved, model, args);
  const ResultColumns columns = make_result_columns(model);
  // Every file of the run says where it came from (io/provenance.hpp).
  const std::string provenance = format_provenance(make_provenance(model, source, options, args.evaluator));
  RunOutput out = open_run_files(files, args, model, options, columns, provenance);
  const SimulationSummary summary = run_to_files(model, options, columns, out);
  // The run's warnings (the constraint watch's, analysis/constraint_watch.hpp), whatever the outcome.
  for (const std::string& w : summary.warnings) fmt::print(stderr, "nhdyn: warning: {}\n", w);
  for (const std::string& w : summary.events.unmet_stops) fmt::print(stderr, "nhdyn: warning: {}\n", w);
  if (!summary.stiffness.empty()) fmt::print(stderr, "nhdyn: warning: {}\n", summary.stiffness);
  // `auto`'s background compile, failed during the run (a compile error): said as before the run.
  if (const std::string notice = jit::background_notice(model); !notice.empty()) fmt::print(stderr, "{}\n", notice);
  if (summary.status != Status::ok) return report_failure(model, summary, out, files);
  const std::string html_notice = commit_run(args, resolved, model, options, columns, summary, provenance, out, files);
  if (!args.quiet) print_summary(args, model, options, summary, out, html_notice);
  return 0;
}

}  // namespace

std::function<int()> add_simulate_command(CLI::App& app) {
  auto args = std::make_shared<SimulateArgs>();
  CLI::App* cmd = app.add_subcommand("simulate", "Simulate a model and write its results as CSV");
  cmd->add_option("MODEL", args->model, "A model file (.toml) or a built-in model (see `nhdyn list`)")->required();
  cmd->add_option("--set", args->sets, "Set a parameter, NAME=EXPR: a number or an expression in numbers, pi, e and the other parameters (repeatable)");
  cmd->add_option("--evaluator", args->evaluator,
                  help_choices(jit::kEvaluatorChoices, jit::EvaluatorChoice::interpreted) +
                      " (compiled: the terms as machine code, cached; docs/cli.md)");
  cmd->add_option("--initial", args->initial,
                  "Set an initial value, NAME=EXPR: a coordinate (x=0.1) or a velocity (\"phi'=0.5\"); EXPR as for "
                  "--set, in numbers and the parameters (repeatable)");
  cmd->add_flag("--fix-initial", args->fix_initial,
                "Move the initial state onto the constraints with the smallest inertia-weighted change");
  cmd->add_option("--stabilize", args->stabilize,
                  "Keep the solution on the constraints: " + help_choices(kStabilizations, Stabilization::none));
  cmd->add_option("--baumgarte-alpha", args->baumgarte_alpha,
                  "Baumgarte: damping rate of the velocity residual [1/s]")->capture_default_str();
  cmd->add_option("--baumgarte-beta", args->baumgarte_beta,
                  "Baumgarte: rate of the position residual [1/s]")->capture_default_str();
  cmd->add_option("--projection-tolerance", args->projection_tolerance,
                  "Projection: residual at which Newton stops")->capture_default_str();
  cmd->add_option("--t-end", args->t_end, "End time [s] (default: the model's)");
  cmd->add_option("--output-step", args->output_step, "Time between output rows [s] (default: the model's)");
  cmd->add_option("--method", args->method, "Formulation: " + help_choices(kFormulations, Formulation::sanh));
  cmd->add_option("--complement", args->complement, "Where D comes from (sanh, nullspace): " + help_choices(kComplements, Complement::qr));
  cmd->add_option("--integrator", args->integrator, help_choices(kIntegrators, IntegratorKind::dopri5));
  cmd->add_option("--rtol", args->rtol, "Relative tolerance of the adaptive integrators (default: the model's, else 1e-8)");
  cmd->add_option("--atol", args->atol, "Absolute tolerance of the adaptive integrators (default: the model's, else 1e-10)");
  cmd->add_option("--step", args->step, "rk4: step size [s] (default output step / 10); adaptive: first step");
  cmd->add_option("-o,--output", args->output, "CSV file to write (default results/MODEL.csv)");
  cmd->add_option("--plot", args->plot, "PNG file to draw with gnuplot (panels: docs/cli.md)");
  cmd->add_option("--plot-columns", args->plot_columns,
                  "The columns --plot draws, comma-separated (default: coordinates, velocities, path, reactions, "
                  "residuals, energy balance error)")
      ->delimiter(',');
  cmd->add_option("--html", args->html, "HTML report to write: 3-D animation, plots, equations (docs/report.md)");
  cmd->add_option("--stop-when", args->stop_when,
                  "End the run when a condition becomes true, e.g. \"abs(phi) > 1.2\" (located exactly; repeatable)");
  cmd->add_option("--event", args->events,
                  "Record the zero crossings of an expression, NAME=EXPR (e.g. upright=phi; repeatable)");
  cmd->add_option("--max-steps", args->max_steps,
                  "Step budget of the integrator, accepted + rejected steps (default 50000000)");
  cmd->add_option("--program-feedback", args->program_feedback,
                  "Programs: PD feedback ALPHA,BETA [1/s] on their residuals (docs/derivations/program-motion.md)");
  cmd->add_flag("-q,--quiet", args->quiet, "Print no summary");
  return [args] { return run_simulate(*args); };
}

}  // namespace nhdyn::cli
