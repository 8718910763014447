// Tapes (straight-line code): every instruction against the std:: function it stands for, the
// validation of operands, the sincos companion, TapeEvaluator's layout of the terms, its
// prepared tapes against the tapes as given (to the bit), and a run that allocates nothing
// (counted at malloc, as in tests/formulation/allocation_test.cpp).
#include "nhdyn/model/tape.hpp"

#include <gtest/gtest.h>

#include "support/address_sanitizer.hpp"

#include <atomic>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <iterator>
#include <new>
#include <stdexcept>
#include <vector>

#include "nhdyn/model/data.hpp"
#include "nhdyn/model/model.hpp"
#include "nhdyn/model/terms.hpp"

namespace {
std::atomic<long> g_allocations{0};
std::atomic<bool> g_counting{false};
void count() {
  if (g_counting.load(std::memory_order_relaxed)) g_allocations.fetch_add(1, std::memory_order_relaxed);
}
}  // namespace

#if defined(NHDYN_ADDRESS_SANITIZER)
// AddressSanitizer owns malloc: count at operator new (the release build counts malloc itself).
// GCC 12 sees gtest's `new T` inlined next to these definitions and reports the free() as a
// mismatched deallocation: it is not (every operator new here is malloc).
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic ignored "-Wmismatched-new-delete"
#endif
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
#else
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
#endif

