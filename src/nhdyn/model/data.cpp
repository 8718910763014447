#include "nhdyn/model/data.hpp"

#include "nhdyn/core/detail/finite.hpp"

#include <fmt/format.h>
#include <unistd.h>

#include <Eigen/OrderingMethods>
#include <Eigen/SparseQR>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>

#include "nhdyn/core/error.hpp"

namespace nhdyn {
namespace {

// What the dense workspace holds for one choice of options.
struct DenseWorkspace {
  bool stacked = false;     // dense sanh: M, rhs, lu_n
  bool complement = false;  // D and the QR and partition workspaces
  bool kkt = false;         // K, lu_kkt (lagrange, projection)
  bool gauss = false;       // udwadia-kalaba: llt_n, bWt, qr_bWt
  bool reduced = false;     // nullspace: DA, DAD, llt_k
  bool orthogonal = false;  // Q_full (QR complement, udwadia-kalaba)
};

DenseWorkspace dense_workspace(const DataOptions& options) {
  DenseWorkspace w;
  const auto wants = [&](Formulation m) { return !options.method || *options.method == m; };
  w.stacked = wants(Formulation::sanh);
  w.complement = wants(Formulation::sanh) || wants(Formulation::nullspace);
  w.kkt = wants(Formulation::lagrange) || options.projection;
  w.gauss = wants(Formulation::udwadia_kalaba);
  w.reduced = wants(Formulation::nullspace);
  w.orthogonal = w.complement || w.gauss;
  return w;
}

std::string methods_with_sparse_kernels() { return "sanh, lagrange"; }

const char* method_label(Formulation m) {
  switch (m) {
    case Formulation::sanh: return "sanh";
    case Formulation::lagrange: return "lagrange";
    case Formulation::udwadia_kalaba: return "udwadia-kalaba";
    case Formulation::nullspace: return "nullspace";
  }
  return "?";
}

bool has_sparse_kernels(Formulation m) { return m == Formulation::sanh || m == Formulation::lagrange; }

// A sparse matrix on `pattern` (values zero), built without triplets: the pattern is already in
// compressed columns.
SparseMatrix on_pattern(const SparsityPattern& pattern) {
  SparseMatrix m(pattern.rows, pattern.cols);
  m.resizeNonZeros(pattern.nonzeros());
  std::copy(pattern.outer.begin(), pattern.outer.end(), m.outerIndexPtr());
  std::copy(pattern.inner.begin(), pattern.inner.end(), m.innerIndexPtr());
  std::fill(m.valuePtr(), m.valuePtr() + pattern.nonzeros(), 0.0);
  return m;
}

Data make_dense_data(const Model& model, const DataOptions& options) {
  check_dense_memory(model, physical_memory_bytes(), options);
  const int n = model.n();
  const int s = model.s();
  const int k = model.k();
  const DenseWorkspace use = dense_workspace(options);
  const auto sized = [](bool used, int rows, int cols) { return used ? Matrix::Zero(rows, cols) : Matrix(0, 0); };
  Data d;
  d.A = Matrix::Zero(n, n);
  d.b = Matrix::Zero(s, n);
  d.D = sized(use.complement, k, n);
  d.M = sized(use.stacked, n, n);
  d.rhs = Vector::Zero(n);
  d.K = sized(use.kkt, n + s, n + s);
  d.bt = sized(use.complement, n, s);
  d.bt_order.assign(use.complement ? static_cast<std::size_t>(n) : 0, 0);
  d.Q_full = sized(use.orthogonal, n, n);
  d.DA = sized(use.reduced, k, n);
  d.DAD = sized(use.reduced, k, k);
  d.bWt = sized(use.gauss, n, s);
  d.b_dep = sized(use.complement, s, s);
  d.b_ind = sized(use.complement, s, k);
  d.X = sized(use.complement, s, k);
  d.lu_n = Eigen::PartialPivLU<Matrix>(use.stacked ? n : 0);
  d.lu_kkt = Eigen::PartialPivLU<Matrix>(use.kkt ? n + s : 0);
  d.lu_s = Eigen::PartialPivLU<Matrix>(use.complement ? s : 0);
  d.qr_bt = Eigen::ColPivHouseholderQR<Matrix>(use.complement ? n : 0, use.complement ? s : 0);
  d.qr_b = Eigen::ColPivHouseholderQR<Matrix>(use.complement ? s : 0, use.complement ? n : 0);
  // Factor an identity once rather than assign a default-constructed LLT, whose status is
  // uninitialized (copying it is undefined behaviour); the storage is sized either way.
  d.llt_k.compute(Matrix::Identity(use.reduced ? k : 0, use.reduced ? k : 0));
  d.llt_n.compute(Matrix::Identity(use.gauss ? n : 0, use.gauss ? n : 0));
  d.qr_bWt = Eigen::ColPivHouseholderQR<Matrix>(use.gauss ? n : 0, use.gauss ? s : 0);
  d.projection_workspace = use.kkt;
  return d;
}

// The dependent coordinates: the first s columns of a sparse QR of b with column pivoting (Eigen
// moves columns whose remaining norm is negligible to the end). Empty when b has rank below s.
bool choose_dependent(const SparseMatrix& b, std::vector<int>& dependent, long& rank) {
  const int s = static_cast<int>(b.rows());
  dependent.clear();
  rank = 0;
  if (s == 0) return true;
  Eigen::SparseQR<SparseMatrix, Eigen::COLAMDOrdering<int>> qr;
  qr.compute(b);
  if (qr.info() != Eigen::Success) return false;
  rank = qr.rank();
  if (rank < s) return false;
  const auto& permutation = qr.colsPermutation().indices();
  for (int i = 0; i < s; ++i) dependent.push_back(permutation[i]);
  std::sort(dependent.begin(), dependent.end());
  return true;
}

Data make_sparse_data(const Model& model) {
  const TermsSparsity& sparsity = *model.evaluator->sparsity();
  const int n = model.n(), s = model.s(), k = model.k();
  // Only D (k x n), A D^T (n x k) and D A D^T (k x k) are dense: small for few degrees of freedom.
  const double dense_bytes = 8.0 * (2.0 * k * n + double(k) * k + 2.0 * s * (k + 1.0));
  const double available = physical_memory_bytes();
  if (s > 0 && available > 0.0 && dense_bytes > available)
    throw ModelError(fmt::format(
        "model '{}': the sparse sanh solve keeps D (k x n) and D A D^T (k x k) dense, {:.3g} GB for k = {} degrees "
        "of freedom and n = {} coordinates, more than this machine's {:.3g} GB; use --method lagrange (a sparse "
        "KKT solve)",
        model.name, dense_bytes / 1e9, k, n, available / 1e9));
  Data d;
  d.sparse = true;
  d.projection_workspace = true;
  d.A = Matrix(0, 0);
  d.b = Matrix(0, 0);
  d.A_sparse = on_pattern(sparsity.A);
  d.b_sparse = on_pattern(sparsity.b);
  d.rhs = Vector(0);
  if (s > 0) {
    d.D = Matrix::Zero(k, n);
    d.AD = Matrix::Zero(n, k);
    d.DAD = Matrix::Zero(k, k);
    d.llt_k.compute(Matrix::Identity(k, k));  // sized; see make_dense_data
    d.b_ind = Matrix::Zero(s, k + 1);
    d.X = Matrix::Zero(s, k + 1);
  } else {
    d.llt_a = std::make_unique<SparseLLT>();
    d.llt_a->analyzePattern(d.A_sparse);
  }
  // KKT pattern [A b^T; b C], C diagonal: each value's source is A's index (>= 0), ~b's index, or
  // kKktDiagonal.
  {
    std::vector<Eigen::Triplet<double, int>> entries;
    for (int j = 0; j < n; ++j) {
      for (int m = d.A_sparse.outerIndexPtr()[j]; m < d.A_sparse.outerIndexPtr()[j + 1]; ++m)
        entries.emplace_back(d.A_sparse.innerIndexPtr()[m], j, static_cast<double>(m));
      for (int m = d.b_sparse.outerIndexPtr()[j]; m < d.b_sparse.outerIndexPtr()[j + 1]; ++m) {
        const int r = d.b_sparse.innerIndexPtr()[m];
        entries.emplace_back(n + r, j, static_cast<double>(~m));  // b
        entries.emplace_back(j, n + r, static_cast<double>(~m));  // b^T
      }
    }
    for (int i = 0; i < s; ++i) entries.emplace_back(n + i, n + i, static_cast<double>(kKktDiagonal));
    d.K_sparse.resize(n + s, n + s);
    d.K_sparse.setFromTriplets(entries.begin(), entries.end());
    d.K_source.resize(static_cast<std::size_t>(d.K_sparse.nonZeros()));
    for (int m = 0; m < d.K_sparse.nonZeros(); ++m)
      d.K_source[static_cast<std::size_t>(m)] = static_cast<int>(d.K_sparse.valuePtr()[m]);
    d.lu_kkt_sparse.analyze(d.K_sparse);
  }
  return d;
}

}  // namespace

bool calc_sparse_path(const Model& model, const DataOptions& options) {
  const bool compiled_sparse = model.evaluator && model.evaluator->sparsity() != nullptr;
  switch (options.path) {
    case Path::dense: return false;
    case Path::automatic:
      // Program motion has dense kernels only (formulation/program_motion.hpp).
      return compiled_sparse && model.m() == 0 && (!options.method || has_sparse_kernels(*options.method));
    case Path::sparse:
      if (model.m() > 0)
        throw InputError(fmt::format("model '{}' has programs ([[programs]]), which are solved on the dense path only; "
                                     "take the dense path", model.name));
      if (!compiled_sparse)
        throw InputError(fmt::format("model '{}' was not compiled sparse, so it has no sparse path; compile it with "
                                     "TermsLayout::sparse (symbolic/compile.hpp) or take the dense path",
                                     model.name));
      if (options.method && !has_sparse_kernels(*options.method))
        throw InputError(fmt::format("the {} formulation has no sparse kernels; on the sparse path use one of: {}",
                                     method_label(*options.method), methods_with_sparse_kernels()));
      return true;
  }
  return false;
}

double dense_data_bytes(int n, int s) {
  const double dn = n, ds = s;
  return 8.0 * (5.0 * dn * dn + 2.0 * (dn + ds) * (dn + ds) + 6.0 * dn * ds + 2.0 * ds * ds);
}

double dense_data_bytes(int n, int s, const DataOptions& options) {
  if (!options.method && options.projection) return dense_data_bytes(n, s);
  const DenseWorkspace use = dense_workspace(options);
  const double dn = n, ds = s, dk = n - s;
  double entries = dn * dn + ds * dn;  // A, b
  if (use.stacked) entries += 2.0 * dn * dn;                               // M, lu_n
  if (use.complement) entries += dk * dn + 3.0 * dn * ds + 3.0 * ds * ds + 2.0 * ds * dk;  // D, bt, qr_bt, qr_b, b_dep, lu_s, b_ind, X
  if (use.kkt) entries += 2.0 * (dn + ds) * (dn + ds);                     // K, lu_kkt
  if (use.gauss) entries += dn * dn + 2.0 * dn * ds;                       // llt_n, bWt, qr_bWt
  if (use.reduced) entries += dk * dn + 2.0 * dk * dk;                     // DA, DAD, llt_k
  if (use.orthogonal) entries += dn * dn;                                  // Q_full
  return 8.0 * entries;
}

double physical_memory_bytes() {
  // Asked once a process: each make_data wants it, and the question is a system call (sysinfo),
  // a tenth of a small model's short run.
  static const double bytes = [] {
    const long pages = sysconf(_SC_PHYS_PAGES);
    const long page_size = sysconf(_SC_PAGESIZE);
    return pages > 0 && page_size > 0 ? static_cast<double>(pages) * static_cast<double>(page_size) : 0.0;
  }();
  return bytes;
}

void check_dense_memory(const Model& model, double available, const DataOptions& options) {
  const int n = model.n(), s = model.s();
  const double needed = dense_data_bytes(n, s, options);
  if (available <= 0.0 || needed <= available) return;
  // The largest n that fits with the same ratio s / n.
  const double ratio = static_cast<double>(s) / n;
  const double per_n2 = dense_data_bytes(1000, static_cast<int>(std::lround(1000 * ratio)), options) / 1e6;
  const double largest = std::floor(std::sqrt(available / per_n2));
  constexpr double GB = 1e9;
  const bool sparse_possible = model.evaluator && model.evaluator->sparsity() != nullptr;
  throw ModelError(fmt::format(
      "model '{}' is too large for the dense solvers: with n = {} coordinates and s = {} constraints a "
      "simulation's dense matrices need {:.3g} GB (about 8 (5 n^2 + 2 (n + s)^2 + 6 n s + 2 s^2) bytes with every "
      "formulation's workspace), and this machine has {:.3g} GB; the limit here is about n = {:.0f} coordinates. {}",
      model.name, n, s, needed / GB, available / GB, largest,
      sparse_possible ? "Use a formulation with sparse kernels (--method sanh or lagrange: the sparse path of "
                        "docs/performance.md) or a smaller model"
                      : "Use the sparse path (a model compiled sparse, docs/performance.md) or a smaller model"));
}

namespace {

// Makes `dependent` (s ascending coordinate indices) the partition of data: the flags, the
// independent coordinates, the pattern of b_dep with the source of each value among b's values,
// and its symbolic analysis.
void install_partition(const Model& model, Data& data, std::vector<int> dependent) {
  const int n = model.n(), s = model.s();
  std::sort(dependent.begin(), dependent.end());
  data.dependent = std::move(dependent);
  data.is_dependent.assign(static_cast<std::size_t>(n), 0);
  data.independent.clear();
  for (int j : data.dependent) data.is_dependent[static_cast<std::size_t>(j)] = 1;
  for (int j = 0; j < n; ++j)
    if (!data.is_dependent[static_cast<std::size_t>(j)]) data.independent.push_back(j);
  std::vector<Eigen::Triplet<double, int>> entries;
  for (int jj = 0; jj < s; ++jj) {
    const int j = data.dependent[static_cast<std::size_t>(jj)];
    for (int m = data.b_sparse.outerIndexPtr()[j]; m < data.b_sparse.outerIndexPtr()[j + 1]; ++m)
      entries.emplace_back(data.b_sparse.innerIndexPtr()[m], jj, static_cast<double>(m));
  }
  data.b_dep_sparse.resize(s, s);
  data.b_dep_sparse.setFromTriplets(entries.begin(), entries.end());
  data.b_dep_source.resize(static_cast<std::size_t>(data.b_dep_sparse.nonZeros()));
  for (int m = 0; m < data.b_dep_sparse.nonZeros(); ++m)
    data.b_dep_source[static_cast<std::size_t>(m)] = static_cast<int>(data.b_dep_sparse.valuePtr()[m]);
  data.lu_dep.analyze(data.b_dep_sparse);
}

// The independent coordinates that keep X = b_dep^-1 b_ind small: the first k pivots of a
// column-pivoted QR of a basis Z (n x k) of null(b). A sparse QR of b chooses its columns for
// fill-in, not size: on the chain it makes the last body's heading independent, and the lead's then
// follows from it with a factor (f/r)^(N-1), which overflows at N = 1000. Z comes without such
// factors from k KKT solves, [A b^T; b 0] [z; mu] = [A g; 0]: z is the A-orthogonal projection of g
// onto null(b), for k fixed pseudo-random g (generated from integers, so the same on every
// platform). Returns false, leaving the partition as it is, when the KKT matrix is singular.
bool choose_by_null_space(const Model& model, Data& data) {
  const int n = model.n(), s = model.s(), k = model.k();
  if (k == 0) return true;
  const double* a_values = data.A_sparse.valuePtr();
  const double* b_values = data.b_sparse.valuePtr();
  double* k_values = data.K_sparse.valuePtr();
  for (std::size_t m = 0; m < data.K_source.size(); ++m) {
    const int source = data.K_source[m];
    k_values[m] = source == kKktDiagonal ? 0.0 : source >= 0 ? a_values[source] : b_values[~source];
  }
  if (!data.lu_kkt_sparse.factorize(data.K_sparse)) return false;
  Matrix Z(k, n);
  Vector g(n), rhs = Vector::Zero(n + s);
  std::uint64_t state = 0x9e3779b97f4a7c15ULL;
  for (int r = 0; r < k; ++r) {
    for (int i = 0; i < n; ++i) {
      state = state * 6364136223846793005ULL + 1442695040888963407ULL;  // Knuth's MMIX generator
      g(i) = static_cast<double>(state >> 11) * 0x1.0p-53 - 0.5;
    }
    rhs.head(n) = data.A_sparse * g;
    Vector sol = rhs;
    data.lu_kkt_sparse.solve_in_place(sol);
    if (!sol.allFinite()) return false;
    Z.row(r) = sol.head(n).transpose();
  }
  Eigen::ColPivHouseholderQR<Matrix> qr(Z);
  if (qr.rank() < k) return false;
  std::vector<int> dependent;
  for (int i = k; i < n; ++i) dependent.push_back(qr.colsPermutation().indices()(i));
  std::vector<int> previous = data.dependent;
  install_partition(model, data, std::move(dependent));
  // The chosen b_dep must be nonsingular (it is, when Z spans null(b)); else back to the first.
  const double* values = data.b_sparse.valuePtr();
  double* dep_values = data.b_dep_sparse.valuePtr();
  for (std::size_t m = 0; m < data.b_dep_source.size(); ++m) dep_values[m] = values[data.b_dep_source[m]];
  if (!data.lu_dep.factorize(data.b_dep_sparse)) {
    install_partition(model, data, std::move(previous));
    return false;
  }
  return true;
}

}  // namespace

Status compute_sparse_partition(const Model& model, Data& data) {
  if (!data.sparse || model.s() == 0) return Status::ok;
  std::vector<int> dependent;
  long rank = 0;
  if (!choose_dependent(data.b_sparse, dependent, rank)) {
    data.status = Status::dependent_constraints;
    data.failed_quantity.assign("constraint matrix b");
    data.failed_t = data.t;
    return Status::dependent_constraints;
  }
  install_partition(model, data, std::move(dependent));
  choose_by_null_space(model, data);
  ++data.partition_changes;
  return Status::ok;
}

namespace {

// Data::bt_order: the coordinates whose column of b is zero at two generic states (t, q and q'
// away from the round values where entries vanish by accident, sin(0), a coordinate at rest) go
// last, each group in its own order; a column with a NaN counts as touched. The order depends on
// the model alone, so that a run's D, and its results to the bit, do not depend on which state
// a Data saw first. Cold path.
void order_untouched_coordinates_last(const Model& model, Data& d) {
  const int n = model.n();
  const int s = model.s();
  std::vector<char> touched(static_cast<std::size_t>(n), 0);
  Vector q(n), v(n);
  for (int pass = 0; pass < 2; ++pass) {
    for (int j = 0; j < n; ++j) {
      // Other increments in the second pass, so that no difference q_i - q_j is the same in both.
      q(j) = 0.3183 + 0.1077 * j + pass * (0.2371 + 0.0413 * j);
      v(j) = 0.4142 - 0.0931 * j + pass * (0.1713 - 0.0279 * j);
    }
    const TermsOut out{d.A.data(), d.Q.data(), d.G.data(), d.b.data(), d.b0.data()};
    try {
      model.evaluator->terms(model.t0 + 0.5772 + 0.3010 * pass, q.data(), v.data(), d.scratch.data(), out);
    } catch (const std::exception&) {
      // An evaluator that refuses such a state: every order is a valid one, keep q's own.
      std::fill(touched.begin(), touched.end(), 1);
      break;
    }
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < s; ++i) touched[static_cast<std::size_t>(j)] |= static_cast<char>(!(d.b(i, j) == 0.0));
  }
  int next = 0;
  for (const char group : {1, 0})
    for (int j = 0; j < n; ++j)
      if (touched[static_cast<std::size_t>(j)] == group) d.bt_order[static_cast<std::size_t>(next++)] = j;
  d.bt_in_order = true;
  for (int j = 0; j < n; ++j) d.bt_in_order = d.bt_in_order && d.bt_order[static_cast<std::size_t>(j)] == j;
  d.A.setZero();
  d.Q.setZero();
  d.G.setZero();
  d.b.setZero();
  d.b0.setZero();
}

}  // namespace

