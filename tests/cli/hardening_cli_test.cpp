// Hostile input against the newest paths of the command (docs/cli.md, "What bad input gets"): each
// test tries one bad input a tester found and checks that it is a clear error (exit 2 naming the
// value at fault) or a correct answer, never a crash, a destroyed input or a silent wrong answer.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/stat.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <tuple>
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
  void write_blow_up_and_earlier_table() const;
  // out/ holds the earlier table of write_blow_up_and_earlier_table, unchanged, and nothing else.
  void expect_out_untouched(const std::string& what) const;
  ProcessRun nhdyn(const std::vector<std::string>& args, const ProcessOptions& options = {}) const {
    return run_process(args, dir_, options);
  }
  fs::path dir_;
};

constexpr const char* kOscillator = R"(name = "oscillator"
coordinates = ["x"]
kinetic_energy = "m/2 * x'^2"
potential_energy = "k/2 * x^2"
[parameters]
m = 1.0
k = 1.0
[initial]
position = { x = 1 }
velocity = { x = 0 }
)";

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

// A path that never ends (/dev/zero) was read into memory until the machine ran out: a model file
// is read up to 256 MB, a CSV's line up to 64 MB, and a directory is named as one.
TEST_F(Hardening, EndlessOrDirectoryInputsAreRefusedByName) {
  const ProcessRun model = nhdyn({"simulate", "/dev/zero", "-o", "z.csv"});
  EXPECT_EQ(model.code, 2) << model.err;
  EXPECT_TRUE(contains(model.err, "/dev/zero: larger than 256 MB")) << model.err;
  EXPECT_FALSE(fs::exists(dir_ / "z.csv"));
  const ProcessRun runs = nhdyn({"batch", "sled.toml", "--runs", "/dev/zero", "--t-end", "0.1", "-o", "rb"});
  EXPECT_EQ(runs.code, 2) << runs.err;
  EXPECT_TRUE(contains(runs.err, "/dev/zero:1: a line longer than 64 MB")) << runs.err;
  const ProcessRun folder = nhdyn({"batch", "sled.toml", "--runs", ".", "--t-end", "0.1", "-o", "rb"});
  EXPECT_EQ(folder.code, 2) << folder.err;
  EXPECT_TRUE(contains(folder.err, "'.' is a directory; expected a CSV file")) << folder.err;
  EXPECT_FALSE(fs::exists(dir_ / "rb"));
}

// The shared objects (and their check files) in a cache directory, by extension.
std::vector<fs::path> cache_entries(const fs::path& cache, const std::string& extension) {
  std::vector<fs::path> out;
  if (!fs::exists(cache)) return out;
  for (const auto& entry : fs::directory_iterator(cache))
    if (entry.path().extension() == extension) out.push_back(entry.path());
  std::sort(out.begin(), out.end());
  return out;
}

// A truncated object ended every later run in SIGBUS; one copied over another model's name gave
// that model's motion. Each entry is verified before dlopen, and a bad one compiled again.
TEST_F(Hardening, DamagedCompiledModelCacheIsRebuilt) {
  ProcessOptions cached, elsewhere;
  cached.env = {{"XDG_CACHE_HOME", (dir_ / "cache").string()}};
  elsewhere.env = {{"XDG_CACHE_HOME", (dir_ / "other-cache").string()}};
  const fs::path cache = dir_ / "cache" / "nhdyn";
  ASSERT_EQ(nhdyn({"simulate", "sled.toml", "--evaluator", "compiled", "-q", "-o", "sled.csv"}, cached).code, 0);
  ASSERT_EQ(nhdyn({"simulate", "appell.toml", "--evaluator", "compiled", "-q", "-o", "a.csv"}, elsewhere).code, 0);
  const std::string sled = read_whole(dir_ / "sled.csv");
  ASSERT_EQ(cache_entries(cache, ".so").size(), 1u);
  ASSERT_EQ(cache_entries(dir_ / "other-cache" / "nhdyn", ".so").size(), 1u);
  const fs::path sled_object = cache_entries(cache, ".so").front();
  const fs::path other = cache_entries(dir_ / "other-cache" / "nhdyn", ".so").front();
  const ProcessRun again = nhdyn({"simulate", "sled.toml", "--evaluator", "compiled", "-q", "-o", "x.csv"}, cached);
  ASSERT_EQ(again.code, 0);
  EXPECT_EQ(again.err, "") << "a sound entry is loaded without a note";
  const auto damaged_run = [&](const std::string& what) {
    const ProcessRun r = nhdyn({"simulate", "sled.toml", "--evaluator", "compiled", "-q", "-o", "sled2.csv"}, cached);
    EXPECT_EQ(r.code, 0) << what << ": " << r.err;
    EXPECT_TRUE(contains(r.err, "unusable")) << what << ": " << r.err;
    EXPECT_EQ(read_whole(dir_ / "sled2.csv"), sled) << what;
    EXPECT_TRUE(fs::exists(sled_object));
  };
  // Truncated.
  fs::resize_file(sled_object, 1000);
  damaged_run("truncated");
  // Another model's object under this one's name.
  fs::copy_file(other, sled_object, fs::copy_options::overwrite_existing);
  damaged_run("another model's object");
  // And with its check file too.
  fs::copy_file(other, sled_object, fs::copy_options::overwrite_existing);
  fs::copy_file(fs::path(other.string() + ".check"), fs::path(sled_object.string() + ".check"),
                fs::copy_options::overwrite_existing);
  damaged_run("another model's object and check file");
  // A named pipe in place of the object or of its check file (the read of either waited for a
  // writer for ever), and a link to /dev/zero (whose read never ended).
  const fs::path sled_check = sled_object.string() + ".check";
  for (const fs::path& place : {sled_object, sled_check}) {
    fs::remove(place);
    ASSERT_EQ(::mkfifo(place.c_str(), 0644), 0);
    damaged_run("a named pipe at " + place.filename().string());
    fs::remove(place);
    fs::create_symlink("/dev/zero", place);
    damaged_run("a link to /dev/zero at " + place.filename().string());
  }
  // No temporary, source or log is left (the cache of derived models, which the loads may fill,
  // has its own folder there).
  for (const auto& entry : fs::directory_iterator(cache)) {
    const std::string name = entry.path().filename().string();
    EXPECT_TRUE(name.ends_with(".so") || name.ends_with(".so.check") || name == "derivations") << name;
  }
}

// A study with -q whose runs failed exited 1 with nothing on stderr; the failure is said in one
// line with or without -q (the table marks the runs FAILED).
TEST_F(Hardening, AStudyWithFailedRunsSaysSoEvenQuiet) {
  const ProcessRun r = nhdyn({"study", "error-relation", "--tolerances", "1e-3", "--atol-factor", "1e300", "-q", "-o",
                              "er.csv"});
  EXPECT_EQ(r.code, 1) << r.err;
  EXPECT_TRUE(contains(r.err, "nhdyn: error: study error-relation of 'appell': ")) << r.err;
  EXPECT_TRUE(contains(r.err, "runs failed (marked FAILED in the table); the first: ")) << r.err;
}

// An inertia matrix that is not positive definite (on the constraints), which simulate refuses,
// was linearized as if it were a motion, and a sweep through the value where it turns singular
// reported the eigenvalue passing through infinity as a crossing of zero (a divergence).
TEST_F(Hardening, LinearizeAndSweepRefuseAnInertiaSimulateRefuses) {
  const std::string model = (fs::path(NHDYN_SOURCE_DIR) / "examples" / "bicycle_linear.toml").string();
  const ProcessRun one = nhdyn({"linearize", model, "--set", "M_pp=1"});
  EXPECT_EQ(one.code, 2) << one.err;
  EXPECT_TRUE(contains(one.err, "the inertia matrix A is not positive definite at the initial state")) << one.err;
  EXPECT_TRUE(contains(one.err, "smallest eigenvalue -1.69691")) << one.err;
  const ProcessRun sweep = nhdyn({"sweep", model, "--param", "M_pp", "--from", "0", "--to", "40", "--steps", "41", "-q",
                                  "-o", "pole.csv"});
  EXPECT_EQ(sweep.code, 2) << sweep.err;
  EXPECT_TRUE(contains(sweep.err, "at M_pp = 0: model 'bicycle-linear': the inertia matrix A is not positive definite"))
      << sweep.err;
  EXPECT_FALSE(fs::exists(dir_ / "pole.csv"));
  EXPECT_EQ(nhdyn({"linearize", model, "--set", "M_pp=30"}).code, 0);
}

// `example chain --set` takes an expression, as documented (2/3 was "not a finite number"), within
// a parameter's range (1e200 was written into a file that simulate then refused).
TEST_F(Hardening, ExampleSetsTakeExpressionsWithinAParametersRange) {
  ASSERT_EQ(nhdyn({"example", "chain", "--bodies", "2", "--set", "m=2/3", "--set", "J=pi/10", "-o", "c.toml"}).code, 0);
  EXPECT_TRUE(contains(read_whole(dir_ / "c.toml"), "0.6666666666666666")) << read_whole(dir_ / "c.toml");
  EXPECT_EQ(nhdyn({"simulate", "c.toml", "--t-end", "0.1", "-q", "-o", "c.csv"}).code, 0);
  const ProcessRun huge = nhdyn({"example", "chain", "--bodies", "2", "--set", "a=1e200", "-o", "h.toml"});
  EXPECT_EQ(huge.code, 2) << huge.err;
  EXPECT_TRUE(contains(huge.err, "--set a=1e200: parameter 'a' = 1e+200 is too large")) << huge.err;
  EXPECT_FALSE(fs::exists(dir_ / "h.toml"));
}

