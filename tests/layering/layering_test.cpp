// The layering test: the allowed direction between the library's modules is written once, in the
// "layers:" table of src/nhdyn/CMakeLists.txt. This test reads that table and checks the source
// tree against it, so that the layers are checked rather than hoped for:
//   - every module folder of src/nhdyn has a line, and its CMake DEPS are within the line's;
//   - every #include "nhdyn/..." of the library, the CLI, the tests, the benchmarks, the examples,
//     the fuzzer and the Python bindings goes down the table (tests may see what their executable
//     links, per the link_<folder> lines of tests/CMakeLists.txt);
//   - GiNaC (or CLN), included directly or through any project header, is seen only inside
//     src/nhdyn/symbolic and the places listed below with their reason (never the CLI in apps/ nor
//     the Python module); a listed place that no longer sees GiNaC must be removed from the list
//     (so each change tightens it);
//   - SUNDIALS, directly or through headers, is seen only inside src/nhdyn/integrators/sundials;
//   - the umbrella header src/nhdyn/nhdyn.hpp (the public surface, for applications) may include
//     every module's headers but sees neither GiNaC nor SUNDIALS, and no module includes it;
//   - a header of a module's detail/ folder (src/nhdyn/<module>/detail/) is internal: its opening
//     comment says so in a line "// Internal: ...", and a header outside detail/ has no such line;
//   - an internal header is included only by the library and the tests, never by an application
//     (the CLI, Python, examples, benchmarks, fuzzer) nor by the umbrella header, and never by a
//     header outside detail/ (detail/ is not installed: cmake/install.cmake), so the installed
//     headers need none of it.
// The checker itself is tested on small synthetic trees that break each rule once.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstddef>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

namespace fs = std::filesystem;

