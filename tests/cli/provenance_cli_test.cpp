// The provenance header end to end (io/provenance.hpp, docs/cli.md "The CSV"): simulate writes it
// into the CSV, the events file, the partial file and the HTML page; `nhdyn report` reads the
// run's parameters back, so that a report without --set draws the run's scene, and refuses a
// CSV whose model hash is not the model's, or whose header is cut short. batch, compare, sweep,
// linearize and the error-relation, tracking and spread-masses studies write the same header into
// their CSVs.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "support/cli_run.hpp"

namespace fs = std::filesystem;

namespace {

std::string provenance_read(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

void provenance_write(const fs::path& path, const std::string& text) { std::ofstream(path, std::ios::binary) << text; }

// The text without its '#' lines.
std::string without_comments(const std::string& text) {
  std::istringstream in(text);
  std::string out;
  for (std::string line; std::getline(in, line);)
    if (!line.starts_with("#")) out += line + "\n";
  return out;
}

// The page without the HTML comment that holds the provenance (right after the doctype).
std::string without_provenance_comment(const std::string& html) {
  const std::size_t start = html.find("<!--\n# nhdyn version:");
  if (start == std::string::npos) return html;
  const std::size_t end = html.find("-->\n", start);
  return html.substr(0, start) + html.substr(end + 4);
}

class ProvenanceCli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("nhdyn_provenance_" + std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
    fs::remove_all(dir_);
    fs::create_directories(dir_ / "a");
    fs::create_directories(dir_ / "b");
    sled_ = provenance_read(fs::path(NHDYN_SOURCE_DIR) / "examples" / "sled.toml");
    provenance_write(dir_ / "a" / "sled.toml", sled_);
    provenance_write(dir_ / "b" / "sled.toml", sled_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path dir_;
  std::string sled_;
};

TEST_F(ProvenanceCli, TheCsvNamesTheRunAndReportRedrawsItWithoutSet) {
  // a = 0.3 moves the drawn centre of mass ([visual] of examples/sled.toml).
  nhdyn::test::CliOutcome r = nhdyn::test::run_nhdyn(
      "simulate sled.toml --set a=0.3 --set m=2 --t-end 1 --output-step 0.1 --event turn=phi-0.5 -q -o run.csv "
      "--html sim.html",
      dir_ / "a");
  ASSERT_EQ(r.exit_code, 0) << r.out;
  const std::string csv = provenance_read(dir_ / "a" / "run.csv");
  EXPECT_EQ(csv.rfind("# nhdyn version: ", 0), 0u) << csv.substr(0, 400);
  for (const char* line : {"\n# model: sled\n", "\n# model file: sled.toml\n", "\n# parameters: m=2, a=0.3, ",
                           "\n# initial: x=0, y=0, phi=0, x'=1, y'=0, phi'=1\n", "\n# run: method=sanh, ",
                           "integrator=dopri5, rtol=1e-08, atol=1e-10, ", "events=turn:phi-0.5\n",
                           "\n# end of provenance\nt,x,y,phi,"})
    EXPECT_NE(csv.find(line), std::string::npos) << line << "\n" << csv.substr(0, 700);
  const std::string hash_line = csv.substr(csv.find("# model hash: "), csv.find('\n', csv.find("# model hash: ")) -
                                                                           csv.find("# model hash: "));
  EXPECT_EQ(provenance_read(dir_ / "a" / "run-events.csv").rfind(csv.substr(0, csv.find("t,x,y,phi,")), 0), 0u);
  EXPECT_NE(provenance_read(dir_ / "a" / "sim.html").find("<!--\n" + csv.substr(0, csv.find("t,x,y,phi,")) + "-->"),
            std::string::npos);

  // The report of the CSV alone, parameters from its header...
  r = nhdyn::test::run_nhdyn("report run.csv --model sled.toml -q -o page.html", dir_ / "a");
  ASSERT_EQ(r.exit_code, 0) << r.out;
  const std::string page = provenance_read(dir_ / "a" / "page.html");
  EXPECT_NE(page.find(hash_line), std::string::npos);
  // ... is the report of the same rows without a header, given the run's --set again.
  provenance_write(dir_ / "b" / "run.csv", without_comments(csv));
  r = nhdyn::test::run_nhdyn("report run.csv --model sled.toml --set a=0.3 --set m=2 -q -o page.html", dir_ / "b");
  ASSERT_EQ(r.exit_code, 0) << r.out;
  EXPECT_EQ(without_provenance_comment(page), provenance_read(dir_ / "b" / "page.html"));
  // Without either, the scene is the file's (a = 0.5): the comparison above can fail.
  r = nhdyn::test::run_nhdyn("report run.csv --model sled.toml -q -o plain.html", dir_ / "b");
  ASSERT_EQ(r.exit_code, 0) << r.out;
  EXPECT_NE(without_provenance_comment(page), provenance_read(dir_ / "b" / "plain.html"));
}

TEST_F(ProvenanceCli, ReportRefusesAnotherModelOrAnEditedFile) {
  ASSERT_EQ(nhdyn::test::run_nhdyn("simulate sled.toml --t-end 0.5 -q -o run.csv", dir_ / "a").exit_code, 0);
  // The model file edited since the run: m = 1 -> 3.
  std::string edited = sled_;
  const std::size_t at = edited.find("m = { value = 1.0");
  ASSERT_NE(at, std::string::npos);
  edited.replace(at, 17, "m = { value = 3.0");
  provenance_write(dir_ / "a" / "edited.toml", edited);
  nhdyn::test::CliOutcome r = nhdyn::test::run_nhdyn("report run.csv --model edited.toml -o page.html", dir_ / "a");
  EXPECT_EQ(r.exit_code, 2) << r.out;
  EXPECT_NE(r.out.find("run.csv was written by a run of 'sled' from sled.toml (model hash fnv1a64:"), std::string::npos)
      << r.out;
  EXPECT_NE(r.out.find("but edited.toml has hash fnv1a64:"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("parameters that differ: m = 3 in the file, 1 in the run"), std::string::npos) << r.out;
  EXPECT_FALSE(fs::exists(dir_ / "a" / "page.html"));
  // The built-in sled has the same columns but is another model.
  r = nhdyn::test::run_nhdyn("report run.csv --model sled -o page.html", dir_ / "a");
  EXPECT_EQ(r.exit_code, 2) << r.out;
  EXPECT_NE(r.out.find("but the built-in model 'sled' has hash fnv1a64:"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("it is another model"), std::string::npos) << r.out;
}

TEST_F(ProvenanceCli, ReportRefusesATruncatedHeader) {
  ASSERT_EQ(nhdyn::test::run_nhdyn("simulate sled.toml --t-end 0.5 -q -o run.csv", dir_ / "a").exit_code, 0);
  const std::string csv = provenance_read(dir_ / "a" / "run.csv");
  // The header's first four lines, then the columns and rows: parameters onwards are gone.
  std::size_t cut = 0;
  for (int i = 0; i < 4; ++i) cut = csv.find('\n', cut) + 1;
  provenance_write(dir_ / "a" / "cut.csv", csv.substr(0, cut) + csv.substr(csv.find("t,x,y,phi,")));
  const nhdyn::test::CliOutcome r = nhdyn::test::run_nhdyn("report cut.csv --model sled.toml -o page.html", dir_ / "a");
  EXPECT_EQ(r.exit_code, 2) << r.out;
  EXPECT_NE(r.out.find("cut.csv: the provenance header is truncated: it has no 'parameters' line"), std::string::npos)
      << r.out;
  // An edited parameters line was named as a --set the user never gave ("--set m=nan: 'nan' uses
  // 'nan' ..."): the CSV's line is named.
  const std::size_t m = csv.find("# parameters: m=");
  ASSERT_NE(m, std::string::npos);
  for (const auto& [edit, expected] :
       {std::pair<std::string, std::string>{"# parameters: m=nan, junk=", "gives m = nan, which is not a finite number"},
        {"# parameters: zz=3, m=", "names 'zz', which is not a parameter of model 'sled'"}}) {
    std::string edited = csv;
    edited.replace(m, std::string("# parameters: m=").size(), edit);
    provenance_write(dir_ / "a" / "edited.csv", edited);
    const nhdyn::test::CliOutcome e =
        nhdyn::test::run_nhdyn("report edited.csv --model sled.toml -o page.html", dir_ / "a");
    EXPECT_EQ(e.exit_code, 2) << e.out;
    EXPECT_NE(e.out.find("edited.csv: its '# parameters:' line " + expected), std::string::npos) << e.out;
    EXPECT_EQ(e.out.find("--set"), std::string::npos) << e.out;
  }
}

TEST_F(ProvenanceCli, AFailedRunsPartialFileCarriesIt) {
  const nhdyn::test::CliOutcome r = nhdyn::test::run_nhdyn(
      "simulate sled.toml --integrator rk4 --step 5 --t-end 20 --output-step 5 -o run.csv", dir_ / "a");
  ASSERT_EQ(r.exit_code, 1) << r.out;
  const std::string partial = provenance_read(dir_ / "a" / "run.partial.csv");
  EXPECT_EQ(partial.rfind("# nhdyn: simulation of 'sled' failed", 0), 0u) << partial;
  EXPECT_NE(partial.find("\n# nhdyn version: "), std::string::npos) << partial;
  EXPECT_NE(partial.find("integrator=rk4, "), std::string::npos) << partial;
  EXPECT_NE(partial.find("\n# end of provenance\nt,x,y,phi,"), std::string::npos) << partial;
}

// Each batch run's file is that run's: its parameter and initial value as run, so that `report`
// draws it without --set; the summary names the grid. The model hash and version lines are those
// of a simulate run of the same file.
TEST_F(ProvenanceCli, BatchFilesCarryEachRunsValues) {
  nhdyn::test::CliOutcome r = nhdyn::test::run_nhdyn(
      "batch sled.toml --grid a=0.2:0.4:2 --grid 'x(0)=1:3:2' --t-end 0.5 --write-runs -q -o out", dir_ / "a");
  ASSERT_EQ(r.exit_code, 0) << r.out;
  ASSERT_EQ(nhdyn::test::run_nhdyn("simulate sled.toml --t-end 0.5 -q -o run.csv", dir_ / "a").exit_code, 0);
  const std::string single = provenance_read(dir_ / "a" / "run.csv");
  const auto line_of = [](const std::string& text, const std::string& key) {
    const std::size_t at = text.find("\n# " + key + ": ");
    return at == std::string::npos ? std::string("(no " + key + " line)") : text.substr(at + 1, text.find('\n', at + 1) - at - 1);
  };
  const std::string summary = provenance_read(dir_ / "a" / "out" / "summary.csv");
  EXPECT_EQ(line_of(summary, "model hash"), line_of(single, "model hash"));
  EXPECT_NE(line_of(summary, "run").find(", runs=a=0.2:0.4:2 x(0)=1:3:2"), std::string::npos) << summary.substr(0, 900);
  EXPECT_NE(summary.find("\n# end of provenance\nrun,a,x(0),status,"), std::string::npos) << summary.substr(0, 900);
  // Runs in row-major order: run 3 is a = 0.4, x(0) = 3.
  const std::string run3 = provenance_read(dir_ / "a" / "out" / "run_3.csv");
  EXPECT_NE(line_of(run3, "parameters").find(", a=0.4, "), std::string::npos) << line_of(run3, "parameters");
  EXPECT_EQ(line_of(run3, "initial").rfind("# initial: x=3, y=0, phi=0, ", 0), 0u) << line_of(run3, "initial");
  EXPECT_NE(line_of(run3, "run").find(", batch_run=3"), std::string::npos) << line_of(run3, "run");
  // report takes a = 0.4 from the run's header: the same page as the report given --set a=0.4.
  r = nhdyn::test::run_nhdyn("report out/run_3.csv --model sled.toml -q -o from_header.html", dir_ / "a");
  ASSERT_EQ(r.exit_code, 0) << r.out;
  fs::create_directories(dir_ / "b" / "out");  // the same relative path: the page's title names it
  provenance_write(dir_ / "b" / "out" / "run_3.csv", without_comments(run3));
  r = nhdyn::test::run_nhdyn("report out/run_3.csv --model sled.toml --set a=0.4 -q -o given.html", dir_ / "b");
  ASSERT_EQ(r.exit_code, 0) << r.out;
  EXPECT_TRUE(without_provenance_comment(provenance_read(dir_ / "a" / "from_header.html")) ==
              provenance_read(dir_ / "b" / "given.html"));
  // Without the header's a = 0.4 the scene is another (a = 0.5): the comparison above can fail.
  r = nhdyn::test::run_nhdyn("report out/run_3.csv --model sled.toml -q -o plain.html", dir_ / "b");
  ASSERT_EQ(r.exit_code, 0) << r.out;
  EXPECT_FALSE(provenance_read(dir_ / "b" / "plain.html") == provenance_read(dir_ / "b" / "given.html"));
}

// The commands that are not one simulation say which they are and with what options, before
// the same model lines.
TEST_F(ProvenanceCli, CompareSweepLinearizeAndStudiesSayWhatMadeThem) {
  const std::string bicycle = (fs::path(NHDYN_SOURCE_DIR) / "examples" / "bicycle_linear.toml").string();
  struct Case {
    std::string command;
    std::vector<std::string> files;
    std::string run_line;
  };
  const std::vector<Case> cases{
      {"compare sled.toml --methods sanh,lagrange --t-end 0.5 -q -o cmp.csv",
       {"cmp.csv", "cmp-series.csv"},
       "run: command=compare, methods=sanh,lagrange, integrators=dopri5, reference=tight, complement=qr, "},
      {"linearize '" + bicycle + "' --set v=4 -o lin.csv", {"lin.csv"}, "run: command=linearize, tolerance=1e-09"},
      {"sweep '" + bicycle + "' --param v --from 1 --to 3 --steps 3 --eigenvalues -q -o sw.csv",
       {"sw.csv", "sw-crossings.csv"},
       "run: command=sweep, param=v, from=1, to=3, steps=3, tolerance=1e-09"},
      {"study error-relation sled.toml --methods sanh --integrators dopri5 --tolerances 1e-6,1e-8 -q -o er.csv",
       {"er.csv", "er-by-tolerance.csv"},
       "run: command=study error-relation, methods=sanh-qr, integrators=dopri5, tolerances=1e-06,1e-08, "},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.command);
    const nhdyn::test::CliOutcome r = nhdyn::test::run_nhdyn(c.command, dir_ / "a");
    ASSERT_EQ(r.exit_code, 0) << r.out;
    for (const std::string& file : c.files) {
      SCOPED_TRACE(file);
      const std::string text = provenance_read(dir_ / "a" / file);
      EXPECT_EQ(text.rfind("# nhdyn version: ", 0), 0u) << text.substr(0, 300);
      EXPECT_NE(text.find("\n# " + c.run_line), std::string::npos) << text.substr(0, 1200);
      EXPECT_NE(text.find("\n# end of provenance\n"), std::string::npos);
    }
  }
  // study spread-masses: its table too, with the model's parameters as loaded (--set applied).
  {
    const std::string spread = (fs::path(NHDYN_SOURCE_DIR) / "examples" / "spread_masses.toml").string();
    const nhdyn::test::CliOutcome r = nhdyn::test::run_nhdyn(
        "study spread-masses '" + spread + "' --ratios 1,1e3 --samples 1 --set ratio=7 -q -o sm.csv", dir_ / "a");
    ASSERT_EQ(r.exit_code, 0) << r.out;
    const std::string text = provenance_read(dir_ / "a" / "sm.csv");
    EXPECT_EQ(text.rfind("# nhdyn version: ", 0), 0u) << text.substr(0, 300);
    EXPECT_NE(text.find("\n# run: command=study spread-masses, parameter=ratio, ratios=1,1000, samples=1, digits=50, "
                        "formulations=sanh-qr,"),
              std::string::npos)
        << text.substr(0, 1200);
    EXPECT_NE(text.find("\n# parameters: ratio=7"), std::string::npos) << text.substr(0, 1200);
    EXPECT_NE(text.find("\n# end of provenance\nratio,cond_A,"), std::string::npos) << text.substr(0, 1200);
  }
  // linearize's --set is in the parameters as run.
  EXPECT_NE(provenance_read(dir_ / "a" / "lin.csv").find("\n# parameters: v=4, "), std::string::npos)
      << provenance_read(dir_ / "a" / "lin.csv").substr(0, 600);
}

}  // namespace