// A relative XDG_CACHE_HOME made the compiled models' cache in the folder a command ran from; it
// is ignored, as the XDG rules say and the cache of derived models does: $HOME/.cache/nhdyn.
TEST_F(Hardening, ARelativeCacheHomeIsIgnoredByTheCompiledModelsCache) {
  ProcessOptions relative;
  relative.env = {{"XDG_CACHE_HOME", "relcache"}, {"HOME", (dir_ / "home").string()}};
  const ProcessRun r = nhdyn({"simulate", "sled.toml", "--evaluator", "compiled", "-q", "-o", "sled.csv"}, relative);
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_FALSE(fs::exists(dir_ / "relcache"));
  EXPECT_EQ(cache_entries(dir_ / "home" / ".cache" / "nhdyn", ".so").size(), 1u);
}

// An interrupted compile left its source and log, and the compiler ran on; now the compiler's
// process group is ended and nothing is left in the cache.
TEST_F(Hardening, InterruptedCompileLeavesNothing) {
  const fs::path slow = dir_ / "slow-compiler";
  std::ofstream(slow) << "#!/bin/sh\nif [ \"$1\" = --version ]; then exec c++ \"$@\"; fi\nsleep 60\nexec c++ \"$@\"\n";
  fs::permissions(slow, fs::perms::owner_all);
  for (int sig : {SIGINT, SIGTERM, SIGHUP, SIGUSR1}) {
    ProcessOptions options;
    options.env = {{"XDG_CACHE_HOME", (dir_ / "cache").string()}, {"NHDYN_CXX", slow.string()}};
    options.signal = sig;
    options.after = std::chrono::milliseconds(1500);
    options.deadline = 30;
    const ProcessRun r = nhdyn({"simulate", "sled.toml", "--evaluator", "compiled", "-o", "out.csv"}, options);
    EXPECT_EQ(r.code, 128 + sig) << r.err;
    EXPECT_TRUE(cache_entries(dir_ / "cache" / "nhdyn", ".cpp").empty());
    EXPECT_TRUE(cache_entries(dir_ / "cache" / "nhdyn", ".log").empty());
    // Nothing of the compile: the one entry a run may leave there is the cache of derived models
    // (docs/cli.md), which its load may fill and the compile does not touch.
    if (fs::exists(dir_ / "cache" / "nhdyn")) {
      for (const auto& entry : fs::directory_iterator(dir_ / "cache" / "nhdyn")) {
        EXPECT_EQ(entry.path().filename(), "derivations") << "signal " << sig << ": " << entry.path();
      }
    }
    EXPECT_FALSE(fs::exists(dir_ / "out.csv"));
    // No process still runs the slow compiler (its path is unique to this test).
    for (const auto& entry : fs::directory_iterator("/proc")) {
      const std::string cmdline = read_whole(entry.path() / "cmdline");
      EXPECT_FALSE(contains(cmdline, slow.string())) << entry.path() << " still runs the compiler";
    }
  }
}

// Outputs replaced inputs: `report R.csv -o R.csv` (also ./R.csv and a link), `-o MODEL`; outputs
// of one run replaced each other. One rule now: every path listed and checked before any work.
TEST_F(Hardening, NoOutputReplacesAnInputOrAnotherOutput) {
  ASSERT_EQ(nhdyn({"simulate", "sled.toml", "--t-end", "0.5", "-q", "-o", "r.csv"}).code, 0);
  const std::string result = read_whole(dir_ / "r.csv"), model = read_whole(dir_ / "sled.toml");
  fs::create_symlink("r.csv", dir_ / "link.csv");
  fs::create_hard_link(dir_ / "r.csv", dir_ / "hard.csv");
  for (const char* out : {"r.csv", "./r.csv", "link.csv", "hard.csv", "sled.toml"}) {
    const ProcessRun r = nhdyn({"report", "r.csv", "--model", "sled.toml", "-o", out});
    EXPECT_EQ(r.code, 2) << out << ": " << r.err;
    EXPECT_TRUE(contains(r.err, "an input of this run")) << r.err;
  }
  EXPECT_EQ(read_whole(dir_ / "r.csv"), result);
  EXPECT_EQ(read_whole(dir_ / "sled.toml"), model);
  // Two outputs of one run on one file.
  const ProcessRun same = nhdyn({"simulate", "sled.toml", "-q", "-o", "s.csv", "--html", "x.png", "--plot", "./x.png"});
  EXPECT_EQ(same.code, 2);
  EXPECT_TRUE(contains(same.err, "are the same file")) << same.err;
  const ProcessRun events =
      nhdyn({"simulate", "sled.toml", "-q", "-o", "s.csv", "--event", "turn=phi-1", "--html", "s-events.csv"});
  EXPECT_EQ(events.code, 2);
  EXPECT_TRUE(contains(events.err, "the events file")) << events.err;
  EXPECT_FALSE(fs::exists(dir_ / "s.csv"));
  // batch: its model or its --runs table inside the output folder under an output's name.
  fs::create_directories(dir_ / "out");
  fs::copy_file(dir_ / "sled.toml", dir_ / "out" / "run_0.csv");
  const ProcessRun over_model =
      nhdyn({"batch", "out/run_0.csv", "--grid", "a=0.1:0.2:2", "--t-end", "0.2", "--write-runs", "-o", "out"});
  EXPECT_EQ(over_model.code, 2) << over_model.err;
  EXPECT_EQ(read_whole(dir_ / "out" / "run_0.csv"), model);
  write("out/summary.csv", "a\n0.3\n0.4\n");
  const ProcessRun over_runs = nhdyn({"batch", "sled.toml", "--runs", "out/summary.csv", "--t-end", "0.2", "-o", "out"});
  EXPECT_EQ(over_runs.code, 2) << over_runs.err;
  EXPECT_EQ(read_whole(dir_ / "out" / "summary.csv"), "a\n0.3\n0.4\n");
}

// -o '', --html '', --plot '' were read as "not given".
TEST_F(Hardening, EmptyOptionValuesAreRefused) {
  for (const char* option : {"-o", "--html", "--plot"}) {
    const ProcessRun r = nhdyn({"simulate", "sled.toml", "--t-end", "0.1", option, ""});
    EXPECT_EQ(r.code, 2) << option;
    EXPECT_TRUE(contains(r.err, "the value is empty")) << r.err;
  }
  // A list of nothing but commas took the next argument as its value ("unknown integrator '-o'").
  for (const char* list : {",,", ",", " , "}) {
    const ProcessRun r = nhdyn({"compare", "sled.toml", "--integrators", list, "-o", "c.csv"});
    EXPECT_EQ(r.code, 2) << list;
    EXPECT_TRUE(contains(r.err, std::string("--integrators '") + list + "': the list is empty")) << r.err;
    EXPECT_FALSE(fs::exists(dir_ / "c.csv"));
  }
}

// The CLI's batch ignored the model file's [[events]]; a stop event now ends each run where the
// closed form says: x = cos(sqrt(k) t) falls through zero at pi / (2 sqrt(k)).
TEST_F(Hardening, BatchHonoursTheModelFilesEvents) {
  write("osc.toml", std::string(kOscillator) + "[[events]]\nname = \"down\"\nwhen = \"x\"\ndirection = \"falling\"\n"
                                               "action = \"stop\"\n");
  const ProcessRun r = nhdyn({"batch", "osc.toml", "--grid", "k=1:4:2", "--t-end", "5", "--rtol", "1e-10", "-o", "out"});
  ASSERT_EQ(r.code, 0) << r.err;
  std::istringstream in(nhdyn::test::csv_body(nhdyn::test::read_text(dir_ / "out" / "summary.csv")));
  std::string line;
  std::getline(in, line);
  const std::vector<std::string> header = nhdyn::test::split(line);
  const auto at = static_cast<std::size_t>(std::find(header.begin(), header.end(), "t_reached") - header.begin());
  ASSERT_LT(at, header.size());
  for (double k : {1.0, 4.0}) {
    ASSERT_TRUE(std::getline(in, line));
    const double t = std::stod(nhdyn::test::split(line)[at]);
    EXPECT_NEAR(t, 3.14159265358979 / (2 * std::sqrt(k)), 1e-7) << line;
  }
}

// A --runs table with a column twice was accepted (the last won); a grid product past the limit
// was found only after every combination was built (out of memory).
TEST_F(Hardening, BatchTablesAreCheckedFirst) {
  write("runs.csv", "a,a\n0.1,0.2\n");
  const ProcessRun twice = nhdyn({"batch", "sled.toml", "--runs", "runs.csv", "-o", "out"});
  EXPECT_EQ(twice.code, 2);
  EXPECT_TRUE(contains(twice.err, "given twice")) << twice.err;
  ProcessOptions quick;
  quick.deadline = 20;
  const ProcessRun huge = nhdyn({"batch", "sled.toml", "--grid", "a=0.1:0.2:10000000", "--grid", "rho=0.7:0.8:10000000",
                                 "-o", "out"},
                                quick);
  EXPECT_EQ(huge.code, 2) << huge.err;
  EXPECT_TRUE(contains(huge.err, "more than 10000000 runs")) << huge.err;
  // A non-finite initial value is refused with the table, not run and blamed on the model.
  write("initial.csv", "a,phi'(0)\n0.3,1\n0.4,inf\n");
  const ProcessRun infinite = nhdyn({"batch", "sled.toml", "--runs", "initial.csv", "--t-end", "0.1", "-o", "out"});
  EXPECT_EQ(infinite.code, 2) << infinite.err;
  EXPECT_TRUE(contains(infinite.err, "batch run 1: the initial value phi'(0) = inf is not a finite number"))
      << infinite.err;
  EXPECT_FALSE(fs::exists(dir_ / "out"));
  // A subnormal grid value is named as one, as --set names it (it read "not a finite number").
  const ProcessRun subnormal = nhdyn({"batch", "sled.toml", "--grid", "m=1e-320:1:2", "--t-end", "0.1", "-o", "out"});
  EXPECT_EQ(subnormal.code, 2) << subnormal.err;
  EXPECT_TRUE(contains(subnormal.err, "--grid m FROM: the number 1e-320 is subnormal")) << subnormal.err;
}

