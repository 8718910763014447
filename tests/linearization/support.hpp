// Shared by the linearization tests: the example model files compiled with parameters set, and
// the benchmark bicycle's matrices (Meijaard et al. 2007) for the independent 4 x 4 state matrix.
#pragma once

#include <Eigen/Eigenvalues>
#include <complex>
#include <string>
#include <utility>
#include <vector>

#include "nhdyn/analysis/linearization.hpp"
#include "nhdyn/frontend/model_file.hpp"
#include "nhdyn/symbolic/compile.hpp"

namespace nhdyn::testing {

inline std::string example_path(const std::string& file) {
  return std::string(NHDYN_SOURCE_DIR) + "/examples/" + file;
}

inline Model compile_example(const std::string& file, const std::vector<std::pair<std::string, double>>& sets = {}) {
  symbolic::Spec spec = load_model_file(example_path(file));
  for (const auto& [name, value] : sets) spec.set_parameter(name, value);
  return symbolic::compile_model(spec);
}

struct BicycleMatrices {
  Eigen::Matrix2d M, C1, K0, K2;
  double g = 9.81;
  BicycleMatrices() {
    M << 80.81722, 2.31941332208709, 2.31941332208709, 0.29784188199686;
    C1 << 0, 33.86641391492494, -0.85035641456978, 1.68540397397560;
    K0 << -80.95, -2.59951685249872, -2.59951685249872, -0.80329488458618;
    K2 << 0, 76.59734589573222, 0, 2.65431523794604;
  }
  // [[0, I], [-M^-1 (g K0 + v^2 K2), -v M^-1 C1]]
  Eigen::Matrix4d state_matrix(double v) const {
    Eigen::Matrix4d S = Eigen::Matrix4d::Zero();
    S.topRightCorner<2, 2>() = Eigen::Matrix2d::Identity();
    const Eigen::Matrix2d Minv = M.inverse();
    S.bottomLeftCorner<2, 2>() = -Minv * (g * K0 + v * v * K2);
    S.bottomRightCorner<2, 2>() = -v * Minv * C1;
    return S;
  }
  std::vector<std::complex<double>> eigenvalues(double v) const {
    Eigen::EigenSolver<Eigen::Matrix4d> es(state_matrix(v), false);
    std::vector<std::complex<double>> e;
    for (int i = 0; i < 4; ++i) e.push_back(es.eigenvalues()(i));
    sort_eigenvalues(e);
    return e;
  }
};

// The published weave and capsize speeds of the benchmark bicycle [m/s].
constexpr double kWeaveSpeed = 4.29238253634111;
constexpr double kCapsizeSpeed = 6.02426201538837;

}  // namespace nhdyn::testing
