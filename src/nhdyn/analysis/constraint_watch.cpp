#include "nhdyn/analysis/constraint_watch.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <utility>

namespace nhdyn {
namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// The row norms of b into `out` (s), from the dense b or, on the sparse path, from b_sparse's
// columns: O(nonzeros).
void row_norms(const Data& data, Vector& out) {
  if (!data.sparse) {
    const Eigen::Index s = out.size(), n = data.b.cols();
    const double* b = data.b.data();
    for (Eigen::Index i = 0; i < s; ++i) {
      double sum = 0.0;
      for (Eigen::Index c = 0; c < n; ++c) sum += b[i + s * c] * b[i + s * c];
      out(i) = std::sqrt(sum);
    }
    return;
  }
  out.setZero();
  const SparseMatrix& b = data.b_sparse;
  const double* values = b.valuePtr();
  const int* rows = b.innerIndexPtr();
  for (Eigen::Index j = 0; j < b.outerSize(); ++j)
    for (int m = b.outerIndexPtr()[j]; m < b.outerIndexPtr()[j + 1]; ++m) out(rows[m]) += values[m] * values[m];
  out = out.cwiseSqrt();
}

// Growth or shrinkage of a positive measure, as a factor >= 1; infinite when it is not finite or
// has vanished.
double change_factor(double initial, double value) {
  if (!std::isfinite(value) || !(value > 0.0)) return kInfinity;
  return std::max(value / initial, initial / value);
}

// A lower bound of the smallest singular value of the upper triangle of R's leading m x m block
// (nonzero diagonal): 1 / ||R^-1||_F, column by column of R^-1 through `unit` (m). O(m^3), no
// allocation. 0 when it is not finite.
double smallest_singular_value_bound(const Matrix& R, Eigen::Index m, Vector& unit) {
  double sum = 0.0;
  for (Eigen::Index j = 0; j < m; ++j) {
    // Column j of R^-1 has its nonzeros in rows 0..j: solve with the leading (j+1) block.
    auto x = unit.head(j + 1);
    x.setZero();
    x(j) = 1.0;
    R.topLeftCorner(j + 1, j + 1).triangularView<Eigen::Upper>().solveInPlace(x);
    sum += x.squaredNorm();
  }
  const double bound = 1.0 / std::sqrt(sum);
  return std::isfinite(bound) ? bound : 0.0;
}

// The watched rows (the stacked [D A; b], or b alone), their columns scaled by
// watch.column_scale and then each row to unit norm, into watch.rows, and their squared distance
// from the rows of the last estimate; infinity when a row's norm is not finite. Plain loops over
// the column-major storage: Eigen's dynamic-size product and row expressions cost more in
// dispatch than in arithmetic at the sizes where a step is cheap.
double scale_rows(const Model& model, const Data& data, ConstraintWatch& watch) {
  const int k = model.k();
  const int s = model.s();
  Matrix& rows = watch.rows;
  const Eigen::Index n = rows.cols(), watched = rows.rows();
  const Eigen::Index top = watched - s;
  double* M = rows.data();
  const double* column = watch.column_scale.data();
  if (watch.stacked && k > 0) {
    const double* D = data.D.data();
    const double* A = data.A.data();
    for (Eigen::Index c = 0; c < n; ++c)
      for (Eigen::Index i = 0; i < k; ++i) {
        double acc = 0.0;
        for (Eigen::Index l = 0; l < n; ++l) acc += D[i + k * l] * A[l + n * c];
        M[i + watched * c] = acc * column[c];
      }
  }
  const double* b = data.b.data();
  for (Eigen::Index c = 0; c < n; ++c)
    for (Eigen::Index i = 0; i < s; ++i) M[top + i + watched * c] = b[i + s * c] * column[c];
  const double* estimated = watch.estimated_rows.data();
  double moved = 0.0;
  for (Eigen::Index i = 0; i < watched; ++i) {
    double norm = 0.0;
    for (Eigen::Index c = 0; c < n; ++c) norm += M[i + watched * c] * M[i + watched * c];
    norm = std::sqrt(norm);
    if (!std::isfinite(norm)) return kInfinity;
    const double scale = norm > 0.0 ? norm : 1.0;
    for (Eigen::Index c = 0; c < n; ++c) {
      M[i + watched * c] /= scale;
      const double d = M[i + watched * c] - estimated[i + watched * c];
      moved += d * d;
    }
  }
  return moved;
}

// The rows of the stacked [D A; b] (n x n, column-major, n and s known at compile time), columns
// scaled by `column` and rows to unit norm, into `rows`, and their squared distance from the rows
// of the last estimate: the same operations in the same order as scale_rows above, unrolled, for
// the small models whose steps are cheapest (the sled's watch took a twentieth of its run with
// the loops above). Infinity when a row's norm is not finite.
template <int N, int S>
double scaled_stacked_rows(const double* D, const double* A, const double* b, const double* column,
                           const double* estimated, double* rows) {
  constexpr int K = N - S;
  double moved = 0.0;
  for (int i = 0; i < N; ++i) {
    double row[N];
    double norm = 0.0;
    for (int c = 0; c < N; ++c) {
      double acc = 0.0;
      if (i < K)
        for (int l = 0; l < N; ++l) acc += D[i + K * l] * A[l + N * c];
      else
        acc = b[i - K + S * c];
      row[c] = acc * column[c];
    }
    for (int c = 0; c < N; ++c) norm += row[c] * row[c];
    norm = std::sqrt(norm);
    if (!std::isfinite(norm)) return kInfinity;
    const double scale = norm > 0.0 ? norm : 1.0;
    for (int c = 0; c < N; ++c) {
      rows[i + N * c] = row[c] / scale;
      const double d = rows[i + N * c] - estimated[i + N * c];
      moved += d * d;
    }
  }
  return moved;
}

using ScaledStackedRows = double (*)(const double*, const double*, const double*, const double*, const double*,
                                     double*);
constexpr int kFixedWatchMaxN = 8;

template <int N, int... S>
constexpr void fill_watch_row(std::array<std::array<ScaledStackedRows, kFixedWatchMaxN>, kFixedWatchMaxN + 1>& table,
                              std::integer_sequence<int, S...>) {
  ((table[N][S] = &scaled_stacked_rows<N, S>), ...);
}

// kScaledStackedRows[n][s] for 1 <= n <= 8 and 0 <= s < n (k >= 1); other entries null.
template <int... N>
constexpr std::array<std::array<ScaledStackedRows, kFixedWatchMaxN>, kFixedWatchMaxN + 1> make_watch_table(
    std::integer_sequence<int, N...>) {
  std::array<std::array<ScaledStackedRows, kFixedWatchMaxN>, kFixedWatchMaxN + 1> table{};
  (fill_watch_row<N + 1>(table, std::make_integer_sequence<int, N + 1>{}), ...);
  return table;
}

constexpr auto kScaledStackedRows = make_watch_table(std::make_integer_sequence<int, kFixedWatchMaxN>{});

// The conditioning estimate of the row-scaled watched matrix and the index of its last pivot row.
double stacked_condition(const Model& model, const Data& data, ConstraintWatch& watch, Eigen::Index& last) {
  const int k = model.k();
  const int s = model.s();
  Matrix& rows = watch.rows;
  const Eigen::Index n = rows.cols(), watched = rows.rows();
  double moved = 0.0;  // ||M - M at the last estimate||_F^2, in the same pass as the scaling
  if (watch.stacked && k > 0 && n <= kFixedWatchMaxN && watched == n) {
    moved = kScaledStackedRows[static_cast<std::size_t>(n)][static_cast<std::size_t>(s)](
        data.D.data(), data.A.data(), data.b.data(), watch.column_scale.data(), watch.estimated_rows.data(),
        rows.data());
    if (moved == kInfinity) return kInfinity;
  } else {
    moved = scale_rows(model, data, watch);
    if (moved == kInfinity) return kInfinity;
  }
  if (moved <= watch.reuse_radius * watch.reuse_radius && watch.reuse_radius > 0.0) {
    last = watch.last_pivot;
    return watch.condition;
  }
  ++watch.estimates;
  // The columns in the kinetic energy's metric, 1 / sqrt(A_jj) at this state, the rows to unit
  // norm again: a change of units scales M's columns, and A's diagonal with them, so that the
  // estimate does not follow it. Taken relative to the lightest coordinate, sqrt(A_min / A_jj) <= 1
  // (a factor common to every column changes nothing once the rows are scaled, and the entries
  // then only shrink: a mass of 1e-300 does not overflow a row's norm), and a coordinate without
  // inertia at this state as the lightest. The columns' scales are kept until the next estimate,
  // whose distance `moved` is measured in them.
  double lightest = kInfinity;
  for (Eigen::Index c = 0; c < n; ++c)
    if (const double inertia = data.A(c, c); inertia > 0.0 && inertia < lightest) lightest = inertia;
  for (Eigen::Index c = 0; c < n; ++c) {
    const double inertia = data.A(c, c);
    const double scale =
        inertia > 0.0 && std::isfinite(inertia) && std::isfinite(lightest) ? std::sqrt(lightest / inertia) : 1.0;
    rows.col(c) *= scale / watch.column_scale(c);
    watch.column_scale(c) = scale;
  }
  for (Eigen::Index i = 0; i < watched; ++i) {
    const double norm = rows.row(i).norm();
    if (norm > 0.0 && std::isfinite(norm)) rows.row(i) /= norm;
  }
  watch.rows_t = rows.transpose();
  watch.qr.compute(watch.rows_t);
  const Matrix& R = watch.qr.matrixQR();
  double largest = 0.0;
  double smallest = kInfinity;
  const Eigen::Index m = std::min(R.rows(), R.cols());
  for (Eigen::Index i = 0; i < m; ++i) {
    const double d = std::abs(R(i, i));
    largest = std::max(largest, d);
    smallest = std::min(smallest, d);
  }
  last = watch.qr.colsPermutation().indices()(m - 1);
  watch.last_pivot = last;
  watch.estimated_rows = rows;
  watch.reuse_radius = smallest > 0.0 ? kConditioningReuse * smallest_singular_value_bound(R, m, watch.unit) : 0.0;
  if (!(smallest > 0.0)) return kInfinity;
  return largest / smallest;
}

void record(ConstraintWatch& watch, int constraint, int slot, WatchMeasure measure, double t, double initial,
            double value, double factor) {
  char& flag = watch.warned[static_cast<std::size_t>(slot)];
  if (flag) return;
  flag = 1;
  ConstraintWarning w;
  w.constraint = constraint;
  w.measure = measure;
  w.t = t;
  w.initial = initial;
  w.value = value;
  w.factor = factor;
  watch.warnings.push_back(w);  // within the capacity reserved by make_constraint_watch
}

}  // namespace

