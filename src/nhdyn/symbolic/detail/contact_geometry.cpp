// The helpers of the rolling-contact builder that its grounds share (detail/contact_geometry.hpp).
#include "nhdyn/symbolic/detail/contact_geometry.hpp"
#include "nhdyn/symbolic/precise_reference.hpp"

#include <fmt/format.h>

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <exception>
#include <limits>
#include <sstream>
#include <tuple>
#include <utility>

#include "nhdyn/core/error.hpp"
#include "nhdyn/core/join.hpp"
#include "nhdyn/core/detail/suggest.hpp"
#include "nhdyn/symbolic/multibody.hpp"
#include "nhdyn/symbolic/simplify.hpp"

namespace nhdyn::symbolic {

// The value once the parameters are set (t and the coordinates at 0 with `at_reference`);
// nullopt when it is not a finite real number.
std::optional<double> contact_number_of(const GiNaC::ex& e, const Spec& spec, bool at_reference) {
  try {
    GiNaC::lst values = spec.parameter_values();
    if (at_reference) {
      values.append(spec.symbols.time() == 0);
      for (int i = 0; i < spec.n(); ++i) values.append(spec.symbols.coordinate(i) == 0);
    }
    const GiNaC::ex v = e.subs(values).evalf();
    if (!GiNaC::is_a<GiNaC::numeric>(v) || !GiNaC::ex_to<GiNaC::numeric>(v).is_real()) return std::nullopt;
    const double d = GiNaC::ex_to<GiNaC::numeric>(v).to_double();
    if (!std::isfinite(d)) return std::nullopt;
    return d;
  } catch (const std::exception&) {
    return std::nullopt;
  }
}

std::string contact_printed(const GiNaC::ex& e) {
  std::ostringstream out;
  out << e;
  return out.str();
}

bool contact_has_coordinates(const GiNaC::ex& e, const Spec& spec) {
  if (e.has(spec.symbols.time())) return true;
  for (int i = 0; i < spec.n(); ++i)
    if (e.has(spec.symbols.coordinate(i))) return true;
  return false;
}

bool contact_vanishes_identically(const GiNaC::ex& e, const Spec& spec) {
  if (e.is_zero()) return true;
  if (!contact_has_coordinates(e, spec)) return false;  // a constant: its message is the caller's
  // Generic points: t and the coordinates at values no simple motion or angle hits (a prescribed
  // sin(10 pi t) vanishes at every tenth of a second); zero to round-off of the terms' sizes.
  const std::vector<GiNaC::ex> terms = GiNaC::is_a<GiNaC::add>(e) ? std::vector<GiNaC::ex>(e.begin(), e.end())
                                                                  : std::vector<GiNaC::ex>{e};
  for (int sample = 0; sample < 3; ++sample) {
    GiNaC::lst values = spec.parameter_values();
    values.append(spec.symbols.time() == 0.2718281828 + 0.3183098862 * sample);
    for (int i = 0; i < spec.n(); ++i)
      values.append(spec.symbols.coordinate(i) == std::sin(1.7 * (i + 1) + 2.3 * sample));
    try {
      double sum = 0.0, size = 0.0;
      for (const GiNaC::ex& term : terms) {
        const GiNaC::ex v = term.subs(values).evalf();
        if (!GiNaC::is_a<GiNaC::numeric>(v) || !GiNaC::ex_to<GiNaC::numeric>(v).is_real()) return false;
        const double x = GiNaC::ex_to<GiNaC::numeric>(v).to_double();
        sum += x;
        size += std::abs(x);
      }
      if (!std::isfinite(sum) || !(std::abs(sum) <= 1e-12 * size)) return false;
    } catch (const std::exception&) {
      return false;
    }
  }
  return true;
}

GiNaC::ex contact_roots_of_squares(const GiNaC::ex& e, const Spec& spec, std::vector<GiNaC::ex>& roots) {
  struct Roots : GiNaC::map_function {
    const Spec& spec;
    std::vector<GiNaC::ex>& roots;
    Roots(const Spec& s, std::vector<GiNaC::ex>& r) : spec(s), roots(r) {}
    GiNaC::ex operator()(const GiNaC::ex& x) override {
      const GiNaC::ex mapped = x.map(*this);
      if (!GiNaC::is_a<GiNaC::power>(mapped) || !GiNaC::is_a<GiNaC::numeric>(mapped.op(1))) return mapped;
      const GiNaC::numeric k = GiNaC::ex_to<GiNaC::numeric>(mapped.op(1));
      if (!k.is_rational() || k.is_integer() || k.denom() != 2) return mapped;
      const GiNaC::ex squared = simplify(mapped.op(0));
      if (!GiNaC::is_a<GiNaC::power>(squared) || !squared.op(1).is_equal(2)) return mapped;
      // A root of parameters alone (a normalized normal, sqrt(k^2)) is not the rim's: it stays.
      if (!contact_has_coordinates(squared.op(0), spec)) return mapped;
      const std::optional<double> u = contact_number_of(squared.op(0), spec, true);
      if (!u || *u == 0.0) return mapped;
      const GiNaC::ex root = *u > 0 ? squared.op(0) : -squared.op(0);
      if (std::none_of(roots.begin(), roots.end(), [&](const GiNaC::ex& r) { return r.is_equal(root); }))
        roots.push_back(root);
      return GiNaC::pow(root, k * 2);
    }
  } map(spec, roots);
  return map(e);
}

// A kink or a step (abs, csgn, step) anywhere in e: a ground or shape written with one has no
// normal there.
bool contact_not_smooth(const GiNaC::ex& e) {
  return e.has(GiNaC::abs(GiNaC::wild())) || e.has(GiNaC::csgn(GiNaC::wild())) || e.has(GiNaC::step(GiNaC::wild()));
}

std::string contact_option_of(const KeyTexts& options, const std::string& key, const std::string& fallback) {
  for (const auto& [k, v] : options)
    if (k == key) return v;
  return fallback;
}

// The index of the world axis least aligned with `direction` (the first of ties).
int contact_least_aligned_axis(const Vector3& direction, const Spec& spec) {
  int k = 0;
  double smallest = HUGE_VAL;
  for (int i = 0; i < 3; ++i) {
    const double v = std::fabs(contact_number_of(direction[static_cast<std::size_t>(i)], spec).value_or(1.0));
    if (v < smallest - 1e-15) {
      smallest = v;
      k = i;
    }
  }
  return k;
}

// The unit normal of a plane ground: the given one, else opposite to gravity.
Vector3 ground_plane_normal(const ParsedGround& ground, const Spec& spec, const std::optional<Vector3>& gravity,
                     const std::string& context) {
  Vector3 n;
  if (ground.normal) n = *ground.normal;
  else if (gravity) n = scale(-1, *gravity);
  else
    throw_model_error(ground.where, context,
                      fmt::format("no ground plane: give its normal, {}, or a gravity vector, whose opposite is then "
                                  "the normal",
                                  ground.normal_example));
  std::array<double, 3> value{};
  for (std::size_t i = 0; i < 3; ++i) value[i] = contact_number_of(n[i], spec).value_or(0.0);
  const double length = std::sqrt(value[0] * value[0] + value[1] * value[1] + value[2] * value[2]);
  if (!(length > 0.0))
    throw_model_error(ground.where, context,
                      ground.normal ? "the plane's normal is the zero vector; give a nonzero normal, e.g. [0, 0, 1]"
                                    : fmt::format("the gravity vector is zero, so it defines no ground plane; give its "
                                                  "normal, {}",
                                                  ground.normal_example));
  // A normal along an axis as written (its other two components zero, not only at the file's
  // parameter values: --set may change them) is kept exact (+-x, +-y, +-z); others are normalized
  // symbolically, so that the plane follows the parameters.
  for (std::size_t i = 0; i < 3; ++i)
    if (n[(i + 1) % 3].is_zero() && n[(i + 2) % 3].is_zero()) return scale(value[i] > 0 ? 1 : -1, unit(static_cast<int>(i)));
  const GiNaC::ex norm = GiNaC::sqrt(simplify(dot(n, n)));
  return {n[0] / norm, n[1] / norm, n[2] / norm};
}

// The coordinates named in an option's text ("u, v"): `count` of them, distinct, each a coordinate
// of the model (docs/multibody.md: they hold a contact point).
std::vector<int> contact_coordinates(const std::string& names, std::size_t count, const Spec& spec,
                                     const SourceLocation& where, const std::string& context, const std::string& what,
                                     const std::string& example) {
  std::vector<std::string> at;
  std::string current;
  for (const char ch : names + ",") {
    if (ch == ',') {
      const std::size_t first = current.find_first_not_of(' '), last = current.find_last_not_of(' ');
      if (first != std::string::npos) at.push_back(current.substr(first, last - first + 1));
      current.clear();
    } else {
      current += ch;
    }
  }
  if (at.size() != count)
    throw_model_error(where, context,
                      fmt::format("{} needs the {} coordinates that hold its contact point, declared in `coordinates` "
                                  "at the top of the file, e.g. {}; {}",
                                  what, count, example, names.empty() ? "none given" : fmt::format("\"{}\" given", names)));
  std::vector<int> out;
  for (const std::string& name : at) {
    const auto found = std::find(spec.coordinates.begin(), spec.coordinates.end(), name);
    if (found == spec.coordinates.end()) {
      const std::string nearest = nearest_name(name, spec.coordinates);
      throw_model_error(where, context,
                        fmt::format("'{}' is not a coordinate of the model; {}the contact point needs coordinates of "
                                    "its own: add them to `coordinates` (the coordinates are: {})",
                                    name, nearest.empty() ? "" : fmt::format("did you mean '{}'? ", nearest),
                                    join(spec.coordinates)));
    }
    const int index = static_cast<int>(found - spec.coordinates.begin());
    if (std::find(out.begin(), out.end(), index) != out.end())
      throw_model_error(where, context,
                        fmt::format("the contact point needs {} different coordinates; '{}' is named twice", count, name));
    out.push_back(index);
  }
  return out;
}

// The coordinates that hold a contact point: those named by the `coordinates` key, or, without
// it, new ones that nhdyn adds, named after the contact (added_contact_coordinates). `added` says
// which.
std::vector<int> contact_point_coordinates(const std::string& names, ContactPointOn on, const ContactParsers& p,
                                           const SourceLocation& where, const std::string& context,
                                           const std::string& what, const std::string& example, bool& added) {
  const std::size_t count = on == ContactPointOn::terrain ? 2 : 3;
  added = names.empty() && p.add_coordinate;
  if (!added) return contact_coordinates(names, count, *p.spec, where, context, what, example);
  std::vector<int> out;
  for (const std::string& name : added_contact_coordinates(p.contact, on)) {
    const Spec& spec = *p.spec;
    std::string taken;
    if (std::find(spec.coordinates.begin(), spec.coordinates.end(), name) != spec.coordinates.end())
      taken = "a coordinate";
    for (const SpecParameter& parameter : spec.parameters)
      if (parameter.name == name)
        taken = parameter.where.describe().empty() ? "a parameter"
                                                   : fmt::format("a parameter (declared at {})", parameter.where.describe());
    if (!taken.empty())
      throw_model_error(where, context,
                        fmt::format("nhdyn adds the coordinate '{}' to hold the contact point, but '{}' is already {}; "
                                    "rename the contact or that symbol, or name the contact point's coordinates "
                                    "yourself, e.g. {}",
                                    name, name, taken, example));
    out.push_back(p.add_coordinate(name, where));
  }
  return out;
}

// The body's point whose outward normal is -n, and its reach along n from the shape's centre C
// (world): for a ball C - r n directly, without R R^T; otherwise the shape's support point along
// `direction` (body axes, of length `length`: the support mapping reads the direction only, so
// that a ground may pass an unnormalized one and keep a root out of what is differentiated).
std::pair<Vector3, GiNaC::ex> body_support(const ParsedContact& c, const PlacedFrame& F, const Vector3& C,
                                           const Vector3& normal, const Vector3& direction, const GiNaC::ex& length) {
  if (const std::optional<GiNaC::ex> r = c.shape->ball_radius(c.values)) return {subtract(C, scale(*r, normal)), *r};
  const ShapeSupport s = c.shape->support(c.values, direction, length);
  return {add(C, multiply(F.rotation, s.point)), s.reach};
}

// The rows that hold an implicit shape's contact point y (body axes) where the ground's normal is
// n with tangents t1, t2: f(y) = 0 and (R grad f(y)) . t_k = 0 (rolling-bodies.md section 9).
void implicit_shape_rows(const ParsedContact& c, const PlacedFrame& F, const Vector3& t1, const Vector3& t2,
                         ContactGround::Touch& out) {
  const ShapeValues& v = c.values;
  Vector3 gradient;
  for (std::size_t i = 0; i < 3; ++i) gradient[i] = v.surface.diff(GiNaC::ex_to<GiNaC::symbol>(v.point[i]));
  const Vector3 world = multiply(F.rotation, gradient);
  out.locate.push_back({"_on", v.surface});
  out.locate.push_back({"_normal1", dot(world, t1)});
  out.locate.push_back({"_normal2", dot(world, t2)});
}

// A positive scale as an exact rational: between 1e-3 and 1e3 a convergent of its continued
// fraction with a denominator up to 10^6 (short to print: 1, 19/25; within 1e-15 of it where one
// is, and within about 1e-6 at worst, for a value just off a simple fraction: the scale only
// normalizes rows), else the double's own binary value. A float in the derived expressions would combine with their exact
// coefficients in GiNaC's term order, which changes from process to process: the equations
// printed "-1.0 x" in one run and "-x" in another.
GiNaC::numeric exact_scale(double value) {
  if (!(value > 0.0) || !std::isfinite(value)) return GiNaC::numeric(1);
  if (value >= 1e-3 && value <= 1e3) {
    long p0 = 0, q0 = 1, p1 = 1, q1 = 0;  // the convergents before the current one
    double x = value;
    for (int i = 0; i < 40; ++i) {
      const double a = std::floor(x);
      const long p2 = static_cast<long>(a) * p1 + p0, q2 = static_cast<long>(a) * q1 + q0;
      if (q2 > 1000000) break;
      p0 = p1;
      q0 = q1;
      p1 = p2;
      q1 = q2;
      if (std::abs(static_cast<double>(p1) / static_cast<double>(q1) - value) <= 1e-15 * value || x - a < 1e-9) break;
      x = 1.0 / (x - a);
    }
    if (q1 > 0 && p1 > 0) return GiNaC::numeric(p1) / GiNaC::numeric(q1);
  }
  return exact_double(value);
}

GiNaC::numeric exact_double(double value) { return std::isfinite(value) ? exact_rational(value) : GiNaC::numeric(0); }

// |grad g| at the shape's centre where the run starts (the file's initial values and parameters),
// g's scale as a number: 1 where that is not a positive number (a start written nowhere).
double gradient_scale(const Vector3& gradient, const Vector3& U, const Vector3& C, const Spec& spec) {
  try {
    GiNaC::exmap at;
    for (const GiNaC::ex& p : spec.parameter_values()) at[p.op(0)] = p.op(1);
    at[spec.symbols.time()] = GiNaC::numeric(spec.t0);
    for (std::size_t i = 0; i < spec.q0.size() && i < spec.coordinates.size(); ++i)
      at[spec.symbols.coordinate(static_cast<int>(i))] = spec.q0[i];
    GiNaC::exmap on = at;
    for (std::size_t i = 0; i < 3; ++i) on[U[i]] = C[i].subs(at, GiNaC::subs_options::no_pattern).subs(at);
    double sum = 0.0;
    for (const GiNaC::ex& d : gradient) {
      const GiNaC::ex v = d.subs(on, GiNaC::subs_options::no_pattern).subs(at).evalf();
      if (!GiNaC::is_a<GiNaC::numeric>(v) || !GiNaC::ex_to<GiNaC::numeric>(v).is_real()) return 1.0;
      const double x = GiNaC::ex_to<GiNaC::numeric>(v).to_double();
      sum += x * x;
    }
    const double size = std::sqrt(sum);
    return std::isfinite(size) && size > 0.0 ? size : 1.0;
  } catch (const std::exception&) {
    return 1.0;
  }
}

}  // namespace nhdyn::symbolic
