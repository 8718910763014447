#include "nhdyn/frontend/contacts_file.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <optional>

#include "nhdyn/core/error.hpp"
#include "nhdyn/core/join.hpp"
#include "nhdyn/core/detail/suggest.hpp"
#include "nhdyn/symbolic/contact_shapes.hpp"
#include "nhdyn/symbolic/multibody.hpp"
#include "nhdyn/symbolic/rolling_contact.hpp"
#include "nhdyn/symbolic/visual.hpp"

namespace nhdyn {
namespace {

using symbolic::SourceLocation;

class ContactReader {
 public:
  explicit ContactReader(const TomlLocator& at) : at_(at) {}

  [[noreturn]] void fail(const toml::node& node, const std::string& message) const {
    const std::string place = at_(node).describe();
    throw ModelError(place.empty() ? message : place + ": " + message);
  }

  // A number or an expression in quotes, as text for the expression parser.
  std::string text_of(const toml::node& node, const std::string& what, const std::string& example) const {
    if (const auto* s = node.as_string()) return s->get();
    if (const auto* i = node.as_integer()) return fmt::format("{}", i->get());
    if (const auto* f = node.as_floating_point()) {
      const double v = f->get();
      if (!std::isfinite(v)) fail(node, fmt::format("{} must be finite", what));
      return fmt::format("{}", v);
    }
    fail(node, fmt::format("{} must be a number or an expression in quotes, e.g. {}", what, example));
  }

  std::string string_of(const toml::node& node, const std::string& what, const std::string& example) const {
    if (const auto* s = node.as_string()) return s->get();
    fail(node, fmt::format("{} must be a string, e.g. {}", what, example));
  }

  // One value or an array of values, as texts.
  std::vector<std::string> texts_of(const toml::node& node, const std::string& what, const std::string& example) const {
    std::vector<std::string> out;
    if (const auto* array = node.as_array()) {
      // An empty list is not the key left out (a surface's `coordinates = []` would add them).
      if (array->empty())
        fail(node, fmt::format("{} = [] is empty: give its values, e.g. {}, or leave the key out", what, example));
      for (std::size_t i = 0; i < array->size(); ++i)
        out.push_back(text_of(*array->get(i), fmt::format("{}[{}]", what, i + 1), example));
      return out;
    }
    out.push_back(text_of(node, what, example));
    return out;
  }

  // The example an option's message shows: a list of names for `coordinates`.
  static std::string option_example(const std::string& key, const std::string& otherwise) {
    return key == "coordinates" ? "[\"gx\", \"gy\", \"gz\"]" : otherwise;
  }

  void check_keys(const toml::table& table, const std::vector<std::string>& keys, const std::string& where) const {
    for (auto&& [key, value] : table) {
      const std::string name(key.str());
      if (std::find(keys.begin(), keys.end(), name) != keys.end()) continue;
      const std::string nearest = nearest_name(name, keys);
      fail(value, fmt::format("unknown key '{}' {}; {}the keys are: {}", name, where,
                              nearest.empty() ? "" : fmt::format("did you mean '{}'? ", nearest), join(keys)));
    }
  }

  symbolic::ContactText read(const toml::table& table) const {
    check_keys(table, contact_keys(), "in a [[contacts]] entry");
    symbolic::ContactText text;
    text.where = at_(table);
    const auto required = [&](const char* key, const std::string& example) -> const toml::node& {
      const toml::node* node = table.get(key);
      if (node == nullptr) fail(table, fmt::format("[[contacts]] entry has no '{}': give it, e.g. {}", key, example));
      return *node;
    };
    text.name = string_of(required("name", "name = \"ball\""), "contacts.name", "name = \"ball\"");
    const std::string what = fmt::format("contact '{}'", text.name);
    text.body = string_of(required("body", "body = \"ball\""), what + ": body", "body = \"ball\"");
    read_shape(required("shape", "shape = { sphere = \"r\" }"), what, text);
    if (const toml::node* centre = table.get("centre")) {
      const toml::array* array = centre->as_array();
      if (array == nullptr || array->size() != 3)
        fail(*centre, fmt::format("{}: centre must be 3 components in the body's axes, e.g. centre = [0, 0, \"h\"]", what));
      std::array<std::string, 3> c;
      for (std::size_t i = 0; i < 3; ++i) c[i] = text_of(*array->get(i), fmt::format("{}: centre[{}]", what, i + 1), "0");
      text.centre = c;
    }
    if (const toml::node* ground = table.get("ground")) read_ground(*ground, what, text);
    else text.ground.where = text.where;
    if (const toml::node* rolling = table.get("rolling"))
      text.rolling = string_of(*rolling, what + ": rolling", "rolling = \"rolling\"");
    read_modes(table, what, text);
    return text;
  }

