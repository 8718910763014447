// A sparse twin of any model, for the tests of the sparse path without the symbolic compiler: an
// Evaluator that wraps the model's own and reports as structural nonzeros of A and b every entry
// that is nonzero at any of a set of random states (and the diagonal of A). Its sparse_terms
// evaluates the dense terms into its scratch and gathers the nonzeros, so it allocates nothing.
#pragma once

#include <memory>
#include <random>
#include <vector>

#include "nhdyn/model/data.hpp"
#include "nhdyn/model/evaluator.hpp"
#include "nhdyn/model/model.hpp"

namespace nhdyn::testing {

class SparseTwin final : public Evaluator {
 public:
  SparseTwin(std::shared_ptr<const Evaluator> inner, int n, int s, TermsSparsity pattern)
      : inner_(std::move(inner)), n_(n), s_(s), pattern_(std::move(pattern)) {}

  std::size_t scratch_size() const override {
    return inner_->scratch_size() + static_cast<std::size_t>(n_) * static_cast<std::size_t>(n_ + s_);
  }
  void terms(double t, const double* q, const double* v, double* scratch, const TermsOut& out) const override {
    inner_->terms(t, q, v, scratch, out);
  }
  const TermsSparsity* sparsity() const override { return &pattern_; }
  void sparse_terms(double t, const double* q, const double* v, double* scratch, const TermsOut& out) const override {
    double* A = scratch + inner_->scratch_size();
    double* b = A + static_cast<std::size_t>(n_) * static_cast<std::size_t>(n_);
    inner_->terms(t, q, v, scratch, TermsOut{A, out.Q, out.G, b, out.b0});
    gather(pattern_.A, A, out.A);
    gather(pattern_.b, b, out.b);
  }
  bool has_complement() const override { return inner_->has_complement(); }
  void complement(double t, const double* q, const double* v, double* scratch, double* D) const override {
    inner_->complement(t, q, v, scratch, D);
  }
  void position_residual(double t, const double* q, double* scratch, double* phi) const override {
    inner_->position_residual(t, q, scratch, phi);
  }
  void velocity_residual(double t, const double* q, const double* v, double* scratch, double* f) const override {
    inner_->velocity_residual(t, q, v, scratch, f);
  }
  bool has_energy() const override { return inner_->has_energy(); }
  double energy(double t, const double* q, const double* v, double* scratch) const override {
    return inner_->energy(t, q, v, scratch);
  }

 private:
  static void gather(const SparsityPattern& p, const double* dense, double* values) {
    for (int j = 0; j < p.cols; ++j)
      for (int k = p.outer[static_cast<std::size_t>(j)]; k < p.outer[static_cast<std::size_t>(j) + 1]; ++k)
        values[k] = dense[static_cast<std::size_t>(j) * static_cast<std::size_t>(p.rows) +
                          static_cast<std::size_t>(p.inner[static_cast<std::size_t>(k)])];
  }

  std::shared_ptr<const Evaluator> inner_;
  int n_, s_;
  TermsSparsity pattern_;
};

// The model with its evaluator wrapped in a SparseTwin: make_data takes the sparse path for it.
inline Model make_sparse_twin(const Model& model) {
  const int n = model.n(), s = model.s();
  std::vector<char> a_used(static_cast<std::size_t>(n * n), 0), b_used(static_cast<std::size_t>(s * n), 0);
  std::vector<double> scratch(model.evaluator->scratch_size());
  Matrix A(n, n), b(s, n);
  Vector Q(n), G(n), b0(s);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int trial = 0; trial < 20; ++trial) {
    Vector q = model.q0, v = model.v0;
    for (int i = 0; i < n; ++i) {
      q(i) += u(rng);
      v(i) += u(rng);
    }
    model.evaluator->terms(model.t0 + 0.1 * trial, q.data(), v.data(), scratch.data(),
                           TermsOut{A.data(), Q.data(), G.data(), b.data(), b0.data()});
    for (int i = 0; i < n * n; ++i) a_used[static_cast<std::size_t>(i)] |= A.data()[i] != 0.0;
    for (int i = 0; i < s * n; ++i) b_used[static_cast<std::size_t>(i)] |= b.data()[i] != 0.0;
  }
  for (int i = 0; i < n; ++i) a_used[static_cast<std::size_t>(i * n + i)] = 1;
  const auto pattern = [](const std::vector<char>& used, int rows, int cols) {
    SparsityPattern p;
    p.rows = rows;
    p.cols = cols;
    p.outer.push_back(0);
    for (int j = 0; j < cols; ++j) {
      for (int i = 0; i < rows; ++i)
        if (used[static_cast<std::size_t>(j * rows + i)]) p.inner.push_back(i);
      p.outer.push_back(static_cast<int>(p.inner.size()));
    }
    return p;
  };
  Model twin = model;
  twin.evaluator = std::make_shared<SparseTwin>(model.evaluator, n, s,
                                                TermsSparsity{pattern(a_used, n, n), pattern(b_used, s, n)});
  return twin;
}

}  // namespace nhdyn::testing
