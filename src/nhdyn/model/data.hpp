// Data: every time-varying value and every piece of scratch memory of one simulation of a Model,
// allocated once by make_data. Kernels (compute_*) read and write it and allocate nothing.
// One Data per thread is the whole thread-safety story. Each field says its size and which
// kernel fills it; `stage` records how far the kernels have got for the current state, so that a
// kernel called out of order says so instead of reading stale values.
//
// One Data serves both paths (docs/design.md, "One Data, dense or sparse inside"). The dense path
// holds A and b as dense matrices; the sparse path, taken for a model compiled sparse
// (Evaluator::sparsity()), holds them as Eigen sparse matrices on the evaluator's pattern
// (A_sparse, b_sparse) and leaves the dense n x n fields empty. make_data chooses the path and
// sizes only the workspace of the path and of the formulation asked for (DataOptions), so that a
// dense Data made for sanh holds no KKT matrix and a sparse Data holds no n x n matrix at all.
#pragma once

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <Eigen/QR>
#include <Eigen/SVD>
#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "nhdyn/core/status.hpp"
#include "nhdyn/core/types.hpp"
#include "nhdyn/model/contact_forces.hpp"
#include "nhdyn/model/contact_modes.hpp"
#include "nhdyn/model/model.hpp"
#include "nhdyn/model/output.hpp"
#include "nhdyn/model/sparse_lu.hpp"

namespace nhdyn {

using SparseLLT = Eigen::SimplicialLLT<SparseMatrix, Eigen::Lower, Eigen::AMDOrdering<int>>;

// The formulations (formulation/formulation.hpp says what each one solves, and kFormulations
// there their names). Declared here, below formulation/, because make_data sizes the workspace of
// the one it is asked for and model/ may not include formulation/ (docs/design.md, "Choices and
// their reasons").
// The option that chooses one keeps its name `method` (--method, method=, [simulation] method).
enum class Formulation { sanh, lagrange, udwadia_kalaba, nullspace };
// The former name of Formulation, kept for C++ users for one release.
using Method [[deprecated("nhdyn::Method is now nhdyn::Formulation")]] = Formulation;

// Which kernels a Data is made for: `automatic` takes the sparse path for a model compiled sparse
// (Evaluator::sparsity() not null) and a formulation that has sparse kernels (sanh, lagrange),
// the dense path otherwise.
enum class Path { automatic, dense, sparse };

struct DataOptions {
  Path path = Path::automatic;
  // The formulation the Data will run. Empty: the workspace of every formulation (dense path),
  // for tools and tests that switch formulations on one Data.
  std::optional<Formulation> method;
  // The KKT workspace of compute_projection (analysis/projection.hpp): (n + s)^2 on the dense
  // path. Always there on the sparse path, where it costs O(nonzeros).
  bool projection = true;
};

// How far the kernels have got for the state (t, q, v) held in Data.
enum class Stage { empty = 0, terms = 1, acceleration = 2 };

// The workspace and results of program motion (formulation/program_motion.hpp,
// docs/derivations/program-motion.md), m programs on n coordinates. Sized by make_data for a model
// with programs (empty otherwise); filled by compute_program_motion and
// compute_program_residuals.
struct ProgramMotionData {
  Matrix b_p;          // m x n, the programs at acceleration level, b_p q'' + b_p0 = 0
  Vector b_p0;         // m, the model's (without feedback)
  Matrix B;            // n x m, the actuator matrix
  Vector feedback;     // m, 2 alpha f_p + beta^2 phi_p added to b_p0 (program feedback, (P6))
  Vector u;            // m, the actuator forces (units of the generalized force of each column of B)
  Vector qdd0;         // n, q''_0: the motion without actuators, M^-1 [D (Q + G); -b0]
  Matrix DB;           // n x m, [D B; 0]
  Matrix PB;           // n x m, P B = M^-1 [D B; 0]
  Matrix S;            // m x m, b_p P B (P4)
  Matrix S_scaled;     // m x m, S with rows scaled by 1/|b_p_i| and columns by 1/|P B_j|
  Vector row_scale;    // m, |b_p_i|
  Vector col_scale;    // m, |P B_j|
  Vector rhs;          // m, -(b_p q''_0 + b_p0 + feedback)
  Eigen::PartialPivLU<Matrix> lu_S;  // m x m
  int absorbed = -1;   // program whose actuator the constraints absorb (D B_j = 0), -1 if none
  // A fixed-step integrator (rk4) may step across a state where S is singular without landing
  // near it: with watch_sign set (by simulate, for rk4), the sign of det S is kept from solve to
  // solve and a change of sign is a singular S crossed between last_t and the failing time.
  bool watch_sign = false;
  int sign = 0;         // sign of det S at the last solve (0: none yet)
  double last_t = 0.0;  // its time
  bool crossed = false; // the failure was a change of sign (explain_program_failure)
  // Residuals (compute_program_residuals): one per position-level program, one per position- or
  // velocity-level program, and all m at acceleration level, b_p q'' + b_p0.
  Vector phi;
  Vector f;
  Vector e;
};

struct Data {
  // --- how this Data was made (make_data) ---------------------------------------------------------
  bool sparse = false;           // the sparse path: A_sparse, b_sparse and the sparse workspace
  std::optional<Formulation> method;  // the formulation sized for; empty: every formulation
  bool projection_workspace = false;  // whether compute_projection may run on this Data

