// The acceleration solve allocates nothing after Data exists: every formulation and every choice
// of D is run once, then again under a counting global operator new that must stay at zero. On
// the sparse path (the built-in models' sparse twins, formulation/sparse_twin.hpp) the terms,
// residuals, energy and Baumgarte's terms allocate nothing, and neither do sanh's and lagrange's
// solves (KLU refactorizes b_dep and the KKT matrix in the memory of their first factorization).
#include <gtest/gtest.h>

#include "support/address_sanitizer.hpp"

#include <atomic>
#include <cstdlib>
#include <new>
#include <vector>

#include "formulation/sled_heading.hpp"
#include "formulation/sparse_twin.hpp"
#include "nhdyn/analysis/constraint_watch.hpp"
#include "nhdyn/analysis/projection.hpp"
#include "nhdyn/analysis/residuals.hpp"
#include "nhdyn/formulation/baumgarte.hpp"
#include "nhdyn/model/terms.hpp"
#include "nhdyn/formulation/formulation.hpp"
#include "nhdyn/formulation/program_motion.hpp"
#include "nhdyn/model/appell.hpp"
#include "nhdyn/model/sled.hpp"

namespace {
std::atomic<long> g_allocations{0};
std::atomic<bool> g_counting{false};
void count() {
  if (g_counting.load(std::memory_order_relaxed)) g_allocations.fetch_add(1, std::memory_order_relaxed);
}
}  // namespace

#if defined(NHDYN_ADDRESS_SANITIZER)
// GCC 12 sees gtest's `new T` inlined next to these definitions and reports the free() as a
// mismatched deallocation: it is not (every operator new here is malloc).
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic ignored "-Wmismatched-new-delete"
#endif
// AddressSanitizer owns malloc; count at operator new, which sees the standard containers
// (Eigen allocates through malloc, so the release build below is the complete check).
void* operator new(std::size_t size) {
  count();
  if (void* p = std::malloc(size == 0 ? 1 : size)) return p;
  throw std::bad_alloc();
}
void* operator new[](std::size_t size) { return ::operator new(size); }
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }
constexpr bool kCountsMalloc = false;
#else
// Eigen allocates with malloc, not operator new, so the count sits at malloc itself: these
// definitions interpose glibc's for the whole executable, library code included.
extern "C" {
void* __libc_malloc(std::size_t);
void* __libc_calloc(std::size_t, std::size_t);
void* __libc_realloc(void*, std::size_t);
void* __libc_memalign(std::size_t, std::size_t);
void __libc_free(void*);
void* malloc(std::size_t size) {
  count();
  return __libc_malloc(size);
}
void* calloc(std::size_t n, std::size_t size) {
  count();
  return __libc_calloc(n, size);
}
void* realloc(void* p, std::size_t size) {
  count();
  return __libc_realloc(p, size);
}
void* memalign(std::size_t alignment, std::size_t size) {
  count();
  return __libc_memalign(alignment, size);
}
void* aligned_alloc(std::size_t alignment, std::size_t size) {
  count();
  return __libc_memalign(alignment, size);
}
int posix_memalign(void** out, std::size_t alignment, std::size_t size) {
  count();
  *out = __libc_memalign(alignment, size);
  return *out ? 0 : 12;  // ENOMEM
}
void free(void* p) { __libc_free(p); }
}
constexpr bool kCountsMalloc = true;
#endif

