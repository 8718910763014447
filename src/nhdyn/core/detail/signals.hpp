// The signals that stop a run, and threads that never take them. A process-directed signal goes to
// any thread that does not block it; a helper thread of the library (a background compile, a CSV's
// formatting thread) must leave the stopping signals to the threads that run the model, which
// hold them around a compile to stop the compiler and remove its files first (jit/) and which the
// CLI's handlers expect to interrupt (docs/design.md, "Compiled evaluator").
// Internal: used by jit/ and io/, not part of the public API (nhdyn/nhdyn.hpp).
#pragma once

#include <pthread.h>
#include <signal.h>

#include <thread>
#include <utility>

namespace nhdyn {

// The catchable signals that end a process by default and that a user sends to stop a run.
inline sigset_t stopping_signals() {
  sigset_t set;
  sigemptyset(&set);
  for (int sig : {SIGINT, SIGTERM, SIGHUP, SIGQUIT, SIGUSR1, SIGUSR2}) sigaddset(&set, sig);
  return set;
}

// A thread running `job` with the stopping signals blocked for its whole life: a new thread
// inherits its creator's mask, so they are blocked around its creation and the creator's own mask
// restored after (also when the creation throws std::system_error).
template <class Job>
std::thread thread_without_stopping_signals(Job&& job) {
  const sigset_t held = stopping_signals();
  sigset_t old;
  pthread_sigmask(SIG_BLOCK, &held, &old);
  struct Restore {
    sigset_t mask;
    ~Restore() { pthread_sigmask(SIG_SETMASK, &mask, nullptr); }
  } restore{old};
  return std::thread(std::forward<Job>(job));
}

}  // namespace nhdyn