  // friction = mu or ["mu_s", "mu_k"], unilateral, restitution, mode (docs/contact-modes.md), as
  // texts for symbolic::parse_contact_mode.
  void read_modes(const toml::table& table, const std::string& what, symbolic::ContactText& text) const {
    if (const toml::node* friction = table.get("friction")) {
      if (const toml::array* pair = friction->as_array()) {
        if (pair->size() != 2)
          fail(*friction, fmt::format("{}: friction must be one coefficient or two, [\"mu_s\", \"mu_k\"] (static, "
                                      "kinetic); {} are given",
                                      what, pair->size()));
        text.modes.emplace_back("mu_s", text_of(*pair->get(0), what + ": friction[1]", "0.4"));
        text.modes.emplace_back("mu_k", text_of(*pair->get(1), what + ": friction[2]", "0.3"));
      } else {
        text.modes.emplace_back("friction", text_of(*friction, what + ": friction", "friction = 0.3"));
      }
    }
    if (const toml::node* unilateral = table.get("unilateral")) {
      const auto* flag = unilateral->as_boolean();
      if (flag == nullptr) fail(*unilateral, fmt::format("{}: unilateral must be true or false", what));
      text.modes.emplace_back("unilateral", flag->get() ? "true" : "false");
    }
    if (const toml::node* restitution = table.get("restitution"))
      text.modes.emplace_back("restitution", text_of(*restitution, what + ": restitution", "restitution = 0.5"));
    if (const toml::node* mode = table.get("mode"))
      text.modes.emplace_back("mode", string_of(*mode, what + ": mode", "mode = \"sliding\""));
  }

 private:
  // shape = { sphere = "r" }: the one key that names a registered shape, and that shape's options.
  void read_shape(const toml::node& node, const std::string& what, symbolic::ContactText& text) const {
    const std::string example = "shape = { sphere = \"r\" } or { ellipsoid = [\"a\", \"b\", \"c\"] }";
    const toml::table* table = node.as_table();
    if (table == nullptr) fail(node, fmt::format("{}: shape must be a table naming the shape, e.g. {}", what, example));
    text.shape_where = at_(node);
    std::vector<std::string> named, all_keys;
    for (const symbolic::ContactShape* shape : symbolic::contact_shapes()) all_keys.push_back(shape->key());
    for (auto&& [key, value] : *table) {
      const std::string k(key.str());
      if (symbolic::find_contact_shape(k) != nullptr) {
        named.push_back(k);
        text.shape = k;
        text.sizes = texts_of(value, fmt::format("{}: {}", what, k), "\"r\"");
      }
    }
    if (named.size() > 1)
      fail(node, fmt::format("{}: the shape names {} shapes ({}); give one", what, named.size(), join(named)));
    if (named.empty()) {
      // The first key is taken as the shape's name, for the message with the nearest one.
      std::string first = table->empty() ? "" : std::string(table->cbegin()->first.str());
      const std::string nearest = nearest_name(first, all_keys);
      fail(node, fmt::format("{}: unknown shape{}; {}the shapes are: {} (e.g. {})", what,
                             first.empty() ? "" : " '" + first + "'",
                             nearest.empty() ? "" : fmt::format("did you mean '{}'? ", nearest),
                             symbolic::contact_shape_keys(), example));
    }
    for (auto&& [key, value] : *table) {
      const std::string k(key.str());
      if (k == text.shape) continue;
      text.shape_options.emplace_back(k, join(texts_of(value, fmt::format("{}: shape.{}", what, k), option_example(k, "\"y\"")), ", "));
    }
  }

