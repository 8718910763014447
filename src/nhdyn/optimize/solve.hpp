// `nhdyn optimize` as one library call: transcribe the problem (transcription.hpp), solve it with
// IPOPT (nlp.hpp), replay the controls (replay.hpp), and the summary and CSV the command prints
// and writes (docs/optimize.md). The result holds the motion at every point (nodes and, for
// Hermite-Simpson, midpoints) with the controls, whether IPOPT converged or not: a failed solve's
// last iterate is written as a partial result.
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "nhdyn/frontend/optimize_problem.hpp"
#include "nhdyn/optimize/nlp.hpp"

namespace nhdyn {

struct OptimizeOptions {
  NlpOptions nlp;
  // A first guess from a CSV with the columns `optimize` writes (t, the coordinates, their
  // velocities x' and optionally x'' and u_NAME), interpolated linearly to the points; empty for
  // the straight line between the boundary states.
  std::filesystem::path guess;
};

struct OptimizeResult {
  NlpResult solver;                 // status, IPOPT's words, iterations, the last iterate
  double objective = 0.0;           // J at the last iterate
  double constraint_violation = 0.0;  // largest violation of a bound or constraint at the last iterate
  bool replayed = false;
  double replay_difference = 0.0;   // calc_replay (replay.hpp)
  std::string replay_message;       // why the replay stopped, when not replayed
  double t_end = 0.0;
  int points = 0;
  std::vector<double> times;        // P
  std::vector<double> q, v, a, u;   // P x n (or m), a row per point
  std::vector<std::string> notes;   // the rank rule's rows left out, the guess's source, warnings
  // The replay rule (docs/optimize.md, "When the result is not a motion of the model"): a result
  // IPOPT calls solved one of whose intervals, replayed from the optimum's own state at its start,
  // ends further from the optimum than replay_limit in some coordinate is a solution of the
  // discrete equations only, not a motion of the model (a grid too coarse for it, or a problem
  // without solution whose discrete form has one).
  double motion_range = 0.0;        // the largest range (max - min) of a coordinate over the points
  std::vector<double> local_replay;  // n: ReplayResult::local, each coordinate's largest interval error
  std::string replay_coordinate;     // the coordinate judged: the largest local_replay against its limit
  double local_difference = 0.0;     // its local_replay
  double replay_limit = 0.0;         // its limit (replay_limit_of)
  bool replay_rejected = false;     // converged() and local_difference > replay_limit, or an interval's replay failed
  std::string replay_verdict;       // when replay_rejected: the sentence that says so and what to do
  // IPOPT converged (solved, or solved to its acceptable level).
  bool converged() const { return nlp_converged(solver.status); }
  // IPOPT converged and the replay confirms a motion of the model: a result to use.
  bool solved() const { return converged() && !replay_rejected; }
};

// The replay rule's limit for a coordinate: a tenth of its own range over the optimum, and for a
// coordinate that (nearly) stays still 1e-8 (1 + its largest |q|), above the replay's own round-off.
inline constexpr double kReplayShare = 0.1;
inline constexpr double kReplayFloor = 1e-8;

// nlp_status_name of the solver's status, or "not a motion of the model" for a result the
// replay rule rejects.
const char* optimize_status_name(const OptimizeResult& result);

// Throws InputError for a problem the transcription refuses (transcription.hpp) or a guess file
// that lacks a column, holds a value that is not finite, has times that decrease or none inside
// [t0, t_end] (a guess covering part of it gets a note); never for the solver's failure, which the
// result's status says.
OptimizeResult solve_optimal_control(const OptimalControlProblem& problem, const OptimizeOptions& options = {});

// The CSV's columns: t, the coordinates, their velocities (x'), accelerations (x''), then u_NAME per control.
std::vector<std::string> optimize_columns(const OptimalControlProblem& problem);
// One row per point, in the order of optimize_columns.
std::vector<std::vector<double>> optimize_rows(const OptimalControlProblem& problem, const OptimizeResult& result);

// The summary lines: the problem, then status:, iterations:, objective:, constraint violation:,
// replay difference:, and the notes.
std::string format_optimize_summary(const OptimalControlProblem& problem, const OptimizeResult& result);

}  // namespace nhdyn
