// The [optimize] section of a model file (docs/optimize.md) read and compiled into numbers: an
// optimal control problem on the model's Do Sanh equations with controls u along actuator
// directions B(t, q, q'), an objective, boundary states, bounds and path constraints
// (docs/derivations/optimal-programs.md, section 1). The expressions that read the controls (the
// actuator forces B u, the integrand, the final-time term, the path constraints) are compiled into
// tapes (straight-line code) over the "control layout": n + m coordinates [q; u] whose velocities are
// [q'; 0], so that the tangent mode of model/detail/tape_tangent.hpp differentiates them in q, q', u
// and t alike. The transcription and the solver (src/nhdyn/optimize/) read this struct only.
//
//     model file --load_model_described--> Model --load_optimal_control_problem--> OptimalControlProblem
#pragma once

#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "nhdyn/frontend/load_model.hpp"
#include "nhdyn/model/tape.hpp"

namespace nhdyn {

enum class CollocationMethod { trapezoidal, hermite_simpson };
// Where the model's constraints are imposed (docs/derivations/optimal-programs.md, section 5):
// at acceleration level at every point (the Do Sanh form), or at the level given (velocity-level
// constraints only) at every point after the first.
enum class OptimizeConstraintLevel { acceleration, given };

// "trapezoidal", "hermite-simpson"; "acceleration", "given".
const char* collocation_method_name(CollocationMethod method);
const char* constraint_level_name(OptimizeConstraintLevel level);

inline constexpr double kNoBound = std::numeric_limits<double>::infinity();

struct OptimizeControl {
  std::string name;      // the CSV column is u_<name>
  std::string actuator;  // as written: a coordinate or "[e1, ..., en]"
  std::string where;     // file:line:column of the actuator, for messages
  double lower = -kNoBound;
  double upper = kNoBound;
};

// One fixed value of a boundary state: coordinate `index` (velocity when `velocity`).
struct BoundaryValue {
  int index = 0;
  bool velocity = false;
  double value = 0.0;
  std::string where;  // file:line:column of the value, for messages
};

// A path constraint lower <= g(t, q, q', u) <= upper, imposed at every point.
struct PathConstraint {
  std::string text;  // as written, e.g. "(x - 5)^2 + (y - 1)^2 >= 1"
  std::string where;  // file:line:column, for messages
  double lower = -kNoBound;
  double upper = kNoBound;
  // What g reads, 2n + m flags in the order (q, q', u), and t: a constraint that reads only fixed
  // boundary values is decided before the solve (Transcription).
  std::vector<char> reads;
  bool reads_time = false;
};

struct OptimalControlProblem {
  Model model;                           // the system (its evaluator a TapeEvaluator)
  std::vector<OptimizeControl> controls;  // m
  // Programs over the control layout (n + m coordinates [q; u], velocities [q'; 0]), bound to the
  // model's parameter values:
  Tape force;                  // n outputs: B(t, q, q') u, the actuators' generalized force
  Tape actuators;              // n m outputs: B(t, q, q') column by column, for the checks of a first guess
  Tape integrand;              // 1 output: L(t, q, q', u) (the constant 0 when not given)
  std::optional<Tape> final_term;  // 1 output: the Mayer term M(t, q, q') at t_end
  Tape path;                   // one output per path constraint
  std::vector<PathConstraint> path_constraints;
  bool minimum_time = false;      // objective = "time": J = t_end - t0
  std::string objective_text;     // as written, for the summary
  std::string objective_where, final_term_where;  // file:line:column of objective and objective_final
  double t0 = 0.0;
  double t_end = 1.0;             // fixed final time, or the first guess of a free one
  bool free_time = false;         // t_end = { free = [min, max] }
  double duration_min = 0.0, duration_max = 0.0;  // bounds of t_end - t0 when free
  int nodes = 0;                  // N + 1
  CollocationMethod method = CollocationMethod::hermite_simpson;
  OptimizeConstraintLevel level = OptimizeConstraintLevel::acceleration;
  std::vector<BoundaryValue> initial, final;
  // Bounds on the coordinates and velocities at every point: 2n each, [q; q'].
  std::vector<double> state_lower, state_upper;
  std::vector<std::string> state_bounds_where;  // 2n: file:line:column of each bound given, else ""
  std::vector<std::string> warnings;  // e.g. a control that neither the objective nor a bound sees
  // [optimize] guess = "FILE.csv": the first guess when none is given (--guess, guess=), its path
  // relative to the model file's folder resolved; empty without the key.
  std::string guess;

  int n() const { return model.n(); }
  int m() const { return static_cast<int>(controls.size()); }
};

// Reads the [optimize] section of the model file `source` (the text load_model_described
// compiled into `loaded`) and compiles its expressions against the model's names and parameter
// values (after --set). Throws ModelError "file:line:column: ..." for anything wrong in the
// section (an unknown key or symbol, a control named like a coordinate or acting on nothing, lower
// > upper, a number that is not one), InputError when the model has no [optimize] section or is
// not a model file.
OptimalControlProblem load_optimal_control_problem(const ModelSource& source, const LoadedModel& loaded);

}  // namespace nhdyn
