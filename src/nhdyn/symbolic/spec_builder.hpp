// The C++ model-building API: builds a Spec the way a model stands in a paper, from names and
// expressions written as text. The model-file loader (frontend/model_file.hpp) is a thin layer over it.
//
// Expressions use GiNaC's syntax (+ - * / ^, parentheses, sin cos tan exp log sqrt abs asin acos
// atan atan2 sinh cosh tanh, the constant pi), the time t, the coordinates by name, velocities
// with one prime (x') and accelerations with two (x''), and the parameters by name.
// Every error is a ModelError whose message starts with the SourceLocation given (file:line:col).
#pragma once

#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

#include "nhdyn/symbolic/spec.hpp"

namespace nhdyn::symbolic {

class SpecBuilder {
 public:
  explicit SpecBuilder(std::string name, SourceLocation where = {});

  SpecBuilder& description(std::string text);
  // Coordinates and parameters must be declared before the expressions that use them.
  SpecBuilder& coordinate(const std::string& name, SourceLocation where = {});
  SpecBuilder& parameter(const std::string& name, double value, std::string unit = "", SourceLocation where = {});

  // Parses `text` against the symbols declared so far. An unknown name is reported with the
  // nearest known one ("unknown symbol 'rh0'; did you mean 'rho'?"), the velocity of an unknown
  // coordinate as such ("'u'' is the velocity of 'u', which is not a coordinate").
  GiNaC::ex parse(const std::string& text, const SourceLocation& where = {}) const;

  SpecBuilder& kinetic_energy(const std::string& text, SourceLocation where = {});
  SpecBuilder& potential_energy(const std::string& text, SourceLocation where = {});
  // Nonconservative generalized force on one coordinate (added to -dV/dq).
  SpecBuilder& force(const std::string& coordinate, const std::string& text, SourceLocation where = {});
  // A constraint `text = 0` given at `level`. The level must match the expression: a position
  // constraint may not contain velocities, a velocity constraint must contain some velocity and no
  // acceleration, an acceleration constraint must contain some acceleration.
  SpecBuilder& constraint(const std::string& name, ConstraintLevel level, const std::string& text,
                          SourceLocation where = {});
  // The same with the level inferred from the highest derivative present.
  SpecBuilder& constraint(const std::string& name, const std::string& text, SourceLocation where = {});
  // A program `text = 0` at `level` (docs/derivations/program-motion.md), checked like a
  // constraint, realized by a generalized force on the coordinate `actuator` (a torque or force
  // on it), or along `actuator_direction` (n expressions over t, q, q' and the parameters). The
  // name must differ from every constraint's and program's.
  SpecBuilder& program(const std::string& name, ConstraintLevel level, const std::string& text,
                       const std::string& actuator, SourceLocation where = {}, SourceLocation actuator_where = {});
  SpecBuilder& program(const std::string& name, ConstraintLevel level, const std::string& text,
                       const std::vector<std::string>& actuator_direction, SourceLocation where = {},
                       SourceLocation actuator_where = {});
  // k coordinates to keep independent: the partitioned D is then the one for this choice.
  SpecBuilder& independent(const std::vector<std::string>& coordinates, SourceLocation where = {});
  // An analytic D, k rows of n expressions each.
  SpecBuilder& complement(const std::vector<std::vector<std::string>>& rows, SourceLocation where = {});
  // Initial value of one coordinate and its velocity (expressions in the parameters).
  SpecBuilder& initial(const std::string& coordinate, const std::string& q0, const std::string& v0,
                       SourceLocation where = {});
  SpecBuilder& initial_time(double t0);
  // The exact motion of one coordinate, q(t), as an expression in t and the parameters (a closed
  // form such as docs/derivations/appell.md gives). Velocity and acceleration are its derivatives.
  // Give it for every coordinate or none; compile_model checks it against the initial state.
  SpecBuilder& solution(const std::string& coordinate, const std::string& text, SourceLocation where = {});
  SpecBuilder& defaults(const SimulationDefaults& defaults);
  SpecBuilder& method(const std::string& name);
  SpecBuilder& integrator(const std::string& name);
  SpecBuilder& tolerances(std::optional<double> rtol, std::optional<double> atol);
  SpecBuilder& path(const std::string& x, const std::string& y);

