// A progress bar on stderr for runs that last longer than about a second, shown only when stderr
// is a terminal so that logs and pipes stay clean.
#pragma once

#include <chrono>

namespace nhdyn::cli {

class ProgressBar {
 public:
  ProgressBar(double t0, double t_end);
  ~ProgressBar();
  void update(double t);  // cheap when nothing is drawn
  void finish();

 private:
  double t0_, t_end_;
  bool enabled_;
  bool drawn_ = false;
  std::chrono::steady_clock::time_point start_, last_draw_;
  long calls_ = 0;
};

}  // namespace nhdyn::cli
