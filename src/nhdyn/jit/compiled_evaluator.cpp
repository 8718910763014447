#include "nhdyn/jit/compiled_evaluator.hpp"

#include <dlfcn.h>
#include <fcntl.h>
#include <pthread.h>
#include <sched.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <fmt/format.h>

#include <array>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <optional>
#include <system_error>
#include <sstream>
#include <thread>
#include <utility>
#include <vector>

#include "nhdyn/jit/detail/source.hpp"
#include "nhdyn/core/detail/cache_root.hpp"
#include "nhdyn/core/detail/hash.hpp"
#include "nhdyn/core/detail/signals.hpp"
#include "nhdyn/model/contact_forces.hpp"
#include "nhdyn/model/tape.hpp"

extern char** environ;

namespace nhdyn::jit {
namespace {

namespace fs = std::filesystem;

// Flags: optimised, position-independent, and no contraction of a * b + c into a fused
// multiply-add (the interpreter rounds twice; so must the compiled code).
const std::vector<std::string> kFlags = {"-std=c++17", "-O2", "-fPIC", "-shared", "-ffp-contract=off",
                                         "-fno-math-errno"};

std::string env(const char* name) {
  const char* value = std::getenv(name);
  return value ? value : "";
}

std::string read_file(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// Holds the stopping signals in this thread for its lifetime; release() lets them through again
// and re-raises the one that was caught, so that the process's own disposition (exit, a handler,
// Python's KeyboardInterrupt) applies once the files are gone.
class HeldSignals {
 public:
  HeldSignals() {
    const sigset_t set = stopping_signals();
    pthread_sigmask(SIG_BLOCK, &set, &old_);
  }
  ~HeldSignals() { pthread_sigmask(SIG_SETMASK, &old_, nullptr); }
  HeldSignals(const HeldSignals&) = delete;
  HeldSignals& operator=(const HeldSignals&) = delete;
  void release_and_raise(int sig) {
    pthread_sigmask(SIG_SETMASK, &old_, nullptr);
    ::raise(sig);
  }

 private:
  sigset_t old_{};
};

// The process groups of the background compilers running now (0: a free slot), for
// stop_background_compiles, which a signal handler may call: lock-free atomics only.
constexpr int kBackgroundSlots = 16;
std::atomic<pid_t> background_groups[kBackgroundSlots];
static_assert(std::atomic<pid_t>::is_always_lock_free);

// Registers a background compiler's group for its lifetime (none when every slot is taken: it is
// then stopped only by the run's end, as before).
class BackgroundGroup {
 public:
  explicit BackgroundGroup(pid_t group) {
    for (int i = 0; i < kBackgroundSlots && slot_ < 0; ++i) {
      pid_t free = 0;
      if (background_groups[i].compare_exchange_strong(free, group)) slot_ = i;
    }
  }
  ~BackgroundGroup() {
    if (slot_ >= 0) background_groups[slot_].store(0);
  }
  BackgroundGroup(const BackgroundGroup&) = delete;
  BackgroundGroup& operator=(const BackgroundGroup&) = delete;

 private:
  int slot_ = -1;
};

// Runs argv (searched in PATH) with stdout and stderr to `log`, in its own process group; returns
// its exit code, or -1 with errno's text in `error` when it cannot start. A stopping signal sent
// to this process meanwhile (HeldSignals must be in force) ends the whole group (the compiler
// driver and its cc1plus, as, ld), waits for it and returns -2 with the signal in `caught`; so does
// `cancel` turning true (a background compile no longer wanted), returning -3.
int run(const std::vector<std::string>& argv, const fs::path& log, std::string& error, int& caught,
        const std::atomic<bool>* cancel = nullptr) {
  caught = 0;
  std::vector<char*> args;
  for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 1, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_adddup2(&actions, 1, 2);
  posix_spawn_file_actions_addopen(&actions, 0, "/dev/null", O_RDONLY, 0);
  posix_spawnattr_t attributes;
  posix_spawnattr_init(&attributes);
  sigset_t none;
  sigemptyset(&none);
  const sigset_t held = stopping_signals();
  posix_spawnattr_setsigmask(&attributes, &none);
  posix_spawnattr_setsigdefault(&attributes, &held);
  posix_spawnattr_setpgroup(&attributes, 0);
  posix_spawnattr_setflags(&attributes, POSIX_SPAWN_SETSIGMASK | POSIX_SPAWN_SETSIGDEF | POSIX_SPAWN_SETPGROUP);
  pid_t pid = 0;
  const int spawned = posix_spawnp(&pid, args[0], &actions, &attributes, args.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  posix_spawnattr_destroy(&attributes);
  if (spawned != 0) {
    error = std::strerror(spawned);
    return -1;
  }
  int status = 0;
  std::optional<BackgroundGroup> registered;
  if (cancel != nullptr) registered.emplace(pid);
  for (;;) {
    const pid_t done = waitpid(pid, &status, WNOHANG);
    if (done == pid) break;
    if (done < 0 && errno != EINTR) {
      error = std::strerror(errno);
      return -1;
    }
    // A compile nobody waits for is checked more often: the run that cancels it waits for this.
    const timespec wait{0, cancel != nullptr ? 2'000'000 : 20'000'000};
    const int sig = sigtimedwait(&held, nullptr, &wait);
    const bool cancelled = cancel != nullptr && cancel->load();
    if (sig > 0 || cancelled) {
      caught = sig > 0 ? sig : 0;
      ::kill(-pid, SIGTERM);  // the driver removes its own temporaries on SIGTERM
      for (int i = 0; i < 2500 && waitpid(pid, &status, WNOHANG) == 0; ++i) ::usleep(2'000);
      ::kill(-pid, SIGKILL);  // whatever is left of the group after 5 s
      while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
      }
      return sig > 0 ? -2 : -3;
    }
  }
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + (WIFSIGNALED(status) ? WTERMSIG(status) : 0);
}

// The first line of a compiler's output that says "error", else its first line.
std::string first_error(const std::string& output) {
  std::istringstream in(output);
  std::string line, first;
  while (std::getline(in, line)) {
    if (first.empty()) first = line;
    if (line.find("error") != std::string::npos) return line;
  }
  return first.empty() ? "no output" : first;
}

fs::path cache_directory(const JitOptions& options) {
  if (!options.cache_dir.empty()) return options.cache_dir;
  if (std::optional<fs::path> root = nhdyn_cache_root()) return *root;
  throw JitError("no cache directory: neither XDG_CACHE_HOME nor HOME is set to an absolute path");
}

// A name no other process or thread uses at the same time.
std::string unique_suffix() {
  static std::atomic<unsigned> counter{0};
  return fmt::format("{}-{}", ::getpid(), counter++);
}

using StageSize = std::size_t (*)();
using Stage = void (*)(const double*, double*);
using Terms = void (*)(const double*, double, const double*, const double*, double*, double*, double*, double*,
                       double*);

// A loaded shared object, closed when the last evaluator using it goes.
struct Library {
  void* handle = nullptr;
  StageSize stage_size = nullptr;
  Stage stage = nullptr;
  Terms terms = nullptr;
  Terms terms_dense = nullptr;
  const char* (*key)() = nullptr;  // the cache key the object was compiled under
  ~Library() {
    if (handle) dlclose(handle);
  }
};

// Loads `path`; null with the reason in `error` when it cannot be used.
std::shared_ptr<Library> load(const fs::path& path, bool sparse, std::string& error) {
  auto library = std::make_shared<Library>();
  library->handle = dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL);
  if (!library->handle) {
    const char* e = dlerror();
    error = e ? e : "dlopen failed";
    return nullptr;
  }
  const auto version = reinterpret_cast<int (*)()>(dlsym(library->handle, "nhdyn_jit_version"));
  library->stage_size = reinterpret_cast<StageSize>(dlsym(library->handle, "nhdyn_jit_stage_size"));
  library->stage = reinterpret_cast<Stage>(dlsym(library->handle, "nhdyn_jit_stage"));
  library->terms = reinterpret_cast<Terms>(dlsym(library->handle, "nhdyn_jit_terms"));
  library->terms_dense = reinterpret_cast<Terms>(dlsym(library->handle, "nhdyn_jit_terms_dense"));
  library->key = reinterpret_cast<const char* (*)()>(dlsym(library->handle, "nhdyn_jit_key"));
  if (!version || version() != kInterfaceVersion || !library->stage_size || !library->stage || !library->terms ||
      (sparse && !library->terms_dense)) {
    error = fmt::format("{} is not an nhdyn object of interface version {}", path.string(), kInterfaceVersion);
    return nullptr;
  }
  return library;
}

// The check file beside a cached object: its key, size and two hashes of its bytes.
std::string entry_check(const std::string& key, const std::string& bytes) {
  return fmt::format("nhdyn compiled model\nkey {}\nsize {}\nhash {:016x}{:016x}\n", key, bytes.size(),
                     fnv1a(bytes, kFnvOffset), fnv1a(bytes, kFnvOtherOffset));
}

// The largest cached object read (to hash it): a compiled model is far smaller, and a device or
// a link to one in its place is never read to its end.
constexpr std::uintmax_t kMaxObjectBytes = std::uintmax_t{1} << 30;
constexpr std::uintmax_t kMaxCheckBytes = 4096;

// "" when `object` is whole and belongs to `key` by its check file; else what is wrong. Only
// regular files of a plausible size are read: a named pipe would block the read, a device never
// end it.
std::string verify_entry(const fs::path& object, const fs::path& check, const std::string& key) {
  std::error_code ec;
  if (!fs::exists(object, ec)) return "the object is missing";
  if (!fs::exists(check, ec)) return "its check file is missing";
  for (const auto& [path, limit] : {std::pair{object, kMaxObjectBytes}, std::pair{check, kMaxCheckBytes}}) {
    if (!fs::is_regular_file(path, ec)) return fmt::format("{} is not a regular file", path.filename().string());
    const std::uintmax_t size = fs::file_size(path, ec);
    if (ec || size > limit) return fmt::format("{} is larger than any cache entry", path.filename().string());
  }
  const std::string expected = read_file(check);
  if (expected.find(fmt::format("key {}\n", key)) == std::string::npos) return "its check file names another model";
  if (entry_check(key, read_file(object)) != expected) return "the object is truncated or altered";
  return "";
}


using TapeStageFunction = void (*)(const double*, double*);
using TapeRunFunction = void (*)(const double*, double, const double*, const double*, double*);

// A tape of make_tape_source in a loaded object (the contact forces', the outputs').
class CompiledTape final : public NativeTape {
 public:
  CompiledTape(std::shared_ptr<const Library> library, StageSize size, TapeStageFunction stage, TapeRunFunction run)
      : library_(std::move(library)), size_(size), stage_(stage), run_(run) {}
  std::size_t stage_size() const override { return size_(); }
  void stage(const double* parameters, double* stage) const override { stage_(parameters, stage); }
  void run(const double* stage, double t, const double* q, const double* v, double* outputs) const override {
    run_(stage, t, q, v, outputs);
  }

 private:
  std::shared_ptr<const Library> library_;  // keeps the object loaded
  StageSize size_;
  TapeStageFunction stage_;
  TapeRunFunction run_;
};

// The tape NAME of the loaded object, or null when the object lacks it.
std::shared_ptr<const NativeTape> native_tape(const std::shared_ptr<const Library>& library,
                                                    const std::string& name) {
  const auto size = reinterpret_cast<StageSize>(dlsym(library->handle, ("nhdyn_jit_" + name + "_stage_size").c_str()));
  const auto stage = reinterpret_cast<TapeStageFunction>(dlsym(library->handle, ("nhdyn_jit_" + name + "_stage").c_str()));
  const auto run = reinterpret_cast<TapeRunFunction>(dlsym(library->handle, ("nhdyn_jit_" + name).c_str()));
  if (!size || !stage || !run) return nullptr;
  return std::make_shared<CompiledTape>(library, size, stage, run);
}

// The tapes of an output row that the evaluator runs (the residuals, the energy, h and the
// power), compiled when the model has them; null: the interpreter's.
enum RowTape { kPositionResidual, kVelocityResidual, kEnergy, kEnergyFunction, kPower, kRowTapes };
const char* const kRowTapeNames[kRowTapes] = {"position_residual", "velocity_residual", "energy",
                                                    "energy_function", "power"};
const Tape* row_tape(const ModelTapes& p, int which) {
  switch (which) {
    case kPositionResidual: return &p.position_residual;
    case kVelocityResidual: return &p.velocity_residual;
    case kEnergy: return p.energy ? &*p.energy : nullptr;
    case kEnergyFunction: return p.energy_function ? &*p.energy_function : nullptr;
    case kPower: return p.power ? &*p.power : nullptr;
    default: return nullptr;
  }
}
using RowTapes = std::array<std::shared_ptr<const NativeTape>, kRowTapes>;

// The interpreter's evaluator behind another: every call forwarded to it. The compiled evaluators
// derive from it and override what they run otherwise (the terms and the tapes of a row).
class OverInterpreter : public Evaluator {
 public:
  explicit OverInterpreter(std::shared_ptr<const TapeEvaluator> base) : base_(std::move(base)) {}
  bool has_initial_state() const override { return base_->has_initial_state(); }
  void initial_state(double* scratch, double* q0, double* v0) const override { base_->initial_state(scratch, q0, v0); }
  std::size_t scratch_size() const override { return base_->scratch_size(); }
  void terms(double t, const double* q, const double* v, double* scratch, const TermsOut& out) const override {
    base_->terms(t, q, v, scratch, out);
  }
  const TermsSparsity* sparsity() const override { return base_->sparsity(); }
  void sparse_terms(double t, const double* q, const double* v, double* scratch, const TermsOut& out) const override {
    base_->sparse_terms(t, q, v, scratch, out);
  }
  bool has_complement() const override { return base_->has_complement(); }
  void complement(double t, const double* q, const double* v, double* scratch, double* D) const override {
    base_->complement(t, q, v, scratch, D);
  }
  void position_residual(double t, const double* q, double* scratch, double* phi) const override {
    base_->position_residual(t, q, scratch, phi);
  }
  void velocity_residual(double t, const double* q, const double* v, double* scratch, double* f) const override {
    base_->velocity_residual(t, q, v, scratch, f);
  }
  bool has_program_constraints() const override { return base_->has_program_constraints(); }
  void program_constraint_terms(double t, const double* q, const double* v, double* scratch, double* b_p,
                                double* b_p0, double* B) const override {
    base_->program_constraint_terms(t, q, v, scratch, b_p, b_p0, B);
  }
  void program_constraint_position_residual(double t, const double* q, double* scratch, double* phi) const override {
    base_->program_constraint_position_residual(t, q, scratch, phi);
  }
  void program_constraint_velocity_residual(double t, const double* q, const double* v, double* scratch,
                                            double* f) const override {
    base_->program_constraint_velocity_residual(t, q, v, scratch, f);
  }
  bool has_energy() const override { return base_->has_energy(); }
  bool has_energy_balance() const override { return base_->has_energy_balance(); }
  bool power_is_zero() const override { return base_->power_is_zero(); }
  bool energy_function_is_energy() const override { return base_->energy_function_is_energy(); }
  double energy_function(double t, const double* q, const double* v, double* scratch) const override {
    return base_->energy_function(t, q, v, scratch);
  }
  void power(double t, const double* q, const double* v, double* scratch, double* out) const override {
    base_->power(t, q, v, scratch, out);
  }
  double energy(double t, const double* q, const double* v, double* scratch) const override {
    return base_->energy(t, q, v, scratch);
  }
  bool has_solution() const override { return base_->has_solution(); }
  void solution(double t, double* scratch, double* qva) const override { base_->solution(t, scratch, qva); }

 protected:
  std::shared_ptr<const TapeEvaluator> base_;
};

// The interpreter's evaluator with its terms, and the tapes of a row, replaced by compiled ones.
class CompiledEvaluator final : public OverInterpreter {
 public:
  CompiledEvaluator(std::shared_ptr<const TapeEvaluator> base, std::shared_ptr<const Library> library,
                    RowTapes rows)
      : OverInterpreter(std::move(base)), library_(std::move(library)), sparse_(base_->sparsity() != nullptr),
        rows_(std::move(rows)) {
    const std::vector<double>& p = base_->parameter_values();
    stage_.assign(library_->stage_size() + 1, 0.0);
    library_->stage(p.data(), stage_.data());
    for (int i = 0; i < kRowTapes; ++i) {
      if (!rows_[i]) continue;
      row_stages_[i].assign(rows_[i]->stage_size() + 1, 0.0);  // + 1: data() of an empty stage
      rows_[i]->stage(p.data(), row_stages_[i].data());
    }
  }

  std::shared_ptr<const Evaluator> with_parameters(const double* values, std::size_t count) const override {
    auto rebound = std::dynamic_pointer_cast<const TapeEvaluator>(base_->with_parameters(values, count));
    if (!rebound) return nullptr;
    return std::make_shared<CompiledEvaluator>(std::move(rebound), library_, rows_);
  }

  void terms(double t, const double* q, const double* v, double* /*scratch*/, const TermsOut& out) const override {
    if (sparse_) {
      // The compiled code writes the nonzeros at their dense places; the rest is zero.
      const std::size_t n = static_cast<std::size_t>(base_->n()), s = static_cast<std::size_t>(base_->s());
      std::fill(out.A, out.A + n * n, 0.0);
      std::fill(out.b, out.b + s * n, 0.0);
      library_->terms_dense(stage_.data(), t, q, v, out.A, out.Q, out.G, out.b, out.b0);
      return;
    }
    library_->terms(stage_.data(), t, q, v, out.A, out.Q, out.G, out.b, out.b0);
  }
  void sparse_terms(double t, const double* q, const double* v, double* /*scratch*/,
                    const TermsOut& out) const override {
    library_->terms(stage_.data(), t, q, v, out.A, out.Q, out.G, out.b, out.b0);
  }

  void position_residual(double t, const double* q, double* scratch, double* phi) const override {
    if (rows_[kPositionResidual])
      rows_[kPositionResidual]->run(row_stages_[kPositionResidual].data(), t, q, nullptr, phi);
    else
      base_->position_residual(t, q, scratch, phi);
  }
  void velocity_residual(double t, const double* q, const double* v, double* scratch, double* f) const override {
    if (rows_[kVelocityResidual])
      rows_[kVelocityResidual]->run(row_stages_[kVelocityResidual].data(), t, q, v, f);
    else
      base_->velocity_residual(t, q, v, scratch, f);
  }
  double energy_function(double t, const double* q, const double* v, double* scratch) const override {
    // Without a tape of its own h is E (T = T2): the compiled energy, not the interpreter's.
    if (!rows_[kEnergyFunction]) return base_->energy_function_is_energy() ? energy(t, q, v, scratch)
                                                                           : base_->energy_function(t, q, v, scratch);
    double h = 0.0;
    rows_[kEnergyFunction]->run(row_stages_[kEnergyFunction].data(), t, q, v, &h);
    return h;
  }
  void power(double t, const double* q, const double* v, double* scratch, double* out) const override {
    if (rows_[kPower])
      rows_[kPower]->run(row_stages_[kPower].data(), t, q, v, out);
    else
      base_->power(t, q, v, scratch, out);
  }
  double energy(double t, const double* q, const double* v, double* scratch) const override {
    if (!rows_[kEnergy]) return base_->energy(t, q, v, scratch);
    double e = 0.0;
    rows_[kEnergy]->run(row_stages_[kEnergy].data(), t, q, v, &e);
    return e;
  }

 private:
  std::shared_ptr<const Library> library_;
  bool sparse_ = false;
  std::vector<double> stage_;  // what the terms read of the parameter stage (one spare entry)
  RowTapes rows_;
  std::array<std::vector<double>, kRowTapes> row_stages_;  // their parameter stages
};

}  // namespace

EvaluatorChoice parse_evaluator_choice(const std::string& text) {
  if (const EvaluatorChoiceInfo* info = find_named(kEvaluatorChoices, text)) return info->value;
  throw InputError(fmt::format("--evaluator: '{}' is not an evaluator; use {}", text,
                               list_names(kEvaluatorChoices, ", ", " or ")));
}

bool is_compiled(const Model& model) {
  return dynamic_cast<const CompiledEvaluator*>(model.evaluator.get()) != nullptr;
}

namespace {

// The C++ source of a model: its terms, and the tapes of the output rows (a compiled model
// computes its rows compiled too).
std::string model_source(const TapeEvaluator& base, const Model& model) {
  std::string source = make_terms_source(base.parametric_tapes().terms, base.n(), base.s(), base.sparsity());
  for (int i = 0; i < kRowTapes; ++i)
    if (const Tape* tape = row_tape(base.parametric_tapes(), i))
      source += make_tape_source(kRowTapeNames[i], *tape);
  if (model.contact_forces) source += make_tape_source("contact", model.contact_forces->tape);
  if (!model.outputs.list.empty()) source += make_tape_source("outputs", model.outputs.tape);
  return source;
}

// The compiler's identity: its --version (which also says whether it runs at all).
std::string compiler_version(const std::string& compiler, const fs::path& dir, const std::string& suffix) {
  const fs::path version_log = dir / ("version-" + suffix + ".log");
  std::string error;
  std::error_code ec;
  int caught = 0;
  int version_status = 0;
  {
    HeldSignals held;
    version_status = run({compiler, "--version"}, version_log, error, caught);
    if (caught) {
      fs::remove(version_log, ec);
      held.release_and_raise(caught);
      throw JitError("interrupted while asking the C++ compiler for its version");
    }
  }
  const std::string version = read_file(version_log);
  fs::remove(version_log, ec);
  if (version_status != 0)
    throw JitError(version_status < 0
                       ? fmt::format("the C++ compiler '{}' cannot be run ({}); set NHDYN_CXX to one", compiler, error)
                       : fmt::format("the C++ compiler '{}' fails on --version ({})", compiler, first_error(version)));
  return version;
}

// Removes the files that compiles of processes now gone left in the cache directory (a run ended by
// a signal while its background compile ran): every temporary is named with its process's id,
// unique_suffix(), as KEY-PID-N.cpp, KEY-PID-N.log, KEY.so.tmp-PID-N, KEY.so.check.tmp-PID-N or
// version-PID-N.log.
void remove_orphans(const fs::path& dir) {
  std::error_code ec;
  for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
    const std::string name = it->path().filename().string();
    std::size_t at = name.find(".tmp-");
    if (at != std::string::npos) {
      at += 5;
    } else if ((at = name.rfind('-', name.rfind('-') - 1)) != std::string::npos &&
               (name.size() > 4 && (name.ends_with(".cpp") || name.ends_with(".log")))) {
      ++at;
    } else {
      continue;
    }
    const std::size_t dash = name.find('-', at);
    if (dash == std::string::npos || dash == at) continue;
    pid_t pid = 0;
    bool digits = true;
    for (std::size_t i = at; i < dash; ++i) {
      if (name[i] < '0' || name[i] > '9') digits = false;
      else pid = pid * 10 + (name[i] - '0');
    }
    if (!digits || pid <= 0 || pid == ::getpid()) continue;
    if (::kill(pid, 0) != 0 && errno == ESRCH) fs::remove(it->path(), ec);
    ec.clear();
  }
}

// The cache entry `object` if it is there and sound, else null (a damaged entry is removed, and
// the report's note says why).
std::shared_ptr<Library> load_cached(const fs::path& object, const fs::path& check, const std::string& key,
                                     bool sparse, JitReport* report) {
  std::error_code ec;
  if (!fs::exists(object, ec) && !fs::exists(check, ec)) return nullptr;
  // Verified before dlopen: a truncated object would end the process in SIGBUS, and an object
  // copied over another model's name would give that model's motion.
  std::shared_ptr<Library> library;
  std::string error;
  std::string damage = verify_entry(object, check, key);
  if (damage.empty()) {
    library = load(object, sparse, error);
    if (!library)
      damage = error;
    else if (!library->key || key != library->key())
      damage = "it was compiled for another model";
  }
  if (damage.empty()) return library;
  library.reset();
  fs::remove(object, ec);
  fs::remove(check, ec);
  if (report)
    report->note = fmt::format("nhdyn: note: the cached compiled model {} was unusable ({}); compiling it again",
                               object.string(), damage);
  return nullptr;
}

// Compiles `source` into the cache entry `object` (with its check file) and loads it. Every
// temporary is removed on failure or interruption.
std::shared_ptr<Library> compile_entry(const std::string& source, const std::string& compiler, const fs::path& dir,
                                       const std::string& key, const std::string& suffix, const Model& model,
                                       bool sparse, JitReport* report, const std::atomic<bool>* cancel) {
  const fs::path object = dir / (key + ".so");
  const fs::path check = dir / (key + ".so.check");
  const fs::path source_file = dir / (key + "-" + suffix + ".cpp");
  const fs::path temporary = dir / (key + ".so.tmp-" + suffix);
  const fs::path check_temporary = dir / (key + ".so.check.tmp-" + suffix);
  const fs::path log = dir / (key + "-" + suffix + ".log");
  std::error_code ec;
  std::string error;
  int caught = 0;
  const auto remove_all = [&] {
    for (const fs::path* p : {&source_file, &temporary, &check_temporary, &log}) fs::remove(*p, ec);
  };
  HeldSignals held;
  {
    std::ofstream out(source_file, std::ios::binary);
    // The key inside the object: a file renamed or copied to another model's name is caught.
    out << source << fmt::format("\nextern \"C\" const char* nhdyn_jit_key() {{ return \"{}\"; }}\n", key);
    if (!out) {
      remove_all();
      throw JitError(fmt::format("cannot write {}", source_file.string()));
    }
  }
  if (cancel != nullptr && cancel->load()) {
    remove_all();
    throw JitError("the compile was cancelled");
  }
  std::vector<std::string> argv = {compiler};
  argv.insert(argv.end(), kFlags.begin(), kFlags.end());
  argv.insert(argv.end(), {"-o", temporary.string(), source_file.string()});
  const auto start = std::chrono::steady_clock::now();
  const int status = run(argv, log, error, caught, cancel);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const std::string output = status == -2 || status == -3 ? std::string() : read_file(log);
  if (status != 0) {
    remove_all();
    if (caught) {
      held.release_and_raise(caught);
      throw JitError("the compile was interrupted");
    }
    if (status == -3) throw JitError("the compile was cancelled");
    throw JitError(status < 0 ? fmt::format("the C++ compiler '{}' cannot be run ({})", compiler, error)
                              : fmt::format("the C++ compiler '{}' failed on model '{}': {}", compiler, model.name,
                                            first_error(output)));
  }
  fs::remove(source_file, ec);
  fs::remove(log, ec);
  // The check file first, then the object: whoever sees the object finds its check. Each is
  // renamed into place whole, so a concurrent process sees no file or the whole one.
  const std::string bytes = read_file(temporary);
  {
    std::ofstream out(check_temporary, std::ios::binary);
    out << entry_check(key, bytes);
    if (!out) {
      remove_all();
      throw JitError(fmt::format("cannot write {}", check_temporary.string()));
    }
  }
  fs::rename(check_temporary, check, ec);
  if (!ec) fs::rename(temporary, object, ec);
  if (ec) {
    const std::string reason = ec.message();
    remove_all();
    throw JitError(fmt::format("cannot move the compiled model into {}: {}", object.string(), reason));
  }
  if (report) {
    report->compiled = true;
    report->compile_seconds = seconds;
  }
  std::shared_ptr<Library> library = load(object, sparse, error);
  if (!library) throw JitError(fmt::format("cannot load the compiled model: {}", error));
  return library;
}

// The model with the library's functions in place of its tapes.
Model bind_library(const Model& model, std::shared_ptr<const TapeEvaluator> base, std::shared_ptr<Library> library,
                   const fs::path& object) {
  Model out = model;
  if (model.contact_forces) {
    auto contact = std::make_shared<ContactForceModel>(*model.contact_forces);
    contact->native = native_tape(library, "contact");
    if (!contact->native) throw JitError(fmt::format("{} lacks the contact forces' tape", object.string()));
    out.contact_forces = std::move(contact);
  }
  if (!model.outputs.list.empty()) {
    out.outputs.native = native_tape(library, "outputs");
    if (!out.outputs.native) throw JitError(fmt::format("{} lacks the outputs' tape", object.string()));
  }
  RowTapes rows;
  for (int i = 0; i < kRowTapes; ++i) {
    if (!row_tape(base->parametric_tapes(), i)) continue;
    rows[static_cast<std::size_t>(i)] = native_tape(library, kRowTapeNames[i]);
    if (!rows[static_cast<std::size_t>(i)])
      throw JitError(fmt::format("{} lacks the tape {}", object.string(), kRowTapeNames[i]));
  }
  out.evaluator = std::make_shared<CompiledEvaluator>(std::move(base), std::move(library), std::move(rows));
  return out;
}

}  // namespace

namespace {

// The compiler to run and the cache directory, made (and rid of the files of compiles whose
// process is gone).
std::pair<std::string, fs::path> compiler_and_cache(const JitOptions& options) {
  std::string compiler = options.compiler.empty() ? env("NHDYN_CXX") : options.compiler;
  if (compiler.empty()) compiler = "c++";
  fs::path dir = cache_directory(options);
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) throw JitError(fmt::format("cannot create the cache directory {}: {}", dir.string(), ec.message()));
  remove_orphans(dir);
  return {compiler, dir};
}

// The cache key of a model's source for a compiler: a hash of the source, the compiler's command
// and --version, and the flags.
std::string cache_key(const std::string& source, const std::string& compiler, const fs::path& dir) {
  const std::string version = compiler_version(compiler, dir, unique_suffix());
  std::string flags;
  for (const std::string& f : kFlags) flags += f + " ";
  const std::string identity = compiler + "\n" + version + "\n" + flags + "\n";
  const std::uint64_t h1 = fnv1a(source, fnv1a(identity, kFnvOffset));
  const std::uint64_t h2 = fnv1a(identity, fnv1a(source, kFnvOtherOffset));
  return fmt::format("{:016x}{:016x}", h1, h2);
}

// make_compiled, stopped (JitError) when `cancel` turns true while the compiler runs.
Model compile_model(const Model& model, const JitOptions& options, JitReport* report, const std::atomic<bool>* cancel) {
  auto base = std::dynamic_pointer_cast<const TapeEvaluator>(model.evaluator);
  if (!base)
    throw JitError(fmt::format("model '{}' has no compiled tapes (a hand-written built-in model): nothing to "
                               "compile",
                               model.name));
  const bool sparse = base->sparsity() != nullptr;
  const std::string source = model_source(*base, model);
  const auto [compiler, dir] = compiler_and_cache(options);

  const std::string suffix = unique_suffix();
  const std::string key = cache_key(source, compiler, dir);
  const fs::path object = dir / (key + ".so");
  if (report) report->object = object.string();

  std::shared_ptr<Library> library = load_cached(object, dir / (key + ".so.check"), key, sparse, report);
  if (!library) library = compile_entry(source, compiler, dir, key, suffix, model, sparse, report, cancel);
  return bind_library(model, std::move(base), std::move(library), object);
}

}  // namespace

