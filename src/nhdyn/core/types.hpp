// Eigen aliases shared by every module. The numeric core works on dynamic-size, column-major
// double matrices; functions take Eigen::Ref<const ...> at their boundaries so that callers may
// pass blocks and maps without copies.
#pragma once

#include <Eigen/Dense>

namespace nhdyn {

using Vector = Eigen::VectorXd;
using Matrix = Eigen::MatrixXd;
using VectorRef = Eigen::Ref<Vector>;
using ConstVectorRef = Eigen::Ref<const Vector>;
using MatrixRef = Eigen::Ref<Matrix>;
using ConstMatrixRef = Eigen::Ref<const Matrix>;

// The largest |v_i|; 0 for an empty vector (Eigen's maxCoeff asserts on one).
inline double max_abs(const Vector& v) { return v.size() > 0 ? v.cwiseAbs().maxCoeff() : 0.0; }

}  // namespace nhdyn
