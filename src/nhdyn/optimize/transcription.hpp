// The direct collocation of an optimal control problem on the Do Sanh form as a nonlinear program
// (docs/derivations/optimal-programs.md, sections 2-7). Variables at every point p (the N + 1
// nodes, and for Hermite-Simpson the N interval midpoints between them):
//     z_p = (q_p, q'_p, q''_p, u_p)      3n + m values, at offset p (3n + m)
// and the duration T last when the final time is free. Constraints, in this order:
//   the collocation defects of each interval, trapezoidal (C1) or Hermite-Simpson (C2), (C3);
//   the dynamics defect (O4) at each point, d = [D r; b a + b0] with r = A a - Q - G - B u and the
//     partition complement D = [I  -b_i^T b_d^-T] (O6) of a split chosen per point at the
//     starting point; with constraint_level = "given" the rows b a + b0 of the points after the
//     first are the velocity-level constraints f(t, q, q') themselves;
//   the constraints at their own level at the first node (phi, and f or d phi/dt), leaving out
//     those the fixed initial values already determine (the rank rule of section 5);
//   the path constraints at each point.
// Boundary values and bounds are bounds on the variables; a fixed final value that the constraints
// determine from the other fixed final values is released (the rank rule of section 5, item 1). The objective is the quadrature (O8) of
// the integrand plus the final term (or T for minimum time). Every derivative is exact: the
// tangent mode of the compiled tapes (model/detail/tape_tangent.hpp), contracted as in (O5), (O7),
// so that no derivative of D is needed; the Hessian of the Lagrangian from forward differences of
// these exact first derivatives (section 8). Plain C++, no solver types.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Dense>

#include "nhdyn/frontend/optimize_problem.hpp"
#include "nhdyn/optimize/nlp.hpp"

namespace nhdyn {

class Transcription final : public Nlp {
 public:
  // Throws InputError when the model is compiled sparse, when a control's force is absorbed by the
  // constraints (D B_j = 0 at the start), when fixed boundary values lie outside the bounds, when
  // the fixed initial values violate a constraint or the fixed final values contradict one (naming
  // it and its residual), or when the constraints are dependent at the starting point.
  explicit Transcription(const OptimalControlProblem& problem);

  const OptimalControlProblem& problem() const { return problem_; }
  int points() const { return points_; }
  int intervals() const { return intervals_; }
  int width() const { return width_; }  // 3n + m
  // Index of q_i, q'_i, q''_i, u_j at point p.
  int q_index(int p, int i) const { return p * width_ + i; }
  int v_index(int p, int i) const { return p * width_ + n_ + i; }
  int a_index(int p, int i) const { return p * width_ + 2 * n_ + i; }
  int u_index(int p, int j) const { return p * width_ + 3 * n_ + j; }
  int duration_index() const { return points_ * width_; }  // only when the final time is free
  double duration(const double* x) const { return problem_.free_time ? x[duration_index()] : fixed_duration_; }
  double tau(int p) const;  // the point's fraction of the duration, in [0, 1]
  double time(int p, const double* x) const { return problem_.t0 + tau(p) * duration(x); }
  // The rows of the first node's constraints left out by the rank rule, as sentences.
  const std::vector<std::string>& notes() const { return notes_; }
  // The starting point (straight lines between the boundary states, q'' = u = 0).
  const std::vector<double>& start() const { return start_; }
  void set_start(std::vector<double> x) { start_ = std::move(x); }
  // The largest violation of the variable bounds and the constraint bounds at x.
  double constraint_violation(const double* x);
  // Before IPOPT: throws InputError naming the expression (its file:line:column), the point's t
  // and state when the objective, the final term, a path constraint, an actuator or the model's
  // terms are not finite at a point of the starting point (start(), the guess set in it), where
  // IPOPT would stop on "Invalid number" with nothing to say where.
  void require_defined_at_start();
  // Entry k of the terms' outputs by name (A(x, y), Q_x, G_x, b(constraint, x), b0(constraint)).
  std::string term_name(int k) const;
  // The names of the residuals' rows: the position-level constraints, then the position- and
  // velocity-level ones ("c1 (position)").
  std::vector<std::string> residual_row_names() const;
  // A bound for IPOPT: an infinite one as its kNlpInfinity.
  static double nlp_bound(double b);

