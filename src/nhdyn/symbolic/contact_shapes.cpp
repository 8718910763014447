#include "nhdyn/symbolic/contact_shapes.hpp"

#include "nhdyn/core/join.hpp"
#include "nhdyn/symbolic/detail/shapes.hpp"

namespace nhdyn::symbolic {

// The table of shapes (one file each in shapes/), in the order the docs list them.
const std::vector<const ContactShape*>& contact_shapes() {
  static const std::vector<const ContactShape*> table = {&shapes::sphere(), &shapes::ellipsoid(), &shapes::disk(),
                                                         &shapes::torus(), &shapes::implicit_surface()};
  return table;
}

const ContactShape* find_contact_shape(const std::string& key) {
  for (const ContactShape* shape : contact_shapes())
    if (shape->key() == key) return shape;
  return nullptr;
}

std::string contact_shape_keys() {
  std::vector<std::string> keys;
  for (const ContactShape* shape : contact_shapes()) keys.push_back(shape->key());
  return join(keys);
}

}  // namespace nhdyn::symbolic