namespace {

// ---------------------------------------------------------------------------------------------
// The rules that are not in the layer table: where GiNaC and SUNDIALS may be seen.

struct Allowance {
  std::string prefix;  // a folder ("tests/io/") or a file path, relative to the source root
  std::string reason;
  bool sources_only = false;  // only the .cpp files under prefix, not the headers
};

bool allows(const Allowance& a, const std::string& path) {
  return path.rfind(a.prefix, 0) == 0 && (!a.sources_only || fs::path(path).extension() == ".cpp");
}

// Places that see GiNaC by design (besides src/nhdyn/symbolic/, its home).
const std::vector<Allowance> kGinacByDesign = {
    {"src/nhdyn/studies/", "studies compute exact or 50-digit references with GiNaC (studies links symbolic)"},
    {"src/nhdyn/io/", "io's sources read the symbolic scene and equations for the report (io links symbolic); its headers stay GiNaC-free", true},
    {"src/nhdyn/frontend/", "frontend's sources translate model files into Specs and compile them (frontend links symbolic); its headers stay GiNaC-free", true},
    {"tests/symbolic/", "tests of the symbolic front end"},
    {"tests/codegen/", "hand-built Specs (GiNaC expressions) turned into C++"},
    {"tests/multibody/", "hand-built multibody Specs, tests of symbolic/multibody"},
    {"tests/support/equation_reader.hpp", "reads printed equations back into GiNaC (tests of the printer)"},
    {"examples/appell_builder.cpp", "the C++ model-building API: a Spec is made of GiNaC expressions"},
    {"bench/compile_bench.cpp", "times the symbolic compiler on hand-built Specs"},
    {"bench/chain_bench.cpp", "times the making of the chain's Spec (symbolic/chain)"},
    {"src/nhdyn/frontend/model_file.hpp", "the model-file parser's interface: it returns the Spec that load_model compiles "
                                          "and the parser's tests inspect; the CLI and Python include load_model.hpp only"},
    {"tests/io/", "tests of the model-file parser: they inspect the Spec it makes (locations, parameters, events)"},
    {"tests/gallery/", "models built with SpecBuilder or symbolic/chain next to their model files, and their equations"},
    {"tests/linearization/", "sweeps that recompile a kept Spec and derivation at each point, against set_parameter"},
    {"tests/studies/", "the spread-masses study takes a Spec (its 50-digit reference is symbolic)"},
    {"tests/report/", "compiles the Specs' [visual] scenes and checks them against the drawn page"},
    {"bench/linearize_bench.cpp", "times compile_model and linearization on a kept derivation"},
    {"bench/multibody_bench.cpp", "times derive() and compile_model() of multibody Specs"},
    {"bench/dop853_bench.cpp", "changes the bicycle's initial speed in its Spec before compiling"},
};

// Known exceptions, to be removed: a place that sees GiNaC only because it has not yet moved to
// load_model (frontend/load_model.hpp, no GiNaC). Empty now: the CLI, the Python module and every
// loader of model files go through the front door; delete each line as soon as the test says it
// is stale, and add none.
const std::vector<Allowance> kGinacToRemove = {};

bool is_ginac_header(const std::string& include) {
  return include.rfind("ginac/", 0) == 0 || include.rfind("cln/", 0) == 0;
}

bool is_sundials_header(const std::string& include) {
  static const std::vector<std::string> folders = {
      "sundials/", "cvode/", "cvodes/", "arkode/", "ida/", "idas/", "kinsol/",
      "nvector/", "sunmatrix/", "sunlinsol/", "sunnonlinsol/", "sunmemory/", "sunadaptcontroller/"};
  return std::any_of(folders.begin(), folders.end(),
                     [&](const std::string& f) { return include.rfind(f, 0) == 0; });
}

// Top-level folders scanned; each file in them is owned by a module, a test folder or an
// application (which may use every public module).
const std::vector<std::string> kScannedRoots = {"src/nhdyn", "apps", "tests", "bench", "examples", "fuzz", "python"};
const std::vector<std::string> kApplicationRoots = {"apps", "bench", "examples", "fuzz", "python"};

// ---------------------------------------------------------------------------------------------
// Reading.

std::string read_text(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream out;
  out << in.rdbuf();
  return out.str();
}

std::vector<std::string> split_words(const std::string& text) {
  std::istringstream in(text);
  std::vector<std::string> words;
  for (std::string w; in >> w;) words.push_back(w);
  return words;
}

bool starts_with(const std::string& s, const std::string& prefix) { return s.rfind(prefix, 0) == 0; }

struct Layer {
  std::set<std::string> pub;   // linked and passed on
  std::set<std::string> priv;  // linked, headers stay inside
  int line = 0;
};
using Layers = std::map<std::string, Layer>;  // module folder (relative to src/nhdyn) -> layer

using Problems = std::vector<std::string>;

// The "# layers:" table of src/nhdyn/CMakeLists.txt: comment lines "#   module: deps [private: deps]
// (remark)" after it, up to the first line that is not of that form.
Layers read_layers(const fs::path& root, Problems& problems) {
  const std::string file = "src/nhdyn/CMakeLists.txt";
  std::istringstream in(read_text(root / file));
  Layers layers;
  bool inside = false;
  int number = 0;
  static const std::regex entry(R"(^#\s+([a-z_/]+):\s*([^()]*?)\s*(\(.*\))?\s*$)");
  for (std::string line; std::getline(in, line);) {
    ++number;
    if (!inside) {
      inside = line.rfind("# layers:", 0) == 0;
      continue;
    }
    std::smatch m;
    if (!std::regex_match(line, m, entry)) break;
    Layer layer;
    layer.line = number;
    bool is_private = false;
    for (const std::string& w : split_words(m[2].str())) {
      if (w == "private:") {
        is_private = true;
        continue;
      }
      (is_private ? layer.priv : layer.pub).insert(w);
    }
    if (!layers.emplace(m[1].str(), layer).second)
      problems.push_back(file + ":" + std::to_string(number) + ": module " + m[1].str() + " has two lines");
  }
  if (layers.empty())
    problems.push_back(file + ": no \"# layers:\" table found (lines \"#   module: deps\" after \"# layers:\")");
  for (const auto& [name, layer] : layers)
    for (const auto* deps : {&layer.pub, &layer.priv})
      for (const std::string& d : *deps)
        if (!layers.count(d))
          problems.push_back(file + ":" + std::to_string(layer.line) + ": module " + name + " names " + d +
                             ", which has no line of its own");
  return layers;
}

// Module `m` and every module it passes on (its public deps, recursively).
std::set<std::string> public_closure(const Layers& layers, const std::string& m) {
  std::set<std::string> seen;
  std::vector<std::string> todo{m};
  while (!todo.empty()) {
    std::string x = todo.back();
    todo.pop_back();
    if (!seen.insert(x).second) continue;
    auto it = layers.find(x);
    if (it != layers.end()) todo.insert(todo.end(), it->second.pub.begin(), it->second.pub.end());
  }
  return seen;
}

// What files of module `m` may include: m, its public and private deps, and what those pass on;
// a module inside another's folder (integrators/sundials) implements that module's interface and
// also sees the enclosing module's headers.
std::set<std::string> visible_from(const Layers& layers, const std::string& m) {
  std::set<std::string> out{m};
  for (fs::path p = fs::path(m).parent_path(); !p.empty(); p = p.parent_path())
    if (layers.count(p.generic_string())) out.insert(p.generic_string());
  const Layer& layer = layers.at(m);
  for (const auto* deps : {&layer.pub, &layer.priv})
    for (const std::string& d : *deps) {
      std::set<std::string> c = public_closure(layers, d);
      out.insert(c.begin(), c.end());
    }
  return out;
}

// The module (a key of `layers`) that owns a path under src/nhdyn ("integrators/sundials/x.hpp" ->
// "integrators/sundials"): the longest key that is a folder prefix of the path.
std::string module_of(const Layers& layers, const std::string& path_in_nhdyn) {
  std::string best;
  for (const auto& [name, layer] : layers)
    if (starts_with(path_in_nhdyn, name + "/") && name.size() > best.size()) best = name;
  return best;
}

// Every nhdyn_module(...) and target_link_libraries(nhdyn_x ...) under src/nhdyn/<folders>: the
// module's nhdyn_* deps, public and private, must be within the table's line.
void check_deps(const fs::path& root, const Layers& layers, Problems& problems) {
  std::map<std::string, std::string> target_to_module;  // "sundials" -> "integrators/sundials"
  for (const auto& [name, layer] : layers) target_to_module[fs::path(name).filename().string()] = name;
  std::map<std::string, Layer> found;
  std::set<std::string> declared;
  static const std::regex call(R"((nhdyn_module|target_link_libraries)\s*\(([^)]*)\))");
  const fs::path base = root / "src/nhdyn";
  for (const auto& e : fs::recursive_directory_iterator(base)) {
    if (!e.is_regular_file() || e.path().filename() != "CMakeLists.txt" || e.path().parent_path() == base) continue;
    const std::string rel = fs::relative(e.path(), root).generic_string();
    std::string text = read_text(e.path());
    // Drop comments (they may mention targets).
    text = std::regex_replace(text, std::regex("#[^\n]*"), "");
    for (auto it = std::sregex_iterator(text.begin(), text.end(), call); it != std::sregex_iterator(); ++it) {
      std::vector<std::string> words = split_words((*it)[2].str());
      if (words.empty()) continue;
      const bool is_module = (*it)[1].str() == "nhdyn_module";
      std::string target = is_module ? words[0] : words[0].substr(starts_with(words[0], "nhdyn_") ? 6 : 0);
      if (!is_module && !starts_with(words[0], "nhdyn_")) continue;
      if (!target_to_module.count(target)) {
        if (is_module)
          problems.push_back(rel + ": module nhdyn_" + target +
                             " has no line in the layer table of src/nhdyn/CMakeLists.txt: add one");
        continue;
      }
      const std::string module = target_to_module[target];
      if (is_module) declared.insert(module);
      Layer& layer = found[module];
      bool in_deps = !is_module, is_private = false;
      for (std::size_t i = 1; i < words.size(); ++i) {
        const std::string& w = words[i];
        if (w == "SOURCES") in_deps = false;
        if (w == "DEPS" || w == "PUBLIC" || w == "INTERFACE") in_deps = true, is_private = false;
        if (w == "PRIVATE") in_deps = true, is_private = true;
        if (!in_deps || !starts_with(w, "nhdyn_") || w == "nhdyn_warnings") continue;
        const std::string dep = w.substr(6);
        if (!target_to_module.count(dep)) {
          problems.push_back(rel + ": nhdyn_" + target + " links " + w + ", which is not a module of the layer table");
          continue;
        }
        (is_private ? layer.priv : layer.pub).insert(target_to_module[dep]);
      }
    }
  }
  for (const auto& [name, layer] : layers) {
    if (!declared.count(name)) {
      problems.push_back("src/nhdyn/CMakeLists.txt:" + std::to_string(layer.line) + ": module " + name +
                         " has no nhdyn_module(" + fs::path(name).filename().string() + " ...) under src/nhdyn/" + name);
      continue;
    }
    const Layer& f = found[name];
    auto list = [](const std::set<std::string>& s) {
      std::string out;
      for (const auto& x : s) out += (out.empty() ? "" : " ") + x;
      return out.empty() ? std::string("(none)") : out;
    };
    // The table is what a module may link: a public dep must be public there, a private one
    // either (the table may also allow more than is linked today).
    auto within = [&](const std::set<std::string>& deps, bool is_private) {
      return std::all_of(deps.begin(), deps.end(), [&](const std::string& d) {
        return layer.pub.count(d) || (is_private && layer.priv.count(d));
      });
    };
    if (!within(f.pub, false) || !within(f.priv, true))
      problems.push_back("src/nhdyn/CMakeLists.txt:" + std::to_string(layer.line) + ": module " + name +
                         ": the table allows public {" + list(layer.pub) + "} private {" + list(layer.priv) +
                         "} but its CMake targets link public {" + list(f.pub) + "} private {" + list(f.priv) +
                         "}: change the table (the layering) or the DEPS");
  }
}

// tests/CMakeLists.txt: "set(link_<folder> nhdyn_a nhdyn_b)", what each test folder's executable links.
std::map<std::string, std::vector<std::string>> read_test_links(const fs::path& root) {
  std::map<std::string, std::vector<std::string>> links;
  std::string text = read_text(root / "tests/CMakeLists.txt");
  static const std::regex set(R"(set\s*\(\s*link_([a-z_]+)([^)]*)\))");
  for (auto it = std::sregex_iterator(text.begin(), text.end(), set); it != std::sregex_iterator(); ++it) {
    std::vector<std::string>& targets = links[(*it)[1].str()];
    for (const std::string& w : split_words((*it)[2].str()))
      if (starts_with(w, "nhdyn_")) targets.push_back(w.substr(6));
  }
  return links;
}

struct Include {
  int line;
  std::string target;  // as written between the quotes or brackets
  bool quoted;
};

struct SourceFile {
  std::vector<Include> includes;
  bool internal = false;  // "// Internal:" in the opening comment: not part of the public API
};

// Whether a path lies in a module's detail/ folder (src/nhdyn/<module>/detail/...): the library's
// own headers and sources, not installed.
bool in_detail(const std::string& path) {
  return path.rfind("src/nhdyn/", 0) == 0 && path.find("/detail/") != std::string::npos;
}
using Tree = std::map<std::string, SourceFile>;  // path relative to the root -> file

Tree scan(const fs::path& root) {
  static const std::regex include(R"(^\s*#\s*include\s*([<"])([^">]+)[">])");
  static const std::set<std::string> extensions = {".hpp", ".cpp", ".h", ".cc", ".hh", ".inl", ".ipp"};
  Tree tree;
  for (const std::string& top : kScannedRoots) {
    if (!fs::is_directory(root / top)) continue;
    for (const auto& e : fs::recursive_directory_iterator(root / top)) {
      if (!e.is_regular_file() || !extensions.count(e.path().extension().string())) continue;
      SourceFile file;
      std::istringstream in(read_text(e.path()));
      int number = 0;
      bool opening = true;  // still in the header's opening comment
      for (std::string line; std::getline(in, line);) {
        ++number;
        if (opening && line.rfind("//", 0) != 0) opening = false;
        if (opening && line.rfind("// Internal:", 0) == 0) file.internal = true;
        std::smatch m;
        if (std::regex_search(line, m, include)) file.includes.push_back({number, m[2].str(), m[1].str() == "\""});
      }
      tree[fs::relative(e.path(), root).generic_string()] = std::move(file);
    }
  }
  return tree;
}