  // --- state, set by compute_terms -------------------------------------------------------------
  double t = 0.0;       // time [s]
  Vector q;             // n coordinates
  Vector v;             // n velocities q'
  Stage stage = Stage::empty;

  // --- terms of the equations (compute_terms, docs/notation.md (2.4), (2.5)) -----------------------
  Matrix A;             // n x n inertia matrix (dense path; 0 x 0 on the sparse path)
  Vector Q;             // n generalized forces
  Vector G;             // n velocity terms
  Matrix b;             // s x n constraint matrix (dense path; 0 x 0 on the sparse path)
  Vector b0;            // s
  SparseMatrix A_sparse;  // n x n on the evaluator's pattern (sparse path; empty on the dense path)
  SparseMatrix b_sparse;  // s x n on the evaluator's pattern (sparse path)
  Vector stabilization; // s, Baumgarte terms 2 alpha f + beta^2 phi (compute_baumgarte_terms)
  Vector b0_model;      // s, the model's b0 while a stabilized one is solved (compute_acceleration)

  // --- complement D (compute_complement; the sparse sanh solve) ----------------------------------
  Matrix D;             // k x n, D b^T = 0 (2.8); 0 x 0 where the formulation needs none
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
  // The energy balance (docs/derivations/energy-balance.md), where the model has one: h (E2)
  // (compute_energy); the power (E3) [W] of the nonconservative forces Q_nc . q', of the
  // reactions R . q' and of the explicit time dependence -dL/dt (compute_power); the work W [J]
  // done by each since t0, integrated along the run (set by simulate at every output).
  double energy_function = 0.0;
  double power_forces = 0.0, power_reactions = 0.0, power_time = 0.0;
  bool power_is_zero = false;  // the evaluator's power_is_zero(), read once by make_data
  double work_forces = 0.0, work_reactions = 0.0, work_time = 0.0;
  // Contacts that slide (contact_modes.hpp): the friction's power -mu_k N |s| (booked apart from
  // power_reactions, which keeps the rest of R . q') and its work since t0 (set by simulate).
  double power_friction = 0.0, work_friction = 0.0;
  // The energy taken by the impacts of touchdowns since t0, h- - h+ summed (set by simulate); W
  // includes -impact_loss.
  double impact_loss = 0.0;
  double balance_error = 0.0;  // h - h(t0) - W, the accuracy figure (set by simulate)
  // Derived outputs (model/output.hpp): their values (compute_outputs) and workspace (make_data).
  OutputData outputs;

  // --- program motion (compute_program_motion; empty for a model without programs) -------------
  ProgramMotionData motion;

