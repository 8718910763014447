#include "nhdyn/jit/compiled_evaluator.hpp"

#include <dlfcn.h>
#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <fmt/format.h>

#include <atomic>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <vector>

#include "nhdyn/jit/source.hpp"
#include "nhdyn/model/program.hpp"

extern char** environ;

namespace nhdyn::jit {
namespace {

namespace fs = std::filesystem;

// Flags: optimised, position-independent, and no contraction of a * b + c into a fused
// multiply-add (the interpreter rounds twice; so must the compiled code).
const std::vector<std::string> kFlags = {"-std=c++17", "-O2", "-fPIC", "-shared", "-ffp-contract=off",
                                         "-fno-math-errno"};

std::uint64_t fnv1a(const std::string& s, std::uint64_t h) {
  for (unsigned char ch : s) {
    h ^= ch;
    h *= 0x100000001b3ULL;
  }
  return h;
}

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

// Runs argv (searched in PATH) with stdout and stderr to `log`; returns its exit code, or -1
// with errno's text in `error` when it cannot start.
int run(const std::vector<std::string>& argv, const fs::path& log, std::string& error) {
  std::vector<char*> args;
  for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 1, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_adddup2(&actions, 1, 2);
  posix_spawn_file_actions_addopen(&actions, 0, "/dev/null", O_RDONLY, 0);
  pid_t pid = 0;
  const int spawned = posix_spawnp(&pid, args[0], &actions, nullptr, args.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (spawned != 0) {
    error = std::strerror(spawned);
    return -1;
  }
  int status = 0;
  while (waitpid(pid, &status, 0) < 0)
    if (errno != EINTR) {
      error = std::strerror(errno);
      return -1;
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
  const std::string xdg = env("XDG_CACHE_HOME");
  if (!xdg.empty()) return fs::path(xdg) / "nhdyn";
  const std::string home = env("HOME");
  if (home.empty()) throw JitError("no cache directory: neither XDG_CACHE_HOME nor HOME is set");
  return fs::path(home) / ".cache" / "nhdyn";
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
  if (!version || version() != kInterfaceVersion || !library->stage_size || !library->stage || !library->terms ||
      (sparse && !library->terms_dense)) {
    error = fmt::format("{} is not an nhdyn object of interface version {}", path.string(), kInterfaceVersion);
    return nullptr;
  }
  return library;
}

// The interpreter's evaluator with its terms replaced by the compiled ones.
class CompiledEvaluator final : public Evaluator {
 public:
  CompiledEvaluator(std::shared_ptr<const ProgramEvaluator> base, std::shared_ptr<const Library> library)
      : base_(std::move(base)), library_(std::move(library)), sparse_(base_->sparsity() != nullptr) {
    const std::vector<double>& p = base_->parameter_values();
    stage_.assign(library_->stage_size() + 1, 0.0);
    library_->stage(p.data(), stage_.data());
  }

  std::shared_ptr<const Evaluator> with_parameters(const double* values, std::size_t count) const override {
    auto rebound = std::dynamic_pointer_cast<const ProgramEvaluator>(base_->with_parameters(values, count));
    if (!rebound) return nullptr;
    return std::make_shared<CompiledEvaluator>(std::move(rebound), library_);
  }
  bool has_initial_state() const override { return base_->has_initial_state(); }
  void initial_state(double* scratch, double* q0, double* v0) const override {
    base_->initial_state(scratch, q0, v0);
  }
  std::size_t scratch_size() const override { return base_->scratch_size(); }

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
  const TermsSparsity* sparsity() const override { return base_->sparsity(); }
  void sparse_terms(double t, const double* q, const double* v, double* /*scratch*/,
                    const TermsOut& out) const override {
    library_->terms(stage_.data(), t, q, v, out.A, out.Q, out.G, out.b, out.b0);
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

 private:
  std::shared_ptr<const ProgramEvaluator> base_;
  std::shared_ptr<const Library> library_;
  bool sparse_ = false;
  std::vector<double> stage_;  // what the terms read of the parameter stage (one spare entry)
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

Model make_compiled(const Model& model, const JitOptions& options, JitReport* report) {
  auto base = std::dynamic_pointer_cast<const ProgramEvaluator>(model.evaluator);
  if (!base)
    throw JitError(fmt::format("model '{}' has no compiled programs (a hand-written built-in model): nothing to "
                               "compile",
                               model.name));
  const bool sparse = base->sparsity() != nullptr;
  const std::string source = make_terms_source(base->parametric_programs().terms, base->n(), base->s(),
                                               base->sparsity());
  std::string compiler = options.compiler.empty() ? env("NHDYN_CXX") : options.compiler;
  if (compiler.empty()) compiler = "c++";
  const fs::path dir = cache_directory(options);
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) throw JitError(fmt::format("cannot create the cache directory {}: {}", dir.string(), ec.message()));

  // The compiler's identity: its --version (which also says whether it runs at all).
  const std::string suffix = unique_suffix();
  const fs::path version_log = dir / ("version-" + suffix + ".log");
  std::string error;
  const int version_status = run({compiler, "--version"}, version_log, error);
  const std::string version = read_file(version_log);
  fs::remove(version_log, ec);
  if (version_status != 0)
    throw JitError(version_status < 0
                       ? fmt::format("the C++ compiler '{}' cannot be run ({}); set NHDYN_CXX to one", compiler, error)
                       : fmt::format("the C++ compiler '{}' fails on --version ({})", compiler, first_error(version)));

  std::string flags;
  for (const std::string& f : kFlags) flags += f + " ";
  const std::string identity = compiler + "\n" + version + "\n" + flags + "\n";
  const std::uint64_t h1 = fnv1a(source, fnv1a(identity, 0xcbf29ce484222325ULL));
  const std::uint64_t h2 = fnv1a(identity, fnv1a(source, 0x84222325cbf29ce4ULL));
  const std::string key = fmt::format("{:016x}{:016x}", h1, h2);
  const fs::path object = dir / (key + ".so");
  if (report) report->object = object.string();

  std::shared_ptr<Library> library;
  if (fs::exists(object)) {
    library = load(object, sparse, error);
    if (!library) fs::remove(object, ec);  // a corrupt entry: compile it again
  }
  if (!library) {
    const fs::path source_file = dir / (key + "-" + suffix + ".cpp");
    const fs::path temporary = dir / (key + ".so.tmp-" + suffix);
    const fs::path log = dir / (key + "-" + suffix + ".log");
    {
      std::ofstream out(source_file, std::ios::binary);
      out << source;
      if (!out) throw JitError(fmt::format("cannot write {}", source_file.string()));
    }
    std::vector<std::string> argv = {compiler};
    argv.insert(argv.end(), kFlags.begin(), kFlags.end());
    argv.insert(argv.end(), {"-o", temporary.string(), source_file.string()});
    const auto start = std::chrono::steady_clock::now();
    const int status = run(argv, log, error);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    const std::string output = read_file(log);
    fs::remove(source_file, ec);
    fs::remove(log, ec);
    if (status != 0) {
      fs::remove(temporary, ec);
      throw JitError(status < 0 ? fmt::format("the C++ compiler '{}' cannot be run ({})", compiler, error)
                                : fmt::format("the C++ compiler '{}' failed on model '{}': {}", compiler, model.name,
                                              first_error(output)));
    }
    // Atomic: a concurrent process sees no file or the whole one.
    fs::rename(temporary, object, ec);
    if (ec) {
      fs::remove(temporary, ec);
      throw JitError(fmt::format("cannot move the compiled model into {}: {}", object.string(), ec.message()));
    }
    if (report) {
      report->compiled = true;
      report->compile_seconds = seconds;
    }
    library = load(object, sparse, error);
    if (!library) throw JitError(fmt::format("cannot load the compiled model: {}", error));
  }
  Model out = model;
  out.evaluator = std::make_shared<CompiledEvaluator>(std::move(base), std::move(library));
  return out;
}

Model with_evaluator(const Model& model, EvaluatorChoice choice, std::string* notice, const JitOptions& options,
                     JitReport* report) {
  if (choice == EvaluatorChoice::interpreted) return model;
  const auto* base = dynamic_cast<const ProgramEvaluator*>(model.evaluator.get());
  if (base == nullptr) {
    if (choice == EvaluatorChoice::compiled && notice)
      *notice = fmt::format(
          "nhdyn: notice: model '{}' is a hand-written built-in model, C++ already: nothing to compile", model.name);
    return model;
  }
  if (choice == EvaluatorChoice::automatic &&
      base->parametric_programs().terms.code().size() < static_cast<std::size_t>(kAutoCompileFrom))
    return model;
  // Asked for or worth it: compiled where possible, and otherwise the interpreter with a notice —
  // a missing compiler or a failed compile never fails a run (make_compiled reports it as an error).
  try {
    return make_compiled(model, options, report);
  } catch (const JitError& e) {
    if (notice) *notice = fmt::format("nhdyn: notice: using the interpreter ({})", e.what());
    return model;
  }
}

}  // namespace nhdyn::jit
