// Model: a numeric description of one constrained mechanical system — its coordinates,
// constraints, parameter values, initial state, simulation defaults, and the Evaluator that
// computes its terms. Built once (by a built-in model's make_* function or the model compiler),
// then only read while it runs; between runs its parameters may change (parameters.hpp), which
// re-binds the evaluator without recompiling. Everything that changes in time lives in Data
// (data.hpp).
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "nhdyn/core/types.hpp"
#include "nhdyn/model/evaluator.hpp"
#include "nhdyn/model/event.hpp"
#include "nhdyn/model/output.hpp"
#include "nhdyn/model/run_options.hpp"

namespace nhdyn {

struct ContactForceModel;  // contact_forces.hpp
struct ContactModeModel;   // contact_modes.hpp

// The level at which a constraint is given (docs/notation.md section 2).
enum class ConstraintLevel { position, velocity, acceleration };

// "position", "velocity" or "acceleration", as messages and printed equations name the level.
inline const char* level_name(ConstraintLevel level) {
  switch (level) {
    case ConstraintLevel::position: return "position";
    case ConstraintLevel::velocity: return "velocity";
    case ConstraintLevel::acceleration: return "acceleration";
  }
  return "acceleration";
}

struct Constraint {
  std::string name;
  ConstraintLevel level = ConstraintLevel::velocity;
  std::string expression;  // as a user reads it, e.g. "y' - tan(phi) x' = 0"
  std::string where = {};  // "file:line:column" where it was written (model files), else ""
};

// A program (docs/derivations/program-motion.md): a constraint the motion must follow that no
// ideal contact enforces, realized by its actuator, a generalized force along the column B_j of the
// actuator matrix with an unknown magnitude u_j. (The code the evaluator runs is a tape,
// model/tape.hpp: "program" means this only.)
struct ProgramConstraint {
  std::string name;
  ConstraintLevel level = ConstraintLevel::position;
  std::string expression;  // as a user reads it, e.g. "phi - omega*t"
  std::string actuator;    // as a user reads it: a coordinate name or "[e1, ..., en]"
};

// A parameter and its current value. A derived parameter has the expression of its value in the
// others (k = "4*m"), re-evaluated when they change (parameters.hpp); a base one has none.
struct Parameter {
  std::string name;
  double value = 0.0;
  std::string unit;
  std::string expression = {};  // "" for a base parameter (the initializer spares {name, value, unit} a warning)
};

// What a run of this model does when the user says nothing else (run_options.hpp).
using SimulationDefaults = RunOptions;

// A pair of coordinates that a plot may draw as a path y(x) (planar systems).
struct PlanarPath {
  int x = 0;
  int y = 1;
};

// Coordinates a model added for a contact point (a [[contacts]] entry without `coordinates`,
// docs/derivations/rolling-bodies.md section 10): their initial values are found at the start of a
// run from the rest of the initial state (analysis/initial_state.hpp, complete_initial_state).
struct ContactCoordinates {
  std::string contact;
  std::string where;             // file:line of the contact
  std::vector<int> coordinates;  // indices into q
  std::vector<int> constraints;  // as many position constraints that hold them (indices into constraints)
};

// A contact whose closed-form point turns singular along a motion (a disk or torus lying flat,
// docs/derivations/rolling-bodies.md section 2): where a run fails and `measure` (one output, in t
// and q, reading the parameters: bind it) is below `threshold` there, the run's message is
// `reason`, naming the contact (analysis/simulation.hpp).
struct ContactWatch {
  std::string contact;
  std::string where;
  Tape measure;
  double threshold = 0.0;
  std::string reason;
  std::string quantity;     // what the measure is, for the message
  bool every_step = false;  // checked at every accepted step (symbolic/spec.hpp, SpecContactWatch)
  bool touching_only = false;  // checked only while the contact touches (contact modes)
  bool free_only = false;      // checked only while the contact is free
  std::string entry = "contact";  // what the message calls it ("wheel" for a [[wheels]] entry)
};

// A value the model file gives that must be positive (a contact's size, a body's mass), in the
// parameters (`value`, one output: bind it). The load judges it at the file's values; a change of
// the parameters (--set, set_parameter) is refused where it makes one zero or negative
// (parameters.hpp, check_positive_values), rather than running a ball of negative radius.
struct PositiveValue {
  std::string where;  // file:line
  std::string what;   // "contact 'ball': sphere r"
  std::string text;   // as written: "r"
  Tape value;
  // The sizes of one contact shape kept in proportion (an ellipsoid's semi-axes:
  // ContactShape::sizes_in_proportion) share a group ("contact 'foot'"), within which they must
  // stay within kLargestSizeRatio of each other (model/parameters.hpp); "" for a value on its own.
  std::string group = {};
};

struct Model {
  std::string name;
  std::string description;
  std::vector<std::string> coordinates;  // n names, in the order of q
  std::vector<Constraint> constraints;   // s, in the order of the rows of b
  // m programs with their actuators, in the order of the rows of b_p and the columns of B; empty
  // for a model without programs. Solved by formulation/program_motion.hpp.
  std::vector<ProgramConstraint> program_constraints;
  std::vector<Parameter> parameters;     // the values the evaluator computes with, in its order;
                                         // change them with set_parameter (parameters.hpp)
  double t0 = 0.0;
  Vector q0;                             // n, initial coordinates
  Vector v0;                             // n, initial velocities
  // Which initial values the model file wrote (n each, or empty: none). --fix-initial keeps them.
  std::vector<bool> q0_written, v0_written;
  std::vector<ContactCoordinates> contact_coordinates;  // found at the start of every run
  std::vector<ContactWatch> contact_watches;            // a failed run looks at them
  std::vector<PositiveValue> positive_values;           // judged at each change of the parameters
  SimulationDefaults defaults;
  std::optional<PlanarPath> path;
  // Immutable and bound to the values of `parameters`: Model copies (one per thread) share it
  // until one of them sets a parameter, which gives that copy a new one.
  std::shared_ptr<const Evaluator> evaluator;
  // The model's own events ([[events]] of its file); a run locates those of its options
  // (SimulationOptions::events, analysis/simulation.hpp), which `nhdyn simulate` starts from these.
  std::vector<Event> events;
  // The contact forces of a multibody model's wheels and knife edges (contact_forces.hpp,
  // docs/derivations/contact-forces.md); null for a model without contacts.
  std::shared_ptr<const ContactForceModel> contact_forces;
  // The contacts that may slide or lift off (contact_modes.hpp, docs/contact-modes.md); null when
  // no contact has `friction` or `unilateral`.
  std::shared_ptr<const ContactModeModel> contact_modes;
  // Derived outputs ([outputs], multibody points): extra result columns (model/output.hpp).
  ModelOutputs outputs;

  int n() const { return static_cast<int>(coordinates.size()); }
  int s() const { return static_cast<int>(constraints.size()); }
  // k = n - s, the degrees of freedom with every constraint held; 0 for a model with s >= n, whose
  // contacts are never all held (contact_modes.hpp, constraints_always_held): its solve keeps the
  // rows of the contacts' current modes.
  int k() const { return n() > s() ? n() - s() : 0; }
  int m() const { return static_cast<int>(program_constraints.size()); }
  // Number of constraints given at position level, and at position or velocity level.
  int position_constraints() const;
  int velocity_constraints() const;
  // The same for the programs.
  int position_programs() const;
  int velocity_programs() const;
};

// Checks the dimensions and names of a model before use; throws ModelError naming what is wrong.
void check_model_shape(const Model& model);

// Throws InputError when the model declares as many constraints as coordinates or more (s >= n,
// allowed for contacts that are never all held, contact_modes.hpp): `what` (a linearization,
// generated code, an optimization) holds every constraint at once, which leaves no motion.
void require_fewer_constraints(const Model& model, const std::string& what);

}  // namespace nhdyn