ConstraintWatch make_constraint_watch(const Model& model, const Data& data, std::optional<Formulation> method,
                                      double threshold) {
  ConstraintWatch watch;
  watch.threshold = threshold;
  const int n = model.n();
  const int s = model.s();
  const int k = model.k();
  watch.initial_norm = Vector::Zero(s);
  watch.norm = Vector::Zero(s);
  watch.warned.assign(static_cast<std::size_t>(s) + 1, 0);
  watch.warnings.reserve(static_cast<std::size_t>(s) + 1);
  watch.in_use.assign(static_cast<std::size_t>(s), 1);
  watch.conditioning = !data.sparse && s > 0;
  if (watch.conditioning) {
    // D is there, k x n, for the formulations that solve with it (sanh, nullspace). Not with
    // contact modes: the rows their solve keeps change with the modes, and D is the ordinary
    // form's only while every contact rolls (formulation/contact_modes.hpp); b alone is watched.
    watch.stacked = method && (*method == Formulation::sanh || *method == Formulation::nullspace) && data.D.rows() == k &&
                    data.D.cols() == n && !data.modes.active;
    const int watched = watch.stacked ? n : s;
    watch.rows = Matrix::Zero(watched, n);
    watch.rows_t = Matrix::Zero(n, watched);
    watch.qr = Eigen::ColPivHouseholderQR<Matrix>(n, watched);
    watch.estimated_rows = Matrix::Zero(watched, n);
    watch.column_scale = Vector::Ones(n);
    watch.unit = Vector::Zero(watched);
  }
  return watch;
}