// A folder that held a larger earlier batch kept its extra run files beside the new summary without
// a word; they are not this batch's to remove, and a note says they are there.
TEST_F(Hardening, BatchNamesRunFilesThatAreNotItsOwn) {
  ASSERT_EQ(nhdyn({"batch", "sled.toml", "--grid", "a=0.2:0.6:5", "--t-end", "0.1", "--write-runs", "-q", "-o", "st"}).code,
            0);
  const ProcessRun again =
      nhdyn({"batch", "sled.toml", "--grid", "m=1:2:2", "--t-end", "0.1", "--write-runs", "-q", "-o", "st"});
  EXPECT_EQ(again.code, 0) << again.err;
  EXPECT_TRUE(contains(again.err, "holds 3 run files not of this batch of 2 runs (run_2.csv, ..., run_4.csv)"))
      << again.err;
  EXPECT_TRUE(fs::exists(dir_ / "st" / "run_4.csv"));
  const ProcessRun alone =
      nhdyn({"batch", "sled.toml", "--grid", "m=1:2:2", "--t-end", "0.1", "--write-runs", "-q", "-o", "fresh"});
  EXPECT_EQ(alone.code, 0) << alone.err;
  EXPECT_FALSE(contains(alone.err, "not of this batch")) << alone.err;
}

// SIGINT during batch --write-runs left hundreds of run files and no summary; SIGHUP and SIGUSR1
// left temporaries. A batch's outputs are written whole or not at all.
TEST_F(Hardening, InterruptedBatchLeavesNothing) {
  write("osc.toml", kOscillator);
  for (int sig : {SIGINT, SIGTERM, SIGHUP, SIGUSR1}) {
    ProcessOptions options;
    options.signal = sig;
    // Into the runs: once the batch has begun writing into out/ (a fixed delay alone raced the
    // start-up on a loaded machine), and at least 300 ms in.
    options.after = std::chrono::milliseconds(300);
    options.signal_when_written = dir_ / "out";
    options.deadline = 60;
    const ProcessRun r = nhdyn({"batch", "osc.toml", "--grid", "k=1:2:4000", "--t-end", "200", "--write-runs",
                                "--threads", "2", "-o", "out"},
                               options);
    EXPECT_EQ(r.code, 128 + sig) << r.err;
    EXPECT_TRUE(contains(r.err, "nothing was written")) << r.err;
    if (fs::exists(dir_ / "out")) {
      EXPECT_TRUE(fs::is_empty(dir_ / "out")) << "signal " << sig;
    }
  }
}

// A full disk while batch --write-runs wrote its run files left some of them, and the message said
// nothing was written. The files are staged and moved into place once all are written, so a write
// that fails (here past a file-size limit, as on a full disk) leaves the output folder empty.
TEST_F(Hardening, BatchOnAFullDiskWritesNothing) {
  write("osc.toml", kOscillator);
  const std::vector<std::string> args = {"batch", "osc.toml", "--grid", "k=1:2:20", "--t-end", "20", "--write-runs",
                                         "-o", "out"};
  ProcessOptions full;
  full.file_size_limit = 64 * 1024;  // a run file of 2001 rows is about 150 kB
  const ProcessRun r = nhdyn(args, full);
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_TRUE(contains(r.err, "failed (disk full?); nothing was written")) << r.err;
  if (fs::exists(dir_ / "out")) {
    EXPECT_TRUE(fs::is_empty(dir_ / "out"));
  }
  // With room, the summary and every run's file.
  ASSERT_EQ(nhdyn(args).code, 0);
  EXPECT_EQ(std::distance(fs::directory_iterator(dir_ / "out"), fs::directory_iterator()), 21);
}

// batch --write-runs kept every trajectory in memory until the end (760 MB for 2000 sled runs):
// each run's file is now written as the run ends, so 100 runs take the memory of 10.
TEST_F(Hardening, BatchWriteRunsStreamsToDisk) {
  write("osc.toml", kOscillator);
  const auto peak_kb = [this](int runs) {
    const ProcessRun r = nhdyn({"batch", "osc.toml", "--grid", "k=1:2:" + std::to_string(runs), "--t-end", "10",
                                "--output-step", "0.002", "--threads", "2", "--write-runs", "-o",
                                "out" + std::to_string(runs)});
    EXPECT_EQ(r.code, 0) << r.err;
    return r.max_rss_kb;
  };
  const long few = peak_kb(10), many = peak_kb(100);
  // Kept, the 90 more trajectories (5001 rows of t, x, x', x'', R_x, residuals, energy) would be
  // about 25 MB more.
  EXPECT_GT(few, 0);
  EXPECT_LT(many - few, 8 * 1024) << few << " kB for 10 runs, " << many << " kB for 100";
}

// rk4 stepped across the singular S of a program (theta = 0.3 + 0.2 t reaches pi/2 at 6.354):
// the sign of det S is watched, and the run fails between the two solves that bracket it.
TEST_F(Hardening, Rk4DoesNotStepAcrossASingularProgramMatrix) {
  const ProcessRun r = nhdyn({"simulate", fs::path(NHDYN_SOURCE_DIR) / "examples" / "cart_pendulum_program.toml",
                              "--t-end", "10", "--integrator", "rk4", "-o", "out.csv"});
  EXPECT_EQ(r.code, 1) << r.err;
  EXPECT_TRUE(contains(r.err, "changed sign")) << r.err;
  const std::size_t at = r.err.find("between t = ");
  ASSERT_NE(at, std::string::npos) << r.err;
  const double from = std::stod(r.err.substr(at + 12));
  const double to = std::stod(r.err.substr(r.err.find(" and t = ", at) + 9));
  const double singular = (3.14159265358979 / 2 - 0.3) / 0.2;
  EXPECT_LE(from, singular);
  EXPECT_GE(to, singular);
  EXPECT_LT(to - from, 0.011);
}

// --event z=1/x reported a crossing at the pole, and atan2's wrap-around counted as one: a sign
// change by a jump of g is not a crossing. x = cos t crosses zero at pi/2 (the event z = x).
// Every integrator that locates events: CVODE's own root finding stopped at the pole too.
TEST_F(Hardening, PolesAndWrapAroundsAreNotCrossings) {
  write("osc.toml", kOscillator);
  for (const char* integrator : {"dopri5", "dop853", "cvode-bdf", "cvode-adams"}) {
    SCOPED_TRACE(integrator);
    const ProcessRun r = nhdyn({"simulate", "osc.toml", "--t-end", "3", "--integrator", integrator, "--event", "p=1/x",
                                "--event", "z=x", "--event", "w=atan2(x, -1)", "-q", "-o", "e.csv"});
    ASSERT_EQ(r.code, 0) << r.err;
    const std::string events = read_whole(dir_ / "e-events.csv");
    EXPECT_FALSE(contains(events, "\np,")) << events;
    EXPECT_FALSE(contains(events, "\nw,")) << events;
    const std::size_t at = events.find("\nz,");
    ASSERT_NE(at, std::string::npos) << events;
    EXPECT_NEAR(std::stod(events.substr(at + 3)), 3.14159265358979 / 2, 1e-6);
  }
}