// The project file an include names, if any: "nhdyn/..." under src/, a quoted path next to the
// includer, or under tests/ (the tests' include folder).
std::string resolve(const Tree& tree, const std::string& from, const Include& inc) {
  if (starts_with(inc.target, "nhdyn/")) return "src/" + inc.target;
  if (!inc.quoted) return {};
  for (const fs::path& base : {fs::path(from).parent_path(), fs::path("tests")}) {
    std::string candidate = (base / inc.target).lexically_normal().generic_string();
    if (tree.count(candidate)) return candidate;
  }
  return {};
}

// The public surface in one header, for applications.
const std::string kUmbrella = "src/nhdyn/nhdyn.hpp";

// Which files may include which modules.
struct Owner {
  std::string what;  // for messages: "module analysis", "tests/io (links nhdyn_io ...)", "application"
  std::set<std::string> visible;
};

Owner owner_of(const std::string& path, const Layers& layers,
               const std::map<std::string, std::vector<std::string>>& test_links, Problems& problems,
               std::set<std::string>& reported) {
  if (path == kUmbrella) {
    std::set<std::string> visible;
    for (const auto& [name, layer] : layers) {
      std::set<std::string> c = public_closure(layers, name);
      visible.insert(c.begin(), c.end());
    }
    return {"the umbrella header", visible};
  }
  if (starts_with(path, "src/nhdyn/")) {
    const std::string m = module_of(layers, path.substr(10));
    if (m.empty()) {
      const std::string folder = fs::path(path).parent_path().generic_string();
      if (reported.insert(folder).second)
        problems.push_back(path + ": folder " + folder +
                           " is no module of the layer table in src/nhdyn/CMakeLists.txt: add its line");
      return {"unknown", {}};
    }
    return {"module " + m, visible_from(layers, m)};
  }
  if (starts_with(path, "tests/")) {
    const std::string rest = path.substr(6);
    const std::string folder = rest.find('/') == std::string::npos ? "" : rest.substr(0, rest.find('/'));
    auto it = test_links.find(folder);
    if (it == test_links.end()) {
      if (reported.insert("tests/" + folder).second)
        problems.push_back(path + ": tests/" + folder + " has no set(link_" + folder +
                           " ...) in tests/CMakeLists.txt saying which modules it links");
      return {"unknown", {}};
    }
    std::set<std::string> visible;
    std::string what = "tests/" + folder + " (links";
    for (const std::string& t : it->second) {
      what += " nhdyn_" + t;
      std::string m;
      for (const auto& [name, layer] : layers)
        if (fs::path(name).filename() == t) m = name;
      if (m.empty()) continue;
      std::set<std::string> c = public_closure(layers, m);
      visible.insert(c.begin(), c.end());
    }
    what += ")";
    // The tests of a module see what the module sees, private parts included.
    if (layers.count(folder)) {
      std::set<std::string> v = visible_from(layers, folder);
      visible.insert(v.begin(), v.end());
    }
    return {what, visible};
  }
  // Applications (the CLI, benchmarks, examples, the fuzzer, the bindings) use the whole library.
  std::set<std::string> visible;
  for (const auto& [name, layer] : layers) {
    std::set<std::string> c = public_closure(layers, name);
    visible.insert(c.begin(), c.end());
  }
  return {"an application (" + path.substr(0, path.find('/')) + ")", visible};
}

