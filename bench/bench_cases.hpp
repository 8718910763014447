// The models and the fixed states that every benchmark in bench/ uses, so that the cost of
// nhdyn's kernels and of the hand-written references (reference_bench.cpp) is measured on exactly
// the same numbers. Parameters and states are those of the reference values printed in
// docs/derivations/sled.md section 10(f) and docs/derivations/appell.md section 6(c); both states
// lie on the constraint. Results of the benchmarks: docs/performance.md.
#pragma once

#include <array>
#include <cmath>
#include <string>
#include <vector>

#include "nhdyn/model/appell.hpp"
#include "nhdyn/model/model.hpp"
#include "nhdyn/model/sled.hpp"

namespace nhdyn::bench {

enum class ModelId { sled, sled_paper, appell };

inline const std::vector<ModelId>& all_models() {
  static const std::vector<ModelId> models{ModelId::sled, ModelId::sled_paper, ModelId::appell};
  return models;
}

inline std::string model_name(ModelId id) {
  switch (id) {
    case ModelId::sled: return "sled";
    case ModelId::sled_paper: return "sled-paper";
    case ModelId::appell: return "appell";
  }
  return "?";
}

// docs/derivations/sled.md section 10: m = 2.3, a = 0.4, rho = 0.7, alpha = 0.35, g = 9.81.
inline SledParameters sled_parameters() {
  SledParameters p;
  p.m = 2.3;
  p.a = 0.4;
  p.rho = 0.7;
  p.alpha = 0.35;
  p.g = 9.81;
  return p;
}

// docs/derivations/appell.md section 6: m = 1.7, g = 9.81, a = 0.6.
inline AppellParameters appell_parameters() {
  AppellParameters p;
  p.m = 1.7;
  p.g = 9.81;
  p.a = 0.6;
  return p;
}

inline Model make_bench_model(ModelId id) {
  switch (id) {
    case ModelId::sled: return make_sled_model(SledVariant::centre_of_mass, sled_parameters());
    case ModelId::sled_paper: return make_sled_model(SledVariant::paper, sled_parameters());
    case ModelId::appell: return make_appell_model(appell_parameters());
  }
  return {};
}

// A state (t = 0, q, q') on the model's constraint.
struct State {
  std::array<double, 3> q;
  std::array<double, 3> v;
};

inline State bench_state(ModelId id) {
  if (id == ModelId::appell) {
    // z' = a |(x', y')| = 0.6 * 1.3: descending branch.
    return {{0.3, -0.2, 0.1}, {1.2, -0.5, 0.78}};
  }
  // Moving along the blade at 1.1 m/s with heading 0.3 rad, turning at 2 rad/s.
  const double phi = 0.3;
  return {{0.0, 0.0, phi}, {1.1 * std::cos(phi), 1.1 * std::sin(phi), 2.0}};
}

// q'' at bench_state, as printed in the derivations (computed there independently, in Python).
inline std::array<double, 3> published_qdd(ModelId id) {
  switch (id) {
    case ModelId::sled: return {3.9484509889392334, 3.5242525440696584, -2.6074114247789315};
    case ModelId::sled_paper: return {3.9484509889392334, 3.5242525440696584, -1.7959183673469388};
    case ModelId::appell: return {3.9950226244343883, -1.6645927601809958, 2.5967647058823524};
  }
  return {};
}

}  // namespace nhdyn::bench