// report could not read nhdyn's own FILE.partial.csv (its reason line), refused a byte-order mark
// with an invisible character in the message, and accepted NaN or decreasing times.
TEST_F(Hardening, ReportReadsItsOwnPartialFilesAndChecksTimes) {
  const fs::path model = fs::path(NHDYN_SOURCE_DIR) / "examples" / "cart_pendulum_program.toml";
  ASSERT_EQ(nhdyn({"simulate", model.string(), "--t-end", "7", "-q", "-o", "cp.csv"}).code, 1);
  ASSERT_TRUE(fs::exists(dir_ / "cp.partial.csv"));
  const ProcessRun partial = nhdyn({"report", "cp.partial.csv", "--model", model.string(), "-q", "-o", "cp.html"});
  EXPECT_EQ(partial.code, 0) << partial.err;
  ASSERT_EQ(nhdyn({"simulate", "sled.toml", "--t-end", "0.3", "-q", "-o", "r.csv"}).code, 0);
  const std::string csv = read_whole(dir_ / "r.csv");
  write("bom.csv", "\xEF\xBB\xBF" + csv);
  EXPECT_EQ(nhdyn({"report", "bom.csv", "--model", "sled.toml", "-q", "-o", "bom.html"}).code, 0);
  // Rows 2 and 3 swapped: t decreases.
  std::vector<std::string> lines;
  std::stringstream in(csv);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  std::size_t names = 0;  // the column names, after the provenance header (io/provenance.hpp)
  while (lines[names].starts_with('#')) ++names;
  std::swap(lines[names + 2], lines[names + 3]);
  std::string swapped;
  for (const std::string& line : lines) swapped += line + "\n";
  write("back.csv", swapped);
  const ProcessRun back = nhdyn({"report", "back.csv", "--model", "sled.toml", "-q", "-o", "back.html"});
  EXPECT_EQ(back.code, 2);
  EXPECT_TRUE(contains(back.err, "never decrease")) << back.err;
  lines[names + 1].replace(0, lines[names + 1].find(','), "nan");
  std::string with_nan;
  for (const std::string& line : lines) with_nan += line + "\n";
  write("nan.csv", with_nan);
  const ProcessRun nan = nhdyn({"report", "nan.csv", "--model", "sled.toml", "-q", "-o", "nan.html"});
  EXPECT_EQ(nan.code, 2);
  EXPECT_TRUE(contains(nan.err, "not finite")) << nan.err;
  // Any other value that is not finite was drawn: E0 = nan gave an energy drift of 0, a NaN
  // residual was left out of its maximum. The row and the column are named; no page is written.
  std::vector<std::string> clean;
  std::stringstream again(csv);
  for (std::string line; std::getline(again, line);) clean.push_back(line);
  const auto split_commas = [](const std::string& line) {
    std::vector<std::string> cells;
    std::stringstream cells_in(line);
    for (std::string cell; std::getline(cells_in, cell, ',');) cells.push_back(cell);
    return cells;
  };
  const std::vector<std::string> header = split_commas(clean[names]);
  // The CSV with the cell of `column` in its second row replaced by `value`, reported from `file`.
  const auto report_edited = [&](std::size_t column, const std::string& value, const std::string& file) {
    std::vector<std::string> cells = split_commas(clean[names + 2]);
    cells[column] = value;
    std::string text;
    for (std::size_t i = 0; i < clean.size(); ++i) {
      if (i != names + 2) {
        text += clean[i] + "\n";
        continue;
      }
      for (std::size_t c = 0; c < cells.size(); ++c) text += (c ? "," : "") + cells[c];
      text += "\n";
    }
    write(file + ".csv", text);
    return nhdyn({"report", file + ".csv", "--model", "sled.toml", "-q", "-o", file + ".html"});
  };
  for (const std::string column : {"x", "energy", "residual_vel_blade"}) {
    const auto at = std::find(header.begin(), header.end(), column);
    ASSERT_NE(at, header.end()) << column;
    const ProcessRun r = report_edited(static_cast<std::size_t>(at - header.begin()), column == "x" ? "-inf" : "nan",
                                       "edited");
    EXPECT_EQ(r.code, 2) << column << ": " << r.err;
    EXPECT_TRUE(contains(r.err, "edited.csv: row 2: " + column + " = ")) << r.err;
    EXPECT_TRUE(contains(r.err, "is not finite; a run writes finite values")) << r.err;
    EXPECT_FALSE(fs::exists(dir_ / "edited.html")) << column;
  }
  // A character after a number is named as the expression readers name it (0xFF was called "an
  // invisible character").
  const ProcessRun zero_width = report_edited(1, "1\u200b", "zw");
  EXPECT_EQ(zero_width.code, 2) << zero_width.err;
  EXPECT_TRUE(contains(zero_width.err, "unexpected character U+200B (a zero-width space, invisible): delete it"))
      << zero_width.err;
  const ProcessRun bad_byte = report_edited(1, "1\xff", "ff");
  EXPECT_EQ(bad_byte.code, 2) << bad_byte.err;
  EXPECT_TRUE(contains(bad_byte.err, "unexpected character (the byte 0xFF, not UTF-8 text)")) << bad_byte.err;
  // strtod read 0x10 as 16.
  const ProcessRun hex = report_edited(1, "0x10", "hex");
  EXPECT_EQ(hex.code, 2) << hex.err;
  EXPECT_TRUE(contains(hex.err, "'0x10' at column 2 is not a decimal number")) << hex.err;
}

// codegen emitted parameters named INFINITY, EOF, errno, NULL as identifiers: the preprocessor
// replaced them and the header did not compile. They get a trailing underscore, as keywords do.
TEST_F(Hardening, CodegenAvoidsStandardMacros) {
  std::string model = kOscillator;
  model.replace(model.find("k = 1.0"), 7, "k = 1.0\nINFINITY = 2.0\nEOF = 1.0\nerrno = 1.0\nNULL = 1.0");
  model.replace(model.find("k/2 * x^2"), 9, "k/2 * x^2 + INFINITY*EOF*errno*NULL*x");
  write("macro.toml", model);
  const ProcessRun r = nhdyn({"codegen", "macro.toml", "-o", "macro.hpp"});
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(contains(read_whole(dir_ / "macro.hpp"), "INFINITY_"));
  write("use.cpp", "#include <cerrno>\n#include <cmath>\n#include <cstddef>\n#include <cstdio>\n#include \"macro.hpp\"\n"
                   "int main() {}\n");
  const std::string compile = "cd '" + dir_.string() + "' && c++ -std=c++20 -fsyntax-only -I'" NHDYN_SOURCE_DIR
                              "/src' -I/usr/include/eigen3 use.cpp 2> compile.log";
  EXPECT_EQ(std::system(compile.c_str()), 0) << read_whole(dir_ / "compile.log");
}

// Duplicate event names (file and command line, or the command line twice) were accepted.
TEST_F(Hardening, DuplicateEventNamesAreRefused) {
  write("osc.toml", std::string(kOscillator) + "[[events]]\nname = \"z\"\nwhen = \"x\"\n");
  const ProcessRun twice = nhdyn({"simulate", "osc.toml", "--event", "y=x'", "--event", "y=x", "-q", "-o", "a.csv"});
  EXPECT_EQ(twice.code, 2);
  EXPECT_TRUE(contains(twice.err, "two events are named 'y'")) << twice.err;
  const ProcessRun file = nhdyn({"simulate", "osc.toml", "--event", "z=x'", "-q", "-o", "a.csv"});
  EXPECT_EQ(file.code, 2);
  EXPECT_TRUE(contains(file.err, "two events are named 'z'")) << file.err;
}

}  // namespace

namespace {

// A [visual] position that is NaN or infinite at a row drawn became null in the page, drawn as
// garbage: the report is refused naming the item, its expression, t and the state; the CSV stays.
TEST_F(Hardening, NonFiniteVisualPositionsAreNamed) {
  write("vis.toml", std::string(kOscillator) + "[visual]\npoints = [{ name = \"p\", position = [\"sqrt(x)\", 0] }]\n");
  const ProcessRun r = nhdyn({"simulate", "vis.toml", "--t-end", "2", "-q", "-o", "v.csv", "--html", "v.html"});
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_TRUE(contains(r.err, "vis.toml:12:")) << r.err;
  EXPECT_TRUE(contains(r.err, "point 'p'")) << r.err;
  EXPECT_TRUE(contains(r.err, "sqrt(x)")) << r.err;
  // x = cos t is negative from pi/2 on: the first row drawn after it.
  const std::size_t at = r.err.find("is NaN at t = ");
  ASSERT_NE(at, std::string::npos) << r.err;
  const double t = std::stod(r.err.substr(at + 14));
  EXPECT_GT(t, 3.14159265358979 / 2);
  EXPECT_LT(t, 3.14159265358979 / 2 + 0.1);
  EXPECT_FALSE(fs::exists(dir_ / "v.html"));
  EXPECT_TRUE(fs::exists(dir_ / "v.csv"));
  // The same through `nhdyn report`, and a pole at the start; constant NaN or inf is refused at load.
  const ProcessRun report = nhdyn({"report", "v.csv", "--model", "vis.toml", "-q", "-o", "w.html"});
  EXPECT_EQ(report.code, 2) << report.err;
  EXPECT_TRUE(contains(report.err, "sqrt(x)")) << report.err;
  write("pole.toml", std::string(kOscillator) + "[visual]\nsegments = [{ name = \"s\", from = [0, 0], to = [\"1/(x-1)\", 0] }]\n");
  const ProcessRun pole = nhdyn({"simulate", "pole.toml", "--t-end", "1", "-q", "-o", "p.csv", "--html", "p.html"});
  EXPECT_EQ(pole.code, 2) << pole.err;
  EXPECT_TRUE(contains(pole.err, "segment 's'") && contains(pole.err, "'to' component 1") &&
              contains(pole.err, "is inf at t = 0")) << pole.err;
  for (const char* bad : {"[nan, 0]", "[inf, 0]", "[\"1/0\", 0]"}) {
    write("bad.toml", std::string(kOscillator) + "[visual]\npoints = [{ name = \"p\", position = " + bad + " }]\n");
    const ProcessRun load = nhdyn({"simulate", "bad.toml", "--t-end", "1", "-q", "-o", "b.csv", "--html", "b.html"});
    EXPECT_EQ(load.code, 2) << bad << ": " << load.err;
    EXPECT_TRUE(contains(load.err, "bad.toml:12:")) << load.err;
    EXPECT_FALSE(contains(load.err, "::")) << load.err;
  }
}

// --program-feedback 1e200,1e200 was accepted and then overflowed, 0x10 read as 16, 1e-400 called
// "not a number", nan and " 10" taken by std::stod.
TEST_F(Hardening, ProgramFeedbackValuesAreChecked) {
  const std::string model = (fs::path(NHDYN_SOURCE_DIR) / "examples" / "cart_pendulum_program.toml").string();
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"1e200,1e200", "above 1e+09 1/s"},      {"0x10,1", "'0x10' is not a decimal number"},
      {"1e-400,1", "below the smallest double"}, {"nan,1", "'nan' is not a decimal number"},
      {" 10,1", "' 10' is not a decimal number"}, {"1e400,1", "beyond the largest double"},
      {"-1,1", "must be finite and non-negative"}, {"10", "give two rates"}};
  for (const auto& [value, words] : cases) {
    const ProcessRun r = nhdyn({"simulate", model, "--t-end", "0.1", "-q", "-o", "p.csv", "--program-feedback", value});
    EXPECT_EQ(r.code, 2) << value << ": " << r.err;
    EXPECT_TRUE(contains(r.err, words)) << value << ": " << r.err;
  }
  EXPECT_EQ(nhdyn({"simulate", model, "--t-end", "0.1", "-q", "-o", "p.csv", "--program-feedback", "+5,.5e1"}).code, 0);
}

