// The model-file loader: TOML (toml++) in, SpecBuilder calls out. The format is documented in
// docs/model-format.md; this file checks only what TOML cannot (which keys exist, their types, the
// shape of each section) and leaves every question about the mechanics to SpecBuilder, passing it
// the source location of each node. Every toml++ node is reached through a type-checked accessor
// (as_string, as_table, ...), so no input can make the loader dereference a missing node.
// This file holds the entry points and the top level of the file; the reader is in
// model_file_cursor.{hpp,cpp}, the sections in model_file_equations.cpp and
// model_file_multibody.cpp (model_file_sections.hpp).
#include "nhdyn/frontend/model_file.hpp"

#include <fmt/format.h>

#include <array>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <sstream>
#include <string>
#include <string_view>
#include <system_error>
#include <utility>
#include <vector>

#include <toml++/toml.h>

#include "nhdyn/core/error.hpp"
#include "nhdyn/core/shown_text.hpp"
#include "nhdyn/frontend/detail/model_file_sections.hpp"
#include "nhdyn/model/parameters.hpp"
#include "nhdyn/symbolic/rolling_contact.hpp"
#include "nhdyn/symbolic/spec_builder.hpp"

namespace nhdyn::model_file {

const std::vector<std::string>& top_level_keys() {
  // In the order docs/model-format.md lists them.
  static const std::vector<std::string> keys = {
      "name",           "description", "coordinates", "parameters",  "kinetic_energy",
      "potential_energy", "forces",    "constraints", "programs", "independent", "complement",
      "initial",        "solution",    "simulation",  "plot",        "visual",
      "events",  // [[events]]: zero crossings located during a run
      "outputs",  // [outputs]: derived result columns
      "optimize",  // [optimize]: an optimal control problem, read by `nhdyn optimize` (frontend/optimize_problem.hpp)
      // The multibody description (docs/multibody.md).
      "gravity", "frames", "points", "bodies", "wheels", "knife_edges", "surfaces", "curves", "contacts"};
  return keys;
}

namespace {

symbolic::Spec load_sections(LoadContext& cx) {
  const Cursor& c = cx.cursor;
  toml::table root;
  try {
    root = toml::parse(c.text(), std::string_view(c.file()));
  } catch (const toml::parse_error& e) {
    c.fail(c.at(e.source()),
           fmt::format("TOML syntax error: {} (docs/model-format.md describes the format)", e.description()));
  }
  c.check_keys(root, top_level_keys(), "at the top level");

  // The name and the description are printed on terminals and into every file a run writes: an
  // invisible character (a right-to-left override, an escape) or a byte that is not UTF-8 there
  // is refused, shown by its code (core/shown_text.hpp).
  const auto visible = [&](const toml::node& node, const char* key, std::string text) {
    if (shown_text(text, true) != text)
      c.fail(c.at(node), fmt::format("{} \"{}\" has an invisible character or a byte that is not UTF-8 (shown here "
                                     "by its code): delete it",
                                     key, shown_text(text, true)));
    return text;
  };
  const toml::node* name = c.required(root, "name", "the model's name, e.g. name = \"sled\"");
  SpecBuilder builder(visible(*name, "name", c.string_of(*name, "name", "name = \"sled\"")), c.at(*name));
  if (const toml::node* description = root.get("description"))
    builder.description(visible(*description, "description",
                                c.string_of(*description, "description", "description = \"A sled on an inclined plane\"")));

  load_coordinates(cx, root, builder);
  if (const toml::node* parameters = root.get("parameters")) load_parameters(cx, *parameters, builder);

  // With [[bodies]], T comes from them; a kinetic_energy given as well is added to theirs.
  const toml::node* kinetic = root.get("bodies") != nullptr
                                  ? root.get("kinetic_energy")
                                  : c.required(root, "kinetic_energy",
                                               "the kinetic energy in the velocities x', e.g. "
                                               "kinetic_energy = \"m/2 * (x'^2 + y'^2)\" (or [[bodies]], "
                                               "docs/multibody.md)");
  if (kinetic != nullptr) {
    const std::string kinetic_text = c.expression_string(*kinetic, "kinetic_energy", "kinetic_energy = \"m/2 * x'^2\"");
    c.located(*kinetic, [&] { builder.kinetic_energy(kinetic_text, c.content_at(*kinetic)); });
  }
  if (const toml::node* potential = root.get("potential_energy")) {
    const std::string potential_text =
        c.expression_string(*potential, "potential_energy", "potential_energy = \"-m * g * z\"");
    c.located(*potential, [&] { builder.potential_energy(potential_text, c.content_at(*potential)); });
  }

  if (const toml::node* forces = root.get("forces")) load_forces(cx, *forces, builder);
  if (const toml::node* constraints = root.get("constraints")) load_constraints(cx, *constraints, builder);
  if (const toml::node* programs = root.get("programs")) load_programs(cx, *programs, builder);
  load_multibody(cx, root, builder);
  if (const toml::node* node = root.get("visual")) load_visual(cx, *node, builder);
  load_complement(cx, root, builder);
  if (const toml::node* initial = root.get("initial")) load_initial(cx, *initial, builder);
  if (const toml::node* solution = root.get("solution")) load_solution(cx, *solution, builder);
  if (const toml::node* simulation = root.get("simulation")) load_simulation(cx, *simulation, builder);
  if (const toml::node* plot = root.get("plot")) load_plot(cx, *plot, builder);
  if (const toml::node* node = root.get("outputs")) load_outputs(cx, *node, builder);
  std::vector<symbolic::SpecEvent> events;
  if (const toml::node* node = root.get("events")) events = load_events(cx, *node, builder);
  symbolic::Spec spec = builder.build();
  spec.events = std::move(events);
  // The definitions of derived parameters, which a --set of a parameter they use re-evaluates.
  for (symbolic::SpecParameter& p : spec.parameters)
    for (const Parameter& loaded : cx.parameter_values)
      if (loaded.name == p.name) p.expression = loaded.expression;
  spec.q0_written = std::move(cx.q0_written);
  spec.v0_written = std::move(cx.v0_written);
  spec.q0_written.resize(spec.coordinates.size(), false);
  spec.v0_written.resize(spec.coordinates.size(), false);
  // A quaternion's components, written or not, are free for --fix-initial: its norm is a gauge,
  // and the smallest change onto the unit sphere is along e itself (e/|e|, the same direction;
  // e' loses its part along e), docs/derivations/quaternion-frame.md.
  for (const std::string& name : cx.quaternion_coordinates)
    for (std::size_t i = 0; i < spec.coordinates.size(); ++i)
      if (spec.coordinates[i] == name) spec.q0_written[i] = spec.v0_written[i] = false;
  // The contact points' coordinates nhdyn added (rolling_contact.hpp): found from the rest.
  symbolic::solve_contact_coordinates(spec);
  return spec;
}

}  // namespace
}  // namespace nhdyn::model_file

