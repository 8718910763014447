#include "nhdyn/formulation/sparse_lagrange.hpp"

#include "nhdyn/model/terms.hpp"

namespace nhdyn {

void fill_sparse_kkt(Data& data, const char* keep) {
  const int n = static_cast<int>(data.A_sparse.rows());
  const double* a_values = data.A_sparse.valuePtr();
  const double* b_values = data.b_sparse.valuePtr();
  double* k_values = data.K_sparse.valuePtr();
  const int* k_rows = data.K_sparse.innerIndexPtr();
  const int* k_outer = data.K_sparse.outerIndexPtr();
  for (int j = 0; j < static_cast<int>(data.K_sparse.cols()); ++j)
    for (int m = k_outer[j]; m < k_outer[j + 1]; ++m) {
      const int source = data.K_source[static_cast<std::size_t>(m)];
      if (source == kKktDiagonal) {
        k_values[m] = keep == nullptr || keep[j - n] ? 0.0 : 1.0;
      } else if (source >= 0) {
        k_values[m] = a_values[source];
      } else {
        // An entry of b (row >= n, column j < n) or of b^T (column j >= n): its constraint.
        const int constraint = j >= n ? j - n : k_rows[m] - n;
        k_values[m] = keep == nullptr || keep[constraint] ? b_values[~source] : 0.0;
      }
    }
}

Status compute_sparse_lagrange_acceleration(const Model& model, Data& data) {
  const int n = model.n(), s = model.s();
  fill_sparse_kkt(data, nullptr);
  data.kkt_rhs.head(n) = data.Q + data.G;
  data.kkt_rhs.tail(s) = -data.b0;
  if (!data.lu_kkt_sparse.factorize(data.K_sparse))
    return record_failure(data, Status::singular_system, "KKT matrix [A b^T; b 0]");
  data.kkt_sol = data.kkt_rhs;
  data.lu_kkt_sparse.solve_in_place(data.kkt_sol);
  data.qdd = data.kkt_sol.head(n);
  data.lambda = -data.kkt_sol.tail(s);
  data.R.noalias() = data.b_sparse.transpose() * data.lambda;
  data.has_multipliers = true;
  return Status::ok;
}

}  // namespace nhdyn