Data make_data(const Model& model, const DataOptions& options) {
  check_model_shape(model);
  const bool sparse = calc_sparse_path(model, options);
  Data d = sparse ? make_sparse_data(model) : make_dense_data(model, options);
  const int n = model.n();
  const int s = model.s();
  const int k = model.k();
  d.method = options.method;
  d.t = model.t0;
  d.q = model.q0;
  d.v = model.v0;
  d.Q = Vector::Zero(n);
  d.G = Vector::Zero(n);
  d.b0 = Vector::Zero(s);
  d.stabilization = Vector::Zero(s);
  d.b0_model = Vector::Zero(s);
  d.independent.assign(static_cast<std::size_t>(k), 0);
  d.qdd = Vector::Zero(n);
  d.R = Vector::Zero(n);
  d.lambda = Vector::Zero(s);
  d.phi = Vector::Zero(model.position_constraints());
  d.f = Vector::Zero(model.velocity_constraints());
  d.e = Vector::Zero(s);
  // Long enough for every quantity name the kernels report, so that setting it never allocates.
  d.failed_quantity.reserve(64);
  d.scratch.assign(model.evaluator->scratch_size(), 0.0);
  d.power_is_zero = model.evaluator->power_is_zero();
  d.outputs = make_output_data(model);
  d.h = Vector::Zero(n);
  d.kkt_rhs = Vector::Zero(n + s);
  d.kkt_sol = Vector::Zero(n + s);
  d.hh_work = Vector::Zero(n);
  d.p = Vector::Zero(n);
  d.w = Vector::Zero(k);
  d.tmp_n = Vector::Zero(n);
  d.tmp_n2 = Vector::Zero(n);
  d.tmp_s = Vector::Zero(s);
  d.tmp_k = Vector::Zero(k);
  d.tmp_s2 = Vector::Zero(s);
  d.tmp_s3 = Vector::Zero(s);
  d.projection_scale = Vector::Ones(s);
  d.projection_rows.assign(static_cast<std::size_t>(s), 0);
  d.dependent.assign(static_cast<std::size_t>(s), 0);
  d.is_dependent.assign(static_cast<std::size_t>(n), 0);
  d.contact = make_contact_force_data(model);
  d.modes = make_contact_mode_data(model);
  if (!sparse) {
    d.terms_non_finite = find_terms_non_finite(n, s);
    d.pair_non_finite = find_pair_non_finite(n);
    if (s > 0 && d.bt_order.size() == static_cast<std::size_t>(n)) order_untouched_coordinates_last(model, d);
  }
  if (const int m = model.m(); m > 0) {
    ProgramMotionData& w = d.motion;
    w.b_p = Matrix::Zero(m, n);
    w.b_p0 = Vector::Zero(m);
    w.B = Matrix::Zero(n, m);
    w.feedback = Vector::Zero(m);
    w.u = Vector::Zero(m);
    w.qdd0 = Vector::Zero(n);
    w.DB = Matrix::Zero(n, m);
    w.PB = Matrix::Zero(n, m);
    w.S = Matrix::Zero(m, m);
    w.S_scaled = Matrix::Zero(m, m);
    w.row_scale = Vector::Zero(m);
    w.col_scale = Vector::Zero(m);
    w.rhs = Vector::Zero(m);
    w.lu_S = Eigen::PartialPivLU<Matrix>(m);
    w.phi = Vector::Zero(model.position_programs());
    w.f = Vector::Zero(model.velocity_programs());
    w.e = Vector::Zero(m);
  }
  if (sparse) {
    // The terms at the initial state, and the dependent coordinates chosen there.
    const TermsOut out{d.A_sparse.valuePtr(), d.Q.data(), d.G.data(), d.b_sparse.valuePtr(), d.b0.data()};
    model.evaluator->sparse_terms(d.t, d.q.data(), d.v.data(), d.scratch.data(), out);
    const auto finite = [](const double* x, Eigen::Index size) { return Eigen::Map<const Vector>(x, size).allFinite(); };
    const char* bad = !finite(d.A_sparse.valuePtr(), d.A_sparse.nonZeros()) ? "inertia matrix A"
                      : !d.Q.allFinite()                                     ? "generalized forces Q"
                      : !d.G.allFinite()                                     ? "velocity terms G"
                      : !finite(d.b_sparse.valuePtr(), d.b_sparse.nonZeros()) ? "constraint matrix b"
                      : !d.b0.allFinite()                                    ? "constraint term b0"
                                                                             : nullptr;
    if (bad != nullptr)
      throw ModelError(fmt::format("model '{}': the {} is not finite at the initial state", model.name, bad));
    if (compute_sparse_partition(model, d) != Status::ok)
      throw ModelError(fmt::format(
          "model '{}': the constraint matrix b has rank below s = {} at the initial state; the constraints are not "
          "independent there, so no coordinates can be chosen as dependent (check the initial state and the "
          "constraints)",
          model.name, s));
    d.partition_changes = 0;
  }
  return d;
}

}  // namespace nhdyn
