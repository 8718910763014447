// Exams: the contact forces of multibody models (model/contact_forces.hpp) against the closed forms
// of docs/derivations/contact-forces.md section 6 — the rolling disk's force from the accelerations
// of its centre (D1) at every output row and at random states, as a function of the state (D4), its
// steady circle (N = m g, F_lat, mu), the checks against R (C2), the falling disk whose normal force
// crosses zero where the closed form says; the bicycle's static wheel loads (section 7); and a sled
// held flat by its frames, whose normal force the model does not determine (NaN, and a note).
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <string>
#include <utility>
#include <variant>
#include <vector>

#include "multibody/multibody_support.hpp"
#include "nhdyn/analysis/simulation.hpp"
#include "nhdyn/frontend/load_model.hpp"
#include "nhdyn/io/results.hpp"
#include "nhdyn/model/contact_forces.hpp"
#include "support/models.hpp"
#include "support/text.hpp"

namespace nhdyn::multibody_test {
namespace {

using nhdyn::test::example;

double parameter(const Model& model, const std::string& name) {
  for (const Parameter& p : model.parameters)
    if (p.name == name) return p.value;
  ADD_FAILURE() << "no parameter " << name;
  return 0.0;
}

int column(const ResultColumns& columns, const std::string& name) {
  for (std::size_t i = 0; i < columns.all.size(); ++i)
    if (columns.all[i] == name) return static_cast<int>(i);
  ADD_FAILURE() << "no column " << name;
  return 0;
}

// The disk's contact force from (q, q', q'') by (D1): m times the acceleration of its centre plus
// its weight, written out in the coordinates x, y, psi, theta, phi.
struct DiskForce {
  double Fx, Fy, Fz;
};
DiskForce disk_force_d1(double m, double r, double g, const double* q, const double* v, const double* a) {
  const double psi = q[2], th = q[3];
  const double dpsi = v[2], dth = v[3];
  const double ddpsi = a[2], ddth = a[3];
  const double At = std::sin(th) * ddpsi + 2 * std::cos(th) * dth * dpsi;
  const double An = std::sin(th) * (dth * dth + dpsi * dpsi) - std::cos(th) * ddth;
  return {m * a[0] + m * r * (std::cos(psi) * At - std::sin(psi) * An),
          m * a[1] + m * r * (std::sin(psi) * At + std::cos(psi) * An),
          m * (g - r * std::cos(th) * dth * dth - r * std::sin(th) * ddth)};
}

// (D4): N, F_long, F_lat as functions of the state alone (the accelerations solved).
struct DiskSplit {
  double N, Flong, Flat;
};
DiskSplit disk_force_d4(double m, double r, double g, const double* q, const double* v) {
  const double th = q[3], dpsi = v[2], dth = v[3], dphi = v[4];
  const double s = std::sin(th), c = std::cos(th);
  return {m * (g * (1 + 4 * c * c) / 5 - r * c * (dth * dth + 1.2 * dphi * dpsi * s + dpsi * dpsi * s * s)),
          m * r * dpsi * dth * c / 3,
          m / 5 * ((6 * s * s - 1) * r * dphi * dpsi + 5 * r * dpsi * dpsi * s * s * s + 5 * r * dth * dth * s -
                   4 * g * s * c)};
}

TEST(ContactForces, RollingDiskMatchesTheCentreOfMassBalanceAtRandomStates) {
  const Model model = load_model(example("rolling_disk_bodies.toml"));
  ASSERT_TRUE(model.contact_forces);
  EXPECT_TRUE(model.contact_forces->notes.empty()) << model.contact_forces->notes.front();
  EXPECT_TRUE(model.contact_forces->single_contact);
  const double m = parameter(model, "m"), r = parameter(model, "r"), g = parameter(model, "g");
  std::mt19937 rng(15);
  for (int trial = 0; trial < 20; ++trial) {
    std::vector<double> q = {uniform(rng, -2, 2), uniform(rng, -2, 2), uniform(rng, -3, 3), uniform(rng, -1.2, 1.2),
                             uniform(rng, -3, 3)};
    std::vector<double> v = {0, 0, uniform(rng, -3, 3), uniform(rng, -3, 3), uniform(rng, -8, 8)};
    v[0] = r * v[4] * std::cos(q[2]);
    v[1] = r * v[4] * std::sin(q[2]);
    Data data = dynamics_at(model, q, v);
    compute_contact_forces(model, data);
    const double* F = data.contact.values.data();  // Fx, Fy, Fz, N, Flong, Flat
    const DiskForce d1 = disk_force_d1(m, r, g, q.data(), v.data(), data.qdd.data());
    const DiskSplit d4 = disk_force_d4(m, r, g, q.data(), v.data());
    const double scale = m * g * (1 + r * 64 / g);  // forces here reach a few m g
    EXPECT_NEAR(F[0], d1.Fx, 1e-12 * scale);
    EXPECT_NEAR(F[1], d1.Fy, 1e-12 * scale);
    EXPECT_NEAR(F[2], d1.Fz, 1e-12 * scale);
    EXPECT_NEAR(F[3], d4.N, 1e-11 * scale);
    EXPECT_NEAR(F[4], d4.Flong, 1e-11 * scale);
    EXPECT_NEAR(F[5], d4.Flat, 1e-11 * scale);
    // (C2): R = (F_x, F_y, 0, 0, -r F_long).
    EXPECT_NEAR(data.R(0), F[0], 1e-11 * scale);
    EXPECT_NEAR(data.R(1), F[1], 1e-11 * scale);
    EXPECT_NEAR(data.R(4), -r * F[4], 1e-11 * scale);
    EXPECT_LT(data.contact.residual, 1e-13);
  }
}

// The steady circle of the example file, from its CSV layout: every row against (D1) from the
// row's q, q', q'' and against the steady values N = m g, F_lat (section 6.3), mu.
TEST(ContactForces, RollingDiskSteadyCircleRowByRow) {
  const Model model = load_model(example("rolling_disk_bodies.toml"));
  const double m = parameter(model, "m"), r = parameter(model, "r"), g = parameter(model, "g");
  const double th0 = parameter(model, "theta0"), Om = parameter(model, "Omega");
  const double F_lat = m * r * Om * Om * std::sin(th0) / 6 - 2 * m * g * std::tan(th0) / 3;
  EXPECT_NEAR(F_lat, -0.991828, 5e-7);  // the derivation's figure
  const ResultColumns columns = make_result_columns(model);
  const int Fx = column(columns, "disk_Fx"), Fy = column(columns, "disk_Fy"), Fz = column(columns, "disk_Fz");
  const int N = column(columns, "disk_N"), Flong = column(columns, "disk_Flong"), Flat = column(columns, "disk_Flat");
  const int check = column(columns, "contact_residual");
  ASSERT_EQ(check, Fx + 6);
  ASSERT_EQ(columns.contact_forces.back(), "contact_residual");
  const int q = column(columns, "x"), v = column(columns, "x'"), a = column(columns, "x''");
  const int Rx = column(columns, "R_x"), Ry = column(columns, "R_y"), Rphi = column(columns, "R_phi");
  SimulationOptions options;
  options.t_end = 3.0;
  options.output_step = 0.05;
  options.integrator.rtol = 1e-11;
  options.integrator.atol = 1e-12;
  std::vector<double> row;
  int rows = 0;
  simulate(model, options, [&](const Data& data) {
    fill_result_row(model, data, row);
    ASSERT_EQ(row.size(), columns.all.size());
    const DiskForce d1 = disk_force_d1(m, r, g, &row[static_cast<std::size_t>(q)], &row[static_cast<std::size_t>(v)],
                                       &row[static_cast<std::size_t>(a)]);
    const auto at = [&](int i) { return row[static_cast<std::size_t>(i)]; };
    EXPECT_NEAR(at(Fx), d1.Fx, 1e-12 * m * g);
    EXPECT_NEAR(at(Fy), d1.Fy, 1e-12 * m * g);
    EXPECT_NEAR(at(Fz), d1.Fz, 1e-12 * m * g);
    EXPECT_NEAR(at(N), m * g, 1e-8 * m * g);
    EXPECT_NEAR(at(Flong), 0.0, 1e-8 * m * g);
    EXPECT_NEAR(at(Flat), F_lat, 1e-8 * m * g);
    EXPECT_NEAR(std::hypot(at(Flong), at(Flat)) / at(N), 0.202208, 1e-6);  // mu_req
    EXPECT_NEAR(at(Rx), at(Fx), 1e-11 * m * g);
    EXPECT_NEAR(at(Ry), at(Fy), 1e-11 * m * g);
    EXPECT_NEAR(at(Rphi), -r * at(Flong), 1e-11 * m * g);
    EXPECT_LT(at(check), 1e-13);
    ++rows;
  });
  EXPECT_EQ(rows, 61);
}

// Section 6.4: released at rest from theta0 = 0.1, the disk topples about its fixed contact point
// and its normal force N = (m g / 5)(1 - 8 k c + 12 c^2), k = cos(theta0), crosses zero at
// cos(theta*) = (2 k + sqrt(4 k^2 - 3)) / 6 (theta* = 1.052986 rad), at t* = 0.49015 s; the
// bilateral contact holds on, N reaches its minimum (m g / 5)(1 - 4 k^2 / 3) and comes back
// through zero at the other root.
TEST(ContactForces, FallingDiskLiftsOffWhereTheClosedFormSays) {
  Model model = load_model(example("rolling_disk_bodies.toml"));
  const double m = parameter(model, "m"), g = parameter(model, "g");
  const double th0 = 0.1;
  model.q0 << 0, 0, 0, th0, 0;
  model.v0.setZero();
  const double k = std::cos(th0);
  const double theta_star = std::acos((2 * k + std::sqrt(4 * k * k - 3)) / 6);
  EXPECT_NEAR(theta_star, 1.052986, 5e-7);
  SimulationOptions options;
  options.t_end = 0.55;
  options.output_step = 0.001;
  options.integrator.rtol = 1e-11;
  options.integrator.atol = 1e-12;
  double t_prev = 0, N_prev = 0, th_prev = 0;
  std::vector<double> t_cross, th_cross;
  double N_min = std::numeric_limits<double>::infinity();
  simulate(model, options, [&](const Data& data) {
    const double th = data.q(3), c = std::cos(th);
    const double N = data.contact.values(3);
    EXPECT_NEAR(N, m * g / 5 * (1 - 8 * k * c + 12 * c * c), 1e-9 * m * g) << "t = " << data.t;
    EXPECT_NEAR(data.contact.values(4), 0.0, 1e-9 * m * g);  // F_long
    N_min = std::min(N_min, N);
    if (data.t > 0 && (N_prev > 0) != (N > 0)) {
      const double s = N_prev / (N_prev - N);  // linear between the rows
      t_cross.push_back(t_prev + s * (data.t - t_prev));
      th_cross.push_back(th_prev + s * (th - th_prev));
    }
    t_prev = data.t;
    N_prev = N;
    th_prev = th;
  });
  // Falling through zero at theta*, and (in the bilateral model) back at the other root.
  ASSERT_EQ(t_cross.size(), 2u);
  EXPECT_NEAR(th_cross[0], theta_star, 2e-5);
  EXPECT_NEAR(t_cross[0], 0.49015, 2e-5);
  EXPECT_NEAR(th_cross[1], std::acos((2 * k - std::sqrt(4 * k * k - 3)) / 6), 2e-5);
  EXPECT_NEAR(N_min, m * g / 5 * (1 - 4 * k * k / 3), 1e-5 * m * g);  // at c = k/3, between the rows
}

// Section 7: upright and straight at constant speed, each wheel carries its share of the weight
// from the moment balance about the rear contact, and nothing else.
TEST(ContactForces, BicycleStaticWheelLoads) {
  const Model model = load_model(example("whipple_bicycle.toml"));
  ASSERT_TRUE(model.contact_forces);
  EXPECT_TRUE(model.contact_forces->notes.empty()) << model.contact_forces->notes.front();
  const double g = parameter(model, "g"), w = parameter(model, "w");
  const double mT = parameter(model, "mR") + parameter(model, "mB") + parameter(model, "mH") + parameter(model, "mF");
  const double xT = (parameter(model, "mB") * parameter(model, "xB") + parameter(model, "mH") * parameter(model, "xH") +
                     parameter(model, "mF") * w) / mT;
  const double N_front = mT * g * xT / w, N_rear = mT * g - N_front;
  EXPECT_NEAR(N_front, 309.3035, 5e-5);
  EXPECT_NEAR(N_rear, 612.8365, 5e-5);
  const ResultColumns columns = make_result_columns(model);
  const int rear = column(columns, "rear_Fx"), front = column(columns, "front_Fx");
  SimulationOptions options;
  options.t_end = 0.5;
  options.output_step = 0.1;
  std::vector<double> row;
  int rows = 0;
  simulate(model, options, [&](const Data& data) {
    fill_result_row(model, data, row);
    const auto at = [&](int i) { return row[static_cast<std::size_t>(i)]; };
    // z down: the normal n = -z, so N = -F_z.
    EXPECT_NEAR(at(rear + 3), N_rear, 1e-9 * N_rear);
    EXPECT_NEAR(at(front + 3), N_front, 1e-9 * N_front);
    EXPECT_NEAR(at(rear + 2), -N_rear, 1e-9 * N_rear);
    EXPECT_NEAR(at(front + 2), -N_front, 1e-9 * N_front);
    for (int base : {rear, front}) {
      EXPECT_NEAR(at(base + 0), 0.0, 1e-9 * N_rear);
      EXPECT_NEAR(at(base + 1), 0.0, 1e-9 * N_rear);
      EXPECT_NEAR(at(base + 4), 0.0, 1e-9 * N_rear);
      EXPECT_NEAR(at(base + 5), 0.0, 1e-9 * N_rear);
    }
    EXPECT_LT(at(column(columns, "contact_residual")), 1e-12);
    ++rows;
  });
  EXPECT_EQ(rows, 6);
}

// test::kFlatSledBodies, a Chaplygin sleigh built from frames: x, y, theta keep it flat on the
// plane, so its frames carry the part of the weight that the one blade cannot (its centre of mass
// is ahead of the blade). The normal force is not determined: NaN, and a note at load; the
// horizontal force is, from R, and equals m times the acceleration of the centre of mass.
TEST(ContactForces, SledHeldFlatByItsFramesHasNoNormalForce) {
  const Model model = load_model_text(test::kFlatSledBodies);
  ASSERT_TRUE(model.contact_forces);
  const ContactForceModel& c = *model.contact_forces;
  ASSERT_FALSE(c.notes.empty());
  std::string notes;
  for (const std::string& note : c.notes) notes += note + "\n";
  EXPECT_NE(notes.find("'sled'"), std::string::npos) << notes;
  EXPECT_NE(notes.find("blade_N"), std::string::npos) << notes;
  EXPECT_NE(notes.find("blade_Fz"), std::string::npos) << notes;
  EXPECT_EQ(notes.find("blade_Flat"), std::string::npos) << notes;
  const std::vector<double> q = {0.2, -0.1, 0.7}, v = {std::cos(0.7) * 1.3, std::sin(0.7) * 1.3, 0.8};
  Data data = dynamics_at(model, q, v);
  compute_contact_forces(model, data);
  const double* F = data.contact.values.data();
  EXPECT_TRUE(std::isnan(F[2]));
  EXPECT_TRUE(std::isnan(F[3]));
  const double m = 2.0, a = 0.3, th = q[2], w = v[2], dw = data.qdd(2);
  const double ax = data.qdd(0) - a * (dw * std::sin(th) + w * w * std::cos(th));
  const double ay = data.qdd(1) + a * (dw * std::cos(th) - w * w * std::sin(th));
  EXPECT_NEAR(F[0], m * ax, 1e-12);
  EXPECT_NEAR(F[1], m * ay, 1e-12);
  EXPECT_NEAR(F[4], 0.0, 1e-12);  // no force along the blade
  EXPECT_NEAR(F[5], m * (-std::sin(th) * ax + std::cos(th) * ay), 1e-12);
  EXPECT_GT(std::abs(F[5]), 0.1);  // a real lateral force, not a zero that passes by accident
  EXPECT_LT(data.contact.residual, 1e-13);
}

TEST(ContactForces, HandWrittenModelsHaveNone) {
  const Model model = load_model(example("rolling_disk.toml"));
  EXPECT_FALSE(model.contact_forces);
  EXPECT_TRUE(contact_force_columns(model).empty());
}

// The check at load (analyse_contact_forces) looks for a state on the constraints near the start
// in the inertia's norm, to the round-off of the constraints' terms: in the coordinates' own units
// a disk 400 mm across, 50 mm above the floor, had its gap closed by tilting it (a step too long for
// the line search) and a ball over a bump 100 km across never met the absolute tolerance 1e-11,
// so that neither was checked (a note said so); a tippe top 40 nm across was given the note of a
// body held by its coordinates. Scaled by any factor (every length, g with them), each model gets
// the notes it has in metres: none.
TEST(ContactForces, TheCheckAtLoadGivesTheSameVerdictInAnyUnits) {
  struct Case {
    const char* file;
    std::vector<std::pair<const char*, double>> lengths;  // the parameters in m, m/s or m/s^2, at scale 1
  };
  const std::vector<Case> cases = {
      {"rolling_disk_hop.toml", {{"r", 0.2}, {"g", 9.81}, {"h", 0.05}}},
      {"ball_over_bump.toml", {{"r", 0.05}, {"g", 9.81}, {"H", 0.05}, {"w", 0.3}, {"V", 0.3}}},
      {"tippe_top.toml", {{"R", 0.02}, {"g", 9.81}}},
  };
  for (const Case& c : cases) {
    const Model metres = load_model(example(c.file));
    ASSERT_TRUE(metres.contact_forces);
    EXPECT_TRUE(metres.contact_forces->notes.empty()) << c.file << ": " << metres.contact_forces->notes.front();
    for (const double scale : {1e-6, 1e-3, 1e3, 1e6}) {
      std::vector<std::pair<std::string, std::variant<double, std::string>>> sets;
      for (const auto& [name, value] : c.lengths) sets.emplace_back(name, value * scale);
      const Model scaled = load_model(example(c.file), sets);
      ASSERT_TRUE(scaled.contact_forces);
      EXPECT_EQ(scaled.contact_forces->notes, metres.contact_forces->notes) << c.file << " scaled by " << scale;
      EXPECT_EQ(scaled.contact_forces->determined, metres.contact_forces->determined) << c.file << " scaled by " << scale;
    }
  }
}

}  // namespace
}  // namespace nhdyn::multibody_test