void check_includes(const Tree& tree, const Layers& layers,
                    const std::map<std::string, std::vector<std::string>>& test_links, Problems& problems) {
  std::set<std::string> reported;
  for (const auto& [path, file] : tree) {
    if (fs::path(path).extension() == ".hpp" && starts_with(path, "src/nhdyn/")) {
      if (in_detail(path) && !file.internal)
        problems.push_back(path + ": a header of detail/ says in its opening comment that it is internal, in a "
                                  "line \"// Internal: <who uses it>\"");
      if (!in_detail(path) && file.internal)
        problems.push_back(path + ": marked \"// Internal:\" but outside detail/: move it to its module's detail/ "
                                  "folder (or drop the mark if it is public)");
    }
    const Owner owner = owner_of(path, layers, test_links, problems, reported);
    if (owner.what == "unknown") continue;
    for (const Include& inc : file.includes) {
      if (!starts_with(inc.target, "nhdyn/")) continue;
      const std::string m = module_of(layers, inc.target.substr(6));
      const std::string where = path + ":" + std::to_string(inc.line) + ": ";
      const bool application = owner.what.rfind("an application", 0) == 0;
      if ("src/" + inc.target == kUmbrella) {
        if (!application && !starts_with(path, "tests/"))
          problems.push_back(where + owner.what + " includes " + inc.target +
                             ", the umbrella header for applications; include the module headers it needs");
        continue;
      }
      const bool internal = in_detail("src/" + inc.target);
      if (internal && (application || path == kUmbrella))
        problems.push_back(where + owner.what + " includes " + inc.target +
                           ", a header internal to the library (detail/); use the public headers (nhdyn/nhdyn.hpp)");
      else if (internal && starts_with(path, "src/nhdyn/") && !in_detail(path) &&
               fs::path(path).extension() == ".hpp")
        problems.push_back(where + "the installed header " + path + " includes " + inc.target +
                           ", which is internal and not installed (detail/); include it from a source file, or "
                           "move the header to detail/ too");
      if (m.empty())
        problems.push_back(where + "includes " + inc.target + ", which is in no module of the layer table");
      else if (!owner.visible.count(m))
        problems.push_back(where + owner.what + " includes " + inc.target + " (module " + m +
                           "), which the layer table of src/nhdyn/CMakeLists.txt does not let it see");
    }
  }
}