Model make_compiled(const Model& model, const JitOptions& options, JitReport* report) {
  return compile_model(model, options, report, nullptr);
}

namespace {

// `auto` on a model not yet in the cache: a thread compiles it while the run goes on with the
// interpreter, and the compiled evaluator is published once loaded. The compiled code does the
// interpreter's operations in its order (no fused multiply-adds), so a run that switches part-way
// gives the interpreter's numbers to the bit. Whoever holds the last reference (the run's end)
// stops a compile still going (its compiler's process group ended, its files removed) instead of
// waiting for it: a short run never waits for the compiler.
class BackgroundCompile {
 public:
  BackgroundCompile(const Model& model, const JitOptions& options) {
    worker_ = std::thread([this, model, options] {
      try {
        // The stopping signals stay with the threads that run the model (held here only, so that
        // this thread's wait for the compiler does not take them).
        HeldSignals held;
        Model compiled = compile_model(model, options, nullptr, &cancel_);
        compiled_ = compiled.evaluator;
        state_.store(BackgroundState::switched, std::memory_order_release);
      } catch (const std::exception& e) {
        failure_ = e.what();
        state_.store(BackgroundState::failed, std::memory_order_release);
      }
    });
  }
  ~BackgroundCompile() {
    cancel_.store(true);
    worker_.join();
  }
  BackgroundCompile(const BackgroundCompile&) = delete;
  BackgroundCompile& operator=(const BackgroundCompile&) = delete;

