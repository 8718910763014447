#include "output_guard.hpp"

#include <signal.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <atomic>
#include <cmath>
#include <cstring>
#include <system_error>

#include "nhdyn/io/atomic_file.hpp"
#include "nhdyn/jit/compiled_evaluator.hpp"

namespace nhdyn::cli {
namespace {

std::atomic<double> time_reached{std::nan("")};
static_assert(std::atomic<double>::is_always_lock_free, "the signal handler reads time_reached");

// Appends `text` to buf[len..] within `size`; for the handler, which may not use fmt or printf.
void append(char* buf, std::size_t size, std::size_t& len, const char* text) {
  while (*text && len + 1 < size) buf[len++] = *text++;
}

// t as "%.6g"-like text with integer arithmetic only (async-signal-safe): sign, integer part,
// up to six decimals, or an exponent form outside [1e-4, 1e15).
void append_time(char* buf, std::size_t size, std::size_t& len, double t) {
  if (!(t == t)) return append(buf, size, len, "?");
  if (t < 0) {
    append(buf, size, len, "-");
    t = -t;
  }
  int exponent = 0;
  if (t != 0.0 && (t < 1e-4 || t >= 1e15)) {
    while (t >= 10.0) { t /= 10.0; ++exponent; }
    while (t < 1.0) { t *= 10.0; --exponent; }
  }
  auto whole = static_cast<unsigned long long>(t);
  auto decimals = static_cast<unsigned long long>((t - static_cast<double>(whole)) * 1e6 + 0.5);
  if (decimals >= 1000000ULL) { ++whole; decimals -= 1000000ULL; }
  char digits[32];
  int n = 0;
  do { digits[n++] = static_cast<char>('0' + whole % 10); whole /= 10; } while (whole && n < 30);
  char text[48];
  int k = 0;
  while (n) text[k++] = digits[--n];
  if (decimals) {
    text[k++] = '.';
    char frac[7];
    for (int i = 5; i >= 0; --i) { frac[i] = static_cast<char>('0' + decimals % 10); decimals /= 10; }
    int last = 5;
    while (frac[last] == '0') --last;
    for (int i = 0; i <= last; ++i) text[k++] = frac[i];
  }
  if (exponent) {
    text[k++] = 'e';
    if (exponent < 0) { text[k++] = '-'; exponent = -exponent; }
    char e[8];
    int m = 0;
    do { e[m++] = static_cast<char>('0' + exponent % 10); exponent /= 10; } while (exponent);
    while (m) text[k++] = e[--m];
  }
  text[k] = '\0';
  append(buf, size, len, text);
}

extern "C" void on_interrupt(int signal_number) {
  remove_temporary_files();
  jit::stop_background_compiles();  // --evaluator auto's compiler, in a process group of its own
  char message[256];
  std::size_t len = 0;
  append(message, sizeof message, len, "\nnhdyn: interrupted by ");
  append(message, sizeof message, len, signal_number == SIGINT ? "SIGINT" : "SIGTERM");
  const double t = time_reached.load(std::memory_order_relaxed);
  if (t == t) {
    append(message, sizeof message, len, " at t = ");
    append_time(message, sizeof message, len, t);
  } else {
    append(message, sizeof message, len, " before the time integration");
  }
  append(message, sizeof message, len, "; its unfinished output files were removed\n");
  [[maybe_unused]] const ssize_t written = ::write(STDERR_FILENO, message, len);
  ::_exit(128 + signal_number);
}

}  // namespace

void install_interrupt_handlers() {
  struct sigaction action{};
  action.sa_handler = on_interrupt;
  sigemptyset(&action.sa_mask);
  ::sigaction(SIGINT, &action, nullptr);
  ::sigaction(SIGTERM, &action, nullptr);
}

std::string first_empty_value(const CLI::App& app) {
  for (const CLI::Option* option : app.get_options()) {
    if (option->count() == 0 || option->get_expected_min() == 0) continue;  // not given, or a flag
    for (const std::string& value : option->results())
      if (value.empty()) return option->get_name();
  }
  for (const CLI::App* sub : app.get_subcommands()) {
    const std::string found = first_empty_value(*sub);
    if (!found.empty()) return found;
  }
  return "";
}

void note_time(double t) { time_reached.store(t, std::memory_order_relaxed); }

}  // namespace nhdyn::cli
