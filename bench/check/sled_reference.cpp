// The sled of examples/sled.toml written by hand: its closed-form accelerations and reactions
// (docs/derivations/sled.md 7.1), a Dormand-Prince 5(4) with Hairer's step-size control and dense
// output, and the CSV rows nhdyn's `simulate` writes for it (t, q, q', q'', R, the blade's
// velocity and acceleration residuals, E). It is the yardstick of `make bench-check`: the whole
// process `nhdyn simulate examples/sled.toml` is timed against this whole process, so the ratio
// says what nhdyn's generality costs on a small model, independently of the machine's speed.
//
//   sled_reference [-o FILE] [--repeat N]   (--repeat: integrate N times, write the last run)
//
// Same parameters, initial state, tolerances (rtol 1e-8, atol 1e-10), t_end (10 s) and output
// step (0.01 s) as `nhdyn simulate examples/sled.toml`; scripts/bench-check compares the two
// CSVs' last rows once so that the yardstick cannot drift from the model it stands for.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

namespace {

using State = std::array<double, 6>;  // x, y, phi, x', y', phi'

// examples/sled.toml: m = 1, a = 0.5, rho = 0.7, alpha = pi/6, g = 9.81.
constexpr double m = 1.0, a = 0.5, rho2 = 0.7 * 0.7, g = 9.81;
const double gs = g * std::sin(M_PI / 6);

struct Row {
  double qdd[3], R[3];
};

// docs/derivations/sled.md 7.1 (potential of the centre of mass), then R = A q'' - Q - G.
Row accelerations(const State& y) {
  const double s = std::sin(y[2]), c = std::cos(y[2]), w = y[5];
  const double speed = c * y[3] + s * y[4];
  const double P = gs * c + a * w * w, S = speed * w, torque = gs * s;
  Row r;
  r.qdd[0] = c * P - s * S;
  r.qdd[1] = s * P + c * S;
  r.qdd[2] = -(a / rho2) * (torque + S);
  const double ma = m * a;
  r.R[0] = m * r.qdd[0] - ma * s * r.qdd[2] - m * gs - ma * c * w * w;
  r.R[1] = m * r.qdd[1] + ma * c * r.qdd[2] - ma * s * w * w;
  r.R[2] = -ma * s * r.qdd[0] + ma * c * r.qdd[1] + m * rho2 * r.qdd[2] + m * torque * a;
  return r;
}

State rhs(const State& y) {
  const Row r = accelerations(y);
  return {y[3], y[4], y[5], r.qdd[0], r.qdd[1], r.qdd[2]};
}

State axpy(const State& y, double h, std::initializer_list<std::pair<double, const State*>> terms) {
  State out = y;
  for (const auto& [c, k] : terms)
    for (int i = 0; i < 6; ++i) out[i] += h * c * (*k)[i];
  return out;
}

struct Writer {
  std::FILE* file = nullptr;
  std::vector<char> buffer;
  void row(double t, const State& y) {
    const Row r = accelerations(y);
    const double s = std::sin(y[2]), c = std::cos(y[2]);
    const double residual_vel = -s * y[3] + c * y[4];
    const double residual_acc = -s * r.qdd[0] + c * r.qdd[1] - y[5] * (c * y[3] + s * y[4]);
    const double vcx = y[3] - a * s * y[5], vcy = y[4] + a * c * y[5];
    const double E = m / 2 * (vcx * vcx + vcy * vcy) + m * (rho2 - a * a) / 2 * y[5] * y[5] -
                     m * gs * (y[0] + a * c);
    if (file == nullptr) return;
    std::fprintf(file, "%.17g", t);
    for (double x : y) std::fprintf(file, ",%.17g", x);
    for (double x : r.qdd) std::fprintf(file, ",%.17g", x);
    for (double x : r.R) std::fprintf(file, ",%.17g", x);
    std::fprintf(file, ",%.17g,%.17g,%.17g\n", residual_vel, residual_acc, E);
  }
};

// Dormand-Prince 5(4) (Hairer, Norsett, Wanner, Solving ODEs I, II.5; the dense output of dopri5.f).
long integrate(Writer& out) {
  constexpr double c2 = 1.0 / 5, c3 = 3.0 / 10, c4 = 4.0 / 5, c5 = 8.0 / 9;
  constexpr double a21 = 1.0 / 5, a31 = 3.0 / 40, a32 = 9.0 / 40, a41 = 44.0 / 45, a42 = -56.0 / 15,
                   a43 = 32.0 / 9, a51 = 19372.0 / 6561, a52 = -25360.0 / 2187, a53 = 64448.0 / 6561,
                   a54 = -212.0 / 729, a61 = 9017.0 / 3168, a62 = -355.0 / 33, a63 = 46732.0 / 5247,
                   a64 = 49.0 / 176, a65 = -5103.0 / 18656, a71 = 35.0 / 384, a73 = 500.0 / 1113,
                   a74 = 125.0 / 192, a75 = -2187.0 / 6784, a76 = 11.0 / 84;
  constexpr double e1 = 71.0 / 57600, e3 = -71.0 / 16695, e4 = 71.0 / 1920, e5 = -17253.0 / 339200,
                   e6 = 22.0 / 525, e7 = -1.0 / 40;
  constexpr double d1 = -12715105075.0 / 11282082432.0, d3 = 87487479700.0 / 32700410799.0,
                   d4 = -10690763975.0 / 1880347072.0, d5 = 701980252875.0 / 199316789632.0,
                   d6 = -1453857185.0 / 822651844.0, d7 = 69997945.0 / 29380423.0;
  (void)c2, (void)c3, (void)c4, (void)c5;  // autonomous: the stage times are not needed
  constexpr double rtol = 1e-8, atol = 1e-10, t_end = 10.0, dt_out = 0.01;
  const long n_out = 1000;
  State y{0, 0, 0, 1.0, 0, 1.0};
  double t = 0.0, h = 1e-3, err_old = 1e-4;
  long steps = 0, next = 1;
  State k1 = rhs(y);
  out.row(0.0, y);
  while (next <= n_out) {
    if (t + h > t_end) h = t_end - t;
    const State k2 = rhs(axpy(y, h, {{a21, &k1}}));
    const State k3 = rhs(axpy(y, h, {{a31, &k1}, {a32, &k2}}));
    const State k4 = rhs(axpy(y, h, {{a41, &k1}, {a42, &k2}, {a43, &k3}}));
    const State k5 = rhs(axpy(y, h, {{a51, &k1}, {a52, &k2}, {a53, &k3}, {a54, &k4}}));
    const State k6 = rhs(axpy(y, h, {{a61, &k1}, {a62, &k2}, {a63, &k3}, {a64, &k4}, {a65, &k5}}));
    const State y1 = axpy(y, h, {{a71, &k1}, {a73, &k3}, {a74, &k4}, {a75, &k5}, {a76, &k6}});
    const State k7 = rhs(y1);
    double err = 0.0;
    for (int i = 0; i < 6; ++i) {
      const double e = h * (e1 * k1[i] + e3 * k3[i] + e4 * k4[i] + e5 * k5[i] + e6 * k6[i] + e7 * k7[i]);
      const double sk = atol + rtol * std::max(std::abs(y[i]), std::abs(y1[i]));
      err += (e / sk) * (e / sk);
    }
    err = std::sqrt(err / 6);
    // Hairer's PI controller (dopri5.f: beta = 0.04, safety 0.9, factors in [0.2, 10]).
    const double fac11 = std::pow(err, 0.2 - 0.04 * 0.75);
    double fac = std::clamp(fac11 / std::pow(err_old, 0.04) / 0.9, 0.1, 5.0);
    if (err <= 1.0) {
      err_old = std::max(err, 1e-4);
      ++steps;
      const double t1 = t + h;
      while (next <= n_out && next * dt_out <= t1 + 1e-12 * t_end) {
        const double tout = std::min(next * dt_out, t_end);
        const double theta = (tout - t) / h, theta1 = 1.0 - theta;
        State yo;
        for (int i = 0; i < 6; ++i) {
          const double ydiff = y1[i] - y[i], bspl = h * k1[i] - ydiff;
          const double r5 = h * (d1 * k1[i] + d3 * k3[i] + d4 * k4[i] + d5 * k5[i] + d6 * k6[i] + d7 * k7[i]);
          yo[i] = y[i] + theta * (ydiff + theta1 * (bspl + theta * (ydiff - h * k7[i] - bspl + theta1 * r5)));
        }
        out.row(tout, yo);
        ++next;
      }
      y = y1;
      k1 = k7;
      t = t1;
      h /= std::clamp(fac, 0.1, 5.0);
    } else {
      h /= std::min(5.0, fac11 / 0.9);
    }
  }
  return steps;
}

}  // namespace

int main(int argc, char** argv) {
  std::string path;
  long repeat = 1;
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "-o") == 0 && i + 1 < argc) {
      path = argv[++i];
    } else if (std::strcmp(argv[i], "--repeat") == 0 && i + 1 < argc) {
      repeat = std::atol(argv[++i]);
    } else {
      std::fprintf(stderr, "usage: sled_reference [-o FILE] [--repeat N]\n");
      return 2;
    }
  }
  long steps = 0;
  for (long r = 0; r < repeat; ++r) {
    Writer w;
    if (r + 1 == repeat && !path.empty()) {
      w.file = std::fopen(path.c_str(), "w");
      if (w.file == nullptr) {
        std::fprintf(stderr, "sled_reference: cannot write %s\n", path.c_str());
        return 2;
      }
      std::fprintf(w.file, "t,x,y,phi,x',y',phi',x'',y'',phi'',R_x,R_y,R_phi,residual_vel_blade,residual_acc_blade,E\n");
    }
    steps = integrate(w);
    if (w.file != nullptr) std::fclose(w.file);
  }
  std::printf("steps %ld\n", steps);
  return 0;
}