namespace {

// The rows of b the contacts' current modes keep (ConstraintWatch::in_use); true when all are.
bool mark_rows_in_use(const Model& model, const Data& data, ConstraintWatch& watch) {
  if (!model.contact_modes || !data.modes.active) return true;
  const std::vector<ContactModeContact>& contacts = model.contact_modes->contacts;
  bool all = true;
  for (int row = 0; row < model.s(); ++row) {
    bool kept = true;
    for (std::size_t c = 0; c < contacts.size() && kept; ++c)
      kept = !contact_mode_drops_row(contacts[c], data.modes.mode[c], row);
    watch.in_use[static_cast<std::size_t>(row)] = kept;
    all = all && kept;
  }
  return all;
}

}  // namespace

void compute_constraint_watch(const Model& model, const Data& data, ConstraintWatch& watch) {
  const int s = model.s();
  if (s == 0) return;
  ++watch.states;
  row_norms(data, watch.norm);
  const bool all_in_use = mark_rows_in_use(model, data, watch);
  Eigen::Index last = 0;
  const bool conditioned = watch.conditioning && all_in_use;
  if (conditioned) watch.condition = stacked_condition(model, data, watch, last);
  if (!watch.started) {
    // The reference: a row that is zero or not finite here was refused before the run began. A
    // row a contact's mode drops (and the conditioning while one is dropped) takes its reference
    // at the first state that keeps it (NaN until then).
    watch.started = true;
    for (int i = 0; i < s; ++i)
      watch.initial_norm(i) = watch.in_use[static_cast<std::size_t>(i)] ? watch.norm(i) : kNaN;
    watch.initial_condition = conditioned ? watch.condition : kNaN;
    return;
  }
  for (int i = 0; i < s; ++i) {
    if (!watch.in_use[static_cast<std::size_t>(i)]) continue;
    if (std::isnan(watch.initial_norm(i))) {
      watch.initial_norm(i) = watch.norm(i);
      continue;
    }
    const double initial = watch.initial_norm(i);
    if (!(initial > 0.0) || !std::isfinite(initial)) continue;
    const double factor = change_factor(initial, watch.norm(i));
    watch.largest_row_factor = std::max(watch.largest_row_factor, factor);
    if (factor >= watch.threshold)
      record(watch, i, i, WatchMeasure::row_norm, data.t, initial, watch.norm(i), factor);
  }
  if (conditioned && std::isnan(watch.initial_condition)) {
    watch.initial_condition = watch.condition;
  } else if (conditioned && watch.initial_condition > 0.0 && std::isfinite(watch.initial_condition)) {
    // Only growth counts: a matrix better conditioned than at the start is no trouble.
    const double factor = std::isfinite(watch.condition) ? watch.condition / watch.initial_condition : kInfinity;
    watch.largest_condition_factor = std::max(watch.largest_condition_factor, factor);
    if (factor >= watch.threshold) {
      // The last pivot: a row of b names its constraint; a row of D A (stacked, index < k) does not.
      const int k = watch.stacked ? model.k() : 0;
      const int row = static_cast<int>(last);
      const int constraint = row >= k ? row - k : -1;
      record(watch, constraint, constraint >= 0 ? constraint : s, WatchMeasure::conditioning, data.t,
             watch.initial_condition, watch.condition, factor);
    }
  }
}

