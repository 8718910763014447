#include "nhdyn/formulation/sparse_lagrange.hpp"

namespace nhdyn {

Status compute_sparse_lagrange_acceleration(const Model& model, SparseData& data) {
  const int n = model.n(), s = model.s();
  const double* a_values = data.A.valuePtr();
  const double* b_values = data.b.valuePtr();
  double* k_values = data.K.valuePtr();
  for (std::size_t m = 0; m < data.K_source.size(); ++m) {
    const int source = data.K_source[m];
    k_values[m] = source >= 0 ? a_values[source] : b_values[~source];
  }
  data.kkt_rhs.head(n) = data.Q + data.G;
  data.kkt_rhs.tail(s) = -data.b0;
  data.lu_kkt->factorize(data.K);
  if (data.lu_kkt->info() != Eigen::Success) {
    data.failed.assign("KKT matrix [A b^T; b 0]");
    return Status::singular_system;
  }
  data.kkt_sol = data.lu_kkt->solve(data.kkt_rhs);
  data.qdd = data.kkt_sol.head(n);
  data.lambda = -data.kkt_sol.tail(s);
  data.R.noalias() = data.b.transpose() * data.lambda;
  return Status::ok;
}

}  // namespace nhdyn
