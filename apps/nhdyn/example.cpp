// `nhdyn example NAME [--bodies N] [--set NAME=VALUE ...] [-o FILE]`: writes a generated model file
// (docs/model-format.md) to stdout or, atomically, to FILE. For now one generator: `chain`, the
// N-trailer chain of src/nhdyn/symbolic/chain.hpp (docs/gallery/chain.md).
#include <fmt/format.h>

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <memory>
#include <string>
#include <vector>

#include "commands.hpp"
#include "nhdyn/core/error.hpp"
#include "nhdyn/io/atomic_file.hpp"
#include "nhdyn/symbolic/chain.hpp"

namespace nhdyn::cli {
namespace {

struct ExampleInfo {
  const char* name;
  const char* description;
};

constexpr ExampleInfo kExamples[] = {
    {"chain", "N Chaplygin sleighs joined by pins (N-trailer), n = 3N: --bodies N, --set m|J|a|f|r|v0|w0=VALUE"},
};

std::string example_list() {
  std::string out;
  for (const ExampleInfo& e : kExamples) out += fmt::format("  {:<8} {}\n", e.name, e.description);
  return out;
}

// --bodies as the user typed it: a whole number from 1 to kMaxChainBodies, nothing else.
int parse_bodies(const std::string& text) {
  const std::string limit = fmt::format("give a whole number of bodies from 1 to {}", symbolic::kMaxChainBodies);
  std::size_t digits = (!text.empty() && (text[0] == '-' || text[0] == '+')) ? 1 : 0;
  const bool integer = text.size() > digits && text.find_first_not_of("0123456789", digits) == std::string::npos;
  if (!integer) throw InputError(fmt::format("--bodies '{}' is not a whole number: {}", text, limit));
  errno = 0;
  const long long value = std::strtoll(text.c_str(), nullptr, 10);
  if (errno == ERANGE || value < 1 || value > symbolic::kMaxChainBodies)
    throw InputError(fmt::format(
        "--bodies {} is out of range: {} (a larger chain's dense matrices, 8 (3N)^2 bytes each, do not fit in memory)", text,
        limit));
  return static_cast<int>(value);
}

double parse_value(const std::string& name, const std::string& text) {
  char* end = nullptr;
  errno = 0;
  const double value = std::strtod(text.c_str(), &end);
  if (text.empty() || end != text.c_str() + text.size() || errno == ERANGE || !std::isfinite(value))
    throw InputError(fmt::format("--set {}: '{}' is not a finite number", name, text));
  return value;
}

void apply_chain_sets(symbolic::ChainParameters& p, const std::vector<std::string>& sets) {
  for (const std::string& set : sets) {
    const std::size_t eq = set.find('=');
    if (eq == std::string::npos)
      throw InputError(fmt::format("--set '{}': write it as NAME=VALUE, e.g. --set m=2", set));
    const std::string name = set.substr(0, eq);
    const double value = parse_value(name, set.substr(eq + 1));
    if (name == "m") p.mass = value;
    else if (name == "J") p.inertia = value;
    else if (name == "a") p.com_offset = value;
    else if (name == "f") p.front_hitch = value;
    else if (name == "r") p.rear_hitch = value;
    else if (name == "v0") p.speed = value;
    else if (name == "w0") p.turn_rate = value;
    else if (name == "t_end") p.t_end = value;
    else
      throw InputError(fmt::format("--set {}: the chain has no parameter '{}'; its parameters are m, J, a, f, r, v0, "
                                   "w0 and t_end",
                                   name, name));
  }
}

}  // namespace

std::function<int()> add_example_command(CLI::App& app) {
  struct Args {
    std::string name;
    std::string bodies = "3";
    std::vector<std::string> sets;
    std::string output;
  };
  auto args = std::make_shared<Args>();
  CLI::App* cmd = app.add_subcommand("example", "Write a generated model file (nhdyn example lists them)");
  cmd->add_option("NAME", args->name, "The example to generate: chain");
  cmd->add_option("--bodies", args->bodies, "chain: number of bodies N (1 to 10000)")->capture_default_str();
  cmd->add_option("--set", args->sets, "Set a parameter, NAME=EXPR: a number or an expression in numbers, pi, e and the other parameters (repeatable)");
  cmd->add_option("-o,--output", args->output, "Write the model file here instead of stdout");
  return [args] {
    if (args->name.empty()) {
      fmt::print("nhdyn example NAME: the generated models are\n{}", example_list());
      return 0;
    }
    if (args->name != "chain")
      throw InputError(fmt::format("unknown example '{}'; the examples are\n{}", args->name, example_list()));
    symbolic::ChainParameters p;
    p.bodies = parse_bodies(args->bodies);
    apply_chain_sets(p, args->sets);
    if (args->output.empty()) {
      fmt::print("{}", symbolic::write_chain_toml(p));
      return 0;
    }
    AtomicFile file(args->output);
    file.write(symbolic::write_chain_toml(p));
    file.commit();
    return 0;
  };
}

}  // namespace nhdyn::cli