  // ground = "plane" or { plane = [...], angular_velocity = "Omega" } or { surface = "...", side = "inside" }.
  void read_ground(const toml::node& node, const std::string& what, symbolic::ContactText& text) const {
    text.ground.where = at_(node);
    std::vector<std::string> keys;
    for (const symbolic::ContactGround* ground : symbolic::contact_grounds()) keys.push_back(ground->key());
    if (const auto* s = node.as_string()) {
      text.ground.key = s->get();
      if (text.ground.key != "plane")
        fail(node, fmt::format("{}: ground = \"{}\" is not a ground; write ground = \"plane\" or a table such as {}",
                               what, text.ground.key,
                               symbolic::find_contact_ground("surface")->example()));
      return;
    }
    const toml::table* table = node.as_table();
    if (table == nullptr)
      fail(node, fmt::format("{}: ground must be \"plane\" or a table, e.g. {}", what,
                             symbolic::find_contact_ground("plane")->example()));
    std::vector<std::string> named;
    for (auto&& [key, value] : *table) {
      const std::string k(key.str());
      if (symbolic::find_contact_ground(k) == nullptr) continue;
      named.push_back(k);
      text.ground.key = k;
      text.ground.value = texts_of(value, fmt::format("{}: ground.{}", what, k), "[0, 0, 1]");
    }
    if (named.size() != 1)
      fail(node, fmt::format("{}: the ground table must name one kind of ground ({}); it names {}", what, join(keys),
                             named.empty() ? "none" : join(named)));
    for (auto&& [key, value] : *table) {
      const std::string k(key.str());
      if (k == text.ground.key) continue;
      text.ground.options.emplace_back(k, join(texts_of(value, fmt::format("{}: ground.{}", what, k), option_example(k, "\"Omega\"")), ", "));
    }
  }