  // The compiled evaluator once it is there, else null.
  const Evaluator* compiled() const {
    return state_.load(std::memory_order_acquire) == BackgroundState::switched ? compiled_.get() : nullptr;
  }
  BackgroundState state() const { return state_.load(std::memory_order_acquire); }
  std::string failure() const { return state() == BackgroundState::failed ? failure_ : std::string(); }

 private:
  std::atomic<bool> cancel_{false};
  std::atomic<BackgroundState> state_{BackgroundState::compiling};
  std::shared_ptr<const Evaluator> compiled_;  // written before state_ says switched
  std::string failure_;                        // written before state_ says failed
  std::thread worker_;                         // last: started once the rest is in place
};

// The interpreter's evaluator until the background compile is loaded, the compiled one after: for
// the terms and for the tapes of a row that the compiled evaluator runs compiled (the rest is the
// interpreter's in both). The contact forces' and the outputs' tapes stay interpreted.
class BackgroundEvaluator final : public OverInterpreter {
 public:
  BackgroundEvaluator(std::shared_ptr<const TapeEvaluator> base, std::shared_ptr<const BackgroundCompile> compile)
      : OverInterpreter(std::move(base)), compile_(std::move(compile)) {}

  const Evaluator& now() const {
    const Evaluator* compiled = compile_->compiled();
    return compiled != nullptr ? *compiled : *base_;
  }
  const BackgroundCompile& compile() const { return *compile_; }

