// The [[contacts]] array of a model file (docs/multibody.md, "Rolling bodies"): reads each entry's
// TOML (name, body, shape, centre, ground, rolling) into a symbolic::ContactText, hands it to the
// multibody builder, and adds the shape's drawing to the scene. The shapes and grounds are those
// registered in symbolic/contact_shapes.cpp and symbolic/rolling_contact.cpp: this file lists none.
// Called by the model-file loader (model_file.cpp) before MultibodyBuilder::apply().
#pragma once

#include <functional>
#include <string>
#include <utility>
#include <vector>

#include <toml++/toml.h>

// Declared only: this header stays free of GiNaC (tests/layering).
namespace nhdyn::symbolic {
class MultibodyBuilder;
struct PlacedFrame;
struct SourceLocation;
struct SpecVisual;
}  // namespace nhdyn::symbolic

namespace nhdyn {

// Where a TOML node is in the file (the loader's own locator).
using TomlLocator = std::function<symbolic::SourceLocation(const toml::node&)>;

// The keys of a [[contacts]] entry, in the order docs/model-format.md lists them.
const std::vector<std::string>& contact_keys();

// Reads `contacts` (an array of tables) into `multibody`, and the drawing of each shape into
// `visual`; `body_frames` are the bodies declared so far with their frames. Throws ModelError
// naming file:line for wrong types and unknown keys, and whatever the builder refuses.
void load_contacts(const toml::node& contacts, symbolic::MultibodyBuilder& multibody, symbolic::SpecVisual& visual,
                   const std::vector<std::pair<std::string, symbolic::PlacedFrame>>& body_frames,
                   const TomlLocator& at);

}  // namespace nhdyn
