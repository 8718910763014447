#include "nhdyn/formulation/sanh.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "nhdyn/formulation/complement.hpp"
#include "nhdyn/formulation/detail/row_scaling.hpp"
#include "nhdyn/formulation/detail/small_dense.hpp"
#include "nhdyn/model/terms.hpp"

namespace nhdyn {

bool lu_is_singular(const Eigen::PartialPivLU<Matrix>& lu) {
  const Matrix& LU = lu.matrixLU();
  double largest = 0.0;
  double smallest = std::numeric_limits<double>::infinity();
  for (Eigen::Index i = 0; i < LU.rows(); ++i) {
    const double d = std::abs(LU(i, i));
    largest = std::max(largest, d);
    smallest = std::min(smallest, d);
  }
  // Only an exactly or numerically zero pivot: rows of [D A; b] carry different units, so a
  // tighter test would refuse well-posed but badly scaled systems.
  return !(smallest > largest * std::numeric_limits<double>::epsilon() * static_cast<double>(LU.rows()));
}

bool factor_equilibrated(Matrix& M, Vector& rhs, Eigen::PartialPivLU<Matrix>& lu) {
  // Rows in different units (the rows D A scale with the masses, the rows b do not) are scaled
  // exactly first (row_scaling.hpp), so that the pivots' test is about the matrix and not its units.
  scale_rows_by_powers_of_two(
      static_cast<int>(M.rows()), [&](int i) { return M.row(i).cwiseAbs().maxCoeff(); },
      [&](int i, int exponent) {
        M.row(i) *= std::ldexp(1.0, -exponent);
        rhs(i) = std::ldexp(rhs(i), -exponent);
      });
  lu.compute(M);
  return !lu_is_singular(lu);
}

Status compute_sanh_acceleration(const Model& model, Data& data, Complement complement) {
  const int k = model.k();
  const int s = model.s();
  const Status status = compute_complement(model, data, complement);
  if (status != Status::ok) return status;
  if (const small::Kernels* kernels = data.small_kernels ? small::find_kernels(model.n(), s) : nullptr) {
    if (!kernels->solve_stacked(data.A.data(), data.Q.data(), data.G.data(), data.b.data(), data.b0.data(),
                                data.D.data(), data.h.data(), data.qdd.data(), data.R.data()))
      return record_failure(data, Status::singular_system, "stacked matrix [D A; b]");
    return Status::ok;
  }
  data.h = data.Q + data.G;
  data.M.topRows(k).noalias() = data.D * data.A;
  data.M.bottomRows(s) = data.b;
  data.rhs.head(k).noalias() = data.D * data.h;
  data.rhs.tail(s) = -data.b0;
  if (!factor_equilibrated(data.M, data.rhs, data.lu_n))
    return record_failure(data, Status::singular_system, "stacked matrix [D A; b]");
  data.qdd = data.lu_n.solve(data.rhs);
  data.R.noalias() = data.A * data.qdd;
  data.R -= data.h;
  return Status::ok;
}

}  // namespace nhdyn