  // Other parameter values: the compiled evaluator's rebinding when it is there, else the
  // interpreter's (which stays interpreted).
  std::shared_ptr<const Evaluator> with_parameters(const double* values, std::size_t count) const override {
    return now().with_parameters(values, count);
  }
  void terms(double t, const double* q, const double* v, double* scratch, const TermsOut& out) const override {
    now().terms(t, q, v, scratch, out);
  }
  void sparse_terms(double t, const double* q, const double* v, double* scratch, const TermsOut& out) const override {
    now().sparse_terms(t, q, v, scratch, out);
  }
  void position_residual(double t, const double* q, double* scratch, double* phi) const override {
    now().position_residual(t, q, scratch, phi);
  }
  void velocity_residual(double t, const double* q, const double* v, double* scratch, double* f) const override {
    now().velocity_residual(t, q, v, scratch, f);
  }
  double energy_function(double t, const double* q, const double* v, double* scratch) const override {
    return now().energy_function(t, q, v, scratch);
  }
  void power(double t, const double* q, const double* v, double* scratch, double* out) const override {
    now().power(t, q, v, scratch, out);
  }
  double energy(double t, const double* q, const double* v, double* scratch) const override {
    return now().energy(t, q, v, scratch);
  }

 private:
  std::shared_ptr<const BackgroundCompile> compile_;
};

// The compiled model when the cache holds its object, sound; else nullopt. Throws JitError when
// the compiler cannot be run (its version is part of the key) or the cache cannot be made.
std::optional<Model> cached_model(const Model& model, const JitOptions& options, JitReport* report) {
  auto base = std::dynamic_pointer_cast<const TapeEvaluator>(model.evaluator);
  if (!base) return std::nullopt;
  const auto [compiler, dir] = compiler_and_cache(options);
  const std::string key = cache_key(model_source(*base, model), compiler, dir);
  const fs::path object = dir / (key + ".so");
  if (report) report->object = object.string();
  std::shared_ptr<Library> library =
      load_cached(object, dir / (key + ".so.check"), key, base->sparsity() != nullptr, report);
  if (!library) return std::nullopt;
  return bind_library(model, std::move(base), std::move(library), object);
}

}  // namespace