// Self and forward references in [outputs] got "unknown symbol 'a'; did you mean 't'?", and a
// chain of outputs each naming the one above several times never finished compiling.
TEST_F(Hardening, OutputReferencesAreInOrderAndBounded) {
  write("self.toml", std::string(kOscillator) + "[outputs]\na = \"a + 1\"\n");
  const ProcessRun self = nhdyn({"simulate", "self.toml", "-q", "-o", "o.csv"});
  EXPECT_EQ(self.code, 2);
  EXPECT_TRUE(contains(self.err, "self.toml:12:") && contains(self.err, "output 'a' is defined through itself"))
      << self.err;
  write("fwd.toml", std::string(kOscillator) + "[outputs]\na = \"2*b\"\nb = \"x\"\n");
  const ProcessRun forward = nhdyn({"simulate", "fwd.toml", "-q", "-o", "o.csv"});
  EXPECT_EQ(forward.code, 2);
  EXPECT_TRUE(contains(forward.err, "'b' is an output declared below 'a' (at fwd.toml:13:1)") &&
              contains(forward.err, "move 'b' above")) << forward.err;
  EXPECT_FALSE(contains(forward.err, "did you mean")) << forward.err;
  // In order, the same outputs are fine; a chain of 40 that each use the one above three times is
  // refused at once (it took minutes from 12 on), naming the line where it passes the limit.
  write("ok.toml", std::string(kOscillator) + "[outputs]\nb = \"x\"\na = \"2*b\"\n");
  EXPECT_EQ(nhdyn({"simulate", "ok.toml", "--t-end", "0.1", "-q", "-o", "o.csv"}).code, 0);
  std::string chain = std::string(kOscillator) + "[outputs]\na0 = \"x + 1\"\n";
  for (int i = 1; i <= 40; ++i)
  {
    const std::string a = "a" + std::to_string(i - 1);
    chain += "a" + std::to_string(i) + " = \"" + a + "^2 - " + a + "*x + sin(" + a + ")\"\n";
  }
  write("chain.toml", chain);
  const auto start = std::chrono::steady_clock::now();
  const ProcessRun r = nhdyn({"simulate", "chain.toml", "--t-end", "0.1", "-q", "-o", "o.csv"});
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), 20.0);
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_TRUE(contains(r.err, "chain.toml:") && contains(r.err, "with the outputs it names written out")) << r.err;
}

// An event at an output time gave two rows at the same t (and two events at one time three).
TEST_F(Hardening, AnEventAtAnOutputTimeIsOneRow) {
  write("osc.toml", kOscillator);
  const ProcessRun r = nhdyn({"simulate", "osc.toml", "--t-end", "2", "--output-step", "0.5", "--event", "z=t-1",
                              "--event", "w=t-1", "-q", "-o", "e.csv"});
  ASSERT_EQ(r.code, 0) << r.err;
  std::vector<double> times;
  std::stringstream in(read_whole(dir_ / "e.csv"));
  for (std::string line; std::getline(in, line);)
    if (!line.empty() && line[0] != '#' && line[0] != 't') times.push_back(std::stod(line));
  ASSERT_EQ(times.size(), 5u) << read_whole(dir_ / "e.csv");
  for (std::size_t i = 0; i < times.size(); ++i) EXPECT_NEAR(times[i], 0.5 * static_cast<double>(i), 1e-12);
  const std::string events = read_whole(dir_ / "e-events.csv");
  EXPECT_TRUE(contains(events, "\nz,1,") && contains(events, "\nw,1,")) << events;
}

// A stop condition that never held let the run go to its end without a word.
TEST_F(Hardening, AStopConditionThatNeverHoldsIsWarned) {
  write("osc.toml", std::string(kOscillator) + "[[events]]\nname = \"up\"\nwhen = \"x - 3\"\naction = \"stop\"\n");
  const ProcessRun r = nhdyn({"simulate", "osc.toml", "--t-end", "2", "--stop-when", "x > 2", "-q", "-o", "e.csv"});
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(contains(r.err, "warning: the stop condition --stop-when \"x > 2\" never became true")) << r.err;
  EXPECT_TRUE(contains(r.err, "osc.toml:13:") && contains(r.err, "the stop event 'up' (x - 3) never crossed zero"))
      << r.err;
  const ProcessRun met = nhdyn({"simulate", "osc.toml", "--t-end", "2", "--stop-when", "x < 0", "-q", "-o", "e.csv"});
  EXPECT_EQ(met.code, 0) << met.err;
  EXPECT_FALSE(contains(met.err, "never")) << met.err;
}

// batch and compare said nothing of a stop condition that never held. batch: simulate's sentence
// once, with the runs it holds for. x = cos t + v sin t reaches sqrt(1 + v^2): 1, 1.41, 2.24 for
// v = 0, 1, 2, so x - 1.2 never crosses zero on run 0 only, and x - 3 on none (but runs 1 and 2
// stop at the first).
TEST_F(Hardening, BatchAndCompareSayWhenAStopConditionNeverHolds) {
  write("osc.toml", std::string(kOscillator) + "[[events]]\nname = \"up\"\nwhen = \"x - 1.2\"\naction = \"stop\"\n" +
                        "[[events]]\nname = \"high\"\nwhen = \"x - 3\"\naction = \"stop\"\n");
  const ProcessRun r = nhdyn({"batch", "osc.toml", "--grid", "x'(0)=0:2:3", "--t-end", "2", "--threads", "2", "-q",
                              "-o", "out"});
  ASSERT_EQ(r.code, 0) << r.err;
  const std::string up = "osc.toml:13:9: the stop event 'up' (x - 1.2) never crossed zero in its direction between "
                         "t = 0 and t = 2: the run went to the end; check its sign, direction or threshold (run 0 of 3)";
  EXPECT_TRUE(contains(r.err, "nhdyn: warning: " + up + "\n")) << r.err;
  // Runs 1 and 2 stopped at 'up', so only run 0 went to its end without meeting 'high'.
  EXPECT_TRUE(contains(r.err, "the stop event 'high' (x - 3) never crossed zero")) << r.err;
  EXPECT_EQ(r.err.find("'high'"), r.err.rfind("'high'")) << r.err;
  // x'(0) up to 0.5: x stays below 1.2 on every run, and each sentence is said once, for all.
  const ProcessRun all = nhdyn({"batch", "osc.toml", "--grid", "x'(0)=0:0.5:3", "--t-end", "2", "-q", "-o", "out2"});
  ASSERT_EQ(all.code, 0) << all.err;
  EXPECT_TRUE(contains(all.err, "(x - 1.2) never crossed zero")) << all.err;
  EXPECT_EQ(all.err.find("'up'"), all.err.rfind("'up'")) << all.err;
  EXPECT_EQ(all.err.find("'high'"), all.err.rfind("'high'")) << all.err;
  EXPECT_EQ(std::count(all.err.begin(), all.err.end(), '\n'), 2) << all.err;
  EXPECT_TRUE(contains(all.err, "threshold (every run of 3)\n")) << all.err;
  // compare does not apply stop events (its cases are measured row by row to t_end): it says so.
  const ProcessRun c = nhdyn({"compare", "osc.toml", "--methods", "sanh", "--t-end", "1", "-q", "-o", "c.csv"});
  ASSERT_EQ(c.code, 0) << c.err;
  EXPECT_TRUE(contains(c.err, "osc.toml:13:9: the stop event 'up' (x - 1.2) is not applied by compare")) << c.err;
  EXPECT_TRUE(contains(c.err, "the stop event 'high' (x - 3) is not applied by compare")) << c.err;
}