  const TomlLocator& at_;
};

// The ground (a plane's axes and rate, a terrain's or a surface's mesh about the contact point),
// and the contact point's path on it: the contact's outputs NAME_X, NAME_Y, NAME_Z.
void add_ground_drawing(const symbolic::ContactText& text, const symbolic::ParsedContact& parsed,
                        const symbolic::MultibodyBuilder& multibody, symbolic::SpecBuilder& builder) {
  const std::vector<std::string> point = {text.name + "_X", text.name + "_Y", text.name + "_Z"};
  std::vector<symbolic::VisualItem> ground;
  if (std::optional<symbolic::VisualItem> drawn =
          parsed.ground.type->drawing(parsed, builder.current(), multibody.gravity_vector()))
    ground.push_back(std::move(*drawn));
  symbolic::VisualItem track;
  track.kind = symbolic::VisualKind::track;
  ground.push_back(std::move(track));
  for (symbolic::VisualItem& item : ground) {
    item.name = text.name;
    item.where = text.where.describe();
    if (item.at.empty()) item.at_outputs = point;
    builder.visual_item(std::move(item));
  }
}

}  // namespace

const std::vector<std::string>& contact_mode_keys() {
  static const std::vector<std::string> keys = {"friction", "unilateral", "restitution", "mode"};
  return keys;
}

const std::vector<std::string>& contact_keys() {
  static const std::vector<std::string> keys = [] {
    std::vector<std::string> all = {"name", "body", "shape", "centre", "ground", "rolling"};
    all.insert(all.end(), contact_mode_keys().begin(), contact_mode_keys().end());
    return all;
  }();
  return keys;
}

bool has_contact_mode_keys(const toml::table& table) {
  for (const std::string& key : contact_mode_keys())
    if (table.get(key) != nullptr) return true;
  return false;
}

void load_wheel_contact(const toml::table& table, const WheelEntry& wheel, symbolic::MultibodyBuilder& multibody,
                        symbolic::SpecBuilder& builder, const TomlLocator& at) {
  const ContactReader reader(at);
  symbolic::ContactText text =
      symbolic::wheel_contact_text(wheel.name, wheel.body, wheel.axis, wheel.radius, wheel.normal, at(table));
  // A normal's messages name its key's place.
  if (const toml::node* normal = table.get("normal")) text.ground.where = text.ground_where = at(*normal);
  reader.read_modes(table, fmt::format("wheel '{}'", wheel.name), text);
  multibody.contact(text);
  // The contact point's track is the contact's; the body is drawn as the wheel it is.
  if (const symbolic::ParsedContact* parsed = multibody.parsed_contact(text.name))
    add_ground_drawing(text, *parsed, multibody, builder);
  multibody.wheel_drawing(wheel.name, wheel.body, wheel.axis, wheel.radius, text.where);
}

void refuse_knife_edge_modes(const toml::node& knives, const TomlLocator& at) {
  const toml::array* array = knives.as_array();
  if (array == nullptr) return;
  std::size_t index = 0;
  for (const toml::node& element : *array) {
    ++index;
    const toml::table* table = element.as_table();
    if (table == nullptr) continue;
    std::string name = fmt::format("[[knife_edges]] entry {}", index);
    if (const toml::node* n = table->get("name"); n != nullptr && n->is_string())
      name = fmt::format("knife edge '{}'", n->as_string()->get());
    for (const std::string& key : contact_mode_keys()) {
      const toml::node* value = table->get(key);
      if (value == nullptr) continue;
      const std::string place = at(*value).describe();
      throw ModelError(fmt::format(
          "{}{}: '{}' is not a key of a knife edge: its constraint forbids the blade's sideways velocity and "
          "carries no normal force of its own (what holds the blade on the plane is the model's coordinates), so "
          "Coulomb's bound mu N, a lift-off at N = 0 and an impact at touchdown are not defined for it "
          "(docs/contact-modes.md, \"Knife edges\"). Remove the key (the blade then holds as it does without "
          "it); for a runner that may skid or lift off, model what touches the ground as a [[wheels]] or "
          "[[contacts]] entry with this key, its height among the coordinates (a knife edge is a wheel whose spin "
          "has no inertia)",
          place.empty() ? "" : place + ": ", name, key));
    }
  }
}

void load_contacts(const toml::node& contacts, symbolic::MultibodyBuilder& multibody, symbolic::SpecBuilder& builder,
                   const std::vector<std::pair<std::string, symbolic::PlacedFrame>>& body_frames,
                   const TomlLocator& at) {
  const ContactReader reader(at);
  const toml::array* array = contacts.as_array();
  if (array == nullptr || !array->is_array_of_tables())
    reader.fail(contacts, "contacts must be an array of tables: write each contact as [[contacts]] followed by its keys");
  for (const toml::node& element : *array) {
    const symbolic::ContactText text = reader.read(*element.as_table());
    multibody.contact(text);
    const symbolic::ParsedContact* parsed = multibody.parsed_contact(text.name);
    if (parsed == nullptr) continue;
    // The shape on its body, at its centre, turning with the body frame.
    for (const auto& [body, frame] : body_frames) {
      if (body != text.body) continue;
      symbolic::VisualItem item = parsed->shape->drawing(parsed->values);
      item.name = text.name;
      item.where = text.where.describe();
      item.axis = std::max(item.axis, 0);
      item.body = body;
      const symbolic::Vector3 centre =
          symbolic::add(frame.origin, symbolic::multiply(frame.rotation, parsed->centre));
      item.at.assign(centre.begin(), centre.end());
      for (unsigned i = 0; i < 3; ++i)
        for (unsigned j = 0; j < 3; ++j) item.other.push_back(frame.rotation(i, j));
      builder.visual_item(std::move(item));
    }
    add_ground_drawing(text, *parsed, multibody, builder);
  }
}

}  // namespace nhdyn
