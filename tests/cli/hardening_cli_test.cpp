// Hostile input against the newest paths of the command (docs/cli.md, "What bad input gets"): each
// test tries one bad input a tester found and checks that it is a clear error (exit 2 naming the
// value at fault) or a correct answer, never a crash, a destroyed input or a silent wrong answer.
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "support/cli_process.hpp"
#include "support/text.hpp"

namespace {

namespace fs = std::filesystem;
using nhdyn::test::contains;
using nhdyn::test::ProcessOptions;
using nhdyn::test::ProcessRun;
using nhdyn::test::read_whole;
using nhdyn::test::run_process;

class Hardening : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("nhdyn-hardening-" + std::to_string(::getpid()) + "-" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    for (const char* name : {"sled.toml", "appell.toml"})
      fs::copy_file(fs::path(NHDYN_SOURCE_DIR) / "examples" / name, dir_ / name);
  }
  void TearDown() override { fs::remove_all(dir_); }
  void write(const std::string& name, const std::string& text) const { std::ofstream(dir_ / name) << text; }
  ProcessRun nhdyn(const std::vector<std::string>& args, const ProcessOptions& options = {}) const {
    return run_process(args, dir_, options);
  }
  fs::path dir_;
};

std::string repeat(const std::string& part, int times) {
  std::string out;
  for (int i = 0; i < times; ++i) out += part;
  return out;
}

// 20 000 nested sqrt( and 100 000 minus signs overflowed the stack of the parameter evaluator.
TEST_F(Hardening, DeeplyNestedParameterExpressionsAreRefused) {
  const std::string nested = repeat("sqrt(", 20000) + "2" + repeat(")", 20000);
  const std::string minus = repeat("-", 100000) + "1";
  for (const std::string& value : {nested, minus}) {
    const ProcessRun set = nhdyn({"simulate", "sled.toml", "--set", "a=" + value, "--t-end", "0.1", "-o", "out.csv"});
    EXPECT_EQ(set.code, 2) << set.err.substr(0, 400);
    EXPECT_TRUE(contains(set.err, "nested deeper than 256 levels")) << set.err.substr(0, 400);
    EXPECT_LT(set.err.size(), 2000u) << "the message quotes the start of the expression only";
  }
  std::string model = read_whole(dir_ / "sled.toml");
  const std::size_t at = model.find("[parameters]");
  ASSERT_NE(at, std::string::npos);
  model.insert(at + 13, "deep = \"" + nested + "\"\n");
  write("deep.toml", model);
  const ProcessRun file = nhdyn({"simulate", "deep.toml", "--t-end", "0.1", "-o", "out.csv"});
  EXPECT_EQ(file.code, 2) << file.err.substr(0, 400);
  EXPECT_TRUE(contains(file.err, "nested deeper than 256 levels")) << file.err.substr(0, 400);
  // 256 levels are still fine.
  const ProcessRun fine =
      nhdyn({"simulate", "sled.toml", "--set", "a=" + repeat("(", 200) + "0.1" + repeat(")", 200), "--t-end", "0.1",
             "-o", "out.csv"});
  EXPECT_EQ(fine.code, 0) << fine.err;
}

// --threads 40000 aborted in std::thread; it is capped at what the machine runs, with a note.
TEST_F(Hardening, HugeThreadCountIsCapped) {
  const ProcessRun r = nhdyn({"batch", "sled.toml", "--grid", "a=0.1:0.2:3", "--t-end", "0.5", "--threads", "40000",
                              "-o", "runs"});
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(contains(r.err, "using at most")) << r.err;
  EXPECT_TRUE(fs::exists(dir_ / "runs" / "summary.csv"));
  for (const auto& entry : fs::directory_iterator(dir_ / "runs"))
    EXPECT_FALSE(contains(entry.path().filename().string(), ".tmp")) << entry.path();
}

}  // namespace