// For every file, the chain of includes by which it sees a header matching `is_foreign` (empty if
// it does not): "a.hpp -> b.hpp -> <ginac/ginac.h>".
std::map<std::string, std::string> foreign_chains(const Tree& tree,
                                                  const std::function<bool(const std::string&)>& is_foreign) {
  std::map<std::string, std::string> chain;
  std::set<std::string> active;  // the files on the current include path (include guards allow cycles)
  std::function<std::string(const std::string&)> visit = [&](const std::string& path) -> std::string {
    auto done = chain.find(path);
    if (done != chain.end()) return done->second;
    std::string result;
    active.insert(path);
    const auto it = tree.find(path);
    if (it != tree.end())
      for (const Include& inc : it->second.includes) {
        if (!inc.quoted && is_foreign(inc.target)) {
          result = "<" + inc.target + "> (line " + std::to_string(inc.line) + ")";
          break;
        }
        const std::string next = resolve(tree, path, inc);
        if (next.empty() || active.count(next)) continue;
        const std::string sub = visit(next);
        if (!sub.empty()) {
          result = next + " -> " + sub;
          break;
        }
      }
    active.erase(path);
    return chain[path] = result;
  };
  for (const auto& [path, file] : tree) visit(path);
  return chain;
}

void check_fence(const Tree& tree, const std::string& name, const std::function<bool(const std::string&)>& is_foreign,
                 const std::string& home, const std::vector<Allowance>& by_design,
                 const std::vector<Allowance>& to_remove, Problems& problems) {
  const std::map<std::string, std::string> chains = foreign_chains(tree, is_foreign);
  auto matches = [](const std::string& path, const std::vector<Allowance>& list) {
    return std::any_of(list.begin(), list.end(), [&](const Allowance& a) { return allows(a, path); });
  };
  for (const auto& [path, chain] : chains) {
    if (chain.empty() || starts_with(path, home) || matches(path, by_design) || matches(path, to_remove)) continue;
    problems.push_back(path + ": sees " + name + " (" + chain + "); only " + home +
                       " may (and the places listed in tests/layering/layering_test.cpp)");
  }
  for (const auto* list : {&by_design, &to_remove})
    for (const Allowance& a : *list) {
      const bool used = std::any_of(chains.begin(), chains.end(), [&](const auto& pc) {
        return !pc.second.empty() && allows(a, pc.first);
      });
      if (!used)
        problems.push_back("tests/layering/layering_test.cpp: " + a.prefix + " is listed as seeing " + name + " (" +
                           a.reason + ") but no file there does any more: remove it from the list");
    }
}

// All rules on the tree at `root`.
Problems check_tree(const fs::path& root, const std::vector<Allowance>& ginac_by_design,
                    const std::vector<Allowance>& ginac_to_remove) {
  Problems problems;
  const Layers layers = read_layers(root, problems);
  if (layers.empty()) return problems;
  check_deps(root, layers, problems);
  const Tree tree = scan(root);
  check_includes(tree, layers, read_test_links(root), problems);
  check_fence(tree, "GiNaC", is_ginac_header, "src/nhdyn/symbolic/", ginac_by_design, ginac_to_remove, problems);
  check_fence(tree, "SUNDIALS", is_sundials_header, "src/nhdyn/integrators/sundials/", {}, {}, problems);
  return problems;
}

std::string join(const Problems& problems) {
  std::string out;
  for (const std::string& p : problems) out += p + "\n";
  return out;
}

// ---------------------------------------------------------------------------------------------
// The real tree.

