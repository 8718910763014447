// The rattleback of examples/rattleback.toml as a hand-written right-hand side of the same
// equations nhdyn derives: the same six coordinates q = (x, y, z, psi, theta, phi) of the
// ellipsoid's centre O and its frame R = Rz(psi) Rx(theta) Ry(phi), the Do Sanh stacked system
// [D A; b] q'' = [D (Q + G); -b0] with A, b, b0, Q + G written by vector mechanics rather than
// derived, an analytic D, and a fixed-size 6 x 6 LU. It is the yardstick of `make bench-check`'s
// rattleback_rhs_* ratios (what nhdyn's generated terms and general solve cost against a right-hand
// side a person would write for these coordinates), and tests/multibody/rattleback_by_hand_test.cpp
// checks nhdyn's derived equations against it at random states.
//
// The mechanics (world axes unless said; e_x, e_y, e_z the world's axes):
//   angular velocity  w = W u, u = (psi', theta', phi'), W = [e_z, Rz e_x, Rz Rx e_y], and
//                     k = W' u = theta' (psi' e_z x W2) + phi' ((psi' e_z + theta' W2) x W3);
//   centre of mass    G = O + rho, rho = R (0, 0, -h): v_G = v_O + w x rho;
//   contact point     P = O + r, r = R p(n), n = R^T e_z (the upward normal in body axes),
//                     p(n) = -M n / sqrt(n.M n), M = diag(a^2, b^2, c^2) (the ellipsoid's lowest
//                     point); its rate r' = w x r + R p'(n) n', n' = n x w_b, w_b = R^T w,
//                     p'(n) n' = -M n' / s + M n (n.M n') / s^3;
//   rolling           v_O + w x r = 0 (three rows: the normal one is the height condition's rate),
//                     b = [1, -[r]x W], b0 = k x r + w x r';
//   D                 the rows of [([r]x W)^T, 1] (3 x 6), orthogonal to those of b;
//   inertia           A = m J^T J + [0 W]^T I_w [0 W], J = [1, -[rho]x W], I_w = R I R^T about G;
//   forces            Q + G = -m J^T (w x (w x rho) + k x rho) - [0 W]^T (I_w k + w x I_w w)
//                     + J^T (0, 0, -m g), so that A q'' = Q + G + R.
#pragma once

#include <Eigen/Dense>
#include <cmath>

namespace nhdyn::bench {

// The parameters of examples/rattleback.toml (inertia per unit mass about the centre of mass).
struct RattlebackParameters {
  double m = 1.0, a = 0.20, b = 0.03, c = 0.02, h = 0.01;
  double A = 2e-4, B = 16e-4, C = 17e-4, D = -0.2e-4, g = 9.81;
};

using Vector6 = Eigen::Matrix<double, 6, 1>;

// q'' and the reactions R = A q'' - Q - G at (q, q'); false where the stacked matrix is singular.
inline bool rattleback_stacked(const RattlebackParameters& p, const double* q, const double* v, Vector6& qdd,
                               Vector6& reaction) {
  using Eigen::Matrix3d;
  using Eigen::Vector3d;
  const double cps = std::cos(q[3]), sps = std::sin(q[3]), cth = std::cos(q[4]), sth = std::sin(q[4]);
  const double cph = std::cos(q[5]), sph = std::sin(q[5]);
  Matrix3d Rz, Rx, Ry;
  Rz << cps, -sps, 0, sps, cps, 0, 0, 0, 1;
  Rx << 1, 0, 0, 0, cth, -sth, 0, sth, cth;
  Ry << cph, 0, sph, 0, 1, 0, -sph, 0, cph;
  const Matrix3d R = Rz * Rx * Ry;
  Matrix3d W;
  W.col(0) = Vector3d::UnitZ();
  W.col(1) << cps, sps, 0;
  W.col(2) << -sps * cth, cps * cth, sth;
  const Vector3d u(v[3], v[4], v[5]);
  const Vector3d w = W * u;
  const Vector3d kappa =
      v[4] * (v[3] * Vector3d::UnitZ()).cross(W.col(1)) + v[5] * (v[3] * Vector3d::UnitZ() + v[4] * W.col(1)).cross(W.col(2));
  const auto skew = [](const Vector3d& x) {
    Matrix3d S;
    S << 0, -x(2), x(1), x(2), 0, -x(0), -x(1), x(0), 0;
    return S;
  };
  // The contact point.
  const Vector3d M(p.a * p.a, p.b * p.b, p.c * p.c);
  const Vector3d n = R.transpose() * Vector3d::UnitZ();
  const Vector3d Mn = M.cwiseProduct(n);
  const double s = std::sqrt(n.dot(Mn));
  const Vector3d r = R * (-Mn / s);
  const Vector3d nd = n.cross(R.transpose() * w);
  const Vector3d Mnd = M.cwiseProduct(nd);
  const Vector3d pd = -Mnd / s + Mn * (n.dot(Mnd) / (s * s * s));
  const Vector3d rd = w.cross(r) + R * pd;
  // Inertia and forces.
  const Vector3d rho = R * Vector3d(0, 0, -p.h);
  Matrix3d Ib;
  Ib << p.A, p.D, 0, p.D, p.B, 0, 0, 0, p.C;
  const Matrix3d Iw = p.m * R * Ib * R.transpose();
  Eigen::Matrix<double, 3, 6> J, Wx;
  J << Matrix3d::Identity(), -skew(rho) * W;
  Wx << Matrix3d::Zero(), W;
  Eigen::Matrix<double, 6, 6> A = p.m * J.transpose() * J + Wx.transpose() * Iw * Wx;
  const Vector6 h = -p.m * J.transpose() * (w.cross(w.cross(rho)) + kappa.cross(rho)) -
                    Wx.transpose() * (Iw * kappa + w.cross(Iw * w)) + J.transpose() * Vector3d(0, 0, -p.m * p.g);
  // The stacked system.
  const Matrix3d rW = skew(r) * W;
  Eigen::Matrix<double, 3, 6> b, D;
  b << Matrix3d::Identity(), -rW;
  D << rW.transpose(), Matrix3d::Identity();
  const Vector3d b0 = kappa.cross(r) + w.cross(rd);
  Eigen::Matrix<double, 6, 6> S;
  S << D * A, b;
  Vector6 rhs;
  rhs << D * h, -b0;
  const Eigen::PartialPivLU<Eigen::Matrix<double, 6, 6>> lu(S);
  if (!(std::abs(lu.matrixLU().diagonal().prod()) > 0.0)) return false;
  qdd = lu.solve(rhs);
  reaction = A * qdd - h;
  return true;
}

}  // namespace nhdyn::bench