std::string format_constraint_warning(const Model& model, const ConstraintWarning& w) {
  const std::string factor = std::isfinite(w.factor) ? fmt::format("{:.3g}", w.factor) : std::string("infinity");
  if (w.measure == WatchMeasure::row_norm) {
    const std::string& name = model.constraints[static_cast<std::size_t>(w.constraint)].name;
    return fmt::format(
        "constraint '{}': the norm of its row of b went from {:.3g} to {:.3g} (a factor of {}) by t = {:.6g}; its "
        "form is (nearly) singular there (such as tan(phi) at phi = pi/2) and the motion past that point may be "
        "wrong: write it in a form that stays regular (multiply through by cos(phi))",
        name, w.initial, w.value, factor, w.t);
  }
  const std::string who =
      w.constraint >= 0
          ? fmt::format("constraint '{}'", model.constraints[static_cast<std::size_t>(w.constraint)].name)
          : std::string("the complement rows D A");
  return fmt::format(
      "{}: the stacked matrix [D A; b] (its columns in the kinetic energy's metric, its rows scaled to unit norm) "
      "lost conditioning by a factor of {} by t = {:.6g} (estimate {:.3g}, {:.3g} at the start), this row the most "
      "nearly dependent on the others; the constraints are becoming dependent or the coordinates singular there, and "
      "the motion past that point may be wrong",
      who, factor, w.t, w.value, w.initial);
}

}  // namespace nhdyn