// A character pasted from a paper or a word processor is named by its code point, with what to
// write instead; an invisible one is never shown raw (a no-break space read as "unexpected
// character ' '").
TEST_F(Hardening, InvisibleAndLookAlikeCharactersAreNamedByTheirCode) {
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"\u00a0", "unexpected character U+00A0 (a no-break space): write a plain space"},
      {"\u200b", "unexpected character U+200B (a zero-width space, invisible): delete it"},
      {"\u2212", "unexpected character '\u2212' U+2212 (a minus sign): write '-'"},
      {"\u03a6", "unexpected character '\u03a6' (U+03A6): expressions are written in ASCII"},
      // A right-to-left override would turn the rest of the message around if shown.
      {"\u202e", "unexpected character U+202E (an invisible control or format character): delete it"}};
  for (const auto& [character, words] : cases) {
    std::string model = kOscillator;
    model.replace(model.find("k/2 * x^2"), 9, "k/2 *" + character + "x^2");
    write("c.toml", model);
    const ProcessRun r = nhdyn({"simulate", "c.toml", "-q", "-o", "c.csv"});
    EXPECT_EQ(r.code, 2) << r.err;
    EXPECT_TRUE(contains(r.err, "c.toml:4:26: potential energy V: syntax error: " + words)) << r.err;
  }
  // A parameter's value, where --set reads it.
  write("osc.toml", kOscillator);
  const ProcessRun set = nhdyn({"simulate", "osc.toml", "--set", "k=2\u00a0", "-q", "-o", "c.csv"});
  EXPECT_EQ(set.code, 2) << set.err;
  EXPECT_TRUE(contains(set.err, "unexpected U+00A0 (a no-break space): write a plain space (column 2)")) << set.err;
  // The exponent's minus sign pasted as U+2212: named at its own column, not as the 'e' before it.
  const ProcessRun exponent = nhdyn({"simulate", "osc.toml", "--set", "k=1e\u22123", "-q", "-o", "c.csv"});
  EXPECT_EQ(exponent.code, 2) << exponent.err;
  EXPECT_TRUE(contains(exponent.err, "unexpected '\u2212' U+2212 (a minus sign): write '-' (column 3)")) << exponent.err;
}

// The value a message echoes (--set's, a generator's, in the same words) shows an invisible character by its code and
// a byte that is not UTF-8 by its value: echoed raw, a right-to-left override turned the rest of
// the line around, and 0xFF reached the terminal as it was.
TEST_F(Hardening, AnEchoedValueNeverCarriesAnInvisibleCharacterOrABadByte) {
  write("osc.toml", kOscillator);
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"k=2\u200b", "--set k=2<U+200B>: '2<U+200B>' is not a valid expression"},
      {"k=\u202e2", "--set k=<U+202E>2: '<U+202E>2' is not a valid expression"},
      {"k=\xff", "--set k=<0xFF>: '<0xFF>' is not a valid expression: unexpected (the byte 0xFF, not UTF-8 text)"},
      {"k\u200b", "--set 'k<U+200B>': write it as NAME=VALUE"}};
  for (const auto& [set, words] : cases) {
    for (const std::vector<std::string>& args :
         {std::vector<std::string>{"simulate", "osc.toml", "--set", set, "-q", "-o", "c.csv"},
          std::vector<std::string>{"example", "chain", "--set", set}}) {
      const ProcessRun r = nhdyn(args);
      EXPECT_EQ(r.code, 2) << r.err;
      EXPECT_TRUE(contains(r.err, words)) << r.err;
      for (const char* raw : {"\u200b", "\u202e", "\xff"}) EXPECT_FALSE(contains(r.err, raw)) << r.err;
    }
  }
  // A model file's name and description, printed on terminals and into every file a run writes,
  // refuse such characters at their line (a raw escape is TOML's own error; written as \u001b it
  // is ours); visible ones (an accent, a Greek letter) stay.
  for (const auto& [key, text, shown] :
       std::vector<std::tuple<std::string, std::string, std::string>>{
           {"name", "sl\u202eed", "sl<U+202E>ed"}, {"description", "a \\u001b[2J sled", "a <U+001B>[2J sled"}}) {
    std::string model = kOscillator;
    if (key == "name") model.replace(model.find("name = \""), 8, "name = \"" + text);
    else model = "description = \"" + text + "\"\n" + model;
    write("named.toml", model);
    const ProcessRun r = nhdyn({"simulate", "named.toml", "-q", "-o", "c.csv"});
    EXPECT_EQ(r.code, 2) << r.err;
    EXPECT_TRUE(contains(r.err, "named.toml:1:") && contains(r.err, key + " \"") && contains(r.err, shown) &&
                contains(r.err, "has an invisible character or a byte that is not UTF-8"))
        << r.err;
  }
  {
    write("named.toml", "description = \"Schlitten \u00e9\u03a6\"\n" + std::string(kOscillator));
    const ProcessRun r = nhdyn({"simulate", "named.toml", "-q", "-o", "c.csv"});
    EXPECT_EQ(r.code, 0) << r.err;
  }
  // An output's path, as the summary names it (the file itself is written where it was asked).
  {
    const ProcessRun r = nhdyn({"simulate", "osc.toml", "--t-end", "0.1", "-o", "a\u202e.csv"});
    EXPECT_EQ(r.code, 0) << r.err;
    EXPECT_TRUE(contains(r.out, "rows -> a<U+202E>.csv")) << r.out;
    EXPECT_FALSE(contains(r.out, "\u202e")) << r.out;
  }
  // Whatever a message echoes of the arguments: an unknown command, option, model or event.
  const std::vector<std::pair<std::vector<std::string>, std::string>> echoes = {
      {{"si\u200bm"}, "unknown command 'si<U+200B>m'"},
      {{"simulate", "osc.toml", "--\u202ex"}, "The following argument was not expected: --<U+202E>x"},
      {{"simulate", "sl\u202eed"}, "unknown model 'sl<U+202E>ed'"},
      {{"simulate", "osc.toml", "--event", "e=x\xff", "-o", "c.csv"}, "--event \"e=x<0xFF>\""}};
  for (const auto& [args, words] : echoes) {
    const ProcessRun r = nhdyn(args);
    EXPECT_EQ(r.code, 2) << r.err;
    EXPECT_TRUE(contains(r.err, words)) << r.err;
    for (const char* raw : {"\u200b", "\u202e", "\xff"}) EXPECT_FALSE(contains(r.err, raw)) << r.err;
  }
}

// GiNaC's own words ("power::eval(): division by zero", "log_eval(): log(0)") reached the user.
TEST_F(Hardening, GinacWordsAreTranslated) {
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"m/2 * x'^2/(0*x)", "divides by zero"}, {"m/2 * x'^2 + 0^0*x", "0^0, which is undefined"},
      {"m/2 * x'^2 + log(0)*x", "log(0), which is not finite"},
      // 0 to a power that is not a number: its derivative made GiNaC throw (exit 3, "internal error").
      {"m/2 * x'^2 + 0^x", "raises 0 to a power that is not a number"},
      {"m/2 * x'^2 + (x - x)^(x + 2)", "raises 0 to a power that is not a number"},
      {"m/2 * (0^x' + 1) * x'^2", "raises 0 to a power that is not a number"}};
  for (const auto& [energy, words] : cases) {
    std::string model = kOscillator;
    model.replace(model.find("m/2 * x'^2"), 10, energy);
    write("g.toml", model);
    const ProcessRun r = nhdyn({"simulate", "g.toml", "-q", "-o", "g.csv"});
    EXPECT_EQ(r.code, 2) << r.err;
    EXPECT_TRUE(contains(r.err, "g.toml:3:") && contains(r.err, words)) << r.err;
    EXPECT_FALSE(contains(r.err, "::") || contains(r.err, "eval()") || contains(r.err, "internal error")) << r.err;
  }
  write("osc.toml", kOscillator);
  const ProcessRun event = nhdyn({"simulate", "osc.toml", "--event", "e=x/(k-k)", "-q", "-o", "g.csv"});
  EXPECT_EQ(event.code, 2);
  EXPECT_TRUE(contains(event.err, "--event \"e=x/(k-k)\"") && contains(event.err, "divides by zero")) << event.err;
  EXPECT_FALSE(contains(event.err, "::")) << event.err;
}

}  // namespace

