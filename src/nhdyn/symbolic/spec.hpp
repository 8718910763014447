// Spec: the symbolic, editable description of a mechanical system, as a user writes it in a paper
// — coordinates, parameters, kinetic and potential energy, nonconservative forces, constraints at
// position, velocity or acceleration level, optional independent coordinates or analytic D,
// initial conditions and simulation defaults. Built by SpecBuilder (spec_builder.hpp), which the
// model-file loader uses too; derived by derive() (derivation.hpp) and compiled into a numeric
// Model by compile_model() (compile.hpp). GiNaC stays inside the symbolic module.
#pragma once

#include <ginac/ginac.h>

#include <array>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "nhdyn/model/model.hpp"
#include "nhdyn/symbolic/visual.hpp"

namespace nhdyn::symbolic {

struct SpecContactForces;  // contact_forces.hpp

// Where a piece of a spec came from, for error messages: "file.toml:12:7". Empty file for specs
// built in C++; line and column are 1-based, 0 when unknown.
struct SourceLocation {
  std::string file;
  int line = 0;
  int column = 0;
  // "file:line:column" (or fewer parts when unknown); "" when nothing is known.
  std::string describe() const;
};

// Throws ModelError("where: context: problem"), leaving out the parts that are empty.
[[noreturn]] void throw_model_error(const SourceLocation& where, const std::string& context, const std::string& problem);

// One symbol table per spec owns every symbol: GiNaC tells symbols apart by identity, so every
// expression of a spec must be built from these. Names: "t"; each coordinate "x", its velocity
// "x'" and acceleration "x''"; each parameter.
class SymbolTable {
 public:
  SymbolTable();
  // The symbols are kept on GiNaC's heap and handed out as references to those objects: an
  // expression made from them holds the symbol itself, where one made from a symbol object of our
  // own gets a copy of it (an allocation per use, and equal symbols that are not the same object).
  const GiNaC::symbol& time() const { return symbol_of(t_); }
  // Adds a coordinate with its velocity and acceleration symbols; returns its index.
  int add_coordinate(const std::string& name);
  void add_parameter(const std::string& name);
  int coordinates() const { return static_cast<int>(q_.size()); }
  const GiNaC::symbol& coordinate(int i) const { return symbol_of(q_[static_cast<std::size_t>(i)]); }
  const GiNaC::symbol& velocity(int i) const { return symbol_of(v_[static_cast<std::size_t>(i)]); }
  const GiNaC::symbol& acceleration(int i) const { return symbol_of(a_[static_cast<std::size_t>(i)]); }
  // The generalized reaction on coordinate i, "R_x" as the results name it: known only to the
  // expressions of outputs and events (SpecBuilder::parse_derived), not to T, V or constraints.
  const GiNaC::symbol& reaction(int i) const { return symbol_of(r_[static_cast<std::size_t>(i)]); }
  const GiNaC::symbol& parameter(const std::string& name) const;  // throws std::out_of_range
  bool has(const std::string& name) const { return by_name_.count(name) > 0; }
  // The symbol called `name`, if any ("t", "x", "x'", "x''", a parameter).
  std::optional<GiNaC::symbol> find(const std::string& name) const;
  // The same as the expression that holds it (nullptr when there is none): no copy of the symbol.
  const GiNaC::ex* expression_of(const std::string& name) const;
  // Every known name, for suggestions in error messages.
  std::vector<std::string> names() const;
  // The parser's table: every name mapped to its symbol, plus the constant pi.
  GiNaC::symtab parser_table() const;

