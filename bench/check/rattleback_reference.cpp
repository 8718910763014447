// The rattleback of examples/rattleback.toml written by hand: Kane and Levinson's body rolling on
// a horizontal plane (docs/derivations/rolling-bodies.md section 6.7), in a body-frame form of its
// own (unit quaternion and body angular velocity, the contact point in closed form), integrated by
// nhdyn's own dop853 at the example's tolerances, with a CSV row every 0.01 s (t, x, y, z of the
// ellipsoid's centre O, the quaternion, omega and its rate in body axes, the contact force in body
// axes, the energy). It is the yardstick of `make bench-check`'s rattleback ratio: the whole
// process `nhdyn simulate examples/rattleback.toml --t-end 50 --integrator dop853` is timed
// against this whole process, so the ratio says what nhdyn's generality (coordinates, constraints
// and the stacked solve, derived from the model file) costs against a right-hand side of the same
// mechanics written by hand. The integrator and its output are the same code, so they cancel.
//
//   rattleback_reference [-o FILE] [--t-end T]
//
// The equations (the reference's own state: q, the unit quaternion body -> world, scalar first;
// w, the angular velocity in body axes; x, y of the centre of mass G). n = R^T e_z is the upward
// vertical in body axes; the ellipsoid's contact point relative to its centre is
// p(n) = -M^-1 n / s with M^-1 = diag(a^2, b^2, c^2) and s = sqrt(n^T M^-1 n), and r = G -> contact
// = (0, 0, h) + p(n). Rolling gives v_G = -w x r; with n' = n x w and
// p'(n) n' = -M^-1 n' / s + M^-1 n (n^T M^-1 n') / s^3, Euler's equations about the contact point
//   (I + m (|r|^2 1 - r r^T)) w' = -w x I w - m r x (w x (w x r + p' n')) + m g r x n,
// q' = q (0, w) / 2, and the contact force (body axes) L = m a_G + m g n with
// a_G = -w' x r - w x (w x r + p' n'). The energy is w.I w / 2 + m |v_G|^2 / 2 - m g n.r.
//
// scripts/bench-check compares the two CSVs' rows at t = 10 (the height of O, the vertical angular
// velocity and the position of O) so that the yardstick cannot drift from the model.
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "nhdyn/integrators/ode.hpp"