void stop_background_compiles() noexcept {
  for (std::atomic<pid_t>& group : background_groups) {
    const pid_t g = group.load();
    if (g > 0) ::kill(-g, SIGKILL);
  }
}

BackgroundState background_state(const Model& model) {
  const auto* background = dynamic_cast<const BackgroundEvaluator*>(model.evaluator.get());
  return background != nullptr ? background->compile().state() : BackgroundState::none;
}

std::string background_notice(const Model& model) {
  const auto* background = dynamic_cast<const BackgroundEvaluator*>(model.evaluator.get());
  if (background == nullptr || background->compile().state() != BackgroundState::failed) return "";
  return fmt::format("nhdyn: notice: the model ran on the interpreter ({})", background->compile().failure());
}

Model with_evaluator(const Model& model, EvaluatorChoice choice, std::string* notice, const JitOptions& options,
                     JitReport* report) {
  if (choice == EvaluatorChoice::interpreted) return model;
  const auto* base = dynamic_cast<const TapeEvaluator*>(model.evaluator.get());
  if (base == nullptr) {
    if (choice == EvaluatorChoice::compiled && notice)
      *notice = fmt::format(
          "nhdyn: notice: model '{}' is a hand-written built-in model, C++ already: nothing to compile", model.name);
    return model;
  }
  if (choice == EvaluatorChoice::automatic &&
      base->parametric_tapes().terms.code().size() < static_cast<std::size_t>(kAutoCompileFrom))
    return model;
  // Asked for or worth it: compiled where possible, and otherwise the interpreter with a notice —
  // a missing compiler or a failed compile never fails a run (make_compiled reports it as an error).
  try {
    JitReport local;
    JitReport* made = report ? report : &local;
    if (choice == EvaluatorChoice::automatic && options.background) {
      // Cached: compiled at once. Else the run starts on the interpreter and switches when the
      // compile that starts now is done (BackgroundCompile).
      std::optional<Model> cached = cached_model(model, options, made);
      if (!made->note.empty() && notice) *notice = made->note;
      if (cached) return std::move(*cached);
      // The compile would take the run's own processor: the interpreter alone is faster.
      cpu_set_t cpus;
      if (sched_getaffinity(0, sizeof cpus, &cpus) == 0 && CPU_COUNT(&cpus) < 2) return model;
      Model out = model;
      try {
        out.evaluator = std::make_shared<BackgroundEvaluator>(
            std::dynamic_pointer_cast<const TapeEvaluator>(model.evaluator), std::make_shared<const BackgroundCompile>(model, options));
      } catch (const std::system_error& e) {  // no thread to be had: the interpreter
        if (notice) *notice = fmt::format("nhdyn: notice: using the interpreter (no thread to compile in: {})", e.what());
        return model;
      }
      return out;
    }
    Model compiled = make_compiled(model, options, made);
    if (!made->note.empty() && notice) *notice = made->note;
    return compiled;
  } catch (const JitError& e) {
    if (notice) *notice = fmt::format("nhdyn: notice: using the interpreter ({})", e.what());
    return model;
  }
}

}  // namespace nhdyn::jit
