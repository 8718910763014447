// What the shapes' files share: the rim direction of a disk or torus and a scene item.
#include "nhdyn/symbolic/detail/shapes.hpp"

namespace nhdyn::symbolic::shapes {

Vector3 rim_direction(const Vector3& nu, const GiNaC::ex& length, int axis, GiNaC::ex& across) {
  const Vector3 e = unit(axis);
  const GiNaC::ex en = nu[static_cast<std::size_t>(axis)];
  across = GiNaC::sqrt(length * length - en * en);
  return scale(1 / across, subtract(scale(en, e), nu));
}

VisualItem drawn(VisualKind kind, std::vector<GiNaC::ex> sizes) {
  VisualItem item;
  item.kind = kind;
  item.sizes = std::move(sizes);
  return item;
}

}  // namespace nhdyn::symbolic::shapes
