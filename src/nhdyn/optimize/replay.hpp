// The replay check of an optimized motion (docs/derivations/optimal-programs.md, section 9): the
// controls, interpolated as the collocation method defines them (linear between the nodes for the
// trapezoidal method, quadratic through node, midpoint, node for Hermite-Simpson), drive the
// model's Do Sanh equations [D A; b] q'' = [D (Q + G + B u); -b0] (D an orthonormal basis of the
// null space of b, another complement than the transcription's) from the optimized initial state,
// integrated interval by interval by dop853 at a tight tolerance, since the controls have kinks at
// the nodes. The largest difference between the replayed and the optimized coordinates at the
// nodes is of the order of the method's global error: it says whether the grid resolves the motion,
// whatever IPOPT's tolerances.
#pragma once

#include <string>
#include <vector>

#include "nhdyn/frontend/optimize_problem.hpp"

namespace nhdyn {

struct ReplayResult {
  bool ok = false;
  std::string message;        // why the replay stopped, when not ok
  double difference = 0.0;    // max over the nodes and coordinates of |q_replay - q_optimized|
  std::vector<double> q_end;  // n: the replayed coordinates at t_end
  // Each interval replayed from the optimum's own state at its start (q and q' of its first
  // point): the largest |q_replay - q_optimized| at its end, per coordinate (n). The error the
  // discretization makes in one interval, which an unstable motion does not amplify over the run
  // as it does the replay from t0.
  bool local_ok = false;
  std::string local_message;  // why an interval's replay stopped, when not local_ok
  std::vector<double> local;  // n
};

// `times` (P point times), `q` and `v` (P x n, row per point), `u` (P x m, row per point) of the
// optimized motion. Points are nodes, or for Hermite-Simpson the nodes with the midpoints between
// them.
ReplayResult calc_replay(const OptimalControlProblem& problem, const std::vector<double>& times,
                         const std::vector<double>& q, const std::vector<double>& v, const std::vector<double>& u);

}  // namespace nhdyn
