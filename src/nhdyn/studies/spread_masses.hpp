// Widely spread masses (docs/studies/spread-masses.md; the paper's claim that the Do Sanh form
// needs no inverse of the inertia matrix): for a model whose parameter `ratio` spreads its masses
// (examples/spread_masses.toml: m, m sqrt(ratio), m ratio), and for each ratio of a list, every
// formulation computes q'' and R in double at a few fixed states, and each is compared with a
// 50-digit reference for exactly the same problem (symbolic/precise_reference.hpp). The study
// reports, per ratio and formulation, the largest relative error of q'' and of R over the states
// (in all, and of the solve alone, against the exact solution of the rounded terms), the
// acceleration-level constraint residual |b q'' + b0|, and per ratio the condition number of A.
#pragma once

#include <string>
#include <vector>

#include "nhdyn/core/status.hpp"
#include "nhdyn/core/types.hpp"
#include "nhdyn/studies/error_relation.hpp"

namespace nhdyn::symbolic {
struct Spec;  // symbolic/spec.hpp: taken by reference, so that this header includes no GiNaC
}

namespace nhdyn {

// The most states per ratio and digits of the reference a study takes (check_spread_masses_options).
inline constexpr int kMaxSpreadMassesSamples = 100000;
inline constexpr int kMaxSpreadMassesDigits = 1000;

struct SpreadMassesOptions {
  std::vector<double> ratios{1.0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10, 1e11, 1e12};
  int samples = 3;                             // states per ratio, 1 to kMaxSpreadMassesSamples
  int digits = 50;                             // of the reference, 20 to kMaxSpreadMassesDigits
  std::string parameter = "ratio";             // the model parameter the study varies
  std::vector<StudyFormulation> formulations;  // empty: every formulation the model allows
};

// One state of the sample: (t, q, v) on the constraints.
struct SpreadMassesState {
  double t = 0.0;
  Vector q, v;
};

// One formulation at one ratio, over all the states.
struct SpreadMassesPoint {
  double error_qdd = 0.0;  // max over states of ||q'' - q''_ref|| / ||q''_ref|| (2-norms)
  double error_R = 0.0;    // max over states of ||R - R_ref|| / ||R_ref||
  // The same errors against the exact solution of the terms A, Q + G, b, b0 as the double
  // evaluation rounded them (symbolic::calc_precise_solution): the error of the solve alone,
  // without the rounding of the terms, which every formulation shares.
  double solve_error_qdd = 0.0;
  double solve_error_R = 0.0;
  double residual = 0.0;   // max over states and constraints of |b q'' + b0| in double
  int failures = 0;        // states where the formulation returned a non-ok status (errors NaN then)
  Status failure = Status::ok;  // the status of the first failure
};

// One ratio: the conditioning of the problem and of the reference.
struct SpreadMassesRatio {
  double ratio = 0.0;
  double cond_A = 0.0;           // max over states of the 2-norm condition number of A (double SVD)
  double reference_error = 0.0;  // max over states of the reference's estimated relative error
  double norm_qdd = 0.0;         // max over states of ||q''_ref||, for scale
  double norm_R = 0.0;           // max over states of ||R_ref||
};

struct SpreadMasses {
  std::string model;
  int digits = 0;
  std::vector<StudyFormulation> formulations;
  std::vector<SpreadMassesState> states;
  std::vector<SpreadMassesRatio> ratios;
  std::vector<SpreadMassesPoint> points;  // for each ratio, each formulation (in that nesting order)
  const SpreadMassesPoint& point(std::size_t ratio, std::size_t formulation) const {
    return points[ratio * formulations.size() + formulation];
  }
};

// The states of the study: the model's initial state, then samples - 1 deterministic
// perturbations of it (of 0.4 in each coordinate and 1 in each velocity, by a fixed pattern)
// moved onto the constraints by fix_initial_state. They are computed once with the parameter at
// 1 and reused for every ratio (the constraints of the model must not depend on it, so that the
// curves change with the masses only). Throws ModelError when a state cannot be fixed.
std::vector<SpreadMassesState> make_spread_masses_states(const symbolic::Spec& spec, const std::string& parameter,
                                                         int samples);

// The one check of the study's ratios, samples and digits, for the command line and a C++ caller
// alike (its messages name the command line's options): InputError naming the value at fault for
// no ratio, a ratio <= 0 or not finite, samples < 1, digits < 20. study_spread_masses calls it; a
// caller may call it first to refuse the value before any work.
void check_spread_masses_options(const SpreadMassesOptions& options);

// Throws InputError naming the value at fault (check_spread_masses_options; a model without the
// parameter; an analytic complement for a model without one); ModelError when the reference
// system is singular at a state.
SpreadMasses study_spread_masses(const symbolic::Spec& spec, const SpreadMassesOptions& options);

}  // namespace nhdyn
