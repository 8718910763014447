// `nhdyn study spread-masses [MODEL]`: the relative error of q'' and R of every formulation against
// a 50-digit reference as the ratio of the largest to the smallest mass grows from 1 to 1e12
// (studies/spread_masses.hpp, docs/studies/spread-masses.md). Prints the tables, writes them as
// one CSV (one row per ratio) and draws the two plots, q'' and R, against the ratio on log-log axes.
#include <fmt/format.h>

#include <cmath>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "nhdyn/core/error.hpp"
#include "nhdyn/core/join.hpp"
#include "nhdyn/core/shown_text.hpp"
#include "nhdyn/frontend/describe.hpp"
#include "nhdyn/frontend/load_model.hpp"
#include "nhdyn/frontend/provenance.hpp"
#include "nhdyn/io/csv.hpp"
#include "nhdyn/io/plot.hpp"
#include "nhdyn/io/xy_plot.hpp"
#include "nhdyn/studies/spread_masses.hpp"
#include "run_files.hpp"
#include "study.hpp"

namespace nhdyn::cli {
namespace {

struct SpreadMassesArgs {
  std::string model = "examples/spread_masses.toml";
  std::vector<double> ratios = SpreadMassesOptions{}.ratios;
  int samples = SpreadMassesOptions{}.samples;
  int digits = SpreadMassesOptions{}.digits;
  std::string parameter = "ratio";
  std::vector<std::string> sets;
  std::string output = "results/spread-masses.csv";
  std::string plot;
  bool quiet = false;
};

// The plot of R goes beside the plot of q'': out.png -> out-reactions.png.
std::filesystem::path reactions_plot_path(const std::filesystem::path& plot) {
  std::filesystem::path out = plot;
  out.replace_filename(plot.stem().string() + "-reactions" + plot.extension().string());
  return out;
}

// One CSV row per ratio: the ratio, cond(A), the reference's error, then each formulation's errors.
void write_spread_masses_rows(const SpreadMasses& study, CsvWriter& csv) {
  std::vector<double> row;
  for (std::size_t r = 0; r < study.ratios.size(); ++r) {
    const SpreadMassesRatio& ratio = study.ratios[r];
    row = {ratio.ratio, ratio.cond_A, ratio.reference_error};
    for (std::size_t f = 0; f < study.formulations.size(); ++f) row.push_back(study.point(r, f).error_qdd);
    for (std::size_t f = 0; f < study.formulations.size(); ++f) row.push_back(study.point(r, f).error_R);
    for (std::size_t f = 0; f < study.formulations.size(); ++f) row.push_back(study.point(r, f).solve_error_qdd);
    for (std::size_t f = 0; f < study.formulations.size(); ++f) row.push_back(study.point(r, f).solve_error_R);
    for (std::size_t f = 0; f < study.formulations.size(); ++f) row.push_back(study.point(r, f).residual);
    csv.write_row(row);
  }
}

// --plot: the errors of q'' in one plot, those of R in a second beside it.
void plot_spread_masses(const SpreadMasses& study, const std::filesystem::path& table_path,
                        const std::vector<std::string>& qdd_columns, const std::vector<std::string>& R_columns,
                        const std::string& plot) {
  XyPlotRequest request;
  request.csv = table_path;
  request.x = "ratio";
  request.x_label = "mass ratio (largest / smallest)";
  request.title = fmt::format("{}: relative error of the accelerations q'', {}-digit reference (max over {} states)",
                              study.model, study.digits, study.states.size());
  request.y = qdd_columns;
  request.y_label = "|q'' - q''_ref| / |q''_ref|";
  write_xy_plot(request, plot);
  request.title = fmt::format("{}: relative error of the reactions R, {}-digit reference (max over {} states)",
                              study.model, study.digits, study.states.size());
  request.y = R_columns;
  request.y_label = "|R - R_ref| / |R_ref|";
  write_xy_plot(request, reactions_plot_path(plot));
}

// The summary on standard output: one block per error, each formulation's refusals, the reference.
void print_spread_masses(const SpreadMasses& study, const std::filesystem::path& table_path, const std::string& plot) {
  fmt::print("nhdyn study spread-masses {}: {} states per ratio, reference at {} digits (Lagrange system, "
             "exact rationals)\n",
             study.model, study.states.size(), study.digits);
  const auto block = [&](const char* title, auto value) {
    fmt::print("\n{}\n{:>8} {:>9}", title, "ratio", "cond(A)");
    for (const StudyFormulation& f : study.formulations) fmt::print(" {:>14}", formulation_label(f));
    fmt::print("\n");
    for (std::size_t r = 0; r < study.ratios.size(); ++r) {
      fmt::print("{:>8.0e} {:>9.1e}", study.ratios[r].ratio, study.ratios[r].cond_A);
      for (std::size_t f = 0; f < study.formulations.size(); ++f) {
        const SpreadMassesPoint& p = study.point(r, f);
        if (p.failures > 0)
          fmt::print(" {:>14}", "refused");
        else
          fmt::print(" {:>14.2e}", value(p));
      }
      fmt::print("\n");
    }
  };
  block("relative error of q'' (max over the states)", [](const SpreadMassesPoint& p) { return p.error_qdd; });
  block("relative error of R (max over the states)", [](const SpreadMassesPoint& p) { return p.error_R; });
  block("relative error of q'' of the solve alone (against the exact solution of the rounded terms)",
        [](const SpreadMassesPoint& p) { return p.solve_error_qdd; });
  block("relative error of R of the solve alone", [](const SpreadMassesPoint& p) { return p.solve_error_R; });
  block("acceleration-level residual max |b q'' + b0|", [](const SpreadMassesPoint& p) { return p.residual; });
  for (std::size_t f = 0; f < study.formulations.size(); ++f)
    for (std::size_t r = 0; r < study.ratios.size(); ++r)
      if (study.point(r, f).failures > 0) {
        fmt::print("\n{} refused {} of {} states from ratio {:g} on, first: {}\n", formulation_label(study.formulations[f]),
                   study.point(r, f).failures, study.states.size(), study.ratios[r].ratio,
                   describe(study.point(r, f).failure));
        break;
      }
  double reference_error = 0.0;
  for (const SpreadMassesRatio& r : study.ratios) reference_error = std::max(reference_error, r.reference_error);
  fmt::print("\nreference: estimated relative error at most {:.1e} (against {} digits)\n", reference_error,
             study.digits + 20);
  fmt::print("table -> {}\n", shown_text(table_path.string()));
  if (!plot.empty())
    fmt::print("plots -> {}, {}\n", shown_text(plot), shown_text(reactions_plot_path(plot).string()));
}

int run_spread_masses(const SpreadMassesArgs& args) {
  RunFiles files(args.model);
  // Options first, so that a bad value is reported before the model file is read.
  SpreadMassesOptions options;
  options.ratios = args.ratios;
  options.samples = args.samples;
  options.digits = args.digits;
  options.parameter = args.parameter;
  check_spread_masses_options(options);  // the library's check, before the model file is read
  const ModelSource source = read_model_source(args.model);
  const auto description = load_description(source, parse_parameter_sets(args.sets));

  namespace fs = std::filesystem;
  const fs::path table_path = args.output;
  files.output(table_path, "the table CSV", Folder::make);
  files.plot(args.plot);
  files.plot(args.plot.empty() ? fs::path() : reactions_plot_path(args.plot), "the reactions plot");
  files.check();

  // Every formulation the model allows, named before the run so that the CSV (its columns) is
  // opened, and its directory proved writable, before anything is computed.
  options.formulations = {{Formulation::sanh, Complement::qr}, {Formulation::sanh, Complement::partition}};
  if (description_gives_complement(*description)) options.formulations.push_back({Formulation::sanh, Complement::analytic});
  for (Formulation m : {Formulation::lagrange, Formulation::udwadia_kalaba, Formulation::nullspace}) options.formulations.push_back({m, Complement::qr});
  std::vector<std::string> columns{"ratio", "cond_A", "reference_error"};
  std::vector<std::string> qdd_columns, R_columns, other_columns;
  for (const StudyFormulation& f : options.formulations) {
    const std::string label = formulation_label(f);
    qdd_columns.push_back("error_qdd_" + label);
    R_columns.push_back("error_R_" + label);
  }
  for (const char* prefix : {"solve_error_qdd_", "solve_error_R_", "residual_acc_"})
    for (const StudyFormulation& f : options.formulations) other_columns.push_back(prefix + formulation_label(f));
  columns.insert(columns.end(), qdd_columns.begin(), qdd_columns.end());
  columns.insert(columns.end(), R_columns.begin(), R_columns.end());
  columns.insert(columns.end(), other_columns.begin(), other_columns.end());
  // The CSV says what made it (io/provenance.hpp), as every CSV nhdyn writes: the model as loaded
  // (compiled once for its parameters and initial state) and the study's options.
  std::vector<std::string> ratios, labels;
  for (double ratio : options.ratios) ratios.push_back(fmt::format("{}", ratio));
  for (const StudyFormulation& f : options.formulations) labels.push_back(formulation_label(f));
  const std::string provenance = format_provenance(make_command_provenance(
      load_model(source, parse_parameter_sets(args.sets)), source, "study spread-masses",
      {{"parameter", options.parameter},
       {"ratios", join(ratios, ",")},
       {"samples", fmt::format("{}", options.samples)},
       {"digits", fmt::format("{}", options.digits)},
       {"formulations", join(labels, ",")}}));
  CsvWriter& csv = files.open_csv(table_path, columns, provenance);

  const SpreadMasses study = study_spread_masses(description_spec(*description), options);
  write_spread_masses_rows(study, csv);
  files.commit();

  if (!args.plot.empty()) plot_spread_masses(study, table_path, qdd_columns, R_columns, args.plot);
  if (!args.quiet) print_spread_masses(study, table_path, args.plot);
  // A formulation that refuses a badly scaled system is one of the study's findings (printed
  // and left as NaN in the CSV), not a failure of the command.
  return 0;
}

}  // namespace

std::function<int()> add_spread_masses_study(CLI::App& study) {
  auto args = std::make_shared<SpreadMassesArgs>();
  CLI::App* cmd = study.add_subcommand(
      "spread-masses", "Accuracy of q'' and R of every formulation against a 50-digit reference as the masses spread");
  cmd->add_option("MODEL", args->model, "A model file (.toml) with a parameter that spreads the masses")
      ->capture_default_str();
  cmd->add_option("--ratios", args->ratios, "Mass ratios, comma-separated")->delimiter(',')->capture_default_str();
  cmd->add_option("--samples", args->samples, "States per ratio")->capture_default_str();
  cmd->add_option("--digits", args->digits, "Decimal digits of the reference")->capture_default_str();
  cmd->add_option("--parameter", args->parameter, "The model parameter that holds the mass ratio")
      ->capture_default_str();
  cmd->add_option("--set", args->sets, "Set a parameter, NAME=EXPR: a number or an expression in numbers, pi, e and the other parameters (repeatable)");
  cmd->add_option("-o,--output", args->output, "Table CSV, one row per ratio")->capture_default_str();
  cmd->add_option("--plot", args->plot,
                  "PNG of the error of q'' against the ratio (log-log); that of R goes to NAME-reactions.png");
  cmd->add_flag("-q,--quiet", args->quiet, "Print no table");
  return [args] { return run_spread_masses(*args); };
}

}  // namespace nhdyn::cli
