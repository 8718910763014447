// The HTML report's library parts and the command line around it: the scene's program against
// closed-form positions (the sled's blade, the rolling disk's centre and contact point), the
// equivalent ellipsoid of a body, the rule that thins long runs, the page being self-contained and
// reproducible, and bad input (a [visual] table that cannot be drawn, a CSV of another model, an
// --html path that cannot be written, a model with nothing to draw). The page in a browser is
// tests/report/report_test.py.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "nhdyn/core/error.hpp"
#include "nhdyn/io/csv.hpp"
#include "nhdyn/io/model_file.hpp"
#include "nhdyn/io/report.hpp"
#include "nhdyn/symbolic/compile.hpp"
#include "nhdyn/symbolic/visual.hpp"

namespace {

namespace fs = std::filesystem;
using nhdyn::symbolic::VisualKind;

fs::path example(const std::string& name) { return fs::path(NHDYN_SOURCE_DIR) / "examples" / name; }

std::vector<double> run_scene(const nhdyn::symbolic::VisualScene& scene, double t, const std::vector<double>& q,
                              const std::vector<double>& v) {
  std::vector<double> registers(static_cast<std::size_t>(scene.program.registers()));
  std::vector<double> out(static_cast<std::size_t>(scene.program.outputs()));
  scene.program.run(t, q.data(), v.data(), registers.data(), out.data());
  return out;
}

double parameter(const nhdyn::symbolic::Spec& spec, const std::string& name) {
  for (const auto& p : spec.parameters)
    if (p.name == name) return p.value;
  ADD_FAILURE() << "no parameter " << name;
  return 0.0;
}

TEST(Visual, SledBladeAndCentreOfMassFollowTheClosedForm) {
  const nhdyn::symbolic::Spec spec = nhdyn::load_model_file(example("sled.toml"));
  const nhdyn::symbolic::VisualScene scene = nhdyn::symbolic::compile_visual(spec);
  ASSERT_EQ(scene.shapes.size(), 3u);
  EXPECT_TRUE(scene.planar);
  EXPECT_FALSE(scene.ground);
  auto find = [&](const std::string& name) {
    for (const nhdyn::symbolic::VisualShape& shape : scene.shapes)
      if (shape.name == name) return shape;
    ADD_FAILURE() << "no shape " << name;
    return nhdyn::symbolic::VisualShape{};
  };
  const nhdyn::symbolic::VisualShape blade = find("blade"), mass = find("centre of mass");
  EXPECT_EQ(blade.kind, VisualKind::segment);
  EXPECT_EQ(mass.kind, VisualKind::sphere);
  EXPECT_DOUBLE_EQ(mass.size[0], 0.08);
  // phi is an angle (inside cos and sin), x and y are lengths.
  EXPECT_EQ(scene.angles, (std::vector<bool>{false, false, true}));
  const double a = parameter(spec, "a");
  for (const double phi : {0.0, 0.7, -2.1, 3.0}) {
    const double x = 1.3, y = -0.4;
    const std::vector<double> out = run_scene(scene, 0.0, {x, y, phi}, {0.1, 0.2, 0.3});
    const int b = blade.offset, c = mass.offset;
    EXPECT_NEAR(out[b + 0], x - 0.25 * std::cos(phi), 1e-14);
    EXPECT_NEAR(out[b + 1], y - 0.25 * std::sin(phi), 1e-14);
    EXPECT_EQ(out[b + 2], 0.0);
    EXPECT_NEAR(out[b + 3], x + 0.25 * std::cos(phi), 1e-14);
    EXPECT_NEAR(out[b + 4], y + 0.25 * std::sin(phi), 1e-14);
    EXPECT_NEAR(out[c + 0], x + a * std::cos(phi), 1e-14);
    EXPECT_NEAR(out[c + 1], y + a * std::sin(phi), 1e-14);
  }
}

// The disk of examples/rolling_disk_bodies.toml: centre (x + r sin(theta) sin(psi),
// y - r sin(theta) cos(psi), r cos(theta)); the lowest point of its rim, found from the axle as the
// page finds it, is the contact point (x, y, 0) of the model's coordinates.
TEST(Visual, RollingDiskCentreAndContactPoint) {
  const nhdyn::symbolic::Spec spec = nhdyn::load_model_file(example("rolling_disk_bodies.toml"));
  const nhdyn::symbolic::VisualScene scene = nhdyn::symbolic::compile_visual(spec);
  EXPECT_TRUE(scene.ground);
  EXPECT_FALSE(scene.planar);
  int wheel = -1, body = -1;
  for (std::size_t i = 0; i < scene.shapes.size(); ++i) {
    if (scene.shapes[i].kind == VisualKind::wheel) wheel = static_cast<int>(i);
    if (scene.shapes[i].kind == VisualKind::body) body = static_cast<int>(i);
  }
  ASSERT_GE(wheel, 0);
  ASSERT_GE(body, 0);
  const double r = parameter(spec, "r");
  EXPECT_DOUBLE_EQ(scene.shapes[static_cast<std::size_t>(wheel)].size[0], r);
  EXPECT_EQ(scene.shapes[static_cast<std::size_t>(wheel)].axis, 1);
  const double x = 0.4, y = -1.1, psi = 0.9, theta = 0.35, phi = 2.0;
  const std::vector<double> out = run_scene(scene, 0.0, {x, y, psi, theta, phi}, {0, 0, 0, 0, 0});
  const int o = scene.shapes[static_cast<std::size_t>(wheel)].offset;
  const double c[3] = {out[o], out[o + 1], out[o + 2]};
  EXPECT_NEAR(c[0], x + r * std::sin(theta) * std::sin(psi), 1e-14);
  EXPECT_NEAR(c[1], y - r * std::sin(theta) * std::cos(psi), 1e-14);
  EXPECT_NEAR(c[2], r * std::cos(theta), 1e-14);
  // R is a rotation: orthonormal columns.
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      double dot = 0.0;
      for (int k = 0; k < 3; ++k) dot += out[o + 3 + 3 * k + i] * out[o + 3 + 3 * k + j];
      EXPECT_NEAR(dot, i == j ? 1.0 : 0.0, 1e-14);
    }
  const double axle[3] = {out[o + 3 + 1], out[o + 6 + 1], out[o + 9 + 1]};
  double d[3] = {-axle[2] * axle[0], -axle[2] * axle[1], 1.0 - axle[2] * axle[2]};
  const double norm = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
  EXPECT_NEAR(c[0] - r * d[0] / norm, x, 1e-14);
  EXPECT_NEAR(c[1] - r * d[1] / norm, y, 1e-14);
  EXPECT_NEAR(c[2] - r * d[2] / norm, 0.0, 1e-14);
  // The body's equivalent ellipsoid: I = m r^2 (1/4, 1/2, 1/4) gives semi-axes sqrt(5)/2 r in the
  // disk's plane and none along the axle, shown as a tenth of the others.
  std::array<double, 3> semi = scene.shapes[static_cast<std::size_t>(body)].size;
  std::sort(semi.begin(), semi.end());
  EXPECT_NEAR(semi[2], std::sqrt(5.0) / 2 * r, 1e-14);
  EXPECT_NEAR(semi[1], std::sqrt(5.0) / 2 * r, 1e-14);
  EXPECT_NEAR(semi[0], 0.1 * std::sqrt(5.0) / 2 * r, 1e-14);
  // psi, theta and phi are angles; x and y lengths.
  EXPECT_EQ(scene.angles, (std::vector<bool>{false, false, true, true, true}));
}

