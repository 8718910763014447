#include "nhdyn/formulation/lagrange.hpp"

#include "nhdyn/formulation/sanh.hpp"
#include "nhdyn/model/terms.hpp"

namespace nhdyn {

Status compute_lagrange_acceleration(const Model& model, Data& data) {
  const int n = model.n();
  const int s = model.s();
  data.K.topLeftCorner(n, n) = data.A;
  data.K.topRightCorner(n, s) = data.b.transpose();
  data.K.bottomLeftCorner(s, n) = data.b;
  data.K.bottomRightCorner(s, s).setZero();
  data.kkt_rhs.head(n) = data.Q + data.G;
  data.kkt_rhs.tail(s) = -data.b0;
  data.lu_kkt.compute(data.K);
  if (lu_is_singular(data.lu_kkt)) return record_failure(data, Status::singular_system, "KKT matrix [A b^T; b 0]");
  data.kkt_sol = data.lu_kkt.solve(data.kkt_rhs);
  data.qdd = data.kkt_sol.head(n);
  data.lambda = -data.kkt_sol.tail(s);
  data.R.noalias() = data.b.transpose() * data.lambda;
  data.has_multipliers = true;
  return Status::ok;
}

}  // namespace nhdyn
