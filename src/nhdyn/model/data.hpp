// Data: every time-varying value and every piece of scratch memory of one simulation of a Model,
// allocated once by make_data. Kernels (compute_*) read and write it and allocate nothing.
// One Data per thread is the whole thread-safety story. Each field says its size and which
// kernel fills it; `stage` records how far the kernels have got for the current state, so that a
// kernel called out of order says so instead of reading stale values.
#pragma once

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <Eigen/QR>
#include <Eigen/SVD>
#include <string>
#include <vector>

#include "nhdyn/core/status.hpp"
#include "nhdyn/core/types.hpp"
#include "nhdyn/model/model.hpp"

namespace nhdyn {

// How far the kernels have got for the state (t, q, v) held in Data.
enum class Stage { empty = 0, terms = 1, acceleration = 2 };

struct Data {
  // --- state, set by compute_terms -------------------------------------------------------------
  double t = 0.0;       // time [s]
  Vector q;             // n coordinates
  Vector v;             // n velocities q'
  Stage stage = Stage::empty;

  // --- terms of the equations (compute_terms, FORMULATION.md (2.4), (2.5)) -----------------------
  Matrix A;             // n x n inertia matrix
  Vector Q;             // n generalized forces
  Vector G;             // n velocity terms
  Matrix b;             // s x n constraint matrix
  Vector b0;            // s
  Vector stabilization; // s, Baumgarte terms 2 alpha f + beta^2 phi (compute_baumgarte_terms)
  Vector b0_model;      // s, the model's b0 while a stabilized one is solved (compute_acceleration)

  // --- complement D (compute_complement) ---------------------------------------------------------
  Matrix D;             // k x n, D b^T = 0 (2.8)
  std::vector<int> independent;  // k indices of the independent coordinates (partitioned D only)

  // --- results (compute_acceleration) ------------------------------------------------------------
  Vector qdd;           // n accelerations q''
  Vector R;             // n reactions, R = A q'' - Q - G (2.15)
  Vector lambda;        // s multipliers, R = b^T lambda (lagrange, udwadia-kalaba, nullspace)
  bool has_multipliers = false;  // whether lambda was computed by the last formulation

  // --- residuals and energy (compute_residuals, compute_energy) ------------------------------------
  Vector phi;           // position-level constraint residuals (one per position constraint)
  Vector f;             // velocity-level residuals (one per position or velocity constraint)
  Vector e;             // s acceleration-level residuals b q'' + b0 (2.14)
  double energy = 0.0;  // T + V where the model defines it

  // --- failure details (set when a kernel returns a non-ok status) --------------------------------
  Status status = Status::ok;
  std::string failed_quantity;  // e.g. "A", "q''": preallocated, see make_data
  double failed_t = 0.0;
  double failed_value = 0.0;    // the residual reached, for Status::projection_failed

  // --- counters ------------------------------------------------------------------------------
  long term_evaluations = 0;     // calls of compute_terms
  long acceleration_solves = 0;  // successful calls of compute_acceleration

  // --- scratch (owned by the kernels; sizes fixed by make_data) ---------------------------------
  // Whether the formulations may take their fixed-size path for small n (formulation/
  // small_dense.hpp). Both paths compute the same values; tests clear it to compare them.
  bool small_kernels = true;
  std::vector<double> scratch;   // evaluator workspace, Evaluator::scratch_size()
  Vector h;                      // n, Q + G
  Matrix M;                      // n x n, stacked sanh matrix [D A; b]
  Vector rhs;                    // n, stacked right-hand side [D (Q + G); -b0]
  Matrix K;                      // (n + s) x (n + s), KKT matrix
  Vector kkt_rhs;                // n + s
  Vector kkt_sol;                // n + s
  Matrix bt;                     // n x s, b^T
  Matrix Q_full;                 // n x n, orthogonal factor of b^T
  Vector hh_work;                // n, Householder workspace
  Matrix DA;                     // k x n, D A
  Matrix DAD;                    // k x k, D A D^T
  Vector p;                      // n, particular solution of b p = -b0
  Vector w;                      // k, reduced accelerations
  Vector tmp_n;                  // n
  Vector tmp_n2;                 // n
  Vector tmp_s;                  // s
  Vector tmp_k;                  // k
  Vector tmp_s2;                 // s
  Vector projection_scale;       // s, ratio of each constraint's gradient to its row of b (compute_projection)
  Matrix bWt;                    // n x s, (b A^(-1/2))^T
  Matrix b_dep;                  // s x s, columns of b of the dependent coordinates
  Matrix b_ind;                  // s x k, columns of b of the independent coordinates
  Matrix X;                      // s x k, b_dep^(-1) b_ind
  std::vector<int> dependent;    // s indices of the dependent coordinates
  std::vector<char> is_dependent;  // n flags
  Eigen::PartialPivLU<Matrix> lu_n;          // n x n
  Eigen::PartialPivLU<Matrix> lu_kkt;        // (n + s) x (n + s)
  Eigen::PartialPivLU<Matrix> lu_s;          // s x s
  Eigen::ColPivHouseholderQR<Matrix> qr_bt;  // n x s
  Eigen::ColPivHouseholderQR<Matrix> qr_b;   // s x n
  Eigen::LLT<Matrix> llt_k;                  // k x k
  Eigen::LLT<Matrix> llt_n;                  // n x n
  Eigen::ColPivHouseholderQR<Matrix> qr_bWt;    // n x s, (b A^(-1/2))^T
};

// Allocates every field of Data for `model` and sets the state to the model's initial state.
// Throws ModelError (check_dense_memory) when its dense matrices would not fit in this machine's
// memory, before allocating anything.
Data make_data(const Model& model);

// Bytes of the dense matrices of a Data for n coordinates and s constraints: about
// 8 (5 n^2 + 2 (n + s)^2 + 6 n s + 2 s^2) (A, M, the KKT matrix and the factorizations).
double dense_data_bytes(int n, int s);

// Throws ModelError when dense_data_bytes(n, s) exceeds `available` bytes, saying how much is
// needed, how much there is, the largest n that fits, and the way out (the sparse path of
// docs/performance.md, or a smaller model).
void check_dense_memory(const Model& model, double available);

// The physical memory of this machine in bytes (0 when the system does not say).
double physical_memory_bytes();

}  // namespace nhdyn
