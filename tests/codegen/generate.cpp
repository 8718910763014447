// Writes the generated C++ of the hand-built sled and Appell specs (hand_built_specs.hpp) into the
// folder given as argument: <folder>/sled_model.hpp and <folder>/appell_model.hpp, namespace
// nhdyn::generated. Run at build time by tests/codegen/CMakeLists.txt; once the model-file loader
// exists, `nhdyn codegen examples/<model>.toml -o ...` takes its place.
#include <cstdio>
#include <exception>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>

#include "codegen/hand_built_specs.hpp"
#include "nhdyn/symbolic/codegen.hpp"

namespace {

// Writes `text` whole: to a temporary file beside the target, then renamed.
void write_file(const std::filesystem::path& path, const std::string& text) {
  const std::filesystem::path tmp = path.string() + ".tmp";
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    out << text;
    if (!out.flush()) throw std::runtime_error("cannot write " + tmp.string());
  }
  std::filesystem::rename(tmp, path);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: %s <output folder>\n", argv[0]);
    return 2;
  }
  try {
    const std::filesystem::path folder = argv[1];
    std::filesystem::create_directories(folder);
    const nhdyn::testing::HandBuilt sled = nhdyn::testing::make_hand_built_sled();
    const nhdyn::testing::HandBuilt appell = nhdyn::testing::make_hand_built_appell();
    write_file(folder / "sled_model.hpp", nhdyn::symbolic::generate_code(sled.spec, sled.derivation));
    write_file(folder / "appell_model.hpp", nhdyn::symbolic::generate_code(appell.spec, appell.derivation));
  } catch (const std::exception& e) {
    std::fprintf(stderr, "codegen: %s\n", e.what());
    return 1;
  }
  return 0;
}