namespace {

// An ellipsoid one of whose semi-axes is set more than 1e6 times smaller than another is flat to
// double precision (a = 1e-100 fell through the floor with exit 0): refused with both sizes, from
// the file or --set; 1.5e5 apart it runs.
TEST_F(Hardening, ContactShapeSizesFarApartAreRefused) {
  const std::string model = (fs::path(NHDYN_SOURCE_DIR) / "examples" / "rattleback.toml").string();
  const ProcessRun thin = nhdyn({"simulate", model, "--set", "a=1e-9", "--t-end", "0.1", "-q", "-o", "r.csv"});
  EXPECT_EQ(thin.code, 2) << thin.err;
  EXPECT_TRUE(contains(thin.err, "rattleback.toml:53:") &&
              contains(thin.err, "its sizes \"a\" = 1e-09 and \"b\" = 0.03 are more than 1e+06 apart"))
      << thin.err;
  EXPECT_FALSE(fs::exists(dir_ / "r.csv"));
  EXPECT_EQ(nhdyn({"simulate", model, "--set", "a=2e-7", "--t-end", "0.1", "-q", "-o", "r.csv"}).code, 0);
}

// --set m=1e154 or 1e-300 (allowed; the sled's motion does not depend on m) failed as "[D A; b] is
// singular": the rows D A scale with m, the row b does not. The same motion at every mass.
TEST_F(Hardening, ExtremeParameterMagnitudesAreNotSingular) {
  const auto last_row = [&](const std::string& file) {
    std::stringstream in(read_whole(dir_ / file));
    std::string line, last;
    while (std::getline(in, line))
      if (!line.empty() && line[0] != '#') last = line;
    std::vector<double> values;
    std::stringstream fields(last);
    for (std::string field; values.size() < 7 && std::getline(fields, field, ',');) values.push_back(std::stod(field));
    return values;
  };
  ASSERT_EQ(nhdyn({"simulate", "sled.toml", "--t-end", "2", "-q", "-o", "m1.csv"}).code, 0);
  const std::vector<double> reference = last_row("m1.csv");
  for (const char* m : {"1e154", "1e100", "1e-100", "1e-300"}) {
    const ProcessRun r = nhdyn({"simulate", "sled.toml", "--set", std::string("m=") + m, "--t-end", "2", "-q", "-o", "m.csv"});
    ASSERT_EQ(r.code, 0) << m << ": " << r.err;
    const std::vector<double> values = last_row("m.csv");
    ASSERT_GE(values.size(), 7u);
    for (std::size_t i = 0; i < 7; ++i)  // t, x, y, phi and their velocities
      EXPECT_NEAR(values[i], reference[i], 1e-9 * (1.0 + std::abs(reference[i]))) << m << " column " << i;
  }
}

// The same for the program-motion solve and the contact modes' solves (the stacked matrix, the
// effective inverse mass of a sliding contact): every force of these models scales with m, so
// m = 1e154, 1e-100 or 1e-300 gives the motion of the file's m; and a singular system (a program that no
// actuator can realize, Painleve's paradox) is still refused at every scale.
TEST_F(Hardening, ExtremeMassesInProgramsAndContactModesAreNotSingular) {
  const fs::path examples = fs::path(NHDYN_SOURCE_DIR) / "examples";
  // The state columns t, q, q' of the last row.
  const auto last_state = [&](const std::string& file, std::size_t columns) {
    std::stringstream in(read_whole(dir_ / file));
    std::string line, last;
    while (std::getline(in, line))
      if (!line.empty() && line[0] != '#') last = line;
    std::vector<double> values;
    std::stringstream fields(last);
    for (std::string field; values.size() < columns && std::getline(fields, field, ',');) values.push_back(std::stod(field));
    return values;
  };
  for (const auto& [model, columns] : {std::pair<const char*, std::size_t>{"sled_heading_program.toml", 7},
                                       {"ball_thrown_sliding.toml", 13}}) {
    SCOPED_TRACE(model);
    const std::string path = (examples / model).string();
    const ProcessRun one = nhdyn({"simulate", path, "--t-end", "0.5", "-q", "-o", "one.csv"});
    ASSERT_EQ(one.code, 0) << one.err;
    const std::vector<double> reference = last_state("one.csv", columns);
    ASSERT_EQ(reference.size(), columns);
    for (const char* m : {"1e154", "1e-100", "1e-300"}) {
      const ProcessRun r =
          nhdyn({"simulate", path, "--set", std::string("m=") + m, "--t-end", "0.5", "-q", "-o", "scaled.csv"});
      ASSERT_EQ(r.code, 0) << m << ": " << r.err;
      const std::vector<double> values = last_state("scaled.csv", columns);
      ASSERT_EQ(values.size(), columns);
      for (std::size_t i = 0; i < columns; ++i)
        EXPECT_NEAR(values[i], reference[i], 1e-8 * (1.0 + std::abs(reference[i]))) << m << " column " << i;
    }
  }
  // Singular at any scale: the cart's force cannot turn a horizontal pendulum (S = 0 at theta = pi/2).
  for (const char* m : {"1", "1e100", "1e-100"}) {
    const ProcessRun r = nhdyn({"simulate", (examples / "cart_pendulum_program.toml").string(), "--set", "theta0=pi/2",
                                "--set", std::string("mc=") + m, "--set", std::string("mb=") + m, "-q", "-o", "s.csv"});
    EXPECT_EQ(r.code, 2) << m << ": " << r.err;
    EXPECT_TRUE(contains(r.err, "'swing'")) << m << ": " << r.err;
  }
  // Painleve's paradox: a rod on its end tipped by a torque that grows (in proportion to m) would
  // have to start sliding with mu = 1.5 > 4/3 at t = 0.04 (tests/python/test_contact_modes.py).
  write("rod.toml", R"(name = "painleve-rod"
coordinates = ["x", "y", "z", "b"]
gravity = [0, 0, "-g"]
[parameters]
m = 1.0
l = 0.5
rho = 0.01
g = 9.81
b0 = 1.1071487177940904
mu = 1.5
[[frames]]
name = "rod"
translation = ["x", "y", "z"]
rotations = [["y", "b"]]
[[bodies]]
name = "rod"
frame = "rod"
mass = "m"
inertia = ["m*l^2/3", "m*l^2/3", "m*l^2/3"]
[[contacts]]
name = "end"
body = "rod"
shape = { sphere = "rho" }
centre = ["l", 0, 0]
unilateral = true
friction = "mu"
mode = "rolling"
[forces]
b = "-100*m*t"
[initial]
position = { x = 0, y = 0, z = "l*sin(b0) + rho", b = "b0" }
velocity = { x = 0, y = 0, z = 0, b = 0 }
)");
  for (const char* m : {"1", "1e100", "1e-100"}) {
    const ProcessRun r = nhdyn({"simulate", "rod.toml", "--set", std::string("m=") + m, "--t-end", "0.1",
                                "--output-step", "0.01", "-q", "-o", "rod.csv"});
    EXPECT_EQ(r.code, 1) << m << ": " << r.err;
    EXPECT_TRUE(contains(r.err, "contact 'end' slides in Painleve's paradox at t = 0.04")) << m << ": " << r.err;
  }
}

// The contact forces' check at load (what the model determines, model/contact_forces.cpp) solves
// [A b^T; b 0] at a test state: with A's pivots 1e100 smaller than b's it called the disk's normal
// force undetermined at m = 1e-100 (and refused the event that reads it), and gave the ball a false
// note. Every force of these models scales with m, so each verdict and each force over m must be
// those of m = 1.
TEST_F(Hardening, ContactForcesAreDeterminedAtExtremeMasses) {
  const fs::path examples = fs::path(NHDYN_SOURCE_DIR) / "examples";
  // The value of `column` in the first data row of a CSV.
  const auto first = [&](const std::string& file, const std::string& column) {
    std::stringstream in(read_whole(dir_ / file));
    std::string header, row;
    while (std::getline(in, header) && !header.empty() && header[0] == '#') {
    }
    std::getline(in, row);
    std::stringstream names(header), values(row);
    for (std::string name, value; std::getline(names, name, ',') && std::getline(values, value, ',');)
      if (name == column) return std::stod(value);
    ADD_FAILURE() << "no column " << column << " in " << file;
    return 0.0;
  };
  for (const auto& [model, column] : {std::pair<const char*, const char*>{"rolling_disk_liftoff.toml", "disk_N"},
                                      {"ball_thrown_sliding.toml", "ball_N"}}) {
    SCOPED_TRACE(model);
    const std::string path = (examples / model).string();
    const ProcessRun one = nhdyn({"simulate", path, "--set", "m=1", "--t-end", "0.1", "-o", "one.csv"});
    ASSERT_EQ(one.code, 0) << one.err;
    const double reference = first("one.csv", column);
    ASSERT_GT(std::abs(reference), 1.0);  // the weight of 1 kg, about
    for (const char* m : {"1e-300", "1e-100", "1e100", "1e154"}) {
      const ProcessRun r = nhdyn({"simulate", path, "--set", std::string("m=") + m, "--t-end", "0.1", "-o", "m.csv"});
      ASSERT_EQ(r.code, 0) << m << ": " << r.err;
      EXPECT_EQ(contains(r.err, "note: contact forces"), contains(one.err, "note: contact forces")) << m << ": " << r.err;
      EXPECT_NEAR(first("m.csv", column) / std::stod(m), reference, 1e-10 * std::abs(reference)) << m;
    }
  }
}

// Two independent disks released leaning, of masses m1 and m2 = 1 in one model: each disk's contact
// forces are its own mass times those of a 1 kg disk, whatever m1 (the row scaling of [D A; b] and
// of the contact forces' check at load take out one factor per row). Masses up to 1e12 apart are
// solved; beyond (1e16), mixed within the rows of D A, they are refused as singular (docs/cli.md).
TEST_F(Hardening, ContactForcesOfBodiesOfDifferentMasses) {
  write("two.toml", R"(name = "two-disks"
coordinates = ["x1", "y1", "psi1", "theta1", "phi1", "x2", "y2", "psi2", "theta2", "phi2"]
gravity = [0, 0, "-g"]
[parameters]
m1 = 1.0
m2 = 1.0
r = 0.2
g = 9.81
[[frames]]
name = "heading1"
translation = ["x1", "y1", 0]
rotations = [["z", "psi1"]]
[[frames]]
name = "lean1"
parent = "heading1"
rotations = [["x", "theta1"]]
[[frames]]
name = "disk1"
parent = "lean1"
translation = [0, 0, "r"]
rotations = [["y", "phi1"]]
[[frames]]
name = "heading2"
translation = ["x2", "y2", 0]
rotations = [["z", "psi2"]]
[[frames]]
name = "lean2"
parent = "heading2"
rotations = [["x", "theta2"]]
[[frames]]
name = "disk2"
parent = "lean2"
translation = [0, 0, "r"]
rotations = [["y", "phi2"]]
[[bodies]]
name = "disk1"
frame = "disk1"
mass = "m1"
inertia = ["m1*r^2/4", "m1*r^2/2", "m1*r^2/4"]
[[bodies]]
name = "disk2"
frame = "disk2"
mass = "m2"
inertia = ["m2*r^2/4", "m2*r^2/2", "m2*r^2/4"]
[[wheels]]
name = "d1"
body = "disk1"
axis = "y"
radius = "r"
[[wheels]]
name = "d2"
body = "disk2"
axis = "y"
radius = "r"
[initial]
position = { x1 = 0, y1 = 0, psi1 = 0, theta1 = 0.1, phi1 = 0, x2 = 1, y2 = 0, psi2 = 0, theta2 = 0.2, phi2 = 0 }
)");
  const auto first_row = [&](const std::string& file) {
    std::stringstream in(read_whole(dir_ / file));
    std::string header, row;
    while (std::getline(in, header) && !header.empty() && header[0] == '#') {
    }
    std::getline(in, row);
    std::vector<std::pair<std::string, double>> values;
    std::stringstream names(header), numbers(row);
    for (std::string name, value; std::getline(names, name, ',') && std::getline(numbers, value, ',');)
      values.emplace_back(name, std::stod(value));
    return values;
  };
  ASSERT_EQ(nhdyn({"simulate", "two.toml", "--t-end", "0.02", "-o", "one.csv", "-q"}).code, 0);
  const ProcessRun r = nhdyn({"simulate", "two.toml", "--set", "m1=1e-12", "--t-end", "0.02", "-o", "m.csv", "-q"});
  ASSERT_EQ(r.code, 0) << r.err;
  const auto one = first_row("one.csv"), light = first_row("m.csv");
  ASSERT_EQ(one.size(), light.size());
  int forces = 0;
  for (std::size_t i = 0; i < one.size(); ++i) {
    const bool disk1 = one[i].first.starts_with("d1_"), disk2 = one[i].first.starts_with("d2_");
    if (!disk1 && !disk2) continue;
    ++forces;
    const double expected = one[i].second * (disk1 ? 1e-12 : 1.0);
    EXPECT_NEAR(light[i].second, expected, 1e-12 * std::max(1e-12, std::abs(expected)) + 1e-9 * (disk1 ? 1e-12 : 1.0))
        << one[i].first;
  }
  EXPECT_GE(forces, 12);
  const ProcessRun apart = nhdyn({"simulate", "two.toml", "--set", "m1=1e-16", "--t-end", "0.02", "-o", "far.csv"});
  EXPECT_EQ(apart.code, 1) << apart.err;
  EXPECT_TRUE(contains(apart.err, "singular at t = 0")) << apart.err;
  // The message says why (A's diagonal spans 1e-18 to 1) and what to do, for each formulation; it
  // does not blame a complement D, which lagrange has none of and the default D is by construction.
  for (const char* method : {"sanh", "lagrange"}) {
    const ProcessRun m = nhdyn({"simulate", "two.toml", "--set", "m1=1e-16", "--method", method, "--t-end", "0.02", "-o", "far.csv"});
    EXPECT_EQ(m.code, 1) << method << ": " << m.err;
    EXPECT_TRUE(contains(m.err, "the diagonal of A spans")) << method << ": " << m.err;
    EXPECT_TRUE(contains(m.err, "within about 1e12 of each other")) << method << ": " << m.err;
    EXPECT_FALSE(contains(m.err, "not a complement")) << method << ": " << m.err;
  }
}

}  // namespace

