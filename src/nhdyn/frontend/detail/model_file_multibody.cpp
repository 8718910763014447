// The multibody sections of a model file (model_file_sections.hpp, docs/multibody.md): gravity,
// [[frames]], [[points]], [[bodies]], [[wheels]], [[knife_edges]], [[surfaces]], [[curves]] and
// [[contacts]] (contacts_file.hpp), translated into MultibodyBuilder calls, with the scene the
// report draws of them; and [visual], the scene of a hand-written model.
#include <fmt/format.h>

#include <array>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "nhdyn/core/error.hpp"
#include "nhdyn/frontend/contacts_file.hpp"
#include "nhdyn/frontend/detail/model_file_sections.hpp"
#include "nhdyn/symbolic/multibody.hpp"
#include "nhdyn/symbolic/outputs.hpp"
#include "nhdyn/symbolic/spec_builder.hpp"

namespace nhdyn::model_file {
namespace {

// The keys of each table of these sections (docs/multibody.md, docs/model-format.md), in the
// order the docs list them.
const std::vector<std::string> frame_keys = {"name", "parent", "translation", "rotations", "quaternion"};
const std::vector<std::string> point_keys = {"name", "frame", "position"};
const std::vector<std::string> body_keys = {"name", "frame", "mass", "com", "inertia"};
// A wheel's mode keys (contact_mode_keys(): friction, ...) make it the [[contacts]] disk it is
// (contacts_file.hpp).
const std::vector<std::string> wheel_keys = [] {
  std::vector<std::string> keys = {"name", "body", "axis", "radius", "normal"};
  keys.insert(keys.end(), contact_mode_keys().begin(), contact_mode_keys().end());
  return keys;
}();
const std::vector<std::string> knife_edge_keys = {"name", "point", "axis", "normal"};
const std::vector<std::string> surface_keys = {"name", "point", "surface"};
const std::vector<std::string> curve_keys = {"name", "point", "surfaces"};
const std::vector<std::string> visual_keys = {"points", "segments"};
const std::vector<std::string> visual_point_keys = {"name", "position", "radius"};
const std::vector<std::string> visual_segment_keys = {"name", "from", "to"};

// What the multibody sections build together: the builders (the SpecBuilder holds the scene),
// and the names the automatic outputs and the contacts' scene need.
struct MultibodySections {
  SpecBuilder& builder;
  symbolic::MultibodyBuilder& mb;
  std::vector<std::string> frame_names, point_names;                     // for the automatic outputs
  std::vector<std::pair<std::string, symbolic::PlacedFrame>> body_frames;  // for the contacts' scene
};

// A frame's `rotations = "quaternion"` with `quaternion = ["e0", "e1", "e2", "e3"]`: the four
// coordinates' names; nullopt for a frame turned by angles (docs/derivations/quaternion-frame.md).
std::optional<std::array<std::string, 4>> quaternion_of(const Cursor& c, const toml::table& table,
                                                        const std::string& frame) {
  constexpr std::string_view example = "quaternion = [\"e0\", \"e1\", \"e2\", \"e3\"]";
  const toml::node* rotations = table.get("rotations");
  const toml::node* names = table.get("quaternion");
  const bool by_quaternion = rotations != nullptr && rotations->is_string();
  if (by_quaternion && rotations->value<std::string>().value_or("") != "quaternion")
    c.fail(c.at(*rotations),
           fmt::format("frame '{}': rotations = \"{}\" is not known; write rotations = \"quaternion\" "
                       "(with {}) for a frame turned by a unit quaternion, or a list of [axis, angle] "
                       "pairs such as [[\"z\", \"psi\"], [\"x\", \"theta\"]]",
                       frame, rotations->value<std::string>().value_or(""), example));
  if (!by_quaternion) {
    if (names != nullptr)
      c.fail(c.at(*names), fmt::format("frame '{}': 'quaternion' is given but the frame is not turned by one; add "
                                       "rotations = \"quaternion\" (and no angles), or remove 'quaternion'",
                                       frame));
    return std::nullopt;
  }
  if (names == nullptr)
    c.fail(c.at(*rotations), fmt::format("frame '{}': rotations = \"quaternion\" needs the four coordinates that hold "
                                         "it, scalar first: {} (each listed in `coordinates`)",
                                         frame, example));
  const toml::array& array = c.array_of(*names, fmt::format("frame '{}': quaternion", frame), example);
  if (array.size() != 4)
    c.fail(c.at(*names), fmt::format("frame '{}': a quaternion has 4 components (scalar first), e.g. {}; {} {} given",
                                     frame, example, array.size(), array.size() == 1 ? "is" : "are"));
  std::array<std::string, 4> out;
  for (std::size_t k = 0; k < 4; ++k)
    out[k] = c.string_of(*array.get(k), fmt::format("frame '{}': quaternion[{}]", frame, k + 1), "\"e0\"");
  return out;
}

// [Ixx, Iyy, Izz] (principal axes along the frame's) or a 3 x 3 array.
symbolic::InertiaText inertia_of(const Cursor& c, const toml::node& node, const std::string& body) {
  const std::string what = fmt::format("body '{}': inertia", body);
  constexpr std::string_view example = "[\"Ixx\", \"Iyy\", \"Izz\"] or [[9.2, 0, 2.4], [0, 11, 0], [2.4, 0, 2.8]]";
  const toml::array& array = c.array_of(node, what, example);
  symbolic::InertiaText I;
  for (auto& row : I) row = {"0", "0", "0"};
  if (array.size() == 3 && !array.get(0)->is_array()) {
    for (std::size_t i = 0; i < 3; ++i)
      I[i][i] = c.number_or_expression(*array.get(i), fmt::format("{}[{}]", what, i + 1), example);
    return I;
  }
  if (array.size() != 3)
    c.fail(c.at(node), fmt::format("'{}' must be 3 principal moments or a 3 x 3 array, e.g. {}; it has {} entries",
                                   what, example, array.size()));
  for (std::size_t i = 0; i < 3; ++i) {
    const std::string row_what = fmt::format("{} row {}", what, i + 1);
    const toml::array& row = c.array_of(*array.get(i), row_what, "[9.2, 0, 2.4]");
    if (row.size() != 3)
      c.fail(c.at(*array.get(i)), fmt::format("'{}' must have 3 entries; it has {}", row_what, row.size()));
    for (std::size_t j = 0; j < 3; ++j)
      I[i][j] = c.number_or_expression(*row.get(j), fmt::format("{}[{}]", row_what, j + 1), example);
  }
  return I;
}

// [[frames]]: each turned by angles or by a quaternion, placed in its parent.
void load_frames(LoadContext& cx, const toml::table& root, MultibodySections& scene) {
  const Cursor& c = cx.cursor;
  if (const toml::node* frames = root.get("frames"))
    for (const toml::table* table : c.tables_of(*frames, "frames", frame_keys)) {
      const std::string name = c.name_of(*table, "frames");
      std::string parent = "ground";
      if (const toml::node* node = table->get("parent"))
        parent = c.string_of(*node, fmt::format("frame '{}': parent", name), "parent = \"ground\"");
      symbolic::Triple translation{"0", "0", "0"};
      if (const toml::node* node = table->get("translation"))
        translation =
            c.triple_of(*node, fmt::format("frame '{}': translation", name), "translation = [\"x\", \"y\", 0]");
      if (std::optional<std::array<std::string, 4>> quaternion = quaternion_of(c, *table, name)) {
        scene.mb.quaternion_frame(name, parent, translation, *quaternion, c.at(*table->get("quaternion")));
        cx.quaternion_coordinates.insert(cx.quaternion_coordinates.end(), quaternion->begin(), quaternion->end());
        scene.frame_names.push_back(name);
        scene.builder.visual_item(
            symbolic::frame_item(scene.mb.placed_frame(name), symbolic::VisualKind::frame, c.at(*table)));
        continue;
      }
      std::vector<symbolic::FrameRotation> rotations;
      if (const toml::node* node = table->get("rotations")) {
        constexpr std::string_view example = "rotations = [[\"z\", \"psi\"], [\"x\", \"theta\"]]";
        const toml::array& array = c.array_of(*node, fmt::format("frame '{}': rotations", name), example);
        for (const toml::node& element : array) {
          const std::string what = fmt::format("frame '{}': rotation {}", name, rotations.size() + 1);
          const toml::array& pair = c.array_of(element, what, "[\"z\", \"psi\"] (an axis and an angle)");
          if (pair.size() != 2)
            c.fail(c.at(element), fmt::format("'{}' must be a pair [axis, angle], e.g. [\"z\", \"psi\"]; it has {} "
                                              "entries",
                                              what, pair.size()));
          rotations.push_back({c.string_of(*pair.get(0), what + " axis", "\"z\""),
                               c.number_or_expression(*pair.get(1), what + " angle", "\"psi\""), c.at(element)});
        }
      }
      scene.mb.frame(name, parent, translation, rotations, c.at(*table));
      scene.frame_names.push_back(name);
      scene.builder.visual_item(
          symbolic::frame_item(scene.mb.placed_frame(name), symbolic::VisualKind::frame, c.at(*table)));
    }
}

// [[points]]: fixed in a frame.
void load_points(LoadContext& cx, const toml::table& root, MultibodySections& scene) {
  const Cursor& c = cx.cursor;
  if (const toml::node* points = root.get("points"))
    for (const toml::table* table : c.tables_of(*points, "points", point_keys)) {
      const std::string name = c.name_of(*table, "points");
      const std::string frame = c.string_of(c.member(*table, "points", "frame", "frame = \"wheel\""),
                                            fmt::format("point '{}': frame", name), "frame = \"wheel\"");
      symbolic::Triple position{"0", "0", "0"};
      if (const toml::node* node = table->get("position"))
        position = c.triple_of(*node, fmt::format("point '{}': position", name), "position = [0, 0, \"-l\"]");
      scene.mb.point(name, frame, position, c.at(*table));
      scene.point_names.push_back(name);
    }
}

// [[bodies]]: a mass and inertia on a frame (the builder draws it as its ellipsoid of inertia).
void load_bodies(LoadContext& cx, const toml::table& root, MultibodySections& scene) {
  const Cursor& c = cx.cursor;
  if (const toml::node* bodies = root.get("bodies"))
    for (const toml::table* table : c.tables_of(*bodies, "bodies", body_keys)) {
      const std::string name = c.name_of(*table, "bodies");
      const std::string frame = c.string_of(c.member(*table, "bodies", "frame", "frame = \"wheel\""),
                                            fmt::format("body '{}': frame", name), "frame = \"wheel\"");
      const std::string mass = c.number_or_expression(c.member(*table, "bodies", "mass", "mass = \"m\""),
                                                      fmt::format("body '{}': mass", name), "mass = \"m\"");
      symbolic::Triple com{"0", "0", "0"};
      if (const toml::node* node = table->get("com"))
        com = c.triple_of(*node, fmt::format("body '{}': com", name), "com = [0, 0, \"-l/2\"]");
      const toml::node& inertia_node = c.member(
          *table, "bodies", "inertia", "inertia = [\"Ixx\", \"Iyy\", \"Izz\"] (principal moments) or a 3 x 3 array");
      const symbolic::InertiaText inertia = inertia_of(c, inertia_node, name);
      scene.mb.body(name, frame, mass, com, inertia, c.at(*table));  // drawn by the builder
      scene.body_frames.emplace_back(name, scene.mb.placed_frame(frame));
    }
}

// [[wheels]]: thin wheels rolling on the ground (the builder draws each as a disk about its axle).
void load_wheels(LoadContext& cx, const toml::table& root, MultibodySections& scene) {
  const Cursor& c = cx.cursor;
  if (const toml::node* wheels = root.get("wheels"))
    for (const toml::table* table : c.tables_of(*wheels, "wheels", wheel_keys)) {
      const std::string name = c.name_of(*table, "wheels");
      const std::string what = fmt::format("wheel '{}'", name);
      const std::string body =
          c.string_of(c.member(*table, "wheels", "body", "body = \"disk\""), what + ": body", "body = \"disk\"");
      const std::string axis =
          c.string_of(c.member(*table, "wheels", "axis", "axis = \"y\""), what + ": axis", "axis = \"y\"");
      const std::string radius = c.number_or_expression(c.member(*table, "wheels", "radius", "radius = \"r\""),
                                                        what + ": radius", "radius = \"r\"");
      const std::optional<symbolic::Triple> normal = c.optional_triple(*table, "normal", what + ": normal");
      // The [[contacts]] disk the wheel is, with its modes when it has the keys.
      load_wheel_contact(*table, {name, body, axis, radius, normal}, scene.mb, scene.builder,
                         [&c](const toml::node& node) { return c.at(node); });
    }
}

// [[knife_edges]]: a point that moves only along its blade.
void load_knife_edges(LoadContext& cx, const toml::table& root, MultibodySections& scene) {
  const Cursor& c = cx.cursor;
  if (const toml::node* knives = root.get("knife_edges")) {
    refuse_knife_edge_modes(*knives, [&c](const toml::node& node) { return c.at(node); });
    for (const toml::table* table : c.tables_of(*knives, "knife_edges", knife_edge_keys)) {
      const std::string name = c.name_of(*table, "knife_edges");
      const std::string what = fmt::format("knife edge '{}'", name);
      scene.mb.knife_edge(
          name,
          c.string_of(c.member(*table, "knife_edges", "point", "point = \"blade\""), what + ": point",
                      "point = \"blade\""),
          c.string_of(c.member(*table, "knife_edges", "axis", "axis = \"x\""), what + ": axis", "axis = \"x\""),
          c.optional_triple(*table, "normal", what + ": normal"), c.at(*table));
    }
  }
}

// [[surfaces]]: a point held on a fixed surface.
void load_surfaces(LoadContext& cx, const toml::table& root, MultibodySections& scene) {
  const Cursor& c = cx.cursor;
  if (const toml::node* surfaces = root.get("surfaces"))
    for (const toml::table* table : c.tables_of(*surfaces, "surfaces", surface_keys)) {
      const std::string name = c.name_of(*table, "surfaces");
      const std::string what = fmt::format("surface '{}'", name);
      const toml::node& surface = c.member(*table, "surfaces", "surface", "surface = \"X^2 + Y^2 - R^2\"");
      const std::string text = c.expression_string(surface, what + ": surface", "surface = \"X^2 + Y^2 - R^2\"");
      scene.mb.point_on_surface(
          name,
          c.string_of(c.member(*table, "surfaces", "point", "point = \"bead\""), what + ": point", "point = \"bead\""),
          text, c.content_at(surface));
    }
}

// [[curves]]: a point held on the meeting of two fixed surfaces.
void load_curves(LoadContext& cx, const toml::table& root, MultibodySections& scene) {
  const Cursor& c = cx.cursor;
  if (const toml::node* curves = root.get("curves"))
    for (const toml::table* table : c.tables_of(*curves, "curves", curve_keys)) {
      const std::string name = c.name_of(*table, "curves");
      const std::string what = fmt::format("curve '{}'", name);
      constexpr std::string_view example = "surfaces = [\"X^2 + Y^2 - R^2\", \"Z\"]";
      const toml::node& node = c.member(*table, "curves", "surfaces", example);
      const toml::array& array = c.array_of(node, what + ": surfaces", example);
      if (array.size() != 2)
        c.fail(c.at(node), fmt::format("{}: a curve is the meeting of two surfaces, e.g. {}; {} are given", what,
                                       example, array.size()));
      scene.mb.point_on_curve(
          name,
          c.string_of(c.member(*table, "curves", "point", "point = \"bead\""), what + ": point", "point = \"bead\""),
          c.expression_string(*array.get(0), what + ": surfaces[1]", example),
          c.expression_string(*array.get(1), what + ": surfaces[2]", example), c.at(node));
    }
}

// A position: two (x, y: a planar scene) or three components, expressions in t, q, q' and the
// parameters. `components` is set by the first position met; the others must agree.
std::vector<GiNaC::ex> position_of(const Cursor& c, const toml::node& node, const std::string& what,
                                   SpecBuilder& builder, std::size_t& components) {
  constexpr std::string_view example = "[\"x\", \"y\"] or [\"x\", \"y\", \"z\"]";
  const toml::array& array = c.array_of(node, what, example);
  if (array.size() != 2 && array.size() != 3)
    c.fail(c.at(node), fmt::format("'{}' must have 2 (x, y: a planar scene) or 3 components, e.g. {}; it has {}", what,
                                   example, array.size()));
  if (components == 0) components = array.size();
  if (array.size() != components)
    c.fail(c.at(node), fmt::format("'{}' has {} components but an earlier [visual] position has {}; give every "
                                   "position the same number (2 for a planar scene, 3 otherwise)",
                                   what, array.size(), components));
  std::vector<GiNaC::ex> out;
  for (std::size_t i = 0; i < array.size(); ++i) {
    const toml::node& element = *array.get(i);
    const std::string text = c.number_or_expression(element, fmt::format("{}[{}]", what, i + 1), example);
    out.push_back(c.located(element, [&] { return builder.parse(text, c.content_at(element)); }));
  }
  if (out.size() == 2) out.push_back(0);
  return out;
}

}  // namespace

// ---- The multibody description (docs/multibody.md) ------------------------------------------

void load_multibody(LoadContext& cx, const toml::table& root, SpecBuilder& builder) {
  const Cursor& c = cx.cursor;
  bool any = false;
  for (const char* key :
       {"gravity", "frames", "points", "bodies", "wheels", "knife_edges", "surfaces", "curves", "contacts"})
    any = any || root.get(key) != nullptr;
  if (!any) return;
  symbolic::MultibodyBuilder mb(builder);
  MultibodySections scene{builder, mb, {}, {}, {}};
  if (const toml::node* gravity = root.get("gravity"))
    mb.gravity(c.triple_of(*gravity, "gravity", "gravity = [0, 0, \"-g\"]"), c.at(*gravity));
  load_frames(cx, root, scene);
  load_points(cx, root, scene);
  load_bodies(cx, root, scene);
  load_wheels(cx, root, scene);
  load_knife_edges(cx, root, scene);
  load_surfaces(cx, root, scene);
  load_curves(cx, root, scene);
  if (const toml::node* contacts = root.get("contacts"))
    load_contacts(*contacts, mb, builder, scene.body_frames, [&c](const toml::node& node) { return c.at(node); });
  mb.apply();
  // Every point's and frame origin's world position and velocity as result columns.
  symbolic::add_multibody_outputs(builder, mb, scene.frame_names, scene.point_names);
}

// ---- [visual]: what the report's scene draws of a hand-written model (docs/model-format.md) ----

void load_visual(LoadContext& cx, const toml::node& node, SpecBuilder& builder) {
  const Cursor& c = cx.cursor;
  const toml::table& table =
      c.table_of(node, "visual", "[visual] followed by points = [{ name = \"particle\", position = [\"x\", \"y\"] }]");
  c.check_keys(table, visual_keys, "in [visual]");
  std::size_t components = 0;
  if (const toml::node* points = table.get("points"))
    for (const toml::table* entry : c.tables_of(*points, "visual.points", visual_point_keys)) {
      symbolic::VisualItem item;
      item.kind = symbolic::VisualKind::sphere;
      item.name = c.name_of(*entry, "visual.points");
      item.where = c.at(*entry).describe();
      const std::string what = fmt::format("[visual] point '{}'", item.name);
      item.at = position_of(c, c.member(*entry, "visual.points", "position", "position = [\"x\", \"y\"]"),
                            what + ": position", builder, components);
      item.size = 0.05;
      if (const toml::node* radius = entry->get("radius")) {
        const std::string text = c.number_or_expression(*radius, what + ": radius", "radius = 0.05");
        item.size = c.located(*radius, [&] { return builder.parse(text, c.content_at(*radius)); });
      }
      builder.visual_item(std::move(item));
    }
  if (const toml::node* segments = table.get("segments"))
    for (const toml::table* entry : c.tables_of(*segments, "visual.segments", visual_segment_keys)) {
      symbolic::VisualItem item;
      item.kind = symbolic::VisualKind::segment;
      item.name = c.name_of(*entry, "visual.segments");
      item.where = c.at(*entry).describe();
      const std::string what = fmt::format("[visual] segment '{}'", item.name);
      item.at = position_of(c, c.member(*entry, "visual.segments", "from", "from = [\"x\", \"y\"]"), what + ": from",
                            builder, components);
      item.other = position_of(c, c.member(*entry, "visual.segments", "to", "to = [\"x + l*cos(phi)\", \"y\"]"),
                               what + ": to", builder, components);
      builder.visual_item(std::move(item));
    }
  const bool ground = builder.current().visual.ground;
  builder.visual_scene(components == 2 && !ground, ground);
}

}  // namespace nhdyn::model_file
