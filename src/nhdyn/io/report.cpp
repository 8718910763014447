#include "nhdyn/io/report.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <optional>
#include <sstream>
#include <string_view>
#include <utility>

#include "nhdyn/core/error.hpp"
#include "nhdyn/io/atomic_file.hpp"
#include "nhdyn/io/plot.hpp"
#include "nhdyn/symbolic/derivation.hpp"
#include "nhdyn/symbolic/description.hpp"
#include "nhdyn/symbolic/equations.hpp"
#include "nhdyn/symbolic/spec.hpp"
#include "nhdyn/symbolic/visual.hpp"

// Generated at build time from the Debian packages and io/resources/ (io/resources/embed.cmake).
namespace nhdyn::resources {
struct FontResource {
  const char* name;  // e.g. "KaTeX_Main-Regular"
  const unsigned char* data;
  std::size_t size;
};
extern const std::string_view three_js, katex_js, katex_css, report_js, report_css;
extern const FontResource katex_fonts[];
extern const std::size_t katex_font_count;
}  // namespace nhdyn::resources

namespace nhdyn {
namespace {

// A JSON string, safe inside a <script> element (no "</" can end it early).
void append_string(std::string& out, std::string_view text) {
  out += '"';
  for (const char c : text) {
    switch (c) {
      case '"': out += "\\\""; break;
      case '\\': out += "\\\\"; break;
      case '\n': out += "\\n"; break;
      case '\r': out += "\\r"; break;
      case '\t': out += "\\t"; break;
      case '<': out += "\\u003c"; break;
      default:
        if (static_cast<unsigned char>(c) < 0x20) out += fmt::format("\\u{:04x}", static_cast<int>(c));
        else out += c;
    }
  }
  out += '"';
}

// Six significant digits: a page 0.1 mm off on a metre-sized scene cannot be seen, and the
// numbers are most of the page. Non-finite values become null (a gap in a curve).
void append_number(std::string& out, double x) {
  if (!std::isfinite(x)) {
    out += "null";
    return;
  }
  if (x == 0.0) x = 0.0;  // no "-0"
  out += fmt::format("{:.6g}", x);
}

void append_numbers(std::string& out, const std::vector<double>& values) {
  out += '[';
  for (std::size_t i = 0; i < values.size(); ++i) {
    if (i > 0) out += ',';
    append_number(out, values[i]);
  }
  out += ']';
}

std::string base64(const unsigned char* data, std::size_t size) {
  static constexpr char digits[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((size + 2) / 3 * 4);
  for (std::size_t i = 0; i < size; i += 3) {
    const unsigned a = data[i], b = i + 1 < size ? data[i + 1] : 0u, c = i + 2 < size ? data[i + 2] : 0u;
    const unsigned triple = (a << 16) | (b << 8) | c;
    out += digits[(triple >> 18) & 63];
    out += digits[(triple >> 12) & 63];
    out += i + 1 < size ? digits[(triple >> 6) & 63] : '=';
    out += i + 2 < size ? digits[triple & 63] : '=';
  }
  return out;
}

// KaTeX's stylesheet with every font's list of sources replaced by the embedded woff2 file as a
// data: URL, so that no font is fetched when the page is opened.
std::string katex_css_with_fonts() {
  const std::string_view css = resources::katex_css;
  std::string out;
  std::size_t p = 0;
  while (true) {
    const std::size_t src = css.find("src:", p);
    if (src == std::string_view::npos) break;
    const std::size_t end = css.find_first_of(";}", src);
    if (end == std::string_view::npos) break;
    const std::string_view sources = css.substr(src, end - src);
    out.append(css.substr(p, src - p));
    bool replaced = false;
    for (std::size_t i = 0; i < resources::katex_font_count && !replaced; ++i) {
      const resources::FontResource& font = resources::katex_fonts[i];
      if (sources.find(fmt::format("fonts/{}.woff2", font.name)) == std::string_view::npos) continue;
      out += "src:url(data:font/woff2;base64,";
      out += base64(font.data, font.size);
      out += ") format(\"woff2\")";
      replaced = true;
    }
    if (!replaced) out.append(sources);
    p = end;
  }
  out.append(css.substr(p));
  return out;
}

struct PlotGroup {
  std::string title;
  bool log = false;
  bool drift = false;  // drawn as v - v(first row)
  std::vector<std::string> columns;
  int role = 0;  // groups of one role (0 coordinates, 1 reactions, 2 actuators) share a scale
  bool steps = false;  // piecewise constant (contact modes): drawn as steps, never "constant to round-off"
  double role_scale = 0.0;  // the largest |value| of the groups of its role, for the round-off rule
};

// The PNG panels' rule (io/plot.cpp): a column whose values vary by no more than this fraction of
// the largest magnitude among the columns of its role is constant to round-off, and is drawn as
// the constant it is (flat, labelled so) rather than magnified into noise: the upright bicycle's
// lean of 1e-12 rad beside wheels spinning through hundreds of radians.
constexpr double kReportRoundOff = 1e-9;

// Semi-axes and principal directions of the uniform solid ellipsoid with the body's mass and
// inertia: I_1 = m (b^2 + c^2) / 5 and so on, hence a^2 = 5 (I_2 + I_3 - I_1) / (2 m). A body whose
// moments leave an axis at zero or below (a point mass, a thin rod) gets a tenth of its largest
// semi-axis there, so that it stays visible.
SceneSize equivalent_ellipsoid(double mass, const Eigen::Matrix3d& inertia) {
  SceneSize out;
  if (!(mass > 0.0)) {  // a massless body: a small ball
    out.size = {0.05, 0.05, 0.05};
    return out;
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(inertia);
  Eigen::Matrix3d axes = solver.eigenvectors();
  if (axes.determinant() < 0.0) axes.col(2) = -axes.col(2);
  const Eigen::Vector3d I = solver.eigenvalues();
  double largest = 0.0;
  for (int i = 0; i < 3; ++i) {
    const double square = 5.0 * (I((i + 1) % 3) + I((i + 2) % 3) - I(i)) / (2.0 * mass);
    out.size[static_cast<std::size_t>(i)] = square > 0.0 ? std::sqrt(square) : 0.0;
    largest = std::max(largest, out.size[static_cast<std::size_t>(i)]);
  }
  if (largest == 0.0) largest = 0.05;  // a point mass: a small ball
  for (double& a : out.size) a = std::max(a, 0.1 * largest);
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) out.axes[static_cast<std::size_t>(3 * i + j)] = axes(i, j);
  return out;
}

// The run's values in the order the scene's tapes read them; refused when the names differ (a
// scene compiled from another model than the run's).
std::vector<double> parameter_values_for(const symbolic::VisualScene& scene, const std::vector<Parameter>& parameters,
                                         const std::string& model) {
  std::vector<std::string> names;
  std::vector<double> values;
  for (const Parameter& p : parameters) {
    names.push_back(p.name);
    values.push_back(p.value);
  }
  if (names != scene.parameters)
    throw InputError(fmt::format("the scene of '{}' reads the parameters ({}), the run has ({}): give the run's "
                                 "model with its parameter values",
                                 model, fmt::join(scene.parameters, ", "), fmt::join(names, ", ")));
  return values;
}

}  // namespace

std::vector<SceneSize> calc_scene_sizes(const symbolic::VisualScene& scene, const std::vector<Parameter>& parameters,
                                        const std::string& model) {
  const std::vector<double> values = parameter_values_for(scene, parameters, model);
  const Tape sizes = scene.sizes.bind(values.data(), values.size());
  std::vector<double> registers(static_cast<std::size_t>(sizes.registers()));
  std::vector<double> out(static_cast<std::size_t>(sizes.outputs()));
  sizes.run(0.0, nullptr, nullptr, registers.data(), out.data());
  std::vector<SceneSize> result;
  for (const symbolic::VisualShape& shape : scene.shapes) {
    const double* x = out.data() + shape.size_offset;
    SceneSize size;
    if (shape.kind == symbolic::VisualKind::sphere || shape.kind == symbolic::VisualKind::wheel) {
      if (!(x[0] > 0.0 && std::isfinite(x[0])))
        throw InputError(fmt::format("{}{}[visual] {} '{}' of '{}': its radius is {} with the run's parameter values; "
                                     "it must be positive (check the parameters set with --set)",
                                     shape.where, shape.where.empty() ? "" : ": ",
                                     shape.kind == symbolic::VisualKind::wheel ? "wheel" : "point", shape.name, model,
                                     x[0]));
      size.size = {x[0], x[0], x[0]};
    } else if (shape.kind == symbolic::VisualKind::ellipsoid || shape.kind == symbolic::VisualKind::torus) {
      const int count = symbolic::visual_sizes(shape.kind);
      for (int k = 0; k < count; ++k)
        if (!(x[k] > 0.0 && std::isfinite(x[k])))
          throw InputError(fmt::format("{}{}contact '{}' of '{}': the {}'s size {} is {} with the run's parameter "
                                       "values; it must be positive (check the parameters set with --set)",
                                       shape.where, shape.where.empty() ? "" : ": ", shape.name, model,
                                       symbolic::visual_kind_name(shape.kind), k + 1, x[k]));
      size.size = {x[0], x[1], count > 2 ? x[2] : 0.0};
    } else if (shape.kind == symbolic::VisualKind::body) {
      Eigen::Matrix3d inertia;
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) inertia(i, j) = x[1 + 3 * i + j];
      if (!inertia.allFinite() || !std::isfinite(x[0]))
        throw InputError(fmt::format("{}{}[visual] body '{}' of '{}': its mass or inertia is not finite with the run's "
                                     "parameter values (check the parameters set with --set)",
                                     shape.where, shape.where.empty() ? "" : ": ", shape.name, model));
      size = equivalent_ellipsoid(x[0], inertia);
    }
    result.push_back(size);
  }
  return result;
}

namespace {

// A bound field tape (symbolic/visual.hpp) evaluated at points.
class Field {
 public:
  Field(const Tape& field, const std::vector<double>& parameters)
      : tape_(field.bind(parameters.data(), parameters.size())),
        registers_(static_cast<std::size_t>(tape_.registers())),
        zeros_(static_cast<std::size_t>(tape_.coordinates()), 0.0) {}
  double operator()(double x, double y, double z = 0.0) {
    const double at[3] = {x, y, z};
    double out = 0.0;
    tape_.run(0.0, at, zeros_.data(), registers_.data(), &out);
    return out;
  }

