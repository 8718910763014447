#include "nhdyn/optimize/solve.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include "nhdyn/core/error.hpp"
#include "nhdyn/core/join.hpp"
#include "nhdyn/core/shown_text.hpp"
#include "nhdyn/io/csv.hpp"
#include "nhdyn/optimize/replay.hpp"
#include "nhdyn/optimize/transcription.hpp"

namespace nhdyn {

const char* nlp_status_name(NlpStatus status) {
  switch (status) {
    case NlpStatus::solved: return "solved";
    case NlpStatus::solved_acceptable: return "solved to acceptable level";
    case NlpStatus::infeasible: return "infeasible";
    case NlpStatus::iteration_limit: return "iteration limit";
    case NlpStatus::failed: return "failed";
    case NlpStatus::unavailable: return "unavailable";
  }
  return "failed";
}

namespace {

// The guess CSV interpolated linearly at each point's time (columns found by name), after the
// checks that keep a bad file from reaching IPOPT as numbers it cannot use: every value read
// finite, the times never decreasing and spanning an interval that meets [t0, t_end], each column
// named once. Returns the notes: columns that name nothing in the problem (ignored), and a guess
// that covers only part of [t0, t_end] (its end rows held beyond).
std::vector<std::string> apply_guess(const Transcription& nlp, const std::filesystem::path& path,
                                     std::vector<double>& x) {
  const OptimalControlProblem& problem = nlp.problem();
  const std::string file = path.string();
  const CsvTable table = load_csv(path);
  const auto column = [&](const std::string& name) -> int {
    return table.column(name);
  };
  for (std::size_t c = 0; c < table.header.size(); ++c)
    for (std::size_t d = 0; d < c; ++d)
      if (table.header[c] == table.header[d])
        throw InputError(fmt::format("{}: the guess names the column '{}' twice (columns {} and {}): keep one",
                                     file, table.header[c], d + 1, c + 1));
  const int t_column = column("t");
  if (t_column < 0 || table.rows.size() < 2)
    throw InputError(fmt::format("{}: a guess needs a column t and at least two rows", file));
  const int n = problem.n(), m = problem.m();
  std::vector<std::pair<int, int>> map;  // (variable offset in a point, csv column)
  std::vector<char> known(table.header.size(), 0);
  known[static_cast<std::size_t>(t_column)] = 1;
  for (int i = 0; i < n; ++i) {
    const std::string& name = problem.model.coordinates[static_cast<std::size_t>(i)];
    for (int level = 0; level < 3; ++level) {
      const int c = column(name + std::string(static_cast<std::size_t>(level), '\''));
      if (c < 0 && level < 2)
        throw InputError(fmt::format("{}: the guess has no column '{}{}': give t, the coordinates and their velocities "
                                     "(and optionally x'' and u_NAME) as nhdyn optimize writes them",
                                     file, name, level == 1 ? "'" : ""));
      if (c >= 0) map.emplace_back(level * n + i, c);
    }
  }
  for (int j = 0; j < m; ++j) {
    const int c = column("u_" + problem.controls[static_cast<std::size_t>(j)].name);
    if (c >= 0) map.emplace_back(3 * n + j, c);
  }
  for (const auto& [offset, c] : map) known[static_cast<std::size_t>(c)] = 1;
  const std::size_t tc = static_cast<std::size_t>(t_column);
  // The file's line of data row r: after the comment lines (a FILE.partial.csv's reason) and the
  // header, as load_csv counts them.
  const auto file_line = [&](std::size_t r) { return table.comments.size() + 2 + r; };
  for (std::size_t r = 0; r < table.rows.size(); ++r) {
    for (std::size_t c = 0; c < table.header.size(); ++c)
      if (known[c] && !std::isfinite(table.rows[r][c]))
        throw InputError(fmt::format("{}:{}: {} = {} is not finite; a guess holds finite values", file,
                                     file_line(r), table.header[c], table.rows[r][c]));
    if (r > 0 && table.rows[r][tc] < table.rows[r - 1][tc])
      throw InputError(fmt::format("{}:{}: t = {} is before the row above (t = {}); a guess's times never "
                                   "decrease",
                                   file, file_line(r), table.rows[r][tc], table.rows[r - 1][tc]));
  }
  const double first = table.rows.front()[tc], last = table.rows.back()[tc];
  const double t0 = problem.t0, t_end = nlp.time(nlp.points() - 1, x.data());
  if (!(last > first))
    throw InputError(fmt::format("{}: the guess's times span nothing (every row at t = {}): give rows over [{}, {}]",
                                 file, first, t0, t_end));
  if (last < t0 || first > t_end)
    throw InputError(fmt::format("{}: the guess covers t = {} to {}, outside the problem's [{}, {}]: give rows over "
                                 "[t0, t_end]",
                                 file, first, last, t0, t_end));
  std::vector<std::string> notes;
  const double slack = 1e-9 * (t_end - t0);  // a previous result's last time, rounded in its CSV
  const bool late = first > t0 + slack, early = last < t_end - slack;
  if (late || early)
    notes.push_back(fmt::format("the guess {} covers t = {} to {} of [{}, {}]: its {} held beyond", shown_text(file), first, last,
                                t0, t_end,
                                late && early ? "first and last rows are"
                                : late        ? "first row is"
                                              : "last row is"));
  std::vector<std::string> ignored;
  for (std::size_t c = 0; c < table.header.size(); ++c)
    if (!known[c]) ignored.push_back(table.header[c]);
  if (!ignored.empty())
    notes.push_back(fmt::format("the guess {} has column{} that name{} nothing in the problem, ignored: {} (it takes t, "
                                "the coordinates, x', x'' and u_NAME of the controls)",
                                shown_text(file), ignored.size() > 1 ? "s" : "", ignored.size() > 1 ? "" : "s",
                                shown_text(join(ignored))));
  const auto value = [&](int c, double t) {
    const std::size_t rows = table.rows.size();
    std::size_t hi = 1;
    while (hi + 1 < rows && table.rows[hi][tc] < t) ++hi;
    const double ta = table.rows[hi - 1][tc], tb = table.rows[hi][tc];
    const double s = tb > ta ? std::clamp((t - ta) / (tb - ta), 0.0, 1.0) : 0.0;
    return (1 - s) * table.rows[hi - 1][static_cast<std::size_t>(c)] + s * table.rows[hi][static_cast<std::size_t>(c)];
  };
  for (int p = 0; p < nlp.points(); ++p) {
    const double t = nlp.time(p, x.data());
    for (const auto& [offset, c] : map) x[static_cast<std::size_t>(p * nlp.width() + offset)] = value(c, t);
  }
  return notes;
}

// The solver's options, before any work: IPOPT takes only tol > 0 and max_iter >= 0, and drops
// another value with a note of its own for its default; a tolerance above 1e-2 lets a start that
// violates the boundary conditions and the dynamics by percents count as solved.
constexpr double kLoosestTolerance = 1e-2;

void check_nlp_options(const NlpOptions& options) {
  for (const auto& [name, value] : {std::pair{"tolerance", options.tolerance},
                                    std::pair{"constraint tolerance", options.constraint_tolerance}})
    if (!(value > 0.0 && value <= kLoosestTolerance))
      throw InputError(fmt::format("the optimizer's {} {} must be a number above 0 and at most {:g} (the default is "
                                   "1e-8): a looser one accepts a start far from a solution as solved",
                                   name, value, kLoosestTolerance));
  if (options.max_iterations < 1)
    throw InputError(fmt::format("the optimizer's iteration budget {} must be at least 1 (the default "
                                 "is 3000)",
                                 options.max_iterations));
}

// The replay rule (solve.hpp, docs/optimize.md): each interval, replayed by the simulator from
// the optimum's own state at its start, must end within a tenth of each coordinate's range of the
// optimum. Beyond that the controls do not produce the motion IPOPT found: a grid too coarse for it
// (parking at 3 nodes), or a problem with no solution whose discrete equations have one (an
// actuator x F on a mass at rest at x = 0, which never moves, "reached" x = 1 by a jump in the
// last interval), or a free final time run off to its bound. Judged interval by interval, so that
// an unstable motion (a cart-pole swinging up), which amplifies the replay from t0 over the run
// whatever the grid, is not taken for a wrong one.
void apply_replay_rule(OptimizeResult& result, const std::vector<std::string>& coordinates, const ReplayResult& replay) {
  const int n = static_cast<int>(coordinates.size());
  std::vector<double> range(static_cast<std::size_t>(n), 0.0), largest(static_cast<std::size_t>(n), 0.0);
  for (int i = 0; i < n; ++i) {
    double lo = kNoBound, hi = -kNoBound;
    for (int p = 0; p < result.points; ++p) {
      const double q = result.q[static_cast<std::size_t>(p * n + i)];
      lo = std::min(lo, q);
      hi = std::max(hi, q);
      largest[static_cast<std::size_t>(i)] = std::max(largest[static_cast<std::size_t>(i)], std::abs(q));
    }
    if (result.points > 0) range[static_cast<std::size_t>(i)] = hi - lo;
    result.motion_range = std::max(result.motion_range, range[static_cast<std::size_t>(i)]);
  }
  result.local_replay = replay.local;
  double worst = -1.0;
  for (int i = 0; i < n && replay.local_ok; ++i) {
    // Each coordinate against its own range and magnitude: another's (a flywheel's 5000 rad, a
    // height of 1e9 standing still) says nothing of this one's error.
    const std::size_t u = static_cast<std::size_t>(i);
    const double limit = std::max(kReplayShare * range[u], kReplayFloor * (1.0 + largest[u]));
    if (replay.local[u] / limit > worst) {
      worst = replay.local[u] / limit;
      result.replay_coordinate = coordinates[u];
      result.local_difference = replay.local[u];
      result.replay_limit = limit;
    }
  }
  if (!result.converged()) return;
  if (!replay.local_ok) {
    result.replay_rejected = true;
    result.replay_verdict = fmt::format(
        "IPOPT solved the discrete problem, but its optimum is not a motion of the model: {} (docs/optimize.md). "
        "The controls cannot drive the model along the optimum there: give more nodes, a tighter --tolerance or a "
        "first guess (--guess FILE.csv); or the problem may have no solution whose discrete form has one",
        replay.local_message);
    return;
  }
  if (!(worst > 1.0)) return;
  result.replay_rejected = true;
  result.replay_verdict = fmt::format(
      "IPOPT solved the discrete problem, but its optimum is not a motion of the model: an interval replayed by the "
      "simulator from the optimum's own state at its start ends {:.3e} from it in {}, whose range over the motion is "
      "{:.3e} (the limit is a tenth of it, {:.3e}; docs/optimize.md). The grid may be too coarse for the motion: "
      "give more nodes, a tighter --tolerance or a first guess (--guess FILE.csv). Or the problem may have no "
      "solution (an actuator that cannot move the system, a final state out of reach, a free final time run off to "
      "its bound) whose discrete form has one",
      result.local_difference, result.replay_coordinate, result.replay_limit / kReplayShare, result.replay_limit);
}

}  // namespace

const char* optimize_status_name(const OptimizeResult& result) {
  return result.replay_rejected ? "not a motion of the model" : nlp_status_name(result.solver.status);
}

OptimizeResult solve_optimal_control(const OptimalControlProblem& problem, const OptimizeOptions& options) {
  check_nlp_options(options.nlp);
  Transcription nlp(problem);
  OptimizeResult result;
  result.notes = problem.warnings;
  for (const std::string& note : nlp.notes()) result.notes.push_back(note);
  // The guess given with the solve, else the one the [optimize] section names.
  const std::filesystem::path guess = options.guess.empty() ? std::filesystem::path(problem.guess) : options.guess;
  if (!guess.empty()) {
    std::vector<double> x = nlp.start();
    const std::vector<std::string> notes = apply_guess(nlp, guess, x);
    nlp.set_start(std::move(x));
    result.notes.push_back("first guess: " + guess.string());
    result.notes.insert(result.notes.end(), notes.begin(), notes.end());
  }
  nlp.require_defined_at_start();
  result.solver = solve_nlp(nlp, options.nlp);
  if (result.solver.status == NlpStatus::unavailable) return result;
  std::vector<double> x = result.solver.x.empty() ? nlp.start() : result.solver.x;
  const int n = problem.n(), m = problem.m(), P = nlp.points();
  nlp.objective(x.data(), result.objective);
  result.constraint_violation = nlp.constraint_violation(x.data());
  result.points = P;
  result.t_end = problem.t0 + nlp.duration(x.data());
  for (int p = 0; p < P; ++p) {
    result.times.push_back(nlp.time(p, x.data()));
    for (int i = 0; i < n; ++i) {
      result.q.push_back(x[static_cast<std::size_t>(nlp.q_index(p, i))]);
      result.v.push_back(x[static_cast<std::size_t>(nlp.v_index(p, i))]);
      result.a.push_back(x[static_cast<std::size_t>(nlp.a_index(p, i))]);
    }
    for (int j = 0; j < m; ++j) result.u.push_back(x[static_cast<std::size_t>(nlp.u_index(p, j))]);
  }
  const ReplayResult replay = calc_replay(problem, result.times, result.q, result.v, result.u);
  result.replayed = replay.ok;
  result.replay_difference = replay.difference;
  result.replay_message = replay.message;
  apply_replay_rule(result, problem.model.coordinates, replay);
  if (!result.converged() && guess.empty())
    result.notes.push_back("IPOPT did not converge from the straight line between the boundary states, which can be a "
                           "stationary point of the constraints' violation (as for the Brockett integrator): give a "
                           "first guess, --guess FILE.csv (docs/optimize.md)");
  return result;
}

std::vector<std::string> optimize_columns(const OptimalControlProblem& problem) {
  std::vector<std::string> columns{"t"};
  for (const char* suffix : {"", "'", "''"})
    for (const std::string& c : problem.model.coordinates) columns.push_back(c + suffix);
  for (const OptimizeControl& c : problem.controls) columns.push_back("u_" + c.name);
  return columns;
}

std::vector<std::vector<double>> optimize_rows(const OptimalControlProblem& problem, const OptimizeResult& result) {
  const std::size_t n = static_cast<std::size_t>(problem.n()), m = static_cast<std::size_t>(problem.m());
  std::vector<std::vector<double>> rows;
  for (std::size_t p = 0; p < static_cast<std::size_t>(result.points); ++p) {
    std::vector<double> row{result.times[p]};
    for (const std::vector<double>* block : {&result.q, &result.v, &result.a})
      row.insert(row.end(), block->begin() + static_cast<std::ptrdiff_t>(p * n), block->begin() + static_cast<std::ptrdiff_t>((p + 1) * n));
    row.insert(row.end(), result.u.begin() + static_cast<std::ptrdiff_t>(p * m), result.u.begin() + static_cast<std::ptrdiff_t>((p + 1) * m));
    rows.push_back(std::move(row));
  }
  return rows;
}

std::string format_optimize_summary(const OptimalControlProblem& problem, const OptimizeResult& result) {
  std::string controls;
  for (const OptimizeControl& c : problem.controls) controls += (controls.empty() ? "" : ", ") + c.name;
  std::string out = fmt::format("nhdyn optimize {}: {} nodes, {}, controls {}, objective {}\n", problem.model.name,
                                problem.nodes, collocation_method_name(problem.method), controls,
                                problem.minimum_time ? "time" : "\"" + problem.objective_text + "\"");
  out += fmt::format("status: {} ({}{})\n", optimize_status_name(result), result.replay_rejected ? "IPOPT: " : "",
                     result.solver.message);
  if (result.solver.status == NlpStatus::unavailable) return out;
  out += fmt::format("iterations: {}\n", result.solver.iterations);
  out += fmt::format("objective: {:.10g}\n", result.objective);
  if (problem.free_time) out += fmt::format("t_end: {:.10g}\n", result.t_end);
  out += fmt::format("constraint violation: {:.3e}\n", result.constraint_violation);
  if (result.replayed)
    out += fmt::format("replay difference: {:.3e} (largest |q - q_replayed| at the nodes, replayed from t0; dop853, "
                       "rtol 1e-11)\n",
                       result.replay_difference);
  else
    out += fmt::format("replay difference: none ({})\n", result.replay_message);
  if (!result.replay_coordinate.empty())
    out += fmt::format("interval replay: {:.3e} in {} (largest over the intervals replayed from the optimum's state "
                       "at their start; limit {:.3e})\n",
                       result.local_difference, result.replay_coordinate, result.replay_limit);
  for (const std::string& note : result.notes) out += "note: " + note + "\n";
  return out;
}

}  // namespace nhdyn