  // --- contact forces (compute_contact_forces; inactive for a model without contacts) -----------
  ContactForceData contact;

  // --- contact modes (compute_mode_acceleration; inactive for a model without them) -------------
  ContactModeData modes;

  // --- failure details (set when a kernel returns a non-ok status) --------------------------------
  Status status = Status::ok;
  std::string failed_quantity;  // e.g. "A", "q''": preallocated, see make_data
  double failed_t = 0.0;
  double failed_value = 0.0;    // the residual reached, for Status::projection_failed

  // --- counters ------------------------------------------------------------------------------
  long term_evaluations = 0;     // calls of compute_terms
  long acceleration_solves = 0;  // successful calls of compute_acceleration
  long partition_changes = 0;    // sparse path: times the dependent coordinates were chosen anew

  // --- scratch (owned by the kernels; sizes fixed by make_data) ---------------------------------
  // Fields a formulation does not use are left empty (0 x 0) by make_data.
  // Whether the formulations may take their fixed-size path for small n (formulation/
  // small_dense.hpp). Both paths compute the same values; tests clear it to compare them.
  bool small_kernels = true;
  // The fixed-size finiteness tests of the terms and of q'' and R (core/detail/finite.hpp), set
  // by make_data on the dense path for n <= 8 and s <= n; null: the tests array by array. The
  // terms' test also stores the state (its last two arguments: q and q' here).
  double (*terms_non_finite)(const double*, const double*, const double*, const double*, const double*,
                             const double*, const double*, double*, double*) = nullptr;
  double (*pair_non_finite)(const double*, const double*) = nullptr;
  // Whether compute_complement checks the model's analytic D against b at every evaluation
  // (formulation/complement.hpp): on in debug builds; release builds check D once, at loading.
#ifdef NDEBUG
  bool check_complement = false;
#else
  bool check_complement = true;
#endif
  std::vector<double> scratch;   // evaluator workspace, Evaluator::scratch_size()
  Vector h;                      // n, Q + G
  Matrix M;                      // n x n, stacked sanh matrix [D A; b] (dense sanh)
  Vector rhs;                    // n, stacked right-hand side [D (Q + G); -b0]
  Matrix K;                      // (n + s) x (n + s), KKT matrix (dense lagrange, projection)
  Vector kkt_rhs;                // n + s
  Vector kkt_sol;                // n + s
  Matrix bt;                     // n x s, b^T (QR complement), its rows in the order bt_order
  std::vector<int> bt_order;     // n, the coordinates in the order of bt's rows (and of Q_full's
                                 // after compute_constraint_basis, and in the fixed-size QR): those
                                 // b never touches last (make_data; small_dense.hpp null_space_basis)
  bool bt_in_order = true;       // whether bt_order is 0 .. n-1
  Matrix Q_full;                 // n x n, orthogonal factor of b^T (QR complement, udwadia-kalaba)
  Vector hh_work;                // n, Householder workspace
  Matrix DA;                     // k x n, D A (nullspace)
  Matrix DAD;                    // k x k, D A D^T (nullspace, sparse sanh)
  Matrix AD;                     // n x k, A D^T (sparse sanh)
  Vector p;                      // n, particular solution of b p = -b0
  Vector w;                      // k, reduced accelerations
  Vector tmp_n;                  // n
  Vector tmp_n2;                 // n
  Vector tmp_s;                  // s
  Vector tmp_k;                  // k
  Vector tmp_s2;                 // s
  Vector tmp_s3;                 // s, row scales of b (compute_projection)
  std::vector<char> projection_rows;  // s flags, the constraints a projection step solves (compute_projection)
  Vector projection_scale;       // s, ratio of each constraint's gradient to its row of b (compute_projection)
  Matrix bWt;                    // n x s, (b A^(-1/2))^T (udwadia-kalaba)
  Matrix b_dep;                  // s x s, columns of b of the dependent coordinates (partitioned D)
  Matrix b_ind;                  // s x k, columns of b of the independent coordinates; s x (k + 1)
                                 // on the sparse path, with -b0 as its last column
  Matrix X;                      // s x k, b_dep^(-1) b_ind; s x (k + 1) on the sparse path
  std::vector<int> dependent;    // s indices of the dependent coordinates
  std::vector<char> is_dependent;  // n flags
  Eigen::PartialPivLU<Matrix> lu_n;          // n x n (dense sanh)
  Eigen::PartialPivLU<Matrix> lu_kkt;        // (n + s) x (n + s) (dense lagrange, projection)
  Eigen::PartialPivLU<Matrix> lu_s;          // s x s (partitioned D)
  Eigen::ColPivHouseholderQR<Matrix> qr_bt;  // n x s (QR complement)
  Eigen::ColPivHouseholderQR<Matrix> qr_b;   // s x n (partitioned D)
  Eigen::LLT<Matrix> llt_k;                  // k x k
  Eigen::LLT<Matrix> llt_n;                  // n x n (udwadia-kalaba)
  Eigen::ColPivHouseholderQR<Matrix> qr_bWt;    // n x s, (b A^(-1/2))^T (udwadia-kalaba)