 private:
  Tape tape_;
  std::vector<double> registers_;
  std::vector<double> zeros_;
};

using Point = std::array<double, 3>;
constexpr double kInf = std::numeric_limits<double>::infinity();

// The distance along the unit direction d from `from` to the first zero of f, whose sign at
// `from` is the opposite of its sign far enough along d: found by doubling from `start`, then
// bisection to round-off. NaN when no change of sign is found.
double ray_zero(Field& f, const Point& from, const Point& d, double start) {
  const auto at = [&](double s) { return f(from[0] + s * d[0], from[1] + s * d[1], from[2] + s * d[2]); };
  const bool inside = at(0.0) < 0.0;
  double lo = 0.0, hi = start;
  int doublings = 0;
  while ((at(hi) < 0.0) == inside) {
    lo = hi;
    hi *= 2.0;
    if (++doublings > 80) return std::nan("");
  }
  for (int i = 0; i < 200 && hi - lo > 4 * std::numeric_limits<double>::epsilon() * hi; ++i) {
    const double mid = 0.5 * (lo + hi);
    ((at(mid) < 0.0) == inside ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

// Rows x columns of vertices, row-major: two triangles per cell, leaving out a cell with a vertex
// that is not finite (a terrain undefined there: it is not drawn, rather than drawn at 0; the
// page writes such a vertex as null and draws no grid line to it).
void grid_triangles(int rows, int columns, const std::vector<double>& vertices, std::vector<int>& out) {
  const auto finite = [&](int v) {
    const std::size_t k = 3 * static_cast<std::size_t>(v);
    return std::isfinite(vertices[k]) && std::isfinite(vertices[k + 1]) && std::isfinite(vertices[k + 2]);
  };
  for (int i = 0; i + 1 < rows; ++i)
    for (int j = 0; j + 1 < columns; ++j) {
      const int a = i * columns + j, b = a + 1, c = a + columns, d = c + 1;
      if (finite(a) && finite(b) && finite(c) && finite(d)) out.insert(out.end(), {a, c, b, b, c, d});
    }
}

[[noreturn]] void mesh_failure(const symbolic::VisualShape& shape, const std::string& model, const std::string& why) {
  throw InputError(fmt::format("{}{}contact '{}' of '{}': the report cannot draw its {}: {}", shape.where,
                               shape.where.empty() ? "" : ": ", shape.name, model,
                               shape.kind == symbolic::VisualKind::solid ? "shape" : "ground", why));
}

// A point inside a solid (f < 0) from which every point of its surface is seen: its centre when
// that is inside, else the end of a descent of f from the centre (steepest descent, the gradient
// by central differences, a backtracking line search), towards the minimum of f. A strictly convex
// shape is seen whole from any point inside it. Nothing when no point inside is found.
std::optional<Point> inside_point(Field& f) {
  Point p = {0.0, 0.0, 0.0};
  double fp = f(0.0, 0.0, 0.0);
  if (fp < 0.0) return p;
  if (!std::isfinite(fp)) return std::nullopt;
  double t = 0.0;  // the last accepted step along -grad f; 0: none yet
  for (int iteration = 0; iteration < 200; ++iteration) {
    const double h = 1e-7 * std::max(1.0, std::max({std::abs(p[0]), std::abs(p[1]), std::abs(p[2])}));
    Point g;
    for (std::size_t k = 0; k < 3; ++k) {
      Point a = p, b = p;
      a[k] += h;
      b[k] -= h;
      g[k] = (f(a[0], a[1], a[2]) - f(b[0], b[1], b[2])) / (2 * h);
    }
    const double g2 = g[0] * g[0] + g[1] * g[1] + g[2] * g[2];
    if (!(g2 > 0.0) || !std::isfinite(g2)) break;
    // The first step goes twice as far as the linearization's zero of f; later ones start from
    // twice the last accepted step.
    double step = t > 0.0 ? 2.0 * t : 2.0 * std::abs(fp) / g2;
    bool moved = false;
    for (int halving = 0; halving < 60; ++halving, step *= 0.5) {
      const Point q = {p[0] - step * g[0], p[1] - step * g[1], p[2] - step * g[2]};
      const double fq = f(q[0], q[1], q[2]);
      if (std::isfinite(fq) && fq < fp) {
        p = q;
        fp = fq;
        t = step;
        moved = true;
        break;
      }
    }
    if (!moved) break;
  }
  if (fp < 0.0) return p;
  return std::nullopt;
}

// A solid's zero set along rays from a point inside it (its centre when that is inside): rings of
// constant polar angle about the frame's z.
SceneMesh solid_mesh(Field& f, const symbolic::VisualShape& shape, const std::string& model) {
  constexpr int rings = 25, around = 49;
  const std::optional<Point> inside = inside_point(f);
  if (!inside)
    mesh_failure(shape, model, fmt::format("its surface function is {} at the shape's centre and no point where it "
                                           "is negative (inside) was found by descending it from there; the report "
                                           "samples the surface along rays from a point inside",
                                           f(0.0, 0.0, 0.0)));
  const Point& o = *inside;
  // The rays are spread as the points of the unit sphere stretched by the shape's reach along
  // each axis: on an ellipsoid they fall where its own parameter lines do, so that a long thin
  // shape (a rattleback) is sampled along its length as finely as across it.
  Point reach = {0.0, 0.0, 0.0};
  for (std::size_t k = 0; k < 3; ++k)
    for (const double sign : {1.0, -1.0}) {
      Point axis = {0.0, 0.0, 0.0};
      axis[k] = sign;
      // (std::max would swallow a NaN: a ray that meets no zero is tested first.)
      const double r = ray_zero(f, o, axis, 1e-3);
      reach[k] = std::isfinite(r) ? std::max(reach[k], r) : std::numeric_limits<double>::quiet_NaN();
    }
  if (!(reach[0] > 0.0 && reach[1] > 0.0 && reach[2] > 0.0 && std::isfinite(reach[0]) && std::isfinite(reach[1]) &&
        std::isfinite(reach[2])))
    mesh_failure(shape, model, "a ray along an axis from a point inside it meets no point where the surface function is zero; is the shape closed?");
  SceneMesh mesh;
  for (int i = 0; i < rings; ++i) {
    const double polar = std::numbers::pi * i / (rings - 1);
    for (int j = 0; j < around; ++j) {
      const double azimuth = 2 * std::numbers::pi * j / (around - 1);
      Point d = {reach[0] * std::sin(polar) * std::cos(azimuth), reach[1] * std::sin(polar) * std::sin(azimuth),
                 reach[2] * std::cos(polar)};
      const double length = std::hypot(d[0], d[1], d[2]);
      for (double& x : d) x /= length;
      const double s = ray_zero(f, o, d, 1e-3);
      if (!std::isfinite(s)) mesh_failure(shape, model, "a ray from a point inside it meets no point where the surface function is zero; is the shape closed?");
      mesh.vertices.insert(mesh.vertices.end(), {o[0] + s * d[0], o[1] + s * d[1], o[2] + s * d[2]});
    }
  }
  grid_triangles(rings, around, mesh.vertices, mesh.triangles);
  mesh.rows = rings;
  return mesh;
}

// The finite positions of a shape's three outputs over the frames.
std::vector<Point> shape_path(const symbolic::VisualShape& shape, const std::vector<double>& values, std::size_t stride) {
  std::vector<Point> out;
  for (std::size_t f = 0; f + stride <= values.size(); f += stride) {
    const double* p = values.data() + f + static_cast<std::size_t>(shape.offset);
    if (std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2])) out.push_back({p[0], p[1], p[2]});
  }
  return out;
}

// A terrain's heights over the box its contact point covers, widened by the margin.
SceneMesh terrain_mesh(Field& h, const std::vector<Point>& path, double length) {
  double lo[2] = {0.0, 0.0}, hi[2] = {0.0, 0.0};
  if (!path.empty()) {
    lo[0] = hi[0] = path[0][0];
    lo[1] = hi[1] = path[0][1];
  }
  for (const Point& p : path)
    for (int k = 0; k < 2; ++k) {
      lo[k] = std::min(lo[k], p[static_cast<std::size_t>(k)]);
      hi[k] = std::max(hi[k], p[static_cast<std::size_t>(k)]);
    }
  const double margin = std::max(std::max(hi[0] - lo[0], hi[1] - lo[1]) / 3.0, 4.0 * std::abs(length));
  const double width[2] = {hi[0] - lo[0] + 2 * margin, hi[1] - lo[1] + 2 * margin};
  const double step = std::max(width[0], width[1]) / 48.0;
  // A path that did not move and a shape of no length, or one that ran off to infinity, leave no
  // region to mesh.
  if (!(step > 0.0 && std::isfinite(step))) return {};
  const int nx = std::max(9, static_cast<int>(std::ceil(width[0] / step)) + 1);
  const int ny = std::max(9, static_cast<int>(std::ceil(width[1] / step)) + 1);
  SceneMesh mesh;
  for (int i = 0; i < nx; ++i)
    for (int j = 0; j < ny; ++j) {
      const double x = lo[0] - margin + width[0] * i / (nx - 1), y = lo[1] - margin + width[1] * j / (ny - 1);
      mesh.vertices.insert(mesh.vertices.end(), {x, y, h(x, y)});
    }
  grid_triangles(nx, ny, mesh.vertices, mesh.triangles);
  mesh.rows = nx;
  return mesh;
}

// A fixed surface's zero set along rays from the point K inside it, over the cap around the mean
// direction of the contact point from K that holds every direction of the path, widened by the
// margin (as an angle at the path's mean distance).
SceneMesh surface_mesh(Field& g, const symbolic::VisualShape& shape, const std::string& model,
                       const std::vector<Point>& path, double length, const Point& K) {
  Point mean = {0.0, 0.0, 0.0};
  double distance = 0.0;
  std::vector<Point> directions;
  for (const Point& p : path) {
    const Point d = {p[0] - K[0], p[1] - K[1], p[2] - K[2]};
    const double r = std::hypot(d[0], d[1], d[2]);
    if (!(r > 0.0)) continue;
    directions.push_back({d[0] / r, d[1] / r, d[2] / r});
    for (int k = 0; k < 3; ++k) mean[static_cast<std::size_t>(k)] += directions.back()[static_cast<std::size_t>(k)];
    distance += r;
  }
  double norm = std::hypot(mean[0], mean[1], mean[2]);
  if (directions.empty() || !(norm > 0.0)) {
    mean = {0.0, 0.0, -1.0};
    norm = 1.0;
    distance = 1.0;
  } else {
    distance /= static_cast<double>(directions.size());
  }
  for (double& m : mean) m /= norm;
  double half = 0.0;
  for (const Point& d : directions)
    half = std::max(half, std::acos(std::clamp(d[0] * mean[0] + d[1] * mean[1] + d[2] * mean[2], -1.0, 1.0)));
  half = std::min(std::numbers::pi, half + std::max(half / 3.0, 4.0 * std::abs(length) / distance));
  // e1, e2: unit vectors normal to the mean direction.
  const Point axis = std::abs(mean[2]) < 0.9 ? Point{0.0, 0.0, 1.0} : Point{1.0, 0.0, 0.0};
  Point e1 = {axis[1] * mean[2] - axis[2] * mean[1], axis[2] * mean[0] - axis[0] * mean[2], axis[0] * mean[1] - axis[1] * mean[0]};
  const double n1 = std::hypot(e1[0], e1[1], e1[2]);
  for (double& e : e1) e /= n1;
  const Point e2 = {mean[1] * e1[2] - mean[2] * e1[1], mean[2] * e1[0] - mean[0] * e1[2], mean[0] * e1[1] - mean[1] * e1[0]};
  constexpr int rings = 25, around = 49;
  SceneMesh mesh;
  for (int i = 0; i < rings; ++i) {
    const double a = half * i / (rings - 1);
    for (int j = 0; j < around; ++j) {
      const double b = 2 * std::numbers::pi * j / (around - 1);
      Point d;
      for (std::size_t k = 0; k < 3; ++k)
        d[k] = std::cos(a) * mean[k] + std::sin(a) * (std::cos(b) * e1[k] + std::sin(b) * e2[k]);
      const double s = ray_zero(g, K, d, 1e-3 * distance);
      if (!std::isfinite(s)) mesh_failure(shape, model, "a ray from the point inside it meets no point of the surface");
      mesh.vertices.insert(mesh.vertices.end(), {K[0] + s * d[0], K[1] + s * d[1], K[2] + s * d[2]});
    }
  }
  grid_triangles(rings, around, mesh.vertices, mesh.triangles);
  mesh.rows = rings;
  return mesh;
}

// The zero of g on the line p + s m nearest p (|s| up to 4 range, in both directions); NaN when
// there is none.
double line_zero(Field& g, const Point& p, const Point& m, double range) {
  const auto at = [&](double s) { return g(p[0] + s * m[0], p[1] + s * m[1], p[2] + s * m[2]); };
  const double g0 = at(0.0);
  if (g0 == 0.0) return 0.0;
  if (!std::isfinite(g0)) return std::nan("");
  double previous = 0.0;
  for (double s = 1e-3 * range; s <= 4.0 * range; previous = s, s *= 2.0)
    for (const double sign : {1.0, -1.0}) {
      const double far = at(sign * s);
      if (!std::isfinite(far) || (far > 0.0) == (g0 > 0.0)) continue;
      double lo = sign * previous, hi = sign * s;
      for (int i = 0; i < 200 && std::abs(hi - lo) > 4 * std::numeric_limits<double>::epsilon() * std::abs(hi); ++i) {
        const double mid = 0.5 * (lo + hi);
        ((at(mid) > 0.0) == (g0 > 0.0) ? lo : hi) = mid;
      }
      return 0.5 * (lo + hi);
    }
  return std::nan("");
}

SceneMesh patch_mesh(Field& g, const symbolic::VisualShape& shape, const std::string& model,
                     const std::vector<Point>& path, double length);

// The mean point of a contact's path and g's gradient there (central differences): where the
// drawing of a fixed surface starts.
std::pair<Point, Point> path_mean_and_gradient(Field& g, const std::vector<Point>& path) {
  Point mean = {0.0, 0.0, 0.0};
  for (const Point& p : path)
    for (std::size_t k = 0; k < 3; ++k) mean[k] += p[k] / static_cast<double>(path.size());
  const double h = 1e-6 * std::max({1.0, std::abs(mean[0]), std::abs(mean[1]), std::abs(mean[2])});
  Point m;
  for (std::size_t k = 0; k < 3; ++k) {
    Point a = mean, b = mean;
    a[k] += h;
    b[k] -= h;
    m[k] = (g(a[0], a[1], a[2]) - g(b[0], b[1], b[2])) / (2 * h);
  }
  return {mean, m};
}

// A fixed surface that is not a sphere: along rays from a point K where g < 0 (inside a bowl, or
// inside the solid a hill is the top of), K below the mean of the contact's path along the
// surface's normal by the path's extent (halved until g(K) < 0): from a point inside a convex
// region every ray meets its boundary once, so that the cap covers the whole path, up a bowl's
// wall too. Where that fails, over the tangent plane (patch_mesh).
SceneMesh ground_mesh(Field& g, const symbolic::VisualShape& shape, const std::string& model,
                      const std::vector<Point>& path, double length) {
  if (path.empty()) return {};
  const auto [mean, m] = path_mean_and_gradient(g, path);
  const double norm = std::hypot(m[0], m[1], m[2]);
  double reach = 0.0;
  for (const Point& p : path) reach = std::max(reach, std::hypot(p[0] - mean[0], p[1] - mean[1], p[2] - mean[2]));
  double depth = std::max(reach, 4.0 * std::abs(length));
  if (norm > 0.0 && std::isfinite(norm) && depth > 0.0 && std::isfinite(depth))
    for (int attempt = 0; attempt < 30; ++attempt, depth /= 2) {
      const Point K = {mean[0] - depth * m[0] / norm, mean[1] - depth * m[1] / norm, mean[2] - depth * m[2] / norm};
      if (!(g(K[0], K[1], K[2]) < 0.0)) continue;
      try {
        return surface_mesh(g, shape, model, path, length, K);
      } catch (const InputError&) {
        break;
      }
    }
  return patch_mesh(g, shape, model, path, length);
}

// A fixed surface that is not a sphere: its zero set over the tangent plane at the mean point of
// the contact's path, the zero of g nearest each point of a square grid in that plane along the
// plane's normal. The square holds the path and the margin; where a line meets no zero (the
// surface turns away from the plane, as a closed bowl at its rim) the square is halved.
SceneMesh patch_mesh(Field& g, const symbolic::VisualShape& shape, const std::string& model,
                     const std::vector<Point>& path, double length) {
  if (path.empty()) return {};
  auto [mean, m] = path_mean_and_gradient(g, path);
  const double norm = std::hypot(m[0], m[1], m[2]);
  if (!(norm > 0.0) || !std::isfinite(norm))
    mesh_failure(shape, model, "its gradient at the contact path's mean point is zero or not a number");
  for (double& x : m) x /= norm;
  const Point axis = std::abs(m[2]) < 0.9 ? Point{0.0, 0.0, 1.0} : Point{1.0, 0.0, 0.0};
  Point e1 = {axis[1] * m[2] - axis[2] * m[1], axis[2] * m[0] - axis[0] * m[2], axis[0] * m[1] - axis[1] * m[0]};
  const double n1 = std::hypot(e1[0], e1[1], e1[2]);
  for (double& e : e1) e /= n1;
  const Point e2 = {m[1] * e1[2] - m[2] * e1[1], m[2] * e1[0] - m[0] * e1[2], m[0] * e1[1] - m[1] * e1[0]};
  double reach = 0.0;
  for (const Point& p : path) {
    const Point d = {p[0] - mean[0], p[1] - mean[1], p[2] - mean[2]};
    reach = std::max({reach, std::abs(d[0] * e1[0] + d[1] * e1[1] + d[2] * e1[2]),
                      std::abs(d[0] * e2[0] + d[1] * e2[1] + d[2] * e2[2])});
  }
  double half = reach + std::max(reach / 3.0, 4.0 * std::abs(length));
  if (!(half > 0.0 && std::isfinite(half))) return {};
  constexpr int n = 41;
  for (int attempt = 0; attempt < 8; ++attempt, half /= 2) {
    SceneMesh mesh;
    bool whole = true;
    for (int i = 0; i < n && whole; ++i)
      for (int j = 0; j < n && whole; ++j) {
        const double a = -half + 2 * half * i / (n - 1), b = -half + 2 * half * j / (n - 1);
        const Point p = {mean[0] + a * e1[0] + b * e2[0], mean[1] + a * e1[1] + b * e2[1], mean[2] + a * e1[2] + b * e2[2]};
        const double s = line_zero(g, p, m, half);
        whole = std::isfinite(s);
        mesh.vertices.insert(mesh.vertices.end(), {p[0] + s * m[0], p[1] + s * m[1], p[2] + s * m[2]});
      }
    if (!whole) continue;
    grid_triangles(n, n, mesh.vertices, mesh.triangles);
    mesh.rows = n;
    return mesh;
  }
  mesh_failure(shape, model, "a line along its normal near the contact's path meets no point where its function is zero");
}

}  // namespace

std::vector<SceneMesh> calc_scene_meshes(const symbolic::VisualScene& scene, const std::vector<Parameter>& parameters,
                                         const std::vector<double>& values, std::size_t stride, const std::string& model,
                                         std::vector<std::string>* notes) {
  const std::vector<double> parameter_values = parameter_values_for(scene, parameters, model);
  const Tape sizes = scene.sizes.bind(parameter_values.data(), parameter_values.size());
  std::vector<double> registers(static_cast<std::size_t>(sizes.registers()));
  std::vector<double> size(static_cast<std::size_t>(sizes.outputs()));
  sizes.run(0.0, nullptr, nullptr, registers.data(), size.data());
  std::vector<SceneMesh> out(scene.shapes.size());
  // The solids first: a ground's margin is its contact's size, which an implicit shape gives only
  // through its mesh (its half extent) rather than a size of the model.
  for (std::size_t s = 0; s < scene.shapes.size(); ++s) {
    const symbolic::VisualShape& shape = scene.shapes[s];
    if (shape.kind != symbolic::VisualKind::solid) continue;
    Field field(shape.field, parameter_values);
    out[s] = solid_mesh(field, shape, model);
  }
  const auto length_of = [&](const symbolic::VisualShape& ground, double written) {
    for (std::size_t s = 0; s < scene.shapes.size(); ++s)
      if (scene.shapes[s].kind == symbolic::VisualKind::solid && scene.shapes[s].name == ground.name) {
        const std::vector<double>& v = out[s].vertices;
        double lo[3] = {kInf, kInf, kInf}, hi[3] = {-kInf, -kInf, -kInf};
        for (std::size_t k = 0; k < v.size(); ++k) {
          lo[k % 3] = std::min(lo[k % 3], v[k]);
          hi[k % 3] = std::max(hi[k % 3], v[k]);
        }
        return 0.5 * std::max({hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]});
      }
    return written;
  };
  for (std::size_t s = 0; s < scene.shapes.size(); ++s) {
    const symbolic::VisualShape& shape = scene.shapes[s];
    if (shape.kind != symbolic::VisualKind::terrain && shape.kind != symbolic::VisualKind::surface) continue;
    Field field(shape.field, parameter_values);
    const double* x = size.data() + shape.size_offset;
    const double length = length_of(shape, x[0]);
    if (shape.kind == symbolic::VisualKind::terrain) out[s] = terrain_mesh(field, shape_path(shape, values, stride), length);
    else if (x[4] != 0.0) out[s] = surface_mesh(field, shape, model, shape_path(shape, values, stride), length, {x[1], x[2], x[3]});
    else {
      // A ground the report cannot sample is left undrawn, said in the page's note: the run and
      // its other shapes stand.
      try {
        out[s] = ground_mesh(field, shape, model, shape_path(shape, values, stride), length);
      } catch (const InputError& e) {
        if (notes != nullptr)
          notes->push_back(fmt::format("The ground of contact '{}' is not drawn: {}.", shape.name, e.what()));
      }
    }
  }
  return out;
}

std::string write_model_report(const Model& model, const symbolic::Spec* spec, const CsvTable& table,
                               const std::string& title, const std::vector<std::pair<std::string, std::string>>& extra,
                               const std::filesystem::path& path, const ReportOptions& options) {
  if (spec == nullptr) return write_model_report(model, static_cast<const symbolic::ModelDescription*>(nullptr), table, title, extra, path, options);
  const symbolic::ModelDescription description(*spec);
  return write_model_report(model, &description, table, title, extra, path, options);
}

void check_report_options(const ReportOptions& options) {
  if (options.max_frames < 2)
    throw InputError(fmt::format("the report's max_frames (--max-frames) = {} must be at least 2 (the first and the "
                                 "last row)",
                                 options.max_frames));
}

std::vector<std::size_t> report_frames(std::size_t rows, int max_frames) {
  std::vector<std::size_t> out;
  if (rows == 0) return out;
  const std::size_t most = static_cast<std::size_t>(std::max(max_frames, 2));
  const std::size_t k = rows <= most ? 1 : (rows - 1 + most - 2) / (most - 1);
  for (std::size_t i = 0; i < rows; i += k) out.push_back(i);
  if (out.back() != rows - 1) out.push_back(rows - 1);
  return out;
}

void check_report_columns(const std::vector<std::string>& header, const ResultColumns& expected,
                          const std::string& csv, const std::string& model) {
  const std::vector<std::string>& want = expected.all;
  for (std::size_t i = 0; i < std::max(header.size(), want.size()); ++i) {
    if (i < header.size() && i < want.size() && header[i] == want[i]) continue;
    if (i >= header.size())
      throw InputError(fmt::format("{} does not belong to model '{}': it ends after column {} where the model "
                                   "expects column '{}'; give the CSV that `nhdyn simulate` wrote for this model",
                                   csv, model, i, want[i]));
    if (i >= want.size())
      throw InputError(fmt::format("{} does not belong to model '{}': its column {} '{}' is one more than the model's "
                                   "{} columns; give the CSV that `nhdyn simulate` wrote for this model",
                                   csv, model, i + 1, header[i], want.size()));
    throw InputError(fmt::format("{} does not belong to model '{}': its column {} is '{}' where the model expects "
                                 "'{}'; give the CSV that `nhdyn simulate` wrote for this model",
                                 csv, model, i + 1, header[i], want[i]));
  }
}

void check_report_times(const CsvTable& table, const std::string& csv) {
  const int t = table.column("t");
  if (t < 0) return;
  for (std::size_t r = 0; r < table.rows.size(); ++r) {
    const double value = table.rows[r][static_cast<std::size_t>(t)];
    if (!std::isfinite(value) || (r > 0 && value < table.rows[r - 1][static_cast<std::size_t>(t)]))
      throw InputError(fmt::format("{}: row {}: t = {} {}; a result's times are finite and never decrease", csv, r + 1,
                                   value, std::isfinite(value) ? "is before the row above" : "is not finite"));
  }
}

void check_report_values(const CsvTable& table, const ResultColumns& columns, const std::string& csv) {
  std::vector<bool> may_be_nan(table.header.size(), false);
  for (std::size_t c = 0; c < table.header.size(); ++c)
    may_be_nan[c] = std::find(columns.contact_forces.begin(), columns.contact_forces.end(), table.header[c]) !=
                    columns.contact_forces.end();
  for (std::size_t r = 0; r < table.rows.size(); ++r)
    for (std::size_t c = 0; c < table.rows[r].size() && c < may_be_nan.size(); ++c)
      if (!may_be_nan[c] && !std::isfinite(table.rows[r][c]))
        throw InputError(fmt::format("{}: row {}: {} = {} is not finite; a run writes finite values (only contact "
                                     "forces are NaN, where undetermined): give the CSV as `nhdyn simulate` wrote it",
                                     csv, r + 1, table.header[c], table.rows[r][c]));
}

namespace {

// The values of a column at the frames drawn (NaN for a column the table does not have).
struct FrameColumns {
  const CsvTable& table;
  const std::vector<std::size_t>& frames;
  std::vector<double> operator()(const std::string& name) const {
    const int c = table.column(name);
    std::vector<double> values;
    values.reserve(frames.size());
    for (const std::size_t f : frames) values.push_back(c < 0 ? std::nan("") : table.rows[f][static_cast<std::size_t>(c)]);
    return values;
  }
};

// Panels: lengths and angles apart (their scales differ), then reactions, residuals, energy.
std::vector<PlotGroup> report_plot_groups(const ReportInput& input, const FrameColumns& column) {
  std::vector<PlotGroup> groups;
  // Angles that turn through more than a revolution (a wheel's spin, a heading) get a panel of
  // their own, so that their hundreds of radians do not flatten a lean or a steer of a few degrees.
  PlotGroup lengths{"coordinates", false, false, {}}, angles{"angles [rad]", false, false, {}},
      turns{"angles turning more than once [rad]", false, false, {}};
  for (std::size_t i = 0; i < input.coordinates.size(); ++i) {
    const std::string& name = input.coordinates[i];
    // An angle by use in the scene, or by its name (phi, theta_1, psiR: io/plot.hpp), as the PNG has it.
    if (!((i < input.angles.size() && input.angles[i]) || is_angle_name(name))) {
      lengths.columns.push_back(name);
      continue;
    }
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    for (const double x : column(name)) {
      if (!std::isfinite(x)) continue;
      lo = std::min(lo, x);
      hi = std::max(hi, x);
    }
    (hi - lo > 2 * std::numbers::pi ? turns : angles).columns.push_back(name);
  }
  for (PlotGroup* g : {&lengths, &angles, &turns})
    if (!g->columns.empty()) groups.push_back(*g);
  if (!input.columns.reactions.empty()) groups.push_back({"reactions R", false, false, input.columns.reactions, 1});
  if (!input.columns.actuators.empty())
    groups.push_back({input.actuators_title, false, false, input.columns.actuators, 2});
  // The largest |value| of each role over the rows shown, for the round-off rule.
  double role_scale[3] = {0.0, 0.0, 0.0};
  for (const PlotGroup& g : groups)
    if (!g.log && !g.drift)
      for (const std::string& c : g.columns)
        for (const double x : column(c))
          if (std::isfinite(x)) role_scale[g.role] = std::max(role_scale[g.role], std::abs(x));
  for (PlotGroup& g : groups) g.role_scale = role_scale[g.role];
  // Contacts with modes (docs/contact-modes.md): NAME_mode as steps, after the scaled groups.
  PlotGroup modes{"contact modes: 0 rolling, 1 sliding, 2 free", false, false, {}, 0, true};
  for (const std::string& c : input.columns.contact_forces)
    if (c.size() > 5 && c.compare(c.size() - 5, 5, "_mode") == 0) modes.columns.push_back(c);
  if (!modes.columns.empty()) groups.push_back(modes);
  if (!input.columns.residuals.empty())
    groups.push_back({"|constraint residuals| (log scale)", true, false, input.columns.residuals});
  if (!input.columns.energy_balance.empty())
    groups.push_back({"energy balance error h - h(0) - W", false, true, {input.columns.energy_balance.back()}});
  else if (!input.columns.energy.empty())
    groups.push_back({"energy drift E(t) - E(0)", false, true, {input.columns.energy}});
  return groups;
}

// The "plots" member of the page's data: each group's series at the frames drawn.
void append_plots(std::string& data, const CsvTable& table, const std::vector<PlotGroup>& groups,
                  const FrameColumns& column) {
  for (std::size_t g = 0; g < groups.size(); ++g) {
    data += g > 0 ? ",{\"title\":" : "{\"title\":";
    append_string(data, groups[g].title);
    if (groups[g].steps) data += ",\"steps\":true";
    data += groups[g].log ? ",\"log\":true,\"series\":[" : ",\"log\":false,\"series\":[";
    for (std::size_t s = 0; s < groups[g].columns.size(); ++s) {
      std::vector<double> values = column(groups[g].columns[s]);
      if (groups[g].drift) {
        const double first = table.rows.front()[static_cast<std::size_t>(table.column(groups[g].columns[s]))];
        for (double& v : values) v -= first;
      }
      std::string label = groups[g].columns[s];
      if (!groups[g].log && !groups[g].drift && !groups[g].steps && groups[g].role_scale > 0.0) {
        double lo = std::numeric_limits<double>::infinity(), hi = -lo, sum = 0.0;
        std::size_t finite = 0;
        for (const double x : values)
          if (std::isfinite(x)) {
            lo = std::min(lo, x);
            hi = std::max(hi, x);
            sum += x;
            ++finite;
          }
        if (finite > 0 && hi > lo && hi - lo <= kReportRoundOff * groups[g].role_scale) {
          const double level = sum / static_cast<double>(finite);
          for (double& x : values)
            if (std::isfinite(x)) x = level;
          label += fmt::format(" (constant to round-off, {:.3g})", level);
        }
      }
      data += s > 0 ? ",{\"name\":" : "{\"name\":";
      append_string(data, label);
      data += ",\"v\":";
      append_numbers(data, values);
      data += '}';
    }
    data += "]}";
  }
}

// The rule for a [visual] position or rotation that is NaN or infinite at a row the page draws
// (docs/cli.md, "What bad input gets"): as for a derived output, the item, its expression, t and
// the state are named, and nothing is drawn (never a null that the page would show as garbage).
void require_finite_scene(const symbolic::VisualScene& scene, const ReportInput& input,
                          const std::vector<double>& outputs, double t, const std::vector<double>& q,
                          const std::vector<double>& v) {
  for (const symbolic::VisualShape& shape : scene.shapes) {
    const int count = symbolic::visual_outputs(shape.kind);
    for (int k = 0; k < count; ++k) {
      const double x = outputs[static_cast<std::size_t>(shape.offset + k)];
      if (std::isfinite(x)) continue;
      std::string state;
      for (std::size_t i = 0; i < q.size() && i < input.coordinates.size(); ++i)
        state += fmt::format("{}{} = {:.6g}", i == 0 ? "" : ", ", input.coordinates[i], q[i]);
      for (std::size_t i = 0; i < v.size() && i < input.coordinates.size(); ++i)
        state += fmt::format(", {}' = {:.6g}", input.coordinates[i], v[i]);
      std::string expression = static_cast<std::size_t>(k) < shape.expressions.size()
                                   ? shape.expressions[static_cast<std::size_t>(k)]
                                   : std::string("?");
      if (expression.size() > 200) expression = expression.substr(0, 200) + "...";
      const bool segment = shape.kind == symbolic::VisualKind::segment;
      const char* part = segment ? (k < 3 ? "'from'" : "'to'") : k < 3 ? "position" : "rotation";
      throw InputError(fmt::format(
          "{}{}[visual] {} '{}' of '{}': its {} component {} ({}) is {} at t = {:.6g}, where {}: the scene cannot draw "
          "it, so the report is not written; write the [visual] expression in a form defined along the motion, or "
          "end the run before (--t-end, a stop event)",
          shape.where, shape.where.empty() ? "" : ": ",
          shape.kind == symbolic::VisualKind::sphere ? "point" : symbolic::visual_kind_name(shape.kind), shape.name, input.model,
          part, segment || k < 3 ? k % 3 + 1 : k - 2, expression,
          std::isnan(x) ? std::string("NaN") : fmt::format("{}", x), t, state));
    }
  }
}

// The angle a turntable has turned through at each of `times` (ascending): theta(t), the integral
// of its rate from 0 to t, by Gauss-Legendre's three points on pieces of at most 1/4096 of the
// largest |t| (exact to round-off for a rate polynomial in t of degree up to 5, a constant
// Omega giving Omega t). Throws InputError naming the plane when the rate is not finite.
std::vector<double> turned_angles(const symbolic::VisualShape& plane, const std::vector<double>& parameters,
                                  const std::vector<double>& times, const std::string& model) {
  Field rate(plane.field, parameters);
  const auto at = [&](double t) {
    const double w = rate(t, 0.0);
    if (!std::isfinite(w))
      throw InputError(fmt::format("{}{}contact '{}' of '{}': its ground's angular_velocity is {} at t = {:.6g}: the "
                                   "table's angle in the scene is the integral of the rate from t = 0, so the report "
                                   "is not written; write a rate defined from t = 0 to the end of the run",
                                   plane.where, plane.where.empty() ? "" : ": ", plane.name, model,
                                   std::isnan(w) ? std::string("NaN") : fmt::format("{}", w), t));
    return w;
  };
  double longest = 0.0;
  for (const double t : times) longest = std::max(longest, std::abs(t));
  const double piece = longest / 4096;
  const double node = std::sqrt(0.6);
  std::vector<double> out;
  double angle = 0.0, from = 0.0;
  for (const double to : times) {
    const int pieces = piece > 0.0 ? std::max(1, static_cast<int>(std::ceil(std::abs(to - from) / piece))) : 1;
    const double h = (to - from) / pieces;
    for (int k = 0; k < pieces; ++k) {
      const double mid = from + (k + 0.5) * h;
      angle += h / 2 * (5.0 / 9 * at(mid - node * h / 2) + 8.0 / 9 * at(mid) + 5.0 / 9 * at(mid + node * h / 2));
    }
    out.push_back(angle);
    from = to;
  }
  return out;
}

// A turning plane's axes at `angle` about its normal: R Rz(angle), R row-major (columns t1, t2, n).
void turn_plane(double* R, double angle) {
  const double c = std::cos(angle), s = std::sin(angle);
  for (int i = 0; i < 3; ++i) {
    const double t1 = R[3 * i], t2 = R[3 * i + 1];
    R[3 * i] = c * t1 + s * t2;
    R[3 * i + 1] = -s * t1 + c * t2;
  }
}

// The scene of a model with shapes: each shape's kind, size and place at every frame drawn (a
// body along its principal axes, a turntable turned through its angle).
void append_scene_shapes(std::string& data, const ReportInput& input, const FrameColumns& column,
                         std::vector<std::string>& notes) {
  const CsvTable& table = column.table;
  const std::vector<std::size_t>& frames = column.frames;
  const symbolic::VisualScene& scene = *input.scene;
  const std::vector<SceneSize> sizes = calc_scene_sizes(scene, input.parameters, input.model);
  const std::vector<double> parameter_values = parameter_values_for(scene, input.parameters, input.model);
  const Tape bound = scene.tape.bind(parameter_values.data(), parameter_values.size());
  const int n = bound.coordinates();
  if (n != static_cast<int>(input.coordinates.size()))
    throw InputError(fmt::format("the scene of '{}' has {} coordinates, the run {}", input.model, n,
                                 input.coordinates.size()));
  std::vector<int> qc, vc;
  for (const std::string& q : input.coordinates) {
    qc.push_back(table.column(q));
    vc.push_back(table.column(q + "'"));
  }
  std::vector<double> q(static_cast<std::size_t>(n)), v(static_cast<std::size_t>(n));
  std::vector<double> registers(static_cast<std::size_t>(bound.registers()));
  std::vector<double> outputs(static_cast<std::size_t>(bound.outputs()));
  std::vector<double> values;
  values.reserve(frames.size() * outputs.size());
  const int tc = table.column("t");
  std::vector<double> times;
  for (const std::size_t f : frames) times.push_back(table.rows[f][static_cast<std::size_t>(tc)]);
  std::vector<std::vector<double>> angles(scene.shapes.size());  // per turning plane, per frame
  for (std::size_t s = 0; s < scene.shapes.size(); ++s)
    if (scene.shapes[s].kind == symbolic::VisualKind::plane && scene.shapes[s].field.outputs() > 0)
      angles[s] = turned_angles(scene.shapes[s], parameter_values, times, input.model);
  for (std::size_t frame = 0; frame < frames.size(); ++frame) {
    const std::vector<double>& row = table.rows[frames[frame]];
    for (int i = 0; i < n; ++i) {
      q[static_cast<std::size_t>(i)] = row[static_cast<std::size_t>(qc[static_cast<std::size_t>(i)])];
      v[static_cast<std::size_t>(i)] = row[static_cast<std::size_t>(vc[static_cast<std::size_t>(i)])];
    }
    bound.run(row[static_cast<std::size_t>(tc)], q.data(), v.data(), registers.data(), outputs.data());
    require_finite_scene(scene, input, outputs, row[static_cast<std::size_t>(tc)], q, v);
    // A body is drawn along its principal axes: R E, E's columns the axes in the frame's components.
    for (std::size_t s = 0; s < scene.shapes.size(); ++s) {
      if (scene.shapes[s].kind != symbolic::VisualKind::body) continue;
      double* R = outputs.data() + scene.shapes[s].offset + 3;
      const std::array<double, 9>& E = sizes[s].axes;
      std::array<double, 9> RE{};
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
          for (int k = 0; k < 3; ++k) RE[static_cast<std::size_t>(3 * i + j)] += R[3 * i + k] * E[static_cast<std::size_t>(3 * k + j)];
      std::copy(RE.begin(), RE.end(), R);
    }
    for (std::size_t s = 0; s < scene.shapes.size(); ++s)
      if (!angles[s].empty()) turn_plane(outputs.data() + scene.shapes[s].offset + 3, angles[s][frame]);
    values.insert(values.end(), outputs.begin(), outputs.end());
  }
  const std::vector<SceneMesh> meshes =
      calc_scene_meshes(scene, input.parameters, values, outputs.size(), input.model, &notes);
  data += fmt::format("\"planar\":{},\"ground\":{},\"stride\":{},\"shapes\":[", scene.planar, scene.ground,
                      outputs.size());
  for (std::size_t s = 0; s < scene.shapes.size(); ++s) {
    const symbolic::VisualShape& shape = scene.shapes[s];
    data += fmt::format("{}{{\"kind\":\"{}\",\"name\":", s > 0 ? "," : "", symbolic::visual_kind_name(shape.kind));
    append_string(data, shape.name);
    data += fmt::format(",\"offset\":{},\"axis\":{},\"size\":", shape.offset, shape.axis);
    append_numbers(data, {sizes[s].size[0], sizes[s].size[1], sizes[s].size[2]});
    if (!shape.body.empty()) {
      data += ",\"body\":";
      append_string(data, shape.body);
    }
    if (shape.kind == symbolic::VisualKind::plane && shape.field.outputs() > 0) data += ",\"turns\":true";
    if (!meshes[s].vertices.empty()) {
      data += ",\"mesh\":{\"v\":";
      append_numbers(data, meshes[s].vertices);
      data += fmt::format(",\"i\":[{}],\"rows\":{}}}", fmt::join(meshes[s].triangles, ","), meshes[s].rows);
    }
    data += '}';
  }
  data += "],\"values\":";
  append_numbers(data, values);
}

// The scene of a model with nothing to draw: its path as one moving point. Returns the page's
// note that says so.
std::string append_scene_path(std::string& data, const ReportInput& input, const FrameColumns& column) {
  const std::vector<std::size_t>& frames = column.frames;
  std::pair<std::string, std::string> path;
  if (input.path) path = *input.path;
  else if (input.coordinates.size() >= 2) path = {input.coordinates[0], input.coordinates[1]};
  else if (!input.coordinates.empty()) path = {"t", input.coordinates[0]};
  const std::string note =
      fmt::format("The model '{}' names nothing to draw (no [visual] table, no bodies): the scene shows the path "
                  "({}, {}). docs/model-format.md says how to add a [visual] table.",
                  input.model, path.first, path.second);
  const std::vector<double> x = column(path.first), y = column(path.second);
  std::vector<double> values;
  values.reserve(3 * frames.size());
  double size = 0.0;
  for (std::size_t f = 0; f < frames.size(); ++f) {
    values.insert(values.end(), {x[f], y[f], 0.0});
    if (std::isfinite(x[f]) && std::isfinite(y[f])) size = std::max({size, std::abs(x[f] - x[0]), std::abs(y[f] - y[0])});
  }
  data += "\"planar\":true,\"ground\":false,\"stride\":3,\"shapes\":[{\"kind\":\"sphere\",\"name\":";
  append_string(data, path.first + ", " + path.second);
  data += ",\"offset\":0,\"axis\":0,\"size\":";
  const double r = size > 0.0 ? 0.02 * size : 0.05;
  append_numbers(data, {r, r, r});
  data += "}],\"values\":";
  append_numbers(data, values);
  return note;
}

// The page: the embedded styles and scripts around the data.
std::string make_report_page(const std::string& title, const std::vector<std::string>& provenance,
                             const std::string& data) {
  std::string html;
  html.reserve(data.size() + resources::three_js.size() + resources::katex_js.size() + 600000);
  html += "<!DOCTYPE html>\n";
  if (!provenance.empty()) {
    // The run's provenance (io/provenance.hpp) as the CSV has it, one "# key: value" per line; an
    // HTML comment may not hold "--", which a negative value after '=' could bring.
    html += "<!--\n";
    for (const std::string& line : provenance) {
      std::string text = "#" + line;
      for (std::size_t at = text.find("--"); at != std::string::npos; at = text.find("--", at)) text.replace(at, 2, "- -");
      html += text + "\n";
    }
    html += "-->\n";
  }
  html += "<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<title>";
  for (const char c : title) {
    if (c == '<') html += "&lt;";
    else if (c == '&') html += "&amp;";
    else html += c;
  }
  html += "</title>\n<!-- Written by nhdyn (io/report.hpp). Embedded: three.js (libjs-three, MIT licence), KaTeX and its "
          "fonts (libjs-katex, MIT licence and SIL Open Font Licence). -->\n<style>\n";
  html += katex_css_with_fonts();
  html += "\n</style>\n<style>\n";
  html += resources::report_css;
  html += "</style>\n</head>\n<body>\n<script>\n";
  html += resources::three_js;
  html += "\n</script>\n<script>\n";
  html += resources::katex_js;
  html += "\n</script>\n<script>\nconst NHDYN = ";
  html += data;
  html += ";\n</script>\n<script>\n";
  html += resources::report_js;
  html += "</script>\n</body>\n</html>\n";
  return html;
}

}  // namespace

std::string make_report_html(const ReportInput& input, const ReportOptions& options, std::string* notice) {
  const CsvTable& table = input.table;
  if (table.rows.empty()) throw InputError(fmt::format("the run of '{}' has no row to report", input.model));
  check_report_columns(table.header, input.columns, "the table", input.model);
  const std::vector<std::size_t> frames = report_frames(table.rows.size(), options.max_frames);
  const FrameColumns column{table, frames};
  const std::vector<PlotGroup> groups = report_plot_groups(input, column);

  std::string data = "{\"title\":";
  append_string(data, input.title);
  data += ",\"summary\":[";
  for (std::size_t i = 0; i < input.summary.size(); ++i) {
    data += i > 0 ? ",[" : "[";
    append_string(data, input.summary[i].first);
    data += ',';
    append_string(data, input.summary[i].second);
    data += ']';
  }
  data += "],\"t\":";
  append_numbers(data, column("t"));
  data += ",\"plots\":[";
  append_plots(data, table, groups, column);
  data += ']';

  // The scene: the model's shapes, or the path as one moving point.
  std::string note;
  const bool has_shapes = input.scene != nullptr && !input.scene->shapes.empty();
  data += ",\"scene\":{";
  if (has_shapes) {
    std::vector<std::string> notes;
    append_scene_shapes(data, input, column, notes);
    note = fmt::format("{}", fmt::join(notes, " "));
  } else
    note = append_scene_path(data, input, column);
  data += '}';
  if (frames.size() < table.rows.size())
    note += fmt::format("{}The page shows {} of the run's {} rows (one row in {}, and the last); the CSV has them all.",
                        note.empty() ? "" : " ", frames.size(), table.rows.size(), frames.size() > 1 ? frames[1] : 1);
  data += ",\"note\":";
  append_string(data, note);
  if (notice != nullptr) *notice = note;
  data += ",\"equations\":";
  std::string equations_note = input.equations_note;
  if (input.equations_latex.size() > options.max_equations) {
    append_string(data, "");
    equations_note = fmt::format("The equations of '{}' take {} kB of LaTeX, too many to lay out here; "
                                 "`nhdyn equations MODEL --format latex` prints them.",
                                 input.model, input.equations_latex.size() / 1000);
  } else {
    append_string(data, input.equations_latex);
  }
  data += ",\"equations_note\":";
  append_string(data, equations_note);
  data += '}';

  return make_report_page(input.title, input.table.comments, data);
}

std::string write_report(const ReportInput& input, const std::filesystem::path& path, const ReportOptions& options) {
  std::string notice;
  const std::string html = make_report_html(input, options, &notice);
  AtomicFile file(path);
  file.write(html);
  file.commit();
  return notice;
}

std::string write_model_report(const Model& model, const symbolic::ModelDescription* description, const CsvTable& table, const std::string& title,
                        const std::vector<std::pair<std::string, std::string>>& extra,
                        const std::filesystem::path& path, const ReportOptions& options) {
  check_report_options(options);
  ReportInput input;
  input.title = title;
  input.model = model.name;
  input.coordinates = model.coordinates;
  input.columns = make_result_columns(model);
  if (!options.controls.empty()) {
    input.columns.all.insert(input.columns.all.end(), options.controls.begin(), options.controls.end());
    input.columns.actuators.insert(input.columns.actuators.end(), options.controls.begin(), options.controls.end());
    input.actuators_title = "controls u (the optimum's)";
  }
  check_report_columns(table.header, input.columns, "the results", model.name);
  input.table = table;
  if (description != nullptr) {
    const symbolic::Spec& spec = description->spec();
    const symbolic::VisualScene& scene = description->scene();
    input.angles = scene.angles;
    input.scene = &scene;
    input.parameters = model.parameters;
    input.path = spec.path;
    const symbolic::Derivation& derivation = description->derivation();
    // Terms whose plain printing already exceeds the limit are left out before they are printed
    // and simplified for nothing: the page would not show them.
    std::ostringstream raw;
    raw << derivation.A << derivation.Q << derivation.G << derivation.b << derivation.b0;
    if (raw.str().size() > options.max_equations)
      input.equations_note = fmt::format("The equations of '{}' are too long to lay out here (their terms alone take "
                                         "{} kB); `nhdyn equations MODEL --format latex` prints them.",
                                         model.name, raw.str().size() / 1000);
    else
      input.equations_latex = symbolic::format_equations(spec, derivation, symbolic::EquationFormat::latex);
  } else {
    input.equations_note = fmt::format("'{}' is a built-in model written in C++: it has no symbolic equations to "
                                       "show (its model file in examples/ has).",
                                       model.name);
    if (model.path)
      input.path = std::make_pair(model.coordinates[static_cast<std::size_t>(model.path->x)],
                                  model.coordinates[static_cast<std::size_t>(model.path->y)]);
  }
  input.summary = extra;
  const std::vector<double>& first = table.rows.empty() ? std::vector<double>{} : table.rows.front();
  if (!table.rows.empty()) {
    input.summary.emplace_back("time", fmt::format("{:g} .. {:g} s, {} rows", first[0], table.rows.back()[0],
                                                   table.rows.size()));
    const char* levels[] = {"residual_pos_", "residual_vel_", "residual_acc_"};
    const char* labels[] = {"max |position residual|", "max |velocity residual|", "max |acceleration residual|"};
    for (int level = 0; level < 3; ++level) {
      double largest = -1.0;
      for (std::size_t c = 0; c < table.header.size(); ++c)
        if (table.header[c].starts_with(levels[level]))
          for (const std::vector<double>& row : table.rows) largest = std::max(largest, std::abs(row[c]));
      if (largest >= 0.0) input.summary.emplace_back(labels[level], fmt::format("{:.3g}", largest));
    }
    const int e = input.columns.energy.empty() ? -1 : table.column(input.columns.energy);
    const int balance = input.columns.energy_balance.empty() ? -1 : table.column("balance_error");
    if (e >= 0 && balance >= 0) {
      // docs/derivations/energy-balance.md: the balance is the error, the change of E is physics.
      double largest = 0.0;
      for (const std::vector<double>& row : table.rows)
        largest = std::max(largest, std::abs(row[static_cast<std::size_t>(balance)]));
      input.summary.emplace_back("energy balance error", fmt::format("{:.3g}", largest));
      const auto E = static_cast<std::size_t>(e);
      input.summary.emplace_back("energy change", fmt::format("{:.6g} (E0 = {:.10g})", table.rows.back()[E] - first[E], first[E]));
      const int w = table.column("work");
      if (w >= 0) input.summary.emplace_back("work", fmt::format("{:.6g}", table.rows.back()[static_cast<std::size_t>(w)]));
    } else if (e >= 0) {
      double drift = 0.0;
      for (const std::vector<double>& row : table.rows)
        drift = std::max(drift, std::abs(row[static_cast<std::size_t>(e)] - first[static_cast<std::size_t>(e)]));
      input.summary.emplace_back("energy drift", fmt::format("{:.3g} (E0 = {:.10g})", drift,
                                                             first[static_cast<std::size_t>(e)]));
    }
  }
  return write_report(input, path, options);
}

}  // namespace nhdyn