namespace {

// --fix-initial on a model with programs: the start must lie on the programs as on the constraints.
// It moved only onto the constraints, left phi' at 0 off the program phi = omega t, and then refused
// the start as off its program. Now a free value moves onto the program too, and a written one that
// no free value can mend is named with the program.
TEST_F(Hardening, FixInitialMeetsThePrograms) {
  std::string model = read_whole(fs::path(NHDYN_SOURCE_DIR) / "examples" / "sled_heading_program.toml");
  const auto replace = [&](std::string text, const std::string& from, const std::string& to) {
    const std::size_t at = text.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    if (at != std::string::npos) text.replace(at, from.size(), to);
    return text;
  };
  // y' and phi' left free (phi' then starts at 0), the heading not written.
  std::string free_rate = replace(model, "velocity = { x = \"v0\", y = 0, phi = \"omega\" }", "velocity = { x = \"v0\" }");
  free_rate = replace(free_rate, "position = { x = 0, y = 0, phi = 0 }", "position = { x = 0, y = 0 }");
  write("free.toml", free_rate);
  const ProcessRun refused = nhdyn({"simulate", "free.toml", "--t-end", "1", "-o", "free.csv"});
  EXPECT_EQ(refused.code, 2);
  EXPECT_TRUE(contains(refused.err, "heading (velocity level): residual -1")) << refused.err;
  const ProcessRun fixed = nhdyn({"simulate", "free.toml", "--t-end", "1", "-o", "free.csv", "--fix-initial"});
  ASSERT_EQ(fixed.code, 0) << fixed.err;
  EXPECT_TRUE(contains(fixed.out, "phi' = 1 (changed by +1), was 0")) << fixed.out;  // omega = 1
  // A heading written off the program, with no free value to mend it: the program is named.
  write("off.toml", replace(model, "position = { x = 0, y = 0, phi = 0 }", "position = { x = 0, y = 0, phi = 0.2 }"));
  const ProcessRun off = nhdyn({"simulate", "off.toml", "--t-end", "1", "-o", "off.csv", "--fix-initial"});
  EXPECT_EQ(off.code, 2);
  EXPECT_TRUE(contains(off.err, "no free value enters the program 'heading' (position level), which keeps the residual 0.2"))
      << off.err;
}

// A name near the file system's limit failed: the temporary's name is 12 bytes longer.
TEST_F(Hardening, NamesNearTheFileSystemLimitAreWritten) {
  write("osc.toml", kOscillator);
  const std::string longest = std::string(251, 'a') + ".csv";  // 255 bytes: NAME_MAX on ext4, tmpfs
  const ProcessRun r = nhdyn({"simulate", "osc.toml", "--t-end", "0.1", "-q", "-o", longest});
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(fs::exists(dir_ / longest));
  for (const auto& entry : fs::directory_iterator(dir_))
    EXPECT_FALSE(contains(entry.path().filename().string(), ".tmp.")) << entry.path();
  const ProcessRun over = nhdyn({"simulate", "osc.toml", "--t-end", "0.1", "-q", "-o", "b" + longest});
  EXPECT_EQ(over.code, 2);
  EXPECT_TRUE(contains(over.err, "above the file system's limit of 255")) << over.err;
}

// The files of a run (apps/nhdyn/run_files.hpp) in the commands besides simulate, whose cases
// tests/cli/output_safety_test.cpp tries: a compare whose reference run fails, and one interrupted
// mid-run, leave an existing table as it was and no file of their own (no series, no temporary);
// a --plot into a folder that does not exist is refused before any run by compare and the studies,
// as by simulate (it used to be found only after the runs, once the tables were written).
// An attracting pole at x = 1, which the particle reaches at t = pi/(2 sqrt 2) = 1.1107, where
// every integrator's step underflows; and out/c.csv, an earlier table no refused run may touch.
constexpr const char* kBlowUp = "name = \"blow-up\"\ncoordinates = [\"x\"]\nkinetic_energy = \"x'^2/2\"\n"
                                "potential_energy = \"-1/(1 - x)\"\n[initial]\nposition = { x = 0 }\n"
                                "velocity = { x = 0 }\n";

void Hardening::write_blow_up_and_earlier_table() const {
  write("blow.toml", kBlowUp);
  fs::create_directories(dir_ / "out");
  write("out/c.csv", "an earlier table\n");
}

void Hardening::expect_out_untouched(const std::string& what) const {
  EXPECT_EQ(read_whole(dir_ / "out" / "c.csv"), "an earlier table\n") << what;
  for (const auto& entry : fs::directory_iterator(dir_ / "out"))
    EXPECT_EQ(entry.path().filename(), "c.csv") << what << ": left " << entry.path();
}

TEST_F(Hardening, CompareWhoseReferenceFailsLeavesNothing) {
  write_blow_up_and_earlier_table();
  const ProcessRun r = nhdyn({"compare", "blow.toml", "--t-end", "5", "-q", "-o", "out/c.csv"});
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_TRUE(contains(r.err, "the reference run (sanh, dopri5, rtol 1e-13) failed at t = 1.11")) << r.err;
  expect_out_untouched("a failed reference");
}

TEST_F(Hardening, InterruptedCompareLeavesNothing) {
  fs::create_directories(dir_ / "run");
  ProcessOptions options;
  options.signal = SIGINT;
  options.after = std::chrono::milliseconds(300);
  options.signal_when_written = dir_ / "run";  // once the table's and the series' temporaries are there
  options.deadline = 60;
  const ProcessRun r =
      nhdyn({"compare", "sled.toml", "--t-end", "10000", "--methods", "sanh", "-q", "-o", "run/c.csv"}, options);
  EXPECT_EQ(r.code, 128 + SIGINT) << r.err;
  EXPECT_TRUE(contains(r.err, "interrupted by SIGINT")) << r.err;
  EXPECT_TRUE(fs::is_empty(dir_ / "run"));
}

TEST_F(Hardening, APlotIntoAMissingFolderIsRefusedBeforeAnyRun) {
  const std::vector<std::vector<std::string>> commands{
      {"compare", "sled.toml", "--t-end", "0.2", "-q", "-o", "out/c.csv", "--plot", "nodir/c.png"},
      {"study", "error-relation", "appell.toml", "--tolerances", "1e-3", "-q", "-o", "out/c.csv", "--plot",
       "nodir/e.png"},
  };
  write_blow_up_and_earlier_table();
  for (const std::vector<std::string>& args : commands) {
    const ProcessRun r = nhdyn(args);
    EXPECT_EQ(r.code, 2) << args[0] << ": " << r.err;
    EXPECT_TRUE(contains(r.err, "nodir") || contains(r.err, "gnuplot")) << r.err;
    EXPECT_FALSE(fs::exists(dir_ / "nodir")) << args[0];
    expect_out_untouched(args[0] + " --plot nodir/");
  }
}

}  // namespace
