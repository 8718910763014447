#include "progress.hpp"

#include <fmt/format.h>
#include <unistd.h>

#include <cstdio>
#include <string>

#include "output_guard.hpp"

namespace nhdyn::cli {

ProgressBar::ProgressBar(double t0, double t_end)
    : t0_(t0), t_end_(t_end), enabled_(::isatty(STDERR_FILENO) == 1),
      start_(std::chrono::steady_clock::now()), last_draw_(start_) {}

ProgressBar::~ProgressBar() { finish(); }

void ProgressBar::update(double t) {
  note_time(t);
  if (!enabled_) return;
  // Reading the clock on every row would cost more than writing the row.
  if (++calls_ % 64 != 0) return;
  const auto now = std::chrono::steady_clock::now();
  if (now - start_ < std::chrono::seconds(1) || now - last_draw_ < std::chrono::milliseconds(100)) return;
  last_draw_ = now;
  const double fraction = t_end_ > t0_ ? (t - t0_) / (t_end_ - t0_) : 1.0;
  constexpr int width = 40;
  const int filled = static_cast<int>(fraction * width);
  std::string bar(static_cast<std::size_t>(filled), '=');
  bar.resize(width, ' ');
  std::fprintf(stderr, "\r[%s] %3.0f%%  t = %.4g", bar.c_str(), 100.0 * fraction, t);
  std::fflush(stderr);
  drawn_ = true;
}

void ProgressBar::finish() {
  if (drawn_) {
    std::fprintf(stderr, "\r%*s\r", 70, "");
    std::fflush(stderr);
    drawn_ = false;
  }
}

}  // namespace nhdyn::cli
