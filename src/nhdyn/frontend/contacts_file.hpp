// The [[contacts]] array of a model file (docs/multibody.md, "Rolling bodies"): reads each entry's
// TOML (name, body, shape, centre, ground, rolling) into a symbolic::ContactText, hands it to the
// multibody builder, and adds the shape's drawing to the scene (through the SpecBuilder). Also the contact modes' keys of
// the other helpers (docs/contact-modes.md): a [[wheels]] entry with them is read as the
// [[contacts]] disk it is; a [[knife_edges]] entry with them is refused. The shapes and grounds
// are those registered in symbolic/contact_shapes.cpp and symbolic/rolling_contact.cpp: this file
// lists none.
// Called by the model-file loader (model_file_multibody.cpp) before MultibodyBuilder::apply().
#pragma once

#include <array>
#include <functional>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <toml++/toml.h>

// Declared only: this header stays free of GiNaC (tests/layering).
namespace nhdyn::symbolic {
class MultibodyBuilder;
class SpecBuilder;
struct PlacedFrame;
struct SourceLocation;
}  // namespace nhdyn::symbolic

namespace nhdyn {

// Where a TOML node is in the file (the loader's own locator).
using TomlLocator = std::function<symbolic::SourceLocation(const toml::node&)>;

// The keys of a [[contacts]] entry, in the order docs/model-format.md lists them.
const std::vector<std::string>& contact_keys();

// Reads `contacts` (an array of tables) into `multibody`, and the drawing of each shape into the
// scene of `builder`; `body_frames` are the bodies declared so far with their frames. Throws
// ModelError naming file:line for wrong types and unknown keys, and whatever the builder refuses.
void load_contacts(const toml::node& contacts, symbolic::MultibodyBuilder& multibody, symbolic::SpecBuilder& builder,
                   const std::vector<std::pair<std::string, symbolic::PlacedFrame>>& body_frames,
                   const TomlLocator& at);

// The keys that give a contact its modes (friction, unilateral, restitution, mode), which
// [[contacts]] and [[wheels]] entries take (docs/contact-modes.md).
const std::vector<std::string>& contact_mode_keys();

// Whether `table` has any of contact_mode_keys().
bool has_contact_mode_keys(const toml::table& table);

// A [[wheels]] entry as the model-file loader read it (the texts as written).
struct WheelEntry {
  std::string name, body, axis, radius;
  std::optional<std::array<std::string, 3>> normal;  // the plane's normal; none: opposite to gravity
};

// A [[wheels]] entry `table`, handed to `multibody` as the [[contacts]] entry it is
// (symbolic::wheel_contact_text: a disk on the plane) with the entry's mode keys, read and checked
// as a contact's. So it has the contact's constraints (NAME_contact, NAME_slip1, NAME_slip2; with
// a mode key NAME_roll1, NAME_roll2), columns and switch events. The contact adds to the scene of `builder` what a
// [[contacts]] entry adds besides its shape (the contact point's track), then the multibody
// builder draws the body as the wheel it is (MultibodyBuilder::wheel_drawing). Throws ModelError
// naming file:line for a mode key of the wrong type and whatever the builder refuses.
void load_wheel_contact(const toml::table& table, const WheelEntry& wheel, symbolic::MultibodyBuilder& multibody,
                        symbolic::SpecBuilder& builder, const TomlLocator& at);

// Refuses the mode keys on [[knife_edges]] entries (`knives`, the array as written; anything else
// is left for the loader's own checks): a knife edge's planar model has no normal force for
// Coulomb's law to bound (docs/contact-modes.md). The ModelError names the key's file:line.
void refuse_knife_edge_modes(const toml::node& knives, const TomlLocator& at);

}  // namespace nhdyn