namespace {

// examples/rattleback.toml: m = 1, a = 0.20, b = 0.03, c = 0.02, h = 0.01, A = 2e-4, B = 16e-4,
// C = 17e-4, D = -0.2e-4 (per unit mass), g = 9.81, tilt = 0.5 degree, spin = -5.
constexpr double m = 1.0, a2 = 0.20 * 0.20, b2 = 0.03 * 0.03, c2 = 0.02 * 0.02, h = 0.01, g = 9.81;
constexpr double IA = m * 2e-4, IB = m * 16e-4, IC = m * 17e-4, ID = m * -0.2e-4;
constexpr double tilt = 0.008726646259971648, spin = -5.0;

using V3 = std::array<double, 3>;

V3 cross(const V3& u, const V3& v) {
  return {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
}
double dot(const V3& u, const V3& v) { return u[0] * v[0] + u[1] * v[1] + u[2] * v[2]; }

// Everything a right-hand side or a row needs at one state.
struct Kinematics {
  V3 n, r, w, alpha, aG;
  double s;
};

// State: q0..q3, w1..w3, xG, yG.
Kinematics solve(const double* y) {
  const double q0 = y[0], q1 = y[1], q2 = y[2], q3 = y[3];
  const double nq2 = 1.0 / (q0 * q0 + q1 * q1 + q2 * q2 + q3 * q3);
  Kinematics k;
  k.n = {2 * (q1 * q3 - q0 * q2) * nq2, 2 * (q2 * q3 + q0 * q1) * nq2, 1 - 2 * (q1 * q1 + q2 * q2) * nq2};
  const V3& n = k.n;
  const V3 Mn{a2 * n[0], b2 * n[1], c2 * n[2]};
  k.s = std::sqrt(dot(n, Mn));
  const double s = k.s;
  k.r = {-Mn[0] / s, -Mn[1] / s, h - Mn[2] / s};
  const V3& r = k.r;
  k.w = {y[4], y[5], y[6]};
  const V3& w = k.w;
  const V3 nd = cross(n, w);
  const V3 Mnd{a2 * nd[0], b2 * nd[1], c2 * nd[2]};
  const double kk = dot(n, Mnd) / (s * s * s);
  const V3 dp{-Mnd[0] / s + Mn[0] * kk, -Mnd[1] / s + Mn[1] * kk, -Mnd[2] / s + Mn[2] * kk};
  const V3 wr = cross(w, r);
  const V3 u = cross(w, {wr[0] + dp[0], wr[1] + dp[1], wr[2] + dp[2]});
  const V3 Iw{IA * w[0] + ID * w[1], ID * w[0] + IB * w[1], IC * w[2]};
  const V3 gy = cross(w, Iw), ru = cross(r, u), rn = cross(r, n);
  V3 f;
  for (int i = 0; i < 3; ++i) f[i] = -gy[i] - m * ru[i] + m * g * rn[i];
  const double rr = dot(r, r);
  const double k11 = IA + m * (rr - r[0] * r[0]), k12 = ID - m * r[0] * r[1], k13 = -m * r[0] * r[2];
  const double k22 = IB + m * (rr - r[1] * r[1]), k23 = -m * r[1] * r[2], k33 = IC + m * (rr - r[2] * r[2]);
  const double c11 = k22 * k33 - k23 * k23, c12 = k13 * k23 - k12 * k33, c13 = k12 * k23 - k13 * k22;
  const double c22 = k11 * k33 - k13 * k13, c23 = k12 * k13 - k11 * k23, c33 = k11 * k22 - k12 * k12;
  const double det = k11 * c11 + k12 * c12 + k13 * c13;
  k.alpha = {(c11 * f[0] + c12 * f[1] + c13 * f[2]) / det, (c12 * f[0] + c22 * f[1] + c23 * f[2]) / det,
             (c13 * f[0] + c23 * f[1] + c33 * f[2]) / det};
  const V3 ar = cross(k.alpha, r);
  for (int i = 0; i < 3; ++i) k.aG[i] = -ar[i] - u[i];
  return k;
}

// The body -> world rotation of the quaternion (normalized).
std::array<V3, 3> rotation(const double* y) {
  const double nq = std::sqrt(y[0] * y[0] + y[1] * y[1] + y[2] * y[2] + y[3] * y[3]);
  const double w = y[0] / nq, x = y[1] / nq, yy = y[2] / nq, z = y[3] / nq;
  return {{{1 - 2 * (yy * yy + z * z), 2 * (x * yy - w * z), 2 * (x * z + w * yy)},
           {2 * (x * yy + w * z), 1 - 2 * (x * x + z * z), 2 * (yy * z - w * x)},
           {2 * (x * z - w * yy), 2 * (yy * z + w * x), 1 - 2 * (x * x + yy * yy)}}};
}

class Rattleback final : public nhdyn::OdeSystem {
 public:
  int size() const override { return 9; }
  nhdyn::Status rhs(double, const double* y, double* yd) override {
    const Kinematics k = solve(y);
    const double q0 = y[0], q1 = y[1], q2 = y[2], q3 = y[3], w1 = y[4], w2 = y[5], w3 = y[6];
    yd[0] = 0.5 * (-q1 * w1 - q2 * w2 - q3 * w3);
    yd[1] = 0.5 * (q0 * w1 + q2 * w3 - q3 * w2);
    yd[2] = 0.5 * (q0 * w2 + q3 * w1 - q1 * w3);
    yd[3] = 0.5 * (q0 * w3 + q1 * w2 - q2 * w1);
    yd[4] = k.alpha[0];
    yd[5] = k.alpha[1];
    yd[6] = k.alpha[2];
    // v_G = -w x r in body axes, turned into world axes.
    const V3 v = cross(k.r, k.w);
    const auto R = rotation(y);
    yd[7] = dot(R[0], v);
    yd[8] = dot(R[1], v);
    return nhdyn::Status::ok;
  }
};

struct Writer {
  std::FILE* file = nullptr;
  nhdyn::Status row(double t, const double* y) {
    const Kinematics k = solve(y);
    const auto R = rotation(y);
    // O = G + R (0, 0, h); its height is s = -n.p(n), the contact being on the plane z = 0.
    const double xO = y[7] + h * R[0][2], yO = y[8] + h * R[1][2], zO = k.s;
    V3 L;
    for (int i = 0; i < 3; ++i) L[i] = m * k.aG[i] + m * g * k.n[i];
    const V3 v = cross(k.r, k.w);
    const V3 Iw{IA * k.w[0] + ID * k.w[1], ID * k.w[0] + IB * k.w[1], IC * k.w[2]};
    const double E = 0.5 * dot(k.w, Iw) + 0.5 * m * dot(v, v) - m * g * dot(k.n, k.r);
    const double wz = dot(k.n, k.w);  // the vertical component of the angular velocity
    if (file == nullptr) return nhdyn::Status::ok;
    std::fprintf(file, "%.17g,%.17g,%.17g,%.17g", t, xO, yO, zO);
    for (int i = 0; i < 7; ++i) std::fprintf(file, ",%.17g", y[i]);
    for (double x : k.alpha) std::fprintf(file, ",%.17g", x);
    for (double x : L) std::fprintf(file, ",%.17g", x);
    std::fprintf(file, ",%.17g,%.17g\n", wz, E);
    return nhdyn::Status::ok;
  }
};

// The example's start: R = Rx(tilt) Ry(tilt) (psi = 0, theta = phi = tilt), spinning at `spin`
// about the world vertical, O above the contact, G = O - R (0, 0, h) with O at x = y = 0.
std::vector<double> initial_state() {
  const double ch = std::cos(tilt / 2), sh = std::sin(tilt / 2);
  // q_x(tilt) * q_y(tilt)
  std::vector<double> y{ch * ch, sh * ch, ch * sh, sh * sh, 0, 0, 0, 0, 0};
  const auto R = rotation(y.data());
  for (int i = 0; i < 3; ++i) y[4 + i] = R[2][i] * spin;  // w_body = R^T (0, 0, spin)
  y[7] = -h * R[0][2];
  y[8] = -h * R[1][2];
  return y;
}

}  // namespace

int main(int argc, char** argv) {
  std::string path;
  double t_end = 50.0;
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "-o") == 0 && i + 1 < argc) {
      path = argv[++i];
    } else if (std::strcmp(argv[i], "--t-end") == 0 && i + 1 < argc) {
      t_end = std::atof(argv[++i]);
    } else {
      std::fprintf(stderr, "usage: rattleback_reference [-o FILE] [--t-end T]\n");
      return 2;
    }
  }
  Writer w;
  if (!path.empty()) {
    w.file = std::fopen(path.c_str(), "w");
    if (w.file == nullptr) {
      std::fprintf(stderr, "rattleback_reference: cannot write %s\n", path.c_str());
      return 2;
    }
    std::fprintf(w.file, "t,x,y,z,q0,q1,q2,q3,w1,w2,w3,w1',w2',w3',L1,L2,L3,w_vertical,E\n");
  }
  // The example's output step and tolerances (examples/rattleback.toml [simulation]).
  const long n_out = std::lround(t_end / 0.01);
  std::vector<double> times(static_cast<std::size_t>(n_out) + 1);
  for (long i = 0; i <= n_out; ++i) times[static_cast<std::size_t>(i)] = t_end * static_cast<double>(i) / n_out;
  nhdyn::IntegratorOptions options;
  options.kind = nhdyn::IntegratorKind::dop853;
  options.rtol = 1e-10;
  options.atol = 1e-12;
  Rattleback system;
  const std::vector<double> y0 = initial_state();
  const nhdyn::IntegrationResult result = nhdyn::integrate(
      system, options, 0.0, y0.data(), times, [&](double t, const double* y) { return w.row(t, y); });
  if (w.file != nullptr) std::fclose(w.file);
  if (result.status != nhdyn::Status::ok) {
    std::fprintf(stderr, "rattleback_reference: %s\n", result.message.c_str());
    return 1;
  }
  std::printf("steps %ld rejected %ld rhs %ld\n", result.stats.steps, result.stats.rejected_steps,
              result.stats.rhs_evaluations);
  return 0;
}