TEST(Layering, SourceTreeFollowsTheLayerTable) {
  const Problems problems = check_tree(NHDYN_SOURCE_DIR, kGinacByDesign, kGinacToRemove);
  EXPECT_TRUE(problems.empty()) << problems.size() << " layering problem(s):\n" << join(problems);
}

TEST(Layering, TableHasTheLibraryModules) {
  // Guards against a table that parses to nothing or to a few lines: every folder of src/nhdyn
  // with sources is a module with a line.
  Problems problems;
  const Layers layers = read_layers(NHDYN_SOURCE_DIR, problems);
  ASSERT_TRUE(problems.empty()) << join(problems);
  for (const auto& e : fs::recursive_directory_iterator(fs::path(NHDYN_SOURCE_DIR) / "src/nhdyn")) {
    if (!e.is_regular_file() || e.path().extension() != ".cpp") continue;
    const std::string rel = fs::relative(e.path(), fs::path(NHDYN_SOURCE_DIR) / "src/nhdyn").generic_string();
    EXPECT_FALSE(module_of(layers, rel).empty()) << "src/nhdyn/" << rel << " is in no module of the layer table";
  }
  EXPECT_TRUE(layers.count("core") && layers.count("symbolic") && layers.count("integrators/sundials"));
  EXPECT_TRUE(layers.at("core").pub.empty() && layers.at("core").priv.empty()) << "core depends on no module";
}

// ---------------------------------------------------------------------------------------------
// The checker on synthetic trees: a clean tree passes, and each kind of breach is reported.