  // For front ends that build expressions themselves (multibody.hpp), from this builder's symbols:
  // adds to T and V (what kinetic_energy()/potential_energy() set, or zero), and appends a
  // constraint `expression = 0` whose `text` is shown to users in place of the expression. The
  // constraint's name and level are checked as for the text form.
  SpecBuilder& add_energies(const GiNaC::ex& kinetic, const GiNaC::ex& potential);
  SpecBuilder& constraint(const std::string& name, ConstraintLevel level, const GiNaC::ex& expression,
                          const std::string& text, SourceLocation where = {});
  // What a multibody front end knows about its bodies and contacts, for the contact forces
  // (contact_forces.hpp; set by MultibodyBuilder::apply()).
  SpecBuilder& contact_forces(std::shared_ptr<const SpecContactForces> contacts) {
    spec_.contact_forces = std::move(contacts);
    return *this;
  }
  // An implicit shape's curvatures, checked at the initial state (spec.hpp, SpecConvexity).
  SpecBuilder& convexity(SpecConvexity check) {
    spec_.convexity.push_back(std::move(check));
    return *this;
  }
  // Coordinates a front end added for a contact point, found at the start rather than written
  // (spec.hpp, SpecContactCoordinates): build() does not ask for their initial values.
  SpecBuilder& contact_coordinates(SpecContactCoordinates added) {
    spec_.contact_coordinates.push_back(std::move(added));
    return *this;
  }
  // The report's 3-D scene (spec.visual, visual.hpp), filled by the front ends in the order the
  // model gives its parts: an item drawn (the multibody builder draws its bodies and wheels; the
  // model file adds its frames' axes, its contacts' shapes and its [visual] items).
  SpecBuilder& visual_item(VisualItem item) {
    spec_.visual.items.push_back(std::move(item));
    return *this;
  }
  // Whether the scene is planar (every position has two components: the (x, y) plane, y up) and
  // whether it is drawn over the ground's grid (a multibody model: set by MultibodyBuilder).
  SpecBuilder& visual_scene(bool planar, bool ground) {
    spec_.visual.planar = planar;
    spec_.visual.ground = ground;
    return *this;
  }
  // A contact whose closed-form point may turn singular along the motion (spec.hpp).
  SpecBuilder& contact_watch(SpecContactWatch watch) {
    spec_.contact_watches.push_back(std::move(watch));
    return *this;
  }
  // A value that must stay positive whatever the parameters become (spec.hpp).
  SpecBuilder& positive_value(SpecPositive value) {
    spec_.positive_values.push_back(std::move(value));
    return *this;
  }
  // Derived outputs (docs/model-format.md, [outputs]; symbolic/outputs.hpp): a named expression
  // in t, q, q', q'', the reactions R_x, the parameters and the outputs declared before it, that
  // becomes a column of the results. Its name must be a new name (not a coordinate, parameter,
  // reaction or earlier output); collisions with the other result columns are checked when the
  // columns are made (io/results.hpp). The second form is for front ends that build the
  // expression themselves (the multibody points' positions); `automatic` marks those.
  SpecBuilder& output(const std::string& name, const std::string& text, SourceLocation where = {});
  SpecBuilder& output(const std::string& name, const GiNaC::ex& expression, const std::string& text,
                      SourceLocation where = {}, bool automatic = false);
  // Parses `text` as parse() does, with the reactions R_x and the outputs declared so far known
  // too (each output replaced by its expression): the expressions of outputs and events.
  // `defining`: the output whose expression this is (naming it is refused as a self reference).
  // Refused too: an announced output not declared yet (a forward reference, announce_outputs), and
  // an expression that, with its outputs written out, has more than 2e5 operations (a chain of
  // outputs each naming the one above several times grows exponentially).
  GiNaC::ex parse_derived(const std::string& text, const SourceLocation& where = {},
                          const std::string& defining = {}) const;
  // The names (and places) of every output a front end is about to declare, in order, so that an
  // output naming one declared below it is told so instead of "unknown symbol".
  SpecBuilder& announce_outputs(std::vector<std::pair<std::string, SourceLocation>> names);

  // The spec as built so far: its symbols and parameter values, for such front ends.
  const Spec& current() const { return spec_; }

  // Checks completeness (coordinates, a kinetic energy, fewer constraints than coordinates,
  // names unique, initial values for all or none — none means zero — and a solution for all
  // coordinates or none) and returns the Spec.
  Spec build() const;

 private:
  Spec spec_;
  // Bookkeeping for the checks of build(), not part of the Spec.
  std::vector<bool> initial_given_;   // per coordinate: initial() was called for it
  std::vector<bool> solution_given_;  // per coordinate: solution() was called for it
  SourceLocation independent_where_;  // where independent() was called
  // The index of each coordinate by name: a lookup per initial value, force or solution, which a
  // linear search made quadratic in the number of coordinates (10 000 particles).
  std::unordered_map<std::string, int> coordinate_by_name_;
  // The index of each constraint by name, for the check of duplicated names (quadratic in the
  // number of constraints as a search of the list: 3000 for a 1000-body chain).
  std::unordered_map<std::string, std::size_t> constraint_by_name_;
  void check_constraint_name(const std::string& name, const SourceLocation& where) const;
  std::vector<std::pair<std::string, SourceLocation>> announced_outputs_;  // announce_outputs()
  int coordinate_of(const std::string& name) const;  // -1 when not a coordinate
};

// SpecBuilder::parse_derived against `spec`, a spec already built (a model file's, kept in its
// description: symbolic/description.hpp): t, q, q', q'', the reactions R_x, the parameters, every
// output and the contact-force columns are known, each output replaced by its expression. For
// the command line's events of a model file (symbolic/events.hpp); errors as parse_derived's.
GiNaC::ex parse_derived(const Spec& spec, const std::string& text, const SourceLocation& where = {});

}  // namespace nhdyn::symbolic