namespace nhdyn {
namespace {

TEST(Allocation, AccelerationSolveAllocatesNothingAfterTheFirstCall) {
  for (const Model& model : {make_sled_model(), make_sled_model(SledVariant::paper), make_appell_model()}) {
    Data data = make_data(model);
    for (Formulation m : {Formulation::sanh, Formulation::lagrange, Formulation::udwadia_kalaba, Formulation::nullspace})
      for (Complement c : {Complement::qr, Complement::partition, Complement::analytic}) {
        Vector q(3), v(3);
        q << 0.1, 0.2, 0.3;
        v << 0.5, 0.6, 0.7;
        const FormulationOptions options{m, c};
        ASSERT_EQ(compute_dynamics(model, data, options, 0.0, q.data(), v.data()), Status::ok);
        g_allocations = 0;
        g_counting = true;
        for (int i = 0; i < 10; ++i) {
          q(2) += 0.01;
          v(0) += 0.01;
          compute_dynamics(model, data, options, 0.1 * i, q.data(), v.data());
          compute_residuals(model, data);
          compute_energy(model, data);
        }
        g_counting = false;
        EXPECT_EQ(g_allocations.load(), 0) << model.name << " " << formulation_name(m) << "/" << complement_name(c);
      }
  }
}

TEST(Allocation, ProgramMotionAllocatesNothingAfterTheFirstCall) {
  const Model model = testing::make_sled_heading_model();
  Data data = make_data(model, {Path::automatic, Formulation::sanh});
  const double q[3] = {0.1, -0.2, 0.3}, v[3] = {0.9, 0.1, 1.1};
  for (Complement c : {Complement::qr, Complement::partition, Complement::analytic}) {
    for (bool feedback : {false, true}) {
      FormulationOptions options{Formulation::sanh, c};
      options.program_feedback = {feedback, 2.0, 3.0};
      ASSERT_EQ(compute_dynamics(model, data, options, 0.5, q, v), Status::ok);
      compute_program_residuals(model, data);
      g_allocations = 0;
      g_counting = true;
      const Status status = compute_dynamics(model, data, options, 0.5, q, v);
      compute_residuals(model, data);
      compute_program_residuals(model, data);
      g_counting = false;
      ASSERT_EQ(status, Status::ok);
      EXPECT_EQ(g_allocations.load(), 0) << complement_name(c) << (feedback ? " with feedback" : "");
    }
  }
}

TEST(Allocation, StabilizationAllocatesNothing) {
  // Baumgarte inside the solve, and projection of states that are off the constraints (Appell's
  // scaled row takes several Newton steps with the forward-difference factor).
  for (const Model& model : {make_sled_model(), make_appell_model()}) {
    Data data = make_data(model);
    FormulationOptions options{Formulation::sanh, Complement::qr};
    options.baumgarte.enabled = true;
    Vector q(3), v(3);
    q << 0.1, 0.2, 0.3;
    v << 0.5, 0.6, 0.7;
    ASSERT_EQ(compute_dynamics(model, data, options, 0.0, q.data(), v.data()), Status::ok);
    ProjectionResult result;
    ASSERT_EQ(compute_projection(model, data, 0.0, q.data(), v.data(), ProjectionOptions{}, result), Status::ok);
    g_allocations = 0;
    g_counting = true;
    long iterations = 0;
    for (int i = 0; i < 10; ++i) {
      v(0) += 0.01;
      v(2) += 0.02;
      compute_dynamics(model, data, options, 0.1 * i, q.data(), v.data());
      compute_projection(model, data, 0.1 * i, q.data(), v.data(), ProjectionOptions{}, result);
      iterations += result.velocity_iterations;
    }
    g_counting = false;
    EXPECT_EQ(g_allocations.load(), 0) << model.name;
    EXPECT_GE(iterations, 10) << model.name << ": the projections had nothing to do";
  }
}

template <class F>
long count_allocations(F&& f) {
  g_allocations = 0;
  g_counting = true;
  f();
  g_counting = false;
  return g_allocations.load();
}

TEST(Allocation, SparsePathAllocatesOnlyInsideItsSparseFactorizations) {
  for (const Model& dense_model : {make_sled_model(), make_sled_model(SledVariant::paper), make_appell_model()}) {
    const Model model = testing::make_sparse_twin(dense_model);
    Data data = make_data(model);
    ASSERT_TRUE(data.sparse);
    Vector q(3), v(3);
    q << 0.1, 0.2, 0.3;
    v << 0.5, 0.6, 0.7;
    FormulationOptions options{Formulation::sanh, Complement::qr};
    options.baumgarte.enabled = true;
    ASSERT_EQ(compute_dynamics(model, data, options, 0.0, q.data(), v.data()), Status::ok);
    const long terms = count_allocations([&] {
      for (int i = 0; i < 10; ++i) {
        q(2) += 0.01;
        compute_terms(model, data, 0.1 * i, q.data(), v.data());
        compute_baumgarte_terms(model, data, options.baumgarte);
      }
    });
    ASSERT_EQ(compute_acceleration(model, data, options), Status::ok);
    const long side = terms + count_allocations([&] {
      compute_residuals(model, data);
      compute_energy(model, data);
    });
    EXPECT_EQ(side, 0) << model.name << ": terms, Baumgarte's terms, residuals or energy allocated";
    for (Formulation m : {Formulation::sanh, Formulation::lagrange}) {
      const FormulationOptions plain(m);
      ASSERT_EQ(compute_dynamics(model, data, plain, 0.2, q.data(), v.data()), Status::ok);
      const long solve = count_allocations([&] { compute_acceleration(model, data, plain); });
      // KLU's refactorization reuses the factors of the first (model/sparse_lu.hpp): nothing at all.
      EXPECT_EQ(solve, 0) << model.name << " " << formulation_name(m);
    }
    EXPECT_GT(data.lu_dep.reusing_factorizations(), 0) << model.name;
    EXPECT_GT(data.lu_kkt_sparse.reusing_factorizations(), 0) << model.name;
  }
}

TEST(Allocation, TheCounterSeesAnAllocation) {
  // Guards the test above against a counter that cannot count.
  g_allocations = 0;
  g_counting = true;
  {
    std::vector<double> numbers(100);
    numbers[7] = 1.0;
    g_counting = false;
    EXPECT_EQ(numbers[7], 1.0);
  }
  EXPECT_GE(g_allocations.load(), 1);
  if (kCountsMalloc) {
    g_allocations = 0;
    g_counting = true;
    Vector v = Vector::Constant(100, 2.0);
    g_counting = false;
    EXPECT_EQ(v.sum(), 200.0);
    EXPECT_GE(g_allocations.load(), 1) << "an Eigen allocation went uncounted";
  }
}

TEST(Allocation, ConstraintWatchAllocatesNothingEvenWhenItWarns) {
  // The paper's sled (y' - tan(phi) x') turned towards phi = pi/2: the row of b grows past the
  // watch's factor inside the counted loop, on the dense path (with the stacked matrix's QR) and
  // on the sparse one.
  const Model paper = make_sled_model(SledVariant::paper);
  for (const Model& model : {paper, testing::make_sparse_twin(paper)}) {
    Data data = make_data(model, DataOptions{Path::automatic, Formulation::sanh, false});
    ConstraintWatch watch = make_constraint_watch(model, data, Formulation::sanh);
    const FormulationOptions options{Formulation::sanh, Complement::qr};
    Vector q(3), v(3);
    q << 0.0, 0.0, 0.0;
    v << 1.0, 0.0, 0.0;
    ASSERT_EQ(compute_dynamics(model, data, options, 0.0, q.data(), v.data()), Status::ok);
    compute_constraint_watch(model, data, watch);
    long watched = 0;
    for (int i = 1; i <= 10; ++i) {
      q(2) = 1.5707 * i / 10.0;  // 1/cos(1.5707) = 1.0e4
      ASSERT_EQ(compute_dynamics(model, data, options, 0.1 * i, q.data(), v.data()), Status::ok);
      watched += count_allocations([&] { compute_constraint_watch(model, data, watch); });
    }
    EXPECT_EQ(watched, 0) << model.name << (data.sparse ? " (sparse)" : " (dense)");
    EXPECT_EQ(watch.warnings.size(), 1u) << model.name;
  }
}

}  // namespace
}  // namespace nhdyn
