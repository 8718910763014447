// Shared by the gallery tests (docs/gallery/): load an example model file, optionally with some
// parameters changed, run it through the library's simulation driver, and keep every output row.
#pragma once

#include <gtest/gtest.h>

#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "nhdyn/analysis/simulation.hpp"
#include "nhdyn/frontend/model_file.hpp"
#include "nhdyn/symbolic/compile.hpp"

namespace nhdyn::gallery {

// One output row of a simulation.
struct Row {
  double t = 0.0;
  Vector q, v, qdd, R;
  double energy = 0.0;
};

inline std::string example_path(const std::string& file) {
  return std::string(NHDYN_SOURCE_DIR) + "/examples/" + file;
}

// The model of examples/<file>, with the parameters in `set` changed (like `--set name=value`).
inline Model load_example(const std::string& file, const std::vector<std::pair<std::string, double>>& set = {}) {
  symbolic::Spec spec = load_model_file(example_path(file));
  for (const auto& [name, value] : set) spec.set_parameter(name, value);
  return symbolic::compile_model(spec);
}

// The model of examples/<file> with pieces of its text replaced, in order: the deliberately wrong
// models that show a test can fail (each `from` must occur in the text exactly once).
inline Model load_altered_example(const std::string& file,
                                  const std::vector<std::pair<std::string, std::string>>& replacements) {
  std::ifstream in(example_path(file));
  std::stringstream buffer;
  buffer << in.rdbuf();
  std::string text = buffer.str();
  for (const auto& [from, to] : replacements) {
    const std::size_t at = text.find(from);
    if (at == std::string::npos || text.find(from, at + 1) != std::string::npos)
      throw std::logic_error("'" + from + "' is not in " + file + " exactly once");
    text.replace(at, from.size(), to);
  }
  return symbolic::compile_model(load_model_string(text, file + " (altered)"));
}

inline Model load_altered_example(const std::string& file, const std::string& from, const std::string& to) {
  return load_altered_example(file, {{from, to}});
}

// Options for a tight run: dopri5 at rtol 1e-10, atol 1e-12 (the files' own defaults).
inline SimulationOptions tight_options(double t_end, double output_step, Formulation method = Formulation::sanh) {
  SimulationOptions o;
  o.t_end = t_end;
  o.output_step = output_step;
  o.formulation = {method, Complement::qr};
  o.integrator.kind = IntegratorKind::dopri5;
  o.integrator.rtol = 1e-10;
  o.integrator.atol = 1e-12;
  return o;
}

inline std::vector<Row> run_rows(const Model& model, const SimulationOptions& options,
                                 SimulationSummary* summary = nullptr) {
  std::vector<Row> rows;
  const SimulationSummary s = simulate(model, options, [&](const Data& d) {
    rows.push_back({d.t, d.q, d.v, d.qdd, d.R, d.energy});
  });
  EXPECT_EQ(s.status, Status::ok) << model.name << ": " << s.message;
  if (summary) *summary = s;
  return rows;
}

// The value of a named parameter of a compiled model (throws if it has none: a test bug).
inline double parameter(const Model& model, const std::string& name) {
  for (const Parameter& p : model.parameters)
    if (p.name == name) return p.value;
  throw std::out_of_range("no parameter " + name + " in model " + model.name);
}

// The times where a function f of the rows changes sign, each refined inside its output interval
// on the cubic Hermite interpolant of f and its time derivative df (error O(h^4) in the output
// step h), by bisection. Row 0 is skipped when f vanishes there (a start at rest).
template <class F, class DF>
std::vector<double> sign_changes(const std::vector<Row>& rows, F f, DF df) {
  std::vector<double> times;
  for (std::size_t i = 0; i + 1 < rows.size(); ++i) {
    const double f0 = f(rows[i]), f1 = f(rows[i + 1]);
    if (!(f0 * f1 < 0.0)) continue;
    const double t0 = rows[i].t, h = rows[i + 1].t - t0;
    const double d0 = df(rows[i]) * h, d1 = df(rows[i + 1]) * h;
    const auto cubic = [&](double s) {
      const double s2 = s * s, s3 = s2 * s;
      return (2 * s3 - 3 * s2 + 1) * f0 + (s3 - 2 * s2 + s) * d0 + (-2 * s3 + 3 * s2) * f1 + (s3 - s2) * d1;
    };
    double lo = 0.0, hi = 1.0;
    for (int it = 0; it < 60; ++it) {
      const double mid = 0.5 * (lo + hi);
      if ((cubic(mid) < 0.0) == (f0 < 0.0)) lo = mid; else hi = mid;
    }
    times.push_back(t0 + 0.5 * (lo + hi) * h);
  }
  return times;
}

}  // namespace nhdyn::gallery
