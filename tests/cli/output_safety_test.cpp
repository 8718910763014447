// Outputs never destroy what is not theirs (io/atomic_file.hpp, docs/cli.md "Output files"): the
// built binary is run in a fresh directory and the files around it are checked. `-o` or `--plot`
// naming the model file (by its name, through a link, through a hard link) is refused with exit 2
// and the model left byte for byte; a symbolic link is written through; a FIFO gets the rows
// straight (no temporary, no rename); a default name from a hostile model name stays inside
// results/; a replaced file keeps its mode; SIGINT and SIGTERM remove the temporary file, say
// where the run stopped and exit 130 and 143. Also: every input of fuzz/corpus answers within
// 10 s and none ends in exit 3 (internal error).
#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "support/models.hpp"

namespace {

namespace fs = std::filesystem;

struct CliRun {
  int code = -1;  // exit status, or 128 + signal, or -1 when killed on the deadline
  std::string out, err;
  double seconds = 0.0;
};

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// Runs nhdyn with `args` in `cwd`; stdout and stderr go to files outside `cwd`. With `signal`,
// sends it `after` into the run. Killed (code -1) after `deadline` seconds.
CliRun run_cli(const std::vector<std::string>& args, const fs::path& cwd, int signal = 0,
          std::chrono::milliseconds after = std::chrono::milliseconds(0), double deadline = 60.0) {
  static int counter = 0;
  const fs::path logs = fs::temp_directory_path() / ("nhdyn-safety-logs-" + std::to_string(::getpid()));
  fs::create_directories(logs);
  const fs::path out = logs / (std::to_string(++counter) + ".out"), err = logs / (std::to_string(counter) + ".err");
  std::vector<std::string> strings{NHDYN_CLI_PATH};
  strings.insert(strings.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (std::string& s : strings) argv.push_back(s.data());
  argv.push_back(nullptr);
  const auto start = std::chrono::steady_clock::now();
  const pid_t pid = ::fork();
  if (pid == 0) {
    const int o = ::open(out.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    const int e = ::open(err.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    const int n = ::open("/dev/null", O_RDONLY);
    if (o < 0 || e < 0 || n < 0 || ::dup2(o, 1) < 0 || ::dup2(e, 2) < 0 || ::dup2(n, 0) < 0 ||
        ::chdir(cwd.c_str()) != 0)
      ::_exit(126);
    ::execv(argv[0], argv.data());
    ::_exit(127);
  }
  CliRun r;
  bool signalled = false;
  int status = 0;
  for (;;) {
    const pid_t done = ::waitpid(pid, &status, WNOHANG);
    if (done == pid) break;
    const auto elapsed = std::chrono::steady_clock::now() - start;
    if (signal && !signalled && elapsed >= after) {
      ::kill(pid, signal);
      signalled = true;
    }
    if (elapsed > std::chrono::duration<double>(deadline)) {
      ::kill(pid, SIGKILL);
      ::waitpid(pid, &status, 0);
      r.code = -1;
      r.out = slurp(out);
      r.err = slurp(err);
      r.seconds = deadline;
      return r;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  r.out = slurp(out);
  r.err = slurp(err);
  return r;
}

class OutputSafety : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("nhdyn-safety-" + std::to_string(::getpid()) + "-" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    fs::copy_file(fs::path(NHDYN_SOURCE_DIR) / "examples/appell.toml", dir_ / "appell.toml");
    model_ = slurp(dir_ / "appell.toml");
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::vector<std::string> temporaries() const {
    std::vector<std::string> found;
    for (const auto& e : fs::recursive_directory_iterator(dir_))
      if (e.path().filename().string().find(".tmp") != std::string::npos) found.push_back(e.path().string());
    return found;
  }
  fs::path dir_;
  std::string model_;
};

TEST_F(OutputSafety, TheModelFileIsNeverAnOutput) {
  fs::create_symlink("appell.toml", dir_ / "link.csv");
  fs::create_hard_link(dir_ / "appell.toml", dir_ / "hard.csv");
  const std::vector<std::vector<std::string>> runs{
      {"simulate", "appell.toml", "-o", "appell.toml"},
      {"simulate", "appell.toml", "-o", "./appell.toml"},
      {"simulate", "appell.toml", "-o", "link.csv"},
      {"simulate", "appell.toml", "-o", "hard.csv"},
      {"codegen", "appell.toml", "-o", "appell.toml"},
      {"compare", "appell.toml", "-o", "appell.toml"},
      {"study", "error-relation", "appell.toml", "-o", "appell.toml"},
  };
  for (const std::vector<std::string>& args : runs) {
    const CliRun r = run_cli(args, dir_);
    EXPECT_EQ(r.code, 2) << args[0] << " " << args.back() << ": " << r.err;
    EXPECT_NE(r.err.find("an input of this run"), std::string::npos) << r.err;
    EXPECT_EQ(slurp(dir_ / "appell.toml"), model_) << args[0] << " " << args.back();
  }
  EXPECT_TRUE(temporaries().empty());
}

TEST_F(OutputSafety, ASymbolicLinkIsWrittenThrough) {
  fs::create_directories(dir_ / "real");
  fs::create_symlink("real/results.csv", dir_ / "link.csv");  // dangling until written
  const CliRun r = run_cli({"simulate", "appell.toml", "-o", "link.csv", "-q"}, dir_);
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(fs::is_symlink(fs::symlink_status(dir_ / "link.csv")));
  EXPECT_TRUE(fs::is_regular_file(dir_ / "real/results.csv"));
  EXPECT_NE(slurp(dir_ / "real/results.csv").find("# end of provenance\nt,"), std::string::npos);  // provenance, then the columns
}

TEST_F(OutputSafety, AFifoGetsTheRowsStraight) {
  ASSERT_EQ(::mkfifo((dir_ / "pipe.csv").c_str(), 0644), 0);
  std::string received;
  std::thread reader([&] { received = slurp(dir_ / "pipe.csv"); });
  const CliRun r = run_cli({"simulate", "appell.toml", "-o", "pipe.csv", "-q"}, dir_);
  reader.join();
  ASSERT_EQ(r.code, 0) << r.err;
  struct stat st{};
  ASSERT_EQ(::lstat((dir_ / "pipe.csv").c_str(), &st), 0);
  EXPECT_TRUE(S_ISFIFO(st.st_mode)) << "the FIFO was replaced by a regular file";
  EXPECT_NE(received.find("# end of provenance\nt,"), std::string::npos);  // provenance, then the columns
  EXPECT_GT(std::count(received.begin(), received.end(), '\n'), 10);
  EXPECT_TRUE(temporaries().empty());
}

TEST_F(OutputSafety, ADefaultNameStaysInsideResults) {
  std::string text = model_;
  const std::size_t at = text.find("name = \"");
  ASSERT_NE(at, std::string::npos);
  const std::size_t end = text.find('"', at + 8);
  text.replace(at, end - at + 1, "name = \"../../escape\"");
  std::ofstream(dir_ / "hostile.toml") << text;
  fs::create_directories(dir_ / "work");
  const CliRun r = run_cli({"simulate", "../hostile.toml", "-q"}, dir_ / "work");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(fs::is_regular_file(dir_ / "work/results/_.._escape.csv"));
  EXPECT_FALSE(fs::exists(dir_ / "escape.csv"));
  EXPECT_FALSE(fs::exists(dir_ / "work/escape.csv"));
}

TEST_F(OutputSafety, AReplacedFileKeepsItsMode) {
  std::ofstream(dir_ / "out.csv") << "old\n";
  fs::permissions(dir_ / "out.csv", fs::perms::owner_read | fs::perms::owner_write | fs::perms::group_read);
  const CliRun r = run_cli({"simulate", "appell.toml", "-o", "out.csv", "-q"}, dir_);
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(fs::status(dir_ / "out.csv").permissions() & fs::perms::all,
            fs::perms::owner_read | fs::perms::owner_write | fs::perms::group_read);
  EXPECT_NE(slurp(dir_ / "out.csv").find("# end of provenance\nt,"), std::string::npos);  // provenance, then the columns
}

// A run long enough to be interrupted: rk4 with a tiny step over a long time.
std::vector<std::string> long_run() {
  return {"simulate", "appell.toml", "--integrator", "rk4", "--step", "1e-6", "--t-end", "1000", "-o", "out.csv"};
}

TEST_F(OutputSafety, SigintRemovesTheTemporaryAndSaysWhereItStopped) {
  const CliRun r = run_cli(long_run(), dir_, SIGINT, std::chrono::milliseconds(1500));
  EXPECT_EQ(r.code, 130) << r.err;
  EXPECT_NE(r.err.find("interrupted by SIGINT at t = "), std::string::npos) << r.err;
  EXPECT_TRUE(temporaries().empty());
  EXPECT_FALSE(fs::exists(dir_ / "out.csv"));
}

TEST_F(OutputSafety, SigtermRemovesTheTemporaryAndExits143) {
  const CliRun r = run_cli(long_run(), dir_, SIGTERM, std::chrono::milliseconds(1500));
  EXPECT_EQ(r.code, 143) << r.err;
  EXPECT_NE(r.err.find("interrupted by SIGTERM"), std::string::npos) << r.err;
  EXPECT_TRUE(temporaries().empty());
}

// Every seed of the model-file fuzzer (fuzz/corpus/, and fuzz/corpus_slow/: the Whipple bicycle,
// too slow for the fuzzer under ASan) through the command: `equations` answers within 10 s with
// exit 0 or 2, never 3; and a short `simulate` (the seeds with [outputs], [[events]] and
// [[programs]] run them) ends with 0, 1 or 2, never 3.
std::vector<fs::path> fuzz_seeds() {
  std::vector<fs::path> seeds;
  for (const char* dir : {"fuzz/corpus", "fuzz/corpus_slow"})
    for (const auto& entry : fs::directory_iterator(fs::path(NHDYN_SOURCE_DIR) / dir)) seeds.push_back(entry.path());
  std::sort(seeds.begin(), seeds.end());
  return seeds;
}

TEST(FuzzCorpus, EveryInputAnswersWithinTenSecondsWithoutInternalError) {
  const fs::path work = fs::temp_directory_path() / ("nhdyn-corpus-" + std::to_string(::getpid()));
  fs::create_directories(work);
  const std::vector<fs::path> seeds = fuzz_seeds();
  for (const fs::path& seed : seeds) {
    const CliRun r = run_cli({"equations", seed.string()}, work, 0, {}, 10.0);
    EXPECT_NE(r.code, -1) << seed << " took more than 10 s";
    EXPECT_NE(r.code, 3) << seed << ": " << r.err;
    EXPECT_TRUE(r.code == 0 || r.code == 2) << seed << " exit " << r.code << ": " << r.err;
    EXPECT_EQ(r.err.find("internal error"), std::string::npos) << seed << ": " << r.err;
  }
  EXPECT_GT(seeds.size(), 30u);
  EXPECT_TRUE(std::find(seeds.begin(), seeds.end(),
                        fs::path(NHDYN_SOURCE_DIR) / "fuzz/corpus_slow/whipple_bicycle.toml") != seeds.end());
  fs::remove_all(work);
}

TEST(FuzzCorpus, EveryInputRunsBrieflyWithoutInternalError) {
  const fs::path work = fs::temp_directory_path() / ("nhdyn-corpus-run-" + std::to_string(::getpid()));
  fs::create_directories(work);
  int ran = 0;
  for (const fs::path& seed : fuzz_seeds()) {
    const CliRun r = run_cli({"simulate", seed.string(), "--t-end", "0.01", "--output-step", "0.005", "-q", "-o",
                              (work / "out.csv").string()},
                             work, 0, {}, 10.0);
    EXPECT_NE(r.code, -1) << seed << " took more than 10 s";
    EXPECT_TRUE(r.code == 0 || r.code == 1 || r.code == 2) << seed << " exit " << r.code << ": " << r.err;
    EXPECT_EQ(r.err.find("internal error"), std::string::npos) << seed << ": " << r.err;
    ran += r.code == 0 ? 1 : 0;
  }
  EXPECT_GT(ran, 20);  // most seeds are working models
  fs::remove_all(work);
}

}  // namespace

namespace {

// A blade written as y' - tan(phi) x' = 0 on a body turning at the constant rate phi' = 1 (no
// force, centre of mass at the blade): singular where phi crosses pi/2, at t = 1.5708. The run
// warns, naming the constraint and the time.
TEST(SingularConstraint, ARowOfBThatBlowsUpIsWarnedAbout) {
  const fs::path dir = fs::temp_directory_path() / ("nhdyn-tan-" + std::to_string(::getpid()));
  fs::create_directories(dir);
  std::ofstream(dir / "tan.toml") << nhdyn::test::kTanBlade;
  const CliRun r = run_cli({"simulate", "tan.toml", "--t-end", "3", "--output-step", "0.01", "-o", "out.csv", "-q"}, dir);
  EXPECT_TRUE(r.code == 0 || r.code == 1) << r.err;
  EXPECT_NE(r.err.find("warning: constraint 'blade'"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("by t = 1.57"), std::string::npos) << r.err;
  fs::remove_all(dir);
}

}  // namespace