namespace nhdyn {

symbolic::Spec load_model_string(std::string_view text, std::string file_name) {
  model_file::LoadContext context(text, std::move(file_name));
  return model_file::load_sections(context);
}

std::string read_model_text(const std::filesystem::path& path) {
  std::error_code ec;
  const std::filesystem::file_status status = std::filesystem::status(path, ec);
  if (!std::filesystem::exists(status))
    throw FileError(fmt::format("{}: no such model file; check the path (model files end in .toml, e.g. "
                                "examples/sled.toml)",
                                path.string()));
  if (std::filesystem::is_directory(status))
    throw FileError(fmt::format("{}: is a directory, not a model file; give the path of a .toml file", path.string()));
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    const int error = errno;
    throw FileError(fmt::format("{}: cannot open the model file: {}", path.string(),
                                error != 0 ? std::strerror(error) : "unknown error"));
  }
  // Read up to a bound: a model file is text (the 10 000-body chain's is under 6 MB), and a device
  // such as /dev/zero has no end to read to.
  constexpr std::size_t kMaxModelFile = std::size_t{256} << 20;
  std::string text;
  std::array<char, 1 << 16> chunk;
  while (in.read(chunk.data(), chunk.size()) || in.gcount() > 0) {
    text.append(chunk.data(), static_cast<std::size_t>(in.gcount()));
    if (text.size() > kMaxModelFile)
      throw FileError(fmt::format("{}: larger than {} MB, which no model file is; is it the file you meant?",
                                  path.string(), kMaxModelFile >> 20));
  }
  if (in.bad()) throw FileError(fmt::format("{}: cannot read the model file", path.string()));
  return text;
}

symbolic::Spec load_model_file(const std::filesystem::path& path) {
  return load_model_string(read_model_text(path), path.string());
}

}  // namespace nhdyn