  // --- sparse workspace (sparse path only; make_data analyses every pattern once) ---------------
  SparseMatrix b_dep_sparse;       // s x s, b(:, dependent), values gathered from b_sparse
  std::vector<int> b_dep_source;   // for each value of b_dep_sparse, its index among b_sparse's values
  SparseLuFactor lu_dep;           // b_dep_sparse (KLU: model/sparse_lu.hpp)
  std::unique_ptr<SparseLLT> llt_a;    // A_sparse, for a model without constraints (s = 0)
  SparseMatrix K_sparse;           // (n + s) x (n + s), [A b^T; b C] with C diagonal (0 for lagrange,
                                   // 1 on the rows a projection leaves out)
  std::vector<int> K_source;       // each value of K_sparse: A's index (>= 0), ~b's index, or kKktDiagonal
  SparseLuFactor lu_kkt_sparse;    // K_sparse (KLU: model/sparse_lu.hpp)
};

// The code in Data::K_source of a diagonal entry of the lower right block of K_sparse.
inline constexpr int kKktDiagonal = -(1 << 30);

// Whether make_data(model, options) takes the sparse path. Throws InputError when options ask
// for the sparse path of a model not compiled sparse, or of a formulation without sparse kernels.
bool calc_sparse_path(const Model& model, const DataOptions& options);

// Allocates Data for `model` and the path and formulation of `options`, and sets the state to the
// model's initial state. On the dense path it throws ModelError (check_dense_memory) when the
// dense matrices would not fit in this machine's memory, before allocating anything. On the
// sparse path it evaluates the terms at the initial state and chooses the dependent coordinates
// there (a sparse QR of b with column pivoting); it throws ModelError when a term is not finite
// or b has rank below s there.
Data make_data(const Model& model, const DataOptions& options = {});

// Bytes of the dense matrices of a Data for n coordinates and s constraints with the workspace of
// every formulation: about 8 (5 n^2 + 2 (n + s)^2 + 6 n s + 2 s^2) (A, M, the KKT matrix and the
// factorizations).
double dense_data_bytes(int n, int s);
// The same for the workspace make_data allocates with `options` on the dense path.
double dense_data_bytes(int n, int s, const DataOptions& options);

// Throws ModelError when the dense Data of `options` exceeds `available` bytes, saying how much is
// needed, how much there is, the largest n that fits, and the way out (the sparse path of
// docs/performance.md, or a smaller model).
void check_dense_memory(const Model& model, double available, const DataOptions& options = {});

// The physical memory of this machine in bytes (0 when the system does not say).
double physical_memory_bytes();

// Chooses the dependent coordinates of the sparse path anew at the state held in data (a sparse QR
// of b_sparse with column pivoting) and analyses the pattern of b_dep once more. Cold path: it
// allocates. Returns Status::dependent_constraints when b has rank below s there.
Status compute_sparse_partition(const Model& model, Data& data);

}  // namespace nhdyn