namespace nhdyn {
namespace {

// Runs `program` at (t, q, v) and returns its outputs.
std::vector<double> run(const Tape& program, double t, const std::vector<double>& q, const std::vector<double>& v) {
  std::vector<double> registers(static_cast<std::size_t>(program.registers()));
  std::vector<double> outputs(static_cast<std::size_t>(program.outputs()));
  program.run(t, q.data(), v.data(), registers.data(), outputs.data());
  return outputs;
}

TEST(Tape, InputsAreRegistersAndConstantsAreOutputs) {
  Tape p(2);
  EXPECT_EQ(p.inputs(), 5);
  EXPECT_EQ(p.registers(), 5);
  EXPECT_FALSE(p.reads_time());
  p.add_output(Tape::time_register());
  p.add_output(p.coordinate_register(1));
  EXPECT_FALSE(p.reads_velocities());
  p.add_output(p.velocity_register(0));
  p.add_output(p.push_constant(-2.5));
  p.add_constant_output(7.25);
  EXPECT_EQ(p.registers(), 6);
  const std::vector<double> out = run(p, 0.75, {1.0, 2.0}, {3.0, 4.0});
  EXPECT_EQ(out, (std::vector<double>{0.75, 2.0, 3.0, -2.5, 7.25}));
  EXPECT_TRUE(p.reads_time());
  EXPECT_TRUE(p.reads_coordinates());
  EXPECT_TRUE(p.reads_velocities());
  EXPECT_EQ(p.describe(), "r5 = constant -2.5\noutputs: t q1 v0 r5 7.25\n");
  EXPECT_THROW(p.coordinate_register(2), std::invalid_argument);
  EXPECT_THROW(p.velocity_register(-1), std::invalid_argument);
}

TEST(Tape, EveryInstructionMatchesTheStandardLibrary) {
  const double x = 0.37, y = -1.9, z = 2.6, k = 1.75;
  Tape p(3);
  const int a = p.coordinate_register(0);
  const int b = p.coordinate_register(1);
  const int c = p.coordinate_register(2);
  std::vector<double> expected;
  const auto out = [&](int r, double value) {
    p.add_output(r);
    expected.push_back(value);
  };
  out(p.push(Op::add, a, b), x + y);
  out(p.push(Op::sub, a, b), x - y);
  out(p.push(Op::mul, a, b), x * y);
  out(p.push(Op::div, a, b), x / y);
  out(p.push(Op::neg, b), -y);
  out(p.push(Op::add_k, a, 0, 0, k), x + k);
  out(p.push(Op::mul_k, a, 0, 0, k), k * x);
  out(p.push(Op::mulk, a, b, 0, k), k * (x * y));
  out(p.push(Op::div_k, b, 0, 0, k), k / y);
  const std::size_t muladd = expected.size();
  out(p.push(Op::muladd, a, b, c), x * y + z);
  out(p.push(Op::mulsub, a, b, c), z - x * y);
  out(p.push(Op::mulk_add, a, b, 0, k), k * x + y);
  out(p.push(Op::mulk_muladd, a, b, c, k), k * (x * y) + z);
  out(p.push(Op::square, b), y * y);
  out(p.push(Op::cube, b), y * y * y);
  const std::size_t powi5 = expected.size();
  out(p.push(Op::powi, b, 0, 0, 5), y * y * y * y * y);
  out(p.push(Op::powi, b, 0, 0, -1), 1.0 / y);
  out(p.push(Op::powi, b, 0, 0, -2), 1.0 / (y * y));
  out(p.push(Op::powi, c, 0, 0, 7), std::pow(z, 7));
  out(p.push(Op::pow, c, a), std::pow(z, x));
  out(p.push(Op::pow_k, c, 0, 0, k), std::pow(z, k));
  out(p.push(Op::sqrt, c), std::sqrt(z));
  out(p.push(Op::sin, a), std::sin(x));
  out(p.push(Op::cos, a), std::cos(x));
  const int sc = p.push(Op::sincos, b);
  out(sc, std::sin(y));
  out(sc + 1, std::cos(y));
  out(p.push(Op::tan, a), std::tan(x));
  out(p.push(Op::exp, b), std::exp(y));
  out(p.push(Op::log, c), std::log(z));
  out(p.push(Op::abs, b), std::abs(y));
  out(p.push(Op::asin, a), std::asin(x));
  out(p.push(Op::acos, a), std::acos(x));
  out(p.push(Op::atan, b), std::atan(y));
  out(p.push(Op::atan2, b, a), std::atan2(y, x));
  out(p.push(Op::sinh, b), std::sinh(y));
  out(p.push(Op::cosh, b), std::cosh(y));
  out(p.push(Op::tanh, b), std::tanh(y));
  const std::vector<double> got = run(p, 0.0, {x, y, z}, {0.0, 0.0, 0.0});
  ASSERT_EQ(got.size(), expected.size());
  for (std::size_t i = 0; i < got.size(); ++i)
    EXPECT_NEAR(got[i], expected[i], 4e-16 * std::abs(expected[i])) << "output " << i << "\n" << p.describe();
  // Products and quotients are exactly the C++ expressions, no fused multiply-add.
  EXPECT_EQ(got[muladd], x * y + z);
  EXPECT_EQ(got[powi5], y * ((y * y) * (y * y)));  // by repeated squaring
  EXPECT_FALSE(p.reads_time());
  EXPECT_FALSE(p.reads_velocities());
}

TEST(Tape, SincosWritesTwoRegistersAndItsCompanionIsSkipped) {
  Tape p(1);
  const int x = p.coordinate_register(0);
  const int sc = p.push(Op::sincos, x);
  EXPECT_EQ(sc, 3);
  EXPECT_EQ(p.registers(), 5);
  EXPECT_EQ(p.code()[1].op, Op::nop);
  const int sum = p.push(Op::add, sc, sc + 1);
  p.add_output(sum);
  EXPECT_DOUBLE_EQ(run(p, 0.0, {0.4}, {0.0})[0], std::sin(0.4) + std::cos(0.4));
  EXPECT_NE(p.describe().find("r3, r4 = sincos q0"), std::string::npos) << p.describe();
}

TEST(Tape, RefusesOperandsNotYetWritten) {
  Tape p(2);
  const int x = p.coordinate_register(0);
  EXPECT_THROW(p.push(Op::add, x, 5), std::invalid_argument);
  EXPECT_THROW(p.push(Op::neg, -1), std::invalid_argument);
  EXPECT_THROW(p.push(Op::nop), std::invalid_argument);
  EXPECT_THROW(p.push(Op::powi, x, 0, 0, 0.5), std::invalid_argument);
  EXPECT_THROW(p.push(Op::powi, x, 0, 0, 0.0), std::invalid_argument);
  EXPECT_THROW(p.push(Op::powi, x, 0, 0, 1e7), std::invalid_argument);
  EXPECT_THROW(p.add_output(5), std::invalid_argument);
  const int sc = p.push(Op::sincos, x);
  EXPECT_EQ(p.push(Op::mul, sc, sc + 1), 7);  // the cosine is readable
  EXPECT_EQ(p.count(Op::sincos), 1);
}

// A 2-coordinate system: A = diag(m, m q0^2), Q = (-k q0, 0), G = (m q0 v1^2, -2 m q0 v0 v1),
// one constraint q0' sin(q1) - q1' = 0 at velocity level, given as b = (sin q1, -1),
// b0 = q0' q1' cos(q1); D = (1, sin q1); energy m/2 (v0^2 + q0^2 v1^2) + k/2 q0^2.
ModelTapes polar_programs(double m, double k) {
  ModelTapes p{Tape(2), std::nullopt, Tape(2), Tape(2), std::nullopt, std::nullopt, std::nullopt};
  Tape& t = p.terms;
  const int q0 = t.coordinate_register(0), q1 = t.coordinate_register(1);
  const int v0 = t.velocity_register(0), v1 = t.velocity_register(1);
  const int zero = t.push_constant(0.0);
  const int sc = t.push(Op::sincos, q1);
  const int q0q0 = t.push(Op::square, q0);
  // A, column-major
  t.add_constant_output(m);
  t.add_output(zero);
  t.add_constant_output(0.0);
  t.add_output(t.push(Op::mul_k, q0q0, 0, 0, m));
  // Q
  t.add_output(t.push(Op::mul_k, q0, 0, 0, -k));
  t.add_output(zero);
  // G
  const int v1v1 = t.push(Op::square, v1);
  t.add_output(t.push(Op::mulk, q0, v1v1, 0, m));
  t.add_output(t.push(Op::mul_k, t.push(Op::mul, t.push(Op::mul, q0, v0), v1), 0, 0, -2.0 * m));
  // b (1 x 2), b0
  t.add_output(sc);
  t.add_constant_output(-1.0);
  t.add_output(t.push(Op::mul, t.push(Op::mul, v0, v1), sc + 1));

  Tape d(2);
  d.add_constant_output(1.0);
  d.add_output(d.push(Op::sin, d.coordinate_register(1)));
  p.complement = d;

  Tape& f = p.velocity_residual;
  f.add_output(f.push(Op::sub, f.push(Op::mul, f.velocity_register(0), f.push(Op::sin, f.coordinate_register(1))),
                      f.velocity_register(1)));

  Tape e(2);
  const int x = e.coordinate_register(0), u = e.velocity_register(0), w = e.velocity_register(1);
  const int T = e.push(Op::mul_k, e.push(Op::muladd, e.push(Op::square, x), e.push(Op::square, w), e.push(Op::square, u)),
                       0, 0, 0.5 * m);
  e.add_output(e.push(Op::mulk_add, e.push(Op::square, x), T, 0, 0.5 * k));
  p.energy = e;
  return p;
}

TEST(TapeEvaluator, FillsTheTermsInTheirLayout) {
  const double m = 1.3, k = 2.1;
  const TapeEvaluator evaluator(2, 1, polar_programs(m, k));
  EXPECT_TRUE(evaluator.has_complement());
  EXPECT_TRUE(evaluator.has_energy());
  EXPECT_EQ(evaluator.scratch_size(), static_cast<std::size_t>(evaluator.tapes().terms.registers()));
  const double q[2] = {0.8, -0.4}, v[2] = {0.3, 1.7};
  std::vector<double> scratch(evaluator.scratch_size());
  double A[4], Q[2], G[2], b[2], b0[1], D[2], f[1];
  evaluator.terms(0.0, q, v, scratch.data(), TermsOut{A, Q, G, b, b0});
  EXPECT_EQ(A[0], m);
  EXPECT_EQ(A[1], 0.0);
  EXPECT_EQ(A[2], 0.0);
  EXPECT_DOUBLE_EQ(A[3], m * q[0] * q[0]);
  EXPECT_DOUBLE_EQ(Q[0], -k * q[0]);
  EXPECT_EQ(Q[1], 0.0);
  EXPECT_DOUBLE_EQ(G[0], m * q[0] * v[1] * v[1]);
  EXPECT_DOUBLE_EQ(G[1], -2.0 * m * q[0] * v[0] * v[1]);
  EXPECT_DOUBLE_EQ(b[0], std::sin(q[1]));
  EXPECT_EQ(b[1], -1.0);
  EXPECT_DOUBLE_EQ(b0[0], v[0] * v[1] * std::cos(q[1]));
  evaluator.complement(0.0, q, v, scratch.data(), D);
  EXPECT_EQ(D[0], 1.0);
  EXPECT_DOUBLE_EQ(D[1], std::sin(q[1]));
  evaluator.velocity_residual(0.0, q, v, scratch.data(), f);
  EXPECT_DOUBLE_EQ(f[0], v[0] * std::sin(q[1]) - v[1]);
  EXPECT_DOUBLE_EQ(evaluator.energy(0.0, q, v, scratch.data()),
                   0.5 * m * (v[0] * v[0] + q[0] * q[0] * v[1] * v[1]) + 0.5 * k * q[0] * q[0]);
}

TEST(TapeEvaluator, RefusesProgramsOfTheWrongShape) {
  ModelTapes p = polar_programs(1.0, 1.0);
  EXPECT_THROW(TapeEvaluator(2, 0, p), std::invalid_argument);  // terms outputs for s = 1
  EXPECT_THROW(TapeEvaluator(3, 1, p), std::invalid_argument);  // programs read 2 coordinates
  ModelTapes bad_position = polar_programs(1.0, 1.0);
  bad_position.position_residual.add_output(bad_position.position_residual.velocity_register(0));
  EXPECT_THROW(TapeEvaluator(2, 1, bad_position), std::invalid_argument);
  ModelTapes bad_energy = polar_programs(1.0, 1.0);
  bad_energy.energy->add_constant_output(0.0);
  EXPECT_THROW(TapeEvaluator(2, 1, bad_energy), std::invalid_argument);
}

// A program for n >= 2 coordinates whose `outputs` outputs cycle through registers of every kind
// that TapeEvaluator prepares apart: a parameter-only subexpression (sqrt(2) * 1.3, folded), the
// instructions with a constant operand that become immediates, a register output twice, one that
// later instructions read too, a sincos (or, without the math library, a square and a cube), the
// inputs t and q', a constant output; and an instruction no output needs.
Tape mixed_program(int n, int outputs, bool library) {
  Tape p(n);
  const int t = Tape::time_register(), q0 = p.coordinate_register(0), q1 = p.coordinate_register(1);
  const int v0 = p.velocity_register(0), v1 = p.velocity_register(1);
  const int c = p.push_constant(1.3);
  const int pm = p.push(Op::mul, p.push(Op::sqrt, p.push_constant(2.0)), c);
  const int x = p.push(Op::mul, q0, pm);
  const int y = p.push(Op::sub, v0, c);
  const int z = p.push(Op::div, c, q1);
  const int w = p.push(Op::muladd, q0, c, v1);
  const int add = p.push(Op::add, pm, v0);
  int s = 0, cs = 0;
  if (library) {
    s = p.push(Op::sincos, q1);
    cs = s + 1;
    p.push(Op::exp, q0);  // no output needs it
  } else {
    s = p.push(Op::square, q1);
    cs = p.push(Op::cube, q1);
    p.push(Op::neg, q0);  // no output needs it
  }
  const int u = p.push(Op::muladd, s, x, y);
  const int pool[] = {pm, x, y, z, w, add, s, cs, u, x, v1, t, s, -1, u};
  for (int i = 0; i < outputs; ++i) {
    const int reg = pool[i % static_cast<int>(std::size(pool))];
    if (reg < 0)
      p.add_constant_output(0.5);
    else
      p.add_output(reg);
  }
  return p;
}

TEST(TapeEvaluator, PreparedProgramsGiveTheSameBitsAsTheirPrograms) {
  for (const int n : {2, 3, 5})  // sizes fixed at compile time (n <= 4) or not
    for (const bool library : {true, false}) {
      const int s = 1;
      ModelTapes programs{mixed_program(n, n * n + 2 * n + s * n + s, library),
                             mixed_program(n, (n - s) * n, library), Tape(n), Tape(n), std::nullopt, std::nullopt, std::nullopt};
      programs.velocity_residual = mixed_program(n, 1, library);
      const TapeEvaluator evaluator(n, s, programs);
      const Tape& terms = evaluator.tapes().terms;
      std::vector<double> q(static_cast<std::size_t>(n)), v(static_cast<std::size_t>(n));
      for (const double state : {0.7, -1.3, 0.0}) {
        for (int i = 0; i < n; ++i) {
          q[static_cast<std::size_t>(i)] = state * (1.0 + 0.25 * i);
          v[static_cast<std::size_t>(i)] = state - 0.5 * i;
        }
        const double t = 0.25 * state;
        const std::vector<double> expected = run(terms, t, q, v);
        std::vector<double> scratch(evaluator.scratch_size());
        std::vector<double> got(expected.size(), -7.0);
        double* const out = got.data();
        evaluator.terms(t, q.data(), v.data(), scratch.data(),
                        TermsOut{out, out + n * n, out + n * n + n, out + n * n + 2 * n, out + n * n + 3 * n});
        for (std::size_t i = 0; i < expected.size(); ++i)
          EXPECT_EQ(std::memcmp(&got[i], &expected[i], sizeof(double)), 0)
              << "n = " << n << ", output " << i << ": " << got[i] << " != " << expected[i];
        // The parameter-only subexpression, folded once, is the value computed at run time.
        EXPECT_EQ(got[0], std::sqrt(2.0) * 1.3);

        const std::vector<double> expected_d = run(*programs.complement, t, q, v);
        std::vector<double> d(expected_d.size(), -7.0);
        evaluator.complement(t, q.data(), v.data(), scratch.data(), d.data());
        EXPECT_EQ(std::memcmp(d.data(), expected_d.data(), d.size() * sizeof(double)), 0) << "n = " << n;
        double f = -7.0;
        evaluator.velocity_residual(t, q.data(), v.data(), scratch.data(), &f);
        EXPECT_EQ(f, run(programs.velocity_residual, t, q, v)[0]);
      }
    }
}

// The tapes run beside the evaluator at every row (contact forces, derived outputs, contact modes)
// are PreparedTapes: the same bits as the tape as given, with the steps no output needs left out.
TEST(PreparedTape, GivesTheSameBitsAsItsTapeInFewerSteps) {
  for (const int n : {2, 5})
    for (const bool library : {true, false}) {
      const Tape tape = mixed_program(n, 17, library);
      const PreparedTape prepared(tape);
      EXPECT_EQ(prepared.outputs(), tape.outputs());
      EXPECT_EQ(prepared.registers(), tape.registers());
      std::vector<double> q(static_cast<std::size_t>(n)), v(static_cast<std::size_t>(n));
      for (const double state : {0.7, -1.3, 0.0}) {
        for (int i = 0; i < n; ++i) {
          q[static_cast<std::size_t>(i)] = state * (1.0 + 0.25 * i);
          v[static_cast<std::size_t>(i)] = state - 0.5 * i;
        }
        const std::vector<double> expected = run(tape, 0.25 * state, q, v);
        std::vector<double> registers(static_cast<std::size_t>(prepared.registers())), got(expected.size(), -7.0);
        prepared.run(0.25 * state, q.data(), v.data(), registers.data(), got.data());
        EXPECT_EQ(std::memcmp(got.data(), expected.data(), got.size() * sizeof(double)), 0) << "n = " << n;
      }
    }
  // q0 * (sqrt(2) * 1.3) and a sine no output needs: one step (and the nop that ends them).
  Tape small(1);
  const int k = small.push(Op::mul, small.push(Op::sqrt, small.push_constant(2.0)), small.push_constant(1.3));
  small.add_output(small.push(Op::mul, small.coordinate_register(0), k));
  small.push(Op::sin, small.coordinate_register(0));
  EXPECT_EQ(PreparedTape(small).steps(), 1) << small.describe();
  // A default one has no outputs and runs (nothing).
  const PreparedTape empty;
  double registers[1] = {0.0};
  empty.run(0.0, nullptr, nullptr, registers, nullptr);
  EXPECT_EQ(empty.outputs(), 0);
  Tape parametric(2, 1);
  parametric.add_output(parametric.push(Op::mul, parametric.push_parameter(0), parametric.coordinate_register(0)));
  EXPECT_THROW(PreparedTape{parametric}, std::logic_error);
  const double value = 3.0;
  EXPECT_NO_THROW(PreparedTape{parametric.bind(&value, 1)});
}

TEST(TapeEvaluator, ComputesParameterOnlySubexpressionsOnce) {
  // A(1, 1) = q0 * (sqrt(2) * m) and Q(0) = sqrt(2) * m; everything else constant.
  const double m = 1.3;
  ModelTapes programs{Tape(2), std::nullopt, Tape(2), Tape(2), std::nullopt, std::nullopt, std::nullopt};
  Tape& p = programs.terms;
  const int zero = p.push_constant(0.0);
  const int sm = p.push(Op::mul, p.push(Op::sqrt, p.push_constant(2.0)), p.push_constant(m));
  const int a11 = p.push(Op::mul, p.coordinate_register(0), sm);
  for (const int reg : {zero, zero, zero, a11, sm, zero, zero, zero, zero, zero, zero}) p.add_output(reg);
  const TapeEvaluator evaluator(2, 1, programs);
  EXPECT_EQ(evaluator.terms_operations(), 1) << p.describe();  // k * q0, k folded, into A directly
  const std::vector<double> q{0.7, -0.2}, v{0.3, 0.4};
  const std::vector<double> expected = run(p, 0.0, q, v);
  std::vector<double> scratch(evaluator.scratch_size()), got(expected.size(), -7.0);
  double* const out = got.data();
  evaluator.terms(0.0, q.data(), v.data(), scratch.data(), TermsOut{out, out + 4, out + 6, out + 8, out + 10});
  EXPECT_EQ(got, expected);
  EXPECT_EQ(got[3], q[0] * (std::sqrt(2.0) * m));
  EXPECT_EQ(got[4], std::sqrt(2.0) * m);
}

TEST(TapeEvaluator, AProductUnderAConstantFactorIsOneStep) {
  // k = sqrt(2) m, a parameter stage: k (q0 q1), k (q0 v1) + v0, v1 - k q1 and k (q1 q1) + q0
  // cost one step each (mulk, mulk_muladd, mulk_add, mulk_muladd), rounding as the program does.
  ModelTapes programs{Tape(2), std::nullopt, Tape(2), Tape(2), std::nullopt, std::nullopt, std::nullopt};
  Tape& p = programs.terms;
  const int q0 = p.coordinate_register(0), q1 = p.coordinate_register(1);
  const int v0 = p.velocity_register(0), v1 = p.velocity_register(1);
  const int k = p.push(Op::mul, p.push(Op::sqrt, p.push_constant(2.0)), p.push_constant(1.3));
  const int a = p.push(Op::mul, k, p.push(Op::mul, q0, q1));
  const int b = p.push(Op::muladd, k, p.push(Op::mul, q0, v1), v0);
  const int c = p.push(Op::mulsub, q1, k, v1);
  const int d = p.push(Op::muladd, p.push(Op::square, q1), k, q0);
  const int shared = p.push(Op::mul, q0, v0);  // read twice: computed once, not fused
  const int e = p.push(Op::mul, k, shared);
  const int f = p.push(Op::add, shared, v1);
  for (const int reg : {a, b, c, d, e, f, a, b, c, d, e}) p.add_output(reg);
  const TapeEvaluator evaluator(2, 1, programs);
  // The four, then q0 v0, k (q0 v0) and q0 v0 + v1, then a clone for each further output (5).
  EXPECT_EQ(evaluator.terms_operations(), 4 + 3 + 5) << p.describe();
  std::vector<double> scratch(evaluator.scratch_size());
  for (const double state : {0.7, -1.9, 3.1e-3}) {
    const std::vector<double> q{state, 1.0 - state}, v{0.5 * state, -state * state};
    const std::vector<double> expected = run(p, 0.0, q, v);
    std::vector<double> got(expected.size(), -7.0);
    double* const out = got.data();
    evaluator.terms(0.0, q.data(), v.data(), scratch.data(), TermsOut{out, out + 4, out + 6, out + 8, out + 10});
    for (std::size_t i = 0; i < expected.size(); ++i)
      EXPECT_EQ(std::memcmp(&got[i], &expected[i], sizeof(double)), 0) << "output " << i << ": " << got[i];
    const double K = std::sqrt(2.0) * 1.3;
    EXPECT_EQ(got[0], K * (q[0] * q[1]));
    EXPECT_EQ(got[2], v[1] - q[1] * K);
  }
}

TEST(TapeEvaluator, RunsWithoutAllocating) {
  Model model;
  model.name = "polar";
  model.coordinates = {"r", "theta"};
  model.constraints = {{"c", ConstraintLevel::velocity, "r' sin(theta) - theta' = 0"}};
  model.q0 = Vector::Constant(2, 0.5);
  model.v0 = Vector::Constant(2, 0.25);
  model.evaluator = std::make_shared<TapeEvaluator>(2, 1, polar_programs(1.0, 2.0));
  Data data = make_data(model);
  const double q[2] = {0.8, -0.4}, v[2] = {0.3, 1.7};
  std::vector<double> outputs(16);
  const Tape& terms = static_cast<const TapeEvaluator&>(*model.evaluator).tapes().terms;
  ASSERT_EQ(compute_terms(model, data, 0.0, q, v), Status::ok);
  g_allocations = 0;
  g_counting = true;
  double energy = 0.0;
  for (int i = 0; i < 10; ++i) {
    compute_terms(model, data, 0.1 * i, q, v);
    terms.run(0.0, q, v, data.scratch.data(), outputs.data());
    model.evaluator->complement(0.0, q, v, data.scratch.data(), data.D.data());
    model.evaluator->velocity_residual(0.0, q, v, data.scratch.data(), data.f.data());
    energy += model.evaluator->energy(0.0, q, v, data.scratch.data());
  }
  g_counting = false;
  EXPECT_EQ(g_allocations.load(), 0);
  EXPECT_GT(energy, 0.0);
  // The counter counts.
  g_counting = true;
  std::vector<double> numbers(100);
  g_counting = false;
  numbers[3] = 1.0;
  EXPECT_GE(g_allocations.load(), 1);
}

}  // namespace
}  // namespace nhdyn