class SyntheticTree : public ::testing::Test {
 protected:
  void SetUp() override {
    root_ = fs::path(::testing::TempDir()) /
            ("nhdyn_layering_" + std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
    fs::remove_all(root_);
    write("src/nhdyn/CMakeLists.txt",
          "# layers:\n#   core:\n#   model: core\n#   integrators: core private: integrators/sundials\n"
          "#   integrators/sundials: core   (CVODE)\n#   analysis: model integrators\n"
          "#   symbolic: model   (GiNaC)\nfunction(nhdyn_module name)\nendfunction()\n");
    write("src/nhdyn/core/CMakeLists.txt", "nhdyn_module(core SOURCES a.cpp DEPS Eigen3::Eigen)\n");
    write("src/nhdyn/model/CMakeLists.txt", "nhdyn_module(model SOURCES m.cpp DEPS nhdyn_core)\n");
    write("src/nhdyn/integrators/CMakeLists.txt",
          "# nhdyn_sundials is private\nnhdyn_module(sundials SOURCES sundials/cvode.cpp DEPS nhdyn_core)\n"
          "target_link_libraries(nhdyn_sundials PRIVATE ${SUNDIALS_LIB})\n"
          "nhdyn_module(integrators SOURCES ode.cpp DEPS nhdyn_core)\n"
          "target_link_libraries(nhdyn_integrators PRIVATE nhdyn_sundials)\n");
    write("src/nhdyn/analysis/CMakeLists.txt",
          "nhdyn_module(analysis\n  SOURCES s.cpp\n  DEPS nhdyn_model nhdyn_integrators)\n");
    write("src/nhdyn/symbolic/CMakeLists.txt", "nhdyn_module(symbolic SOURCES spec.cpp DEPS nhdyn_model PkgConfig::GINAC)\n");
    write("src/nhdyn/core/a.hpp", "#include <vector>\n");
    write("src/nhdyn/model/m.hpp", "#include \"nhdyn/core/a.hpp\"\n");
    write("src/nhdyn/integrators/ode.cpp", "#include \"nhdyn/integrators/sundials/cvode.hpp\"\n");
    write("src/nhdyn/integrators/ode.hpp", "#include \"nhdyn/core/a.hpp\"\n");
    write("src/nhdyn/integrators/sundials/cvode.hpp", "#include \"nhdyn/integrators/ode.hpp\"\n");
    write("src/nhdyn/integrators/sundials/cvode.cpp", "#include \"cvode.hpp\"\n#include <cvode/cvode.h>\n");
    write("src/nhdyn/analysis/s.hpp", "#include \"nhdyn/model/m.hpp\"\n#include \"nhdyn/core/a.hpp\"\n");
    write("src/nhdyn/symbolic/spec.hpp", "#include <ginac/ginac.h>\n#include \"nhdyn/model/m.hpp\"\n");
    write("tests/CMakeLists.txt", "set(link_model nhdyn_model)\nset(link_integrators nhdyn_integrators)\n"
                                  "set(link_symbolic nhdyn_symbolic nhdyn_analysis)\n");
    write("tests/model/m_test.cpp", "#include \"nhdyn/model/m.hpp\"\n");
    write("tests/integrators/cvode_test.cpp", "#include \"nhdyn/integrators/sundials/cvode.hpp\"\n");
    write("tests/symbolic/spec_test.cpp", "#include \"nhdyn/symbolic/spec.hpp\"\n#include \"nhdyn/analysis/s.hpp\"\n");
    write("apps/cli/main.cpp", "#include \"nhdyn/analysis/s.hpp\"\n");
  }
  void TearDown() override { fs::remove_all(root_); }

  void write(const std::string& path, const std::string& text) {
    fs::create_directories((root_ / path).parent_path());
    std::ofstream(root_ / path) << text;
  }

  // The problems of the tree, with GiNaC allowed by design in tests/symbolic only.
  Problems check(const std::vector<Allowance>& to_remove = {}) {
    return check_tree(root_, {{"tests/symbolic/", "tests of symbolic"}}, to_remove);
  }

  // Whether exactly one problem is reported, and it contains every one of `parts`.
  static ::testing::AssertionResult one_problem(const Problems& problems, const std::vector<std::string>& parts) {
    if (problems.size() != 1) return ::testing::AssertionFailure() << problems.size() << " problems:\n" << join(problems);
    for (const std::string& part : parts)
      if (problems[0].find(part) == std::string::npos)
        return ::testing::AssertionFailure() << "\"" << part << "\" missing from: " << problems[0];
    return ::testing::AssertionSuccess();
  }

  fs::path root_;
};

TEST_F(SyntheticTree, CleanTreePasses) {
  const Problems problems = check();
  EXPECT_TRUE(problems.empty()) << join(problems);
}

TEST_F(SyntheticTree, UpwardIncludeIsReported) {
  write("src/nhdyn/model/bad.cpp", "#include <cmath>\n\n#include \"nhdyn/analysis/s.hpp\"\n");
  EXPECT_TRUE(one_problem(check(), {"src/nhdyn/model/bad.cpp:3", "module model", "nhdyn/analysis/s.hpp"}));
}

TEST_F(SyntheticTree, PrivateModuleIsNotPassedOn) {
  // analysis links integrators, which keeps integrators/sundials to itself.
  write("src/nhdyn/analysis/t.cpp", "#include \"nhdyn/integrators/sundials/cvode.hpp\"\n");
  EXPECT_TRUE(one_problem(check(), {"src/nhdyn/analysis/t.cpp:1", "integrators/sundials"}));
}

TEST_F(SyntheticTree, TestBeyondItsLinksIsReported) {
  write("tests/model/upward_test.cpp", "#include \"nhdyn/analysis/s.hpp\"\n");
  EXPECT_TRUE(one_problem(check(), {"tests/model/upward_test.cpp:1", "tests/model (links nhdyn_model)"}));
}

TEST_F(SyntheticTree, TestFolderWithoutLinksIsReported) {
  write("tests/extra/x_test.cpp", "#include \"nhdyn/core/a.hpp\"\n");
  EXPECT_TRUE(one_problem(check(), {"tests/extra", "set(link_extra"}));
}

TEST_F(SyntheticTree, GinacThroughHeadersIsReported) {
  // The application sees GiNaC two headers away.
  write("apps/cli/source.hpp", "#include \"nhdyn/symbolic/spec.hpp\"\n");
  write("apps/cli/run.cpp", "#include \"source.hpp\"\n");
  const Problems problems = check();
  ASSERT_EQ(problems.size(), 2U) << join(problems);
  EXPECT_NE(problems[0].find("apps/cli/run.cpp: sees GiNaC (apps/cli/source.hpp -> src/nhdyn/symbolic/spec.hpp -> "
                             "<ginac/ginac.h> (line 1))"),
            std::string::npos)
      << problems[0];
  EXPECT_NE(problems[1].find("apps/cli/source.hpp"), std::string::npos) << problems[1];
  // Listed as a known exception, it passes.
  EXPECT_TRUE(check({{"apps/cli/", "to remove"}}).empty());
}

TEST_F(SyntheticTree, DirectClnIsReported) {
  write("src/nhdyn/model/numbers.cpp", "#include <cln/integer.h>\n");
  EXPECT_TRUE(one_problem(check(), {"src/nhdyn/model/numbers.cpp", "GiNaC", "<cln/integer.h>"}));
}

TEST_F(SyntheticTree, StaleExceptionIsReported) {
  EXPECT_TRUE(one_problem(check({{"apps/cli/", "to remove"}}), {"apps/cli/", "remove it from the list"}));
}

TEST_F(SyntheticTree, SundialsOutsideItsFolderIsReported) {
  write("src/nhdyn/integrators/sundials/cvode.hpp", "#include \"nhdyn/core/a.hpp\"\n#include <nvector/nvector_serial.h>\n");
  // cvode.hpp is inside the fence; ode.cpp and the test now see SUNDIALS through it.
  const Problems problems = check();
  ASSERT_EQ(problems.size(), 2U) << join(problems);
  EXPECT_NE(problems[0].find("src/nhdyn/integrators/ode.cpp: sees SUNDIALS"), std::string::npos) << problems[0];
  EXPECT_NE(problems[1].find("tests/integrators/cvode_test.cpp: sees SUNDIALS"), std::string::npos) << problems[1];
}

TEST_F(SyntheticTree, DepsDisagreeingWithTheTableAreReported) {
  write("src/nhdyn/model/CMakeLists.txt", "nhdyn_module(model SOURCES m.cpp DEPS nhdyn_core nhdyn_integrators)\n");
  EXPECT_TRUE(one_problem(check(), {"module model", "public {core}", "public {core integrators}"}));
}

TEST_F(SyntheticTree, PrivateDepLinkedPubliclyIsReported) {
  write("src/nhdyn/integrators/CMakeLists.txt",
        "nhdyn_module(sundials SOURCES sundials/cvode.cpp DEPS nhdyn_core)\n"
        "nhdyn_module(integrators SOURCES ode.cpp DEPS nhdyn_core nhdyn_sundials)\n");
  EXPECT_TRUE(one_problem(check(), {"module integrators", "private {integrators/sundials}",
                                    "link public {core integrators/sundials}"}));
}

TEST_F(SyntheticTree, SourcesOnlyAllowanceLeavesHeadersFenced) {
  write("src/nhdyn/analysis/load.cpp", "#include \"nhdyn/symbolic/spec.hpp\"\n");
  write("src/nhdyn/analysis/load.hpp", "#include \"nhdyn/symbolic/spec.hpp\"\n");
  const Problems problems = check_tree(root_, {{"tests/symbolic/", "tests"}, {"src/nhdyn/analysis/", "sources", true}}, {});
  // The include itself is reported (analysis does not link symbolic here), then the header that
  // sees GiNaC; the source file is allowed.
  ASSERT_EQ(problems.size(), 3U) << join(problems);
  EXPECT_NE(problems[2].find("src/nhdyn/analysis/load.hpp: sees GiNaC"), std::string::npos) << problems[2];
}

TEST_F(SyntheticTree, UmbrellaHeaderServesApplicationsOnly) {
  write("src/nhdyn/nhdyn.hpp", "#include \"nhdyn/analysis/s.hpp\"\n#include \"nhdyn/integrators/ode.hpp\"\n");
  write("apps/cli/run.cpp", "#include \"nhdyn/nhdyn.hpp\"\n");
  EXPECT_TRUE(check().empty()) << join(check());
  write("src/nhdyn/analysis/t.cpp", "#include \"nhdyn/nhdyn.hpp\"\n");
  EXPECT_TRUE(one_problem(check(), {"src/nhdyn/analysis/t.cpp:1", "umbrella header"}));
}

TEST_F(SyntheticTree, UmbrellaHeaderSeeingGinacIsReported) {
  write("src/nhdyn/nhdyn.hpp", "#include \"nhdyn/symbolic/spec.hpp\"\n");
  EXPECT_TRUE(one_problem(check(), {"src/nhdyn/nhdyn.hpp: sees GiNaC"}));
}

TEST_F(SyntheticTree, InternalHeaderInAnApplicationIsReported) {
  write("src/nhdyn/model/detail/helpers.hpp", "// Kernels' helpers.\n// Internal: not for users.\n#pragma once\n");
  write("src/nhdyn/model/m.cpp", "#include \"nhdyn/model/detail/helpers.hpp\"\n");
  write("tests/model/detail_test.cpp", "#include \"nhdyn/model/detail/helpers.hpp\"\n");
  EXPECT_TRUE(check().empty()) << join(check());
  write("apps/cli/peek.cpp", "#include \"nhdyn/model/detail/helpers.hpp\"\n");
  EXPECT_TRUE(one_problem(check(), {"apps/cli/peek.cpp:1", "internal"}));
}

TEST_F(SyntheticTree, InstalledHeaderIncludingDetailIsReported) {
  write("src/nhdyn/model/detail/helpers.hpp", "// Kernels' helpers.\n// Internal: not for users.\n#pragma once\n");
  write("src/nhdyn/model/m.hpp", "#include \"nhdyn/core/a.hpp\"\n#include \"nhdyn/model/detail/helpers.hpp\"\n");
  EXPECT_TRUE(one_problem(check(), {"src/nhdyn/model/m.hpp:2", "installed header", "not installed"}));
}

TEST_F(SyntheticTree, InternalMarkAndDetailFolderGoTogether) {
  write("src/nhdyn/model/detail/helpers.hpp", "// Kernels' helpers.\n#pragma once\n");
  EXPECT_TRUE(one_problem(check(), {"src/nhdyn/model/detail/helpers.hpp", "// Internal:"}));
  write("src/nhdyn/model/detail/helpers.hpp", "// Kernels' helpers.\n// Internal: for m.cpp.\n#pragma once\n");
  write("src/nhdyn/model/loose.hpp", "// Kernels' helpers.\n// Internal: for m.cpp.\n#pragma once\n");
  EXPECT_TRUE(one_problem(check(), {"src/nhdyn/model/loose.hpp", "outside detail/"}));
}

TEST_F(SyntheticTree, ModuleWithoutLineIsReported) {
  write("src/nhdyn/jit/CMakeLists.txt", "nhdyn_module(jit SOURCES j.cpp DEPS nhdyn_model)\n");
  write("src/nhdyn/jit/j.cpp", "#include \"nhdyn/model/m.hpp\"\n");
  const Problems problems = check();
  ASSERT_EQ(problems.size(), 2U) << join(problems);
  EXPECT_NE(problems[0].find("module nhdyn_jit has no line"), std::string::npos) << problems[0];
  EXPECT_NE(problems[1].find("folder src/nhdyn/jit is no module"), std::string::npos) << problems[1];
}

}  // namespace
