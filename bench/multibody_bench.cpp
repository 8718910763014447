// Cost of building a model from its multibody description (symbolic/multibody.hpp, docs/multibody.md):
//   multibody/<example>/load               the model file read: bodies -> T, V, wheel constraints
//   multibody/<example>/derive_and_compile derive() then compile_model() of the loaded Spec
// for examples/rolling_disk_bodies.toml (n = 5, s = 2) and examples/whipple_bicycle.toml (n = 8,
// s = 5; issue 6 asks for derivation + compilation under 1 s). Results: docs/performance.md.
#include <benchmark/benchmark.h>

#include <filesystem>
#include <string>

#include "nhdyn/io/model_file.hpp"
#include "nhdyn/symbolic/compile.hpp"
#include "nhdyn/symbolic/derivation.hpp"

namespace nhdyn::bench {
namespace {

std::filesystem::path example(const std::string& file) {
  return std::filesystem::path(__FILE__).parent_path().parent_path() / "examples" / file;
}

void load(benchmark::State& state, const std::string& file) {
  for (auto _ : state) benchmark::DoNotOptimize(load_model_file(example(file)));
}

void derive_and_compile(benchmark::State& state, const std::string& file) {
  const symbolic::Spec spec = load_model_file(example(file));
  for (auto _ : state) benchmark::DoNotOptimize(symbolic::compile_model(spec, symbolic::derive(spec)));
}

BENCHMARK_CAPTURE(load, rolling_disk_bodies, std::string("rolling_disk_bodies.toml"))
    ->Name("multibody/rolling_disk_bodies/load")->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(derive_and_compile, rolling_disk_bodies, std::string("rolling_disk_bodies.toml"))
    ->Name("multibody/rolling_disk_bodies/derive_and_compile")->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(load, whipple_bicycle, std::string("whipple_bicycle.toml"))
    ->Name("multibody/whipple_bicycle/load")->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(derive_and_compile, whipple_bicycle, std::string("whipple_bicycle.toml"))
    ->Name("multibody/whipple_bicycle/derive_and_compile")->Unit(benchmark::kMillisecond)->Iterations(3);

}  // namespace
}  // namespace nhdyn::bench
