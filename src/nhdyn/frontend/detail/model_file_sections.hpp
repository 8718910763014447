// The sections of a model file (docs/model-format.md), each read by a function of its own over the
// shared LoadContext (model_file_cursor.hpp) and translated into SpecBuilder or MultibodyBuilder
// calls: the equations and the run's defaults in model_file_equations.cpp, the multibody
// description and the scene in model_file_multibody.cpp. load_model_string (model_file.cpp) calls
// them in the order the format lists them.
// Internal: the model-file loader's own, not part of the public API (nhdyn/nhdyn.hpp).
#pragma once

#include <string_view>
#include <vector>

#include <toml++/toml.h>

#include "nhdyn/frontend/detail/model_file_cursor.hpp"

// Declared only: this header stays free of GiNaC (tests/layering).
namespace nhdyn::symbolic {
class SpecBuilder;
struct SpecEvent;
}  // namespace nhdyn::symbolic

namespace nhdyn::model_file {

using symbolic::SpecBuilder;

// ---- The equations (model_file_equations.cpp) ---------------------------------------------

// `coordinates` (required): the generalized coordinates in order.
void load_coordinates(LoadContext& cx, const toml::table& root, SpecBuilder& builder);
// [parameters]: NAME = value, an expression in the parameters above it, or { value, unit }.
void load_parameters(LoadContext& cx, const toml::node& node, SpecBuilder& builder);
// [forces]: a nonconservative generalized force per coordinate.
void load_forces(LoadContext& cx, const toml::node& node, SpecBuilder& builder);
// [[constraints]]: each at position, velocity or acceleration level.
void load_constraints(LoadContext& cx, const toml::node& node, SpecBuilder& builder);
// [[programs]]: each a constraint the motion must follow, with the actuator that realizes it.
void load_programs(LoadContext& cx, const toml::node& node, SpecBuilder& builder);
// `independent` or [complement]: the coordinates kept independent or an analytic D.
void load_complement(LoadContext& cx, const toml::table& root, SpecBuilder& builder);
// [initial]: t0 and the initial positions and velocities.
void load_initial(LoadContext& cx, const toml::node& node, SpecBuilder& builder);
// [solution]: q(t) per coordinate.
void load_solution(LoadContext& cx, const toml::node& node, SpecBuilder& builder);
// [simulation]: the run's defaults (t_end, output_step, integrator, method, tolerances).
void load_simulation(LoadContext& cx, const toml::node& node, SpecBuilder& builder);
// [plot]: the two coordinates of the path plot.
void load_plot(LoadContext& cx, const toml::node& node, SpecBuilder& builder);
// [outputs]: derived result columns.
void load_outputs(LoadContext& cx, const toml::node& node, SpecBuilder& builder);
// [[events]]: zero crossings located during a run, read against the model's symbols.
std::vector<symbolic::SpecEvent> load_events(LoadContext& cx, const toml::node& node, const SpecBuilder& builder);

// ---- The multibody description and the scene (model_file_multibody.cpp) -----------------

// gravity, [[frames]], [[points]], [[bodies]], [[wheels]], [[knife_edges]], [[surfaces]],
// [[curves]] and [[contacts]] (docs/multibody.md), through one MultibodyBuilder, with their scene
// (through the builders, onto the Spec's); nothing when the file has none of them.
void load_multibody(LoadContext& cx, const toml::table& root, SpecBuilder& builder);
// [visual]: the points and segments the report's scene draws of a hand-written model.
void load_visual(LoadContext& cx, const toml::node& node, SpecBuilder& builder);

}  // namespace nhdyn::model_file