const char* const kPlanarModel = R"toml(
name = "dot"
coordinates = ["x", "y"]
kinetic_energy = "m/2*(x'^2 + y'^2)"
[parameters]
m = 1.0
)toml";

TEST(Visual, BadVisualTablesAreRefusedWithTheirPlace) {
  const std::string base = kPlanarModel;
  try {
    nhdyn::load_model_string(base + "[visual]\npoints = [{ name = \"p\", position = [\"x\", \"y\"] }, "
                                    "{ name = \"q\", position = [\"x\", \"y\", 0] }]\n",
                             "dot.toml");
    ADD_FAILURE() << "mixed 2- and 3-component positions were accepted";
  } catch (const nhdyn::ModelError& e) {
    EXPECT_NE(std::string(e.what()).find("dot.toml:8:"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("same number"), std::string::npos) << e.what();
  }
  try {
    nhdyn::load_model_string(base + "[visual]\npoint = []\n", "dot.toml");
    ADD_FAILURE() << "an unknown key was accepted";
  } catch (const nhdyn::ModelError& e) {
    EXPECT_NE(std::string(e.what()).find("points"), std::string::npos) << e.what();
  }
  try {
    nhdyn::load_model_string(base + "[visual]\npoints = [{ name = \"p\", position = [\"x\", \"w\"] }]\n", "dot.toml");
    ADD_FAILURE() << "an unknown symbol was accepted";
  } catch (const nhdyn::ModelError& e) {
    EXPECT_NE(std::string(e.what()).find("w"), std::string::npos) << e.what();
  }
  const nhdyn::symbolic::Spec spec = nhdyn::load_model_string(
      base + "[visual]\npoints = [{ name = \"p\", position = [\"x\", \"y\"], radius = \"x\" }]\n", "dot.toml");
  try {
    nhdyn::symbolic::compile_visual(spec);
    ADD_FAILURE() << "a radius depending on a coordinate was accepted";
  } catch (const nhdyn::ModelError& e) {
    EXPECT_NE(std::string(e.what()).find("dot.toml:8:"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("parameters only"), std::string::npos) << e.what();
  }
}

TEST(Report, LongRunsAreThinnedByAFixedRule) {
  EXPECT_EQ(nhdyn::report_frames(1001, 2000).size(), 1001u);
  for (const std::size_t rows : {2001u, 10001u, 123457u, 1000000u}) {
    const std::vector<std::size_t> frames = nhdyn::report_frames(rows, 2000);
    const std::size_t k = (rows - 1 + 1998) / 1999;
    ASSERT_LE(frames.size(), 2001u);
    EXPECT_EQ(frames.front(), 0u);
    EXPECT_EQ(frames.back(), rows - 1);
    for (std::size_t i = 1; i + 1 < frames.size(); ++i) EXPECT_EQ(frames[i] - frames[i - 1], k);
    EXPECT_LE(frames.back() - frames[frames.size() - 2], k);
  }
}

TEST(Report, ColumnsOfAnotherModelAreNamed) {
  nhdyn::ResultColumns columns;
  columns.all = {"t", "x", "y", "x'", "y'"};
  nhdyn::check_report_columns(columns.all, columns, "r.csv", "dot");
  try {
    nhdyn::check_report_columns({"t", "x", "z", "x'", "z'"}, columns, "r.csv", "dot");
    ADD_FAILURE() << "a foreign CSV was accepted";
  } catch (const nhdyn::InputError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("column 3 is 'z' where the model expects 'y'"), std::string::npos) << m;
    EXPECT_NE(m.find("r.csv"), std::string::npos) << m;
  }
  EXPECT_THROW(nhdyn::check_report_columns({"t", "x"}, columns, "r.csv", "dot"), nhdyn::InputError);
}

// Runs the command line; returns the exit code, fills stdout and stderr.
int run(const std::string& args, std::string& out, std::string& err, const fs::path& dir) {
  const std::string command = std::string(NHDYN_CLI_PATH) + " " + args + " >" + (dir / "out.txt").string() + " 2>" +
                              (dir / "err.txt").string();
  const int status = std::system(command.c_str());
  std::ifstream o(dir / "out.txt"), e(dir / "err.txt");
  std::stringstream so, se;
  so << o.rdbuf();
  se << e.rdbuf();
  out = so.str();
  err = se.str();
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

struct Cli : ::testing::Test {
  fs::path dir;
  void SetUp() override {
    dir = fs::temp_directory_path() /
          ("nhdyn_report_" + std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()) + "_" +
           std::to_string(::getpid()));
    fs::remove_all(dir);
    fs::create_directories(dir);
  }
  void TearDown() override { fs::remove_all(dir); }
};

TEST_F(Cli, UnwritableHtmlIsRefusedBeforeSimulating) {
  std::string out, err;
  const fs::path csv = dir / "sled.csv";
  EXPECT_EQ(run("simulate " + example("sled.toml").string() + " -o " + csv.string() + " --html " +
                    (dir / "missing" / "r.html").string(),
                out, err, dir),
            2);
  EXPECT_NE(err.find("missing"), std::string::npos) << err;
  EXPECT_FALSE(fs::exists(csv)) << "the run went ahead";
}

TEST_F(Cli, ReportOfSimulateIsSelfContainedAndReproducible) {
  std::string out, err;
  const fs::path csv = dir / "sled.csv", a = dir / "a.html", b = dir / "b.html";
  ASSERT_EQ(run("simulate " + example("sled.toml").string() + " --t-end 2 -o " + csv.string() + " --html " +
                    a.string(),
                out, err, dir),
            0)
      << err;
  EXPECT_NE(out.find("report -> "), std::string::npos) << out;
  ASSERT_EQ(run("report " + csv.string() + " --model " + example("sled.toml").string() + " -o " + b.string(), out, err,
                dir),
            0)
      << err;
  std::ifstream fa(a), fb(b);
  std::stringstream sa, sb;
  sa << fa.rdbuf();
  sb << fb.rdbuf();
  const std::string page = sa.str();
  // Nothing is fetched when the page opens: no external script, stylesheet or font.
  EXPECT_EQ(page.find("<script src"), std::string::npos);
  EXPECT_EQ(page.find("<link"), std::string::npos);
  EXPECT_EQ(page.find("url(fonts/"), std::string::npos);
  EXPECT_NE(page.find("data:font/woff2;base64,"), std::string::npos);
  EXPECT_NE(page.find("const NHDYN = "), std::string::npos);
  EXPECT_NE(page.find("\\\\begin{align*}"), std::string::npos) << "the equations are in the page";
  // Both commands show the same run; the reports differ only in their summary and title.
  ASSERT_EQ(run("report " + csv.string() + " --model " + example("sled.toml").string() + " -o " +
                    (dir / "c.html").string(),
                out, err, dir),
            0);
  std::ifstream fc(dir / "c.html");
  std::stringstream sc;
  sc << fc.rdbuf();
  EXPECT_EQ(sb.str(), sc.str()) << "same input, same bytes";
}

TEST_F(Cli, CsvOfAnotherModelNamesTheColumn) {
  std::string out, err;
  const fs::path csv = dir / "appell.csv";
  ASSERT_EQ(run("simulate " + example("appell.toml").string() + " --t-end 0.5 -q -o " + csv.string(), out, err, dir),
            0)
      << err;
  EXPECT_EQ(run("report " + csv.string() + " --model " + example("sled.toml").string() + " -o " +
                    (dir / "r.html").string(),
                out, err, dir),
            2);
  EXPECT_NE(err.find("does not belong to model 'sled'"), std::string::npos) << err;
  EXPECT_NE(err.find("column 4 is 'z' where the model expects 'phi'"), std::string::npos) << err;
  EXPECT_FALSE(fs::exists(dir / "r.html"));
}

TEST_F(Cli, ModelWithNothingToDrawSaysSoAndDrawsThePath) {
  std::string out, err;
  const fs::path html = dir / "r.html";
  ASSERT_EQ(run("simulate " + example("diff_drive.toml").string() + " --t-end 0.5 -o " + (dir / "d.csv").string() +
                    " --html " + html.string(),
                out, err, dir),
            0)
      << err;
  EXPECT_NE(out.find("names nothing to draw"), std::string::npos) << out;
  std::ifstream f(html);
  std::stringstream s;
  s << f.rdbuf();
  EXPECT_NE(s.str().find("names nothing to draw"), std::string::npos);
}

}  // namespace