 private:
  static const GiNaC::symbol& symbol_of(const GiNaC::ex& e) { return GiNaC::ex_to<GiNaC::symbol>(e); }
  GiNaC::ex t_;
  std::vector<GiNaC::ex> q_, v_, a_, r_;
  std::map<std::string, GiNaC::ex> by_name_;
};

struct SpecParameter {
  std::string name;
  double value = 0.0;  // of a derived parameter: its expression's value (update_parameters)
  std::string unit;
  SourceLocation where;
  std::string expression = {};  // a derived parameter's definition in the others ("4*m"); "" when base
};

struct SpecConstraint {
  std::string name;
  ConstraintLevel level = ConstraintLevel::velocity;
  GiNaC::ex expression;  // phi(t, q), f(t, q, q') or g(t, q, q', q''); the constraint is expression = 0
  std::string text;      // as the user wrote it
  SourceLocation where;
};

// An event ([[events]] of a model file): g(t, q, q') crossing zero (model/event.hpp).
struct SpecEvent {
  std::string name;
  GiNaC::ex expression;  // g
  std::string text;      // as the user wrote it
  SourceLocation where;
  EventDirection direction = EventDirection::both;
  EventAction action = EventAction::record;
};

// A program (docs/derivations/program-motion.md): a constraint the motion must follow, given like
// a SpecConstraint, that no ideal contact enforces: the actuator it names realizes it, with the
// generalized force `actuator` (n entries, the column B_j of the actuator matrix B) times an
// unknown magnitude u_j.
struct SpecProgram {
  SpecConstraint constraint;        // name, level, expression = 0, text, where
  std::vector<GiNaC::ex> actuator;  // n entries: a unit column for `actuator = "delta"`
  std::string actuator_text;        // as the user wrote it: "delta" or "[0, 0, 1]"
  SourceLocation actuator_where;
};

// A derived output ([outputs] of a model file, or a multibody model's automatic point positions
// and velocities): a named expression in t, q, q', q'', the reactions R_x and the parameters,
// written as a column of the results (symbolic/outputs.hpp compiles it).
struct SpecOutput {
  std::string name;
  GiNaC::ex expression;  // in t, q, q', q'', SymbolTable::reaction and the parameters
  std::string text;      // as the user wrote it (for automatic outputs: how it was made)
  SourceLocation where;
  bool automatic = false;  // made by the multibody front end, not written by the user
  GiNaC::symbol symbol;    // stands for the output in the expressions of later outputs and events
};

// A rolling contact whose shape is an implicit surface f = 0 (rolling_contact.hpp): what its
// convexity at the start is judged from (check_contact_convexity), in world axes at (t, q):
// near the contact the shape rises along the ground's normal n by 1/2 w^T body w and the ground by
// 1/2 w^T ground w, for w in the tangent plane. Rolling on the lowest point needs body positive
// definite there and body - ground too (the contact is unique).
struct SpecConvexity {
  std::string contact;
  SourceLocation where;
  std::vector<GiNaC::ex> normal;                  // n, unit (3)
  GiNaC::matrix body = GiNaC::matrix(3, 3);
  GiNaC::matrix ground = GiNaC::matrix(3, 3);     // zero for a plane
  // A thin disk (ContactShape::rim): its rim's direction at the contact point (world axes, any
  // length; empty for other shapes) and its curvature along it, which stand for `body`.
  std::vector<GiNaC::ex> rim;
  GiNaC::ex rim_curvature;
};

// Coordinates that the multibody front end added for a contact point ([[contacts]] without
// `coordinates`, docs/derivations/rolling-bodies.md section 10): nobody writes their initial values;
// nhdyn finds them from the rest of the initial state by solving the position constraints that
// hold them (Newton, solve_contact_coordinates in rolling_contact.hpp), and their velocities from
// those constraints' time derivatives.
struct SpecContactCoordinates {
  std::string contact;
  SourceLocation where;
  std::vector<int> coordinates;          // the added coordinates' indices
  std::vector<std::string> constraints;  // as many position constraints that hold them
  // Where Newton starts: one expression per coordinate in t, q and the parameters (a terrain's
  // u, v: the centre's X, Y). For an implicit shape's point y, 0 here and `ray` below.
  std::vector<GiNaC::ex> start;
  // An implicit shape f(y) = 0: y starts on the ray from its centre along `ray` (body axes, in t,
  // q), where f changes sign; `surface` is f in the three coordinates (empty ray when none).
  std::vector<GiNaC::ex> ray;
  GiNaC::ex surface = 0;
  std::array<int, 3> point = {-1, -1, -1};  // the coordinates of y, when the ray is given
  // A surface ground g(U) = 0 (rolling-bodies.md section 11): U, its first three coordinates,
  // starts where the line from `from` (the shape's centre, world, in t and q) along grad F meets
  // F = 0; F = -sigma g in U's coordinates, negative on the body's side (empty `from` when none).
  std::vector<GiNaC::ex> from;
  GiNaC::ex ground = 0;
  std::array<int, 3> ground_point = {-1, -1, -1};
};

// A closed-form contact point that turns singular along the motion (a disk lying flat): a run
// stops where `measure` (in t, q) falls below `threshold`, with `reason` (rolling_contact.hpp).
struct SpecContactWatch {
  std::string contact;
  SourceLocation where;
  GiNaC::ex measure;
  double threshold = 0.0;
  std::string reason;
  std::string quantity = "1 - (axle . normal)^2";  // what the measure is, in the message
  // Checked at every accepted step, ending the run there (exit 1), rather than only where a run
  // fails: for a singularity that does not make the equations fail (a surface's tangents vanish).
  bool every_step = false;
  // With contact modes: checked only while the contact touches (rolling or sliding: its convexity),
  // or only while it is free (in the air: the point below it); neither: in every mode.
  bool touching_only = false;
  bool free_only = false;
  std::string entry = "contact";  // what the message calls it: "contact 'NAME'", "wheel 'NAME'"
  // The measure is a wheel's |axle x normal| written +-u (contact_geometry.hpp): the load refuses
  // a start where it is below its threshold (check_contact_watches_at_start).
  bool signed_root = false;
};

// A value the file gives that must be positive (a contact's size, a body's mass): the load judges
// it at the file's values, and the model keeps it (Model::positive_values) to judge it again
// whenever the parameters change (--set, set_parameter), where a negative radius would otherwise
// run.
struct SpecPositive {
  SourceLocation where;
  std::string what;  // what the message names: "contact 'ball': sphere r"
  std::string text;  // as written: "r"
  GiNaC::ex value;   // in the parameters
  std::string group = {};  // PositiveValue::group: the sizes of one contact shape kept in proportion
};

struct Spec {
  std::string name;
  std::string description;
  SourceLocation where;
  SymbolTable symbols;
  std::vector<std::string> coordinates;      // n, in order
  std::vector<SpecParameter> parameters;
  GiNaC::ex kinetic_energy;                  // T(t, q, q')
  GiNaC::ex potential_energy = 0;            // V(t, q)
  std::vector<GiNaC::ex> forces;             // n nonconservative generalized forces (0 if none)
  std::vector<SpecConstraint> constraints;
  std::vector<SpecProgram> programs;         // m programs with their actuators ([[programs]])
  std::vector<std::string> independent;      // optional: k coordinates kept independent (partitioned D)
  std::optional<GiNaC::matrix> complement;   // optional analytic D, k x n
  SourceLocation complement_where;
  double t0 = 0.0;
  std::vector<GiNaC::ex> q0, v0;             // n initial values, expressions in the parameters
  // Which of them the model file's [initial] wrote (n each; empty: none, as in a model built in
  // C++). --fix-initial keeps those and moves the others (analysis/initial_state.hpp).
  std::vector<bool> q0_written, v0_written;
  std::vector<SpecContactCoordinates> contact_coordinates;  // found at the start, not written
  std::vector<SpecContactWatch> contact_watches;  // checked where a run fails (model.hpp)
  std::vector<SpecPositive> positive_values;      // judged again at each change of the parameters
  // Optional exact motion q(t) from the initial state, n expressions in t and the parameters
  // (empty when the model gives none); compare --reference analytic measures runs against it.
  std::vector<GiNaC::ex> solution;
  std::vector<SourceLocation> solution_where;  // where each expression was written
  SimulationDefaults defaults;
  std::string method;                        // default formulation, "" = sanh
  std::string integrator;                    // default integrator, "" = dopri5
  std::optional<double> rtol, atol;
  std::optional<std::pair<std::string, std::string>> path;  // coordinates to draw as y(x)
  std::vector<SpecEvent> events;             // compiled into Model::events (symbolic/events.hpp)
  std::vector<SpecOutput> outputs;           // compiled into Model::outputs (symbolic/outputs.hpp)
  SpecVisual visual;  // what a report's 3-D scene draws ([visual], or the bodies): symbolic/visual.hpp
  // The bodies and contacts of a multibody model, for its contact forces (contact_forces.hpp);
  // null for a hand-written model.
  std::shared_ptr<const SpecContactForces> contact_forces;
  std::vector<SpecConvexity> convexity;  // checked at the initial state before the derivation

  int n() const { return static_cast<int>(coordinates.size()); }
  int s() const { return static_cast<int>(constraints.size()); }
  int m() const { return static_cast<int>(programs.size()); }
  // The numeric values of the parameters as a substitution list (parameter symbol == value).
  GiNaC::lst parameter_values() const;
  // Sets a parameter's value (it becomes a base parameter) and re-evaluates the derived ones;
  // throws InputError naming the unknown name and the nearest known one.
  void set_parameter(const std::string& name, double value);
  // `--set NAME=EXPR` for each element of `sets` (model/parameters.hpp, apply_parameter_sets).
  void apply_parameter_sets(const std::vector<std::string>& sets);
};

}  // namespace nhdyn::symbolic