  int variables() const override { return variables_; }
  int constraints() const override { return rows_; }
  void bounds(double* x_lower, double* x_upper, double* g_lower, double* g_upper) const override;
  void starting_point(double* x) const override;
  bool objective(const double* x, double& f) override;
  bool gradient(const double* x, double* grad) override;
  bool constraint_values(const double* x, double* g) override;
  int jacobian_nonzeros() const override { return static_cast<int>(jac_rows_.size()); }
  void jacobian_pattern(int* rows, int* columns) const override;
  bool jacobian_values(const double* x, double* values) override;
  // The Hessian of the Lagrangian by forward differences of its exact gradient sigma grad f + J^T
  // lambda (docs/derivations/optimal-programs.md, section 8): a dense block per point and the row
  // of T. The gradient at a point depends on that point's variables and T only, so one difference
  // along the same variable of every point at once gives a column of every block: 3n + m + 2
  // gradients (each an exact Jacobian), whatever the number of nodes.
  int hessian_nonzeros() const override { return static_cast<int>(hess_rows_.size()); }
  void hessian_pattern(int* rows, int* columns) const override;
  bool hessian_values(const double* x, double sigma, const double* lambda, double* values) override;

 private:
  struct CollocationTerm {
    int column;
    double c;    // constant coefficient
    double c_h;  // coefficient of h = T / N
  };
  // The quadrature weight of point p divided by h.
  double weight(int p) const;
  void build_collocation();
  void build_pattern();
  void build_hessian_pattern();
  // sigma grad f + J^T lambda at x into `out` (variables() values).
  bool lagrangian_gradient(const double* x, double sigma, const double* lambda, double* out);
  void choose_splits_and_initial_rows();
  void make_start();
  void check_controls_act();
  void release_determined_final_values();
  // The constraint rows [phi; f] (position level, then velocity level) at (t, q, q') into `values`,
  // and their derivatives by (q, q') into `jacobian` (rows x 2 n): the linearization that the rank
  // rules at both ends and the first node's rows of the Jacobian read.
  void constraint_rows(double t, const double* q, const double* v, std::vector<double>& values,
                       Eigen::MatrixXd& jacobian);
  // A path constraint that reads only fixed values at the first or last node (a constant one
  // included) is decided before the solve: throws InputError naming it and its value when it fails.
  void require_path_at_fixed_ends();
  // "t = 0, x = 0.5, x' = 0, F = 0": the point p of x, for messages.
  std::string describe_point(int p, const double* x) const;
  // Throws InputError when a relation among the fixed final values (a column of Z, the
  // combinations of the constraint rows that no free final value enters) does not hold with them.
  void require_final_values_agree(const Eigen::MatrixXd& Z, const Eigen::MatrixXd& relations,
                                  const std::vector<double>& residuals, const std::vector<int>& fixed_columns) const;
  // The terms, B u, the split's factorization and r at point p of x (fills the work arrays).
  bool evaluate_point(int p, const double* x);
  // The dynamics rows of the point last evaluated into `out` (n values).
  void dynamics_values(int p, const double* x, double* out);
  // The projection D y of an n-vector (k values) with the split of the point last evaluated.
  void project(const Eigen::VectorXd& y, double* out) const;
  // Derivative of the dynamics rows along (dt, dq, dv, du) at the point last evaluated; da
  // separately (it enters linearly).
  void dynamics_direction(int p, const double* x, double dt, const double* dq, const double* dv, const double* du,
                          double* out);
  void layout_inputs(int p, const double* x);

  OptimalControlProblem problem_;
  int n_ = 0, m_ = 0, s_ = 0, k_ = 0;
  int intervals_ = 0, points_ = 0, width_ = 0, variables_ = 0;
  bool hs_ = false;
  double fixed_duration_ = 0.0;
  int collocation_rows_ = 0, dynamics_row0_ = 0, initial_row0_ = 0, path_row0_ = 0, rows_ = 0;
  int path_count_ = 0;
  std::vector<std::vector<CollocationTerm>> collocation_;  // per collocation row
  std::vector<int> split_;  // per point: n coordinates, the s dependent ones first
  const int* current_split_ = nullptr;  // the split of the point last evaluated
  std::vector<int> initial_rows_;  // rows of [phi; f] at the first node that are imposed
  std::vector<std::string> notes_;
  std::vector<double> start_;
  std::vector<double> x_lower_, x_upper_;
  std::vector<int> jac_rows_, jac_columns_;
  std::vector<int> hess_rows_, hess_columns_;
  std::vector<double> jac_work_, hess_x_, hess_plus_, hess_minus_, hess_blocks_, hess_step_;

  // Work arrays (sized once).
  const Tape* terms_ = nullptr;
  const Tape* position_residual_ = nullptr;
  const Tape* velocity_residual_ = nullptr;
  std::vector<double> terms_registers_, force_registers_, velocity_registers_, other_registers_, tangents_;
  std::vector<double> terms_out_, dterms_, force_out_, dforce_;
  std::vector<double> layout_q_, layout_v_, layout_dq_, layout_dv_;
  Eigen::MatrixXd A_, b_, bt_d_;
  Eigen::VectorXd r_, mu_, work_;
  Eigen::PartialPivLU<Eigen::MatrixXd> lu_;  // of b_d^T
};

}  // namespace nhdyn
