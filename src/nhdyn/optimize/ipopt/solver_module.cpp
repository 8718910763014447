// solve_nlp (optimize/nlp.hpp) through nhdyn's IPOPT module (solver_module.hpp), loaded with dlopen
// the first time a program is solved and kept loaded. The module is looked for, in this order:
//   1. the file NHDYN_IPOPT_MODULE names, when that variable is set (and then nowhere else);
//   2. next to the executable or shared object this code is linked into (the Python package's folder);
//   3. where the installed command's module is, relative to the executable (bin/ -> lib/nhdyn);
//   4. where the build tree puts it.
// A module that is there but cannot be loaded (IPOPT's own libraries missing, another nhdyn's
// module) is reported as it is, not passed over for the next candidate.
#include <dlfcn.h>
#include <unistd.h>

#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "nhdyn/optimize/ipopt/solver_module.hpp"
#include "nhdyn/optimize/nlp.hpp"

namespace nhdyn {
namespace {

struct Module {
  ipopt_module::SolveFunction solve = nullptr;
  std::string error;  // why there is none, when solve is null
};

std::string folder_of(const std::string& path) {
  const std::size_t slash = path.rfind('/');
  return slash == std::string::npos ? std::string() : path.substr(0, slash);
}

// Where the module may be, in the order of the file's header.
std::vector<std::string> candidates() {
  std::vector<std::string> paths;
  Dl_info info{};
  if (dladdr(reinterpret_cast<void*>(&folder_of), &info) != 0 && info.dli_fname != nullptr &&
      std::strchr(info.dli_fname, '/') != nullptr) {
    paths.push_back(folder_of(info.dli_fname) + "/" + ipopt_module::kFileName);
  }
  std::vector<char> executable(4096);
  const ssize_t length = readlink("/proc/self/exe", executable.data(), executable.size() - 1);
  if (length > 0) {
    // /proc/self/exe is the resolved path: bin/.. is its parent, whatever links led to it.
    const std::string installed = folder_of(std::string(executable.data(), static_cast<std::size_t>(length))) +
                                  "/" + NHDYN_IPOPT_INSTALLED_FROM_BINDIR;
    paths.push_back(std::filesystem::path(installed).lexically_normal().string());
  }
  paths.emplace_back(NHDYN_IPOPT_BUILD_MODULE);
  return paths;
}

// `named`: the path is NHDYN_IPOPT_MODULE's, so a path that is no module is the variable's fault.
Module load(const std::string& path, bool named) {
  Module module;
  void* handle = dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL);
  if (handle == nullptr) {
    const char* why = dlerror();
    module.error = fmt::format(
        "nhdyn's IPOPT module {} could not be loaded: {}. {}", path, why != nullptr ? why : "unknown reason",
        named ? fmt::format("NHDYN_IPOPT_MODULE names it: set it to the path of {}, or unset it", ipopt_module::kFileName)
              : "`nhdyn optimize` needs IPOPT's libraries at run time: install coinor-libipopt-dev (sudo apt-get "
                "install coinor-libipopt-dev, or scripts/install-deps)");
    return module;
  }
  // Kept loaded for the life of the process: the solver may be called again.
  const auto interface = reinterpret_cast<ipopt_module::InterfaceFunction>(dlsym(handle, ipopt_module::kInterfaceSymbol));
  const auto solve = reinterpret_cast<ipopt_module::SolveFunction>(dlsym(handle, ipopt_module::kSolveSymbol));
  if (interface == nullptr || solve == nullptr || std::strcmp(interface(), ipopt_module::kInterface) != 0) {
    module.error = fmt::format("{} is not the IPOPT module of this nhdyn ({}): it says \"{}\". Rebuild or reinstall "
                               "nhdyn, or set NHDYN_IPOPT_MODULE to the module built with it",
                               path, ipopt_module::kInterface, interface != nullptr ? interface() : "nothing");
    return module;
  }
  module.solve = solve;
  return module;
}

Module find_and_load() {
  if (const char* named = std::getenv("NHDYN_IPOPT_MODULE"); named != nullptr && *named != '\0') {
    if (access(named, F_OK) != 0) {
      Module module;
      module.error = fmt::format("NHDYN_IPOPT_MODULE names {}, which does not exist: set it to the path of "
                                 "{}, or unset it",
                                 named, ipopt_module::kFileName);
      return module;
    }
    return load(named, true);
  }
  const std::vector<std::string> paths = candidates();
  for (const std::string& path : paths) {
    if (access(path.c_str(), F_OK) == 0) return load(path, false);
  }
  Module module;
  module.error = fmt::format("nhdyn's IPOPT module was not found (looked for {}): reinstall nhdyn, or set "
                             "NHDYN_IPOPT_MODULE to the path of its {}",
                             fmt::join(paths, ", "), ipopt_module::kFileName);
  return module;
}

const Module& module() {
  static const Module loaded = find_and_load();  // once, thread-safe
  return loaded;
}

}  // namespace

bool nlp_solver_available() { return module().solve != nullptr; }

NlpResult solve_nlp(Nlp& nlp, const NlpOptions& options) {
  NlpResult result;
  const Module& solver = module();
  if (solver.solve == nullptr) {
    result.status = NlpStatus::unavailable;
    result.message = solver.error;
    return result;
  }
  solver.solve(nlp, options, result);
  return result;
}

}  // namespace nhdyn
