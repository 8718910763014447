// Inputs the fuzzer found that once crashed or hung the front end (fuzz/regressions/): each must
// now end in a clear nhdyn::Error, quickly.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "nhdyn/core/error.hpp"
#include "nhdyn/frontend/model_file.hpp"
#include "nhdyn/symbolic/compile.hpp"

namespace nhdyn {
namespace {

TEST(FuzzRegressions, EachInputEndsInAClearError) {
  const std::filesystem::path dir = std::filesystem::path(NHDYN_SOURCE_DIR) / "fuzz" / "regressions";
  int files = 0;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    if (entry.path().extension() != ".toml") continue;
    ++files;
    try {
      const symbolic::Spec spec = load_model_file(entry.path());
      symbolic::compile_model(spec);
      ADD_FAILURE() << entry.path() << " was accepted";
    } catch (const Error& e) {
      const std::string message = e.what();
      EXPECT_NE(message.find(entry.path().filename().string()), std::string::npos) << message;
    }
  }
  EXPECT_GE(files, 4);
}

}  // namespace
}  // namespace nhdyn
