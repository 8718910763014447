// The constraint watch: a constraint written in a form that becomes singular along the run
// (y' - tan(phi) x' as phi crosses pi/2) passes the integrator without complaint and gives a wrong
// motion. The watch follows, at the states a run visits (every output time and every accepted step
// whose state Data holds), how far each constraint has drifted from its form at the first state:
//
//   1. the Euclidean norm of its row of b (the tan(phi) form grows like 1/|cos(phi)|), on the dense
//      and the sparse path, O(nonzeros of b);
//   2. on the dense path, a conditioning estimate of the stacked matrix [D A; b] with its rows
//      scaled to unit norm (so that 1. alone speaks about scale and 2. about directions) and its
//      columns in the kinetic energy's metric, column j times 1 / sqrt(A_jj) as at the last
//      estimate (so that the units of the coordinates' columns do not speak either: in
//      kilometres the slider crank's column of its slider's x is a thousand times off its
//      columns of angles, and the estimate with the rows alone scaled followed how the motion
//      mixes the two, a matter of units; in the metric, constraints that merge still do, x' and
//      cos(phi) x' + sin(phi) y' as phi goes to 0, where scaling each column to unit norm would
//      have hidden it; what the metric does not remove is the solve's own D mixing coordinates of
//      different units in one row, k >= 2 with lengths and angles in a constraint, which carries
//      them into the rows D A): the ratio of the largest to the smallest |R_ii| of a QR with
//      column pivoting of its transpose, the last pivot naming the row most nearly dependent on
//      the others. O(n^3), in workspace allocated once. For a formulation without D (lagrange,
//      udwadia-kalaba) the rows of b alone. The factorization is amortized: the rows of b change
//      slowly, so the estimate is made again only once the scaled matrix M has moved, in the Frobenius norm, by more than
//      kConditioningReuse times a lower bound of its smallest singular value at the last estimate
//      (1 / ||R^-1||_F). By Weyl's inequality the true condition number of M in between stays
//      within a factor (1 + r) / (1 - r), r = kConditioningReuse, of its value there, so a loss by
//      orders of magnitude always crosses the bound and is measured. Forming M is O(k n^2).
//
// A measure that has grown (or a row norm that has shrunk) by kConstraintWatchFactor or more from
// its first value, or that is no longer finite, makes one warning per constraint: which measure,
// the time, the factor. The simulate driver (analysis/simulation.hpp) keeps them in its summary;
// docs/cli.md "Warnings" describes them. Called after compute_acceleration; allocates nothing
// once made (a warning is stored in space reserved for it).
#pragma once

#include <Eigen/QR>
#include <optional>
#include <string>
#include <vector>

#include "nhdyn/core/types.hpp"
#include "nhdyn/model/data.hpp"
#include "nhdyn/model/model.hpp"

namespace nhdyn {

// Three orders of magnitude: a well-posed model's rows of b and stacked matrix change with the
// configuration by far less (the sled, the rolling disk and the bicycle stay below 3 over long
// runs, tests/formulation/constraint_watch_test.cpp), while the tan(phi) form reaches it at
// |cos(phi)| = 1e-3, 1 ms of rotation before the singularity at 1 rad/s.
inline constexpr double kConstraintWatchFactor = 1e3;

// How far (relative to its smallest singular value) the row-scaled stacked matrix may move before
// its conditioning is estimated again: the true condition number stays within a factor 5/3 of
// the last estimate, far inside kConstraintWatchFactor.
inline constexpr double kConditioningReuse = 0.25;

// Which measure degraded.
enum class WatchMeasure {
  row_norm,      // the norm of the constraint's row of b grew or shrank
  conditioning,  // the (row-scaled) stacked matrix lost conditioning; its last pivot was this row
};

struct ConstraintWarning {
  int constraint = -1;  // index in Model::constraints; -1: a row of D A, not a constraint's row
  WatchMeasure measure = WatchMeasure::row_norm;
  double t = 0.0;        // time of the first state past the threshold [s]
  double initial = 0.0;  // the measure at the first state watched
  double value = 0.0;    // the measure at t
  double factor = 0.0;   // max(value/initial, initial/value) for row norms, value/initial for
                         // conditioning; infinite when the value is not finite
};

struct ConstraintWatch {
  double threshold = kConstraintWatchFactor;
  bool started = false;      // whether the first state (the reference) has been seen
  bool stacked = false;      // conditioning of [D A; b] (a formulation with D), else of b alone
  bool conditioning = false; // whether measure 2 is followed (dense path, s > 0)
  Vector initial_norm;       // s, row norms of b at the first state
  Vector norm;               // s, row norms of b at the last state watched
  double initial_condition = 0.0;
  double condition = 0.0;
  // The largest degradation factor seen so far of each measure (1 when nothing changed).
  double largest_row_factor = 1.0;
  double largest_condition_factor = 1.0;
  std::vector<char> warned;  // s + 1 flags: each constraint, then the rows of D A
  std::vector<ConstraintWarning> warnings;  // in time order; capacity s + 1, reserved
  Matrix rows;                              // (rows watched) x n, the row-scaled stacked matrix
  Matrix rows_t;                            // n x (rows watched), its transpose for the QR
  Eigen::ColPivHouseholderQR<Matrix> qr;    // of rows_t
  Matrix estimated_rows;                    // rows at the last estimate
  Vector column_scale;                      // n, the columns' scales 1 / sqrt(A_jj) at the last estimate
  double reuse_radius = 0.0;                // kConditioningReuse / ||R^-1||_F there; 0: estimate again
  Eigen::Index last_pivot = 0;              // the last pivot's row at the last estimate
  Vector unit;                              // workspace of the bound, (rows watched)
  long states = 0;                          // states watched
  long estimates = 0;                       // of them, those whose conditioning was estimated
  // With contact modes: the rows of b the current modes keep (a sliding contact drops its no-slip
  // rows, a free one all its rows; model/contact_modes.hpp). A dropped row constrains nothing, so
  // its norm is not compared (a ball flying away from a sphere stretches its rolling rows'
  // unnormalized tangents), and the conditioning is watched only while every row is kept. s flags.
  std::vector<char> in_use;
};

// The watch for a run of `model` on `data` (its path, dense or sparse) with the formulation
// `method`: sizes every workspace. Cold path.
ConstraintWatch make_constraint_watch(const Model& model, const Data& data, std::optional<Formulation> method,
                                      double threshold = kConstraintWatchFactor);

// Watches the state held in data (b, and on the dense path D and A, after compute_acceleration):
// the first call sets the reference, every later one compares with it and records a warning the
// first time a constraint's measure passes the threshold; with contact modes, only the rows the
// current modes keep. Allocates nothing.
void compute_constraint_watch(const Model& model, const Data& data, ConstraintWatch& watch);

// One warning in words: the constraint by name, the measure, t, the factor, and what to do.
std::string format_constraint_warning(const Model& model, const ConstraintWarning& warning);

}  // namespace nhdyn
