// The HTML report's library parts and the command line around it: the scene's program against
// closed-form positions (the sled's blade, the rolling disk's centre and contact point), the
// equivalent ellipsoid of a body, the rule that thins long runs, the page being self-contained and
// reproducible, and bad input (a [visual] table that cannot be drawn, a CSV of another model, an
// --html path that cannot be written, a model with nothing to draw). The page in a browser is
// tests/report/report_test.py.
#include <fmt/format.h>
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <sstream>
#include <string>
#include <vector>

#include "nhdyn/core/error.hpp"
#include "nhdyn/io/csv.hpp"
#include "nhdyn/frontend/model_file.hpp"
#include "nhdyn/io/report.hpp"
#include "nhdyn/symbolic/compile.hpp"
#include "nhdyn/model/parameters.hpp"
#include "nhdyn/symbolic/visual.hpp"
#include "support/cli_run.hpp"
#include "support/text.hpp"

namespace {

namespace fs = std::filesystem;
using nhdyn::symbolic::VisualKind;

fs::path example(const std::string& name) { return fs::path(NHDYN_SOURCE_DIR) / "examples" / name; }

// The spec's parameters as a Model holds them (name, value), in the spec's order.
std::vector<nhdyn::Parameter> spec_parameters(const nhdyn::symbolic::Spec& spec) {
  std::vector<nhdyn::Parameter> out;
  for (const auto& p : spec.parameters) out.push_back({p.name, p.value, p.unit, p.expression});
  return out;
}

// The scene's program bound to the spec's parameter values, run at (t, q, v).
std::vector<double> run_scene(const nhdyn::symbolic::VisualScene& scene, const nhdyn::symbolic::Spec& spec, double t,
                              const std::vector<double>& q, const std::vector<double>& v) {
  std::vector<double> values;
  for (const auto& p : spec.parameters) values.push_back(p.value);
  const nhdyn::Tape program = scene.tape.bind(values.data(), values.size());
  std::vector<double> registers(static_cast<std::size_t>(program.registers()));
  std::vector<double> out(static_cast<std::size_t>(program.outputs()));
  program.run(t, q.data(), v.data(), registers.data(), out.data());
  return out;
}

double parameter(const nhdyn::symbolic::Spec& spec, const std::string& name) {
  for (const auto& p : spec.parameters)
    if (p.name == name) return p.value;
  ADD_FAILURE() << "no parameter " << name;
  return 0.0;
}


// The numbers of the JSON array that follows `key` at or after `from` in a report's page (null, a
// gap, as NaN); empty when the key is missing.
std::vector<double> report_array_after(const std::string& page, const std::string& key, std::size_t from = 0) {
  std::vector<double> out;
  const std::size_t at = page.find(key, from);
  if (at == std::string::npos) return out;
  std::size_t p = page.find('[', at) + 1;
  const std::size_t end = page.find(']', p);
  while (p < end) {
    std::size_t next = page.find(',', p);
    if (next == std::string::npos || next > end) next = end;
    const std::string item = page.substr(p, next - p);
    out.push_back(item == "null" ? std::nan("") : std::stod(item));
    p = next + 1;
  }
  return out;
}

// One shape of a report's scene as the page has it: its offset in the values and its size.
struct ReportShape {
  int offset = -1;
  std::vector<double> size;
};
ReportShape report_shape(const std::string& page, const std::string& kind, const std::string& name) {
  ReportShape shape;
  const std::size_t at = page.find("{\"kind\":\"" + kind + "\",\"name\":\"" + name + "\"", page.find("\"scene\":"));
  if (at == std::string::npos) return shape;
  shape.offset = std::stoi(page.substr(page.find("\"offset\":", at) + 9));
  shape.size = report_array_after(page, "\"size\":", at);
  return shape;
}

// The scene's values per frame shown (stride numbers each) and the times of the frames.
std::vector<double> report_scene_values(const std::string& page) {
  return report_array_after(page, "\"values\":", page.find("\"scene\":"));
}
int report_scene_stride(const std::string& page) {
  return std::stoi(page.substr(page.find("\"stride\":", page.find("\"scene\":")) + 9));
}

TEST(Visual, SledBladeAndCentreOfMassFollowTheClosedForm) {
  const nhdyn::symbolic::Spec spec = nhdyn::load_model_file(example("sled.toml"));
  const nhdyn::symbolic::VisualScene scene = nhdyn::symbolic::compile_visual(spec);
  ASSERT_EQ(scene.shapes.size(), 3u);
  EXPECT_TRUE(scene.planar);
  EXPECT_FALSE(scene.ground);
  auto find = [&](const std::string& name) {
    for (std::size_t i = 0; i < scene.shapes.size(); ++i)
      if (scene.shapes[i].name == name) return i;
    ADD_FAILURE() << "no shape " << name;
    return std::size_t{0};
  };
  const nhdyn::symbolic::VisualShape blade = scene.shapes[find("blade")], mass = scene.shapes[find("centre of mass")];
  EXPECT_EQ(blade.kind, VisualKind::segment);
  EXPECT_EQ(mass.kind, VisualKind::sphere);
  const std::vector<nhdyn::SceneSize> sizes = nhdyn::calc_scene_sizes(scene, spec_parameters(spec), spec.name);
  EXPECT_DOUBLE_EQ(sizes[find("centre of mass")].size[0], 0.08);
  // phi is an angle (inside cos and sin), x and y are lengths.
  EXPECT_EQ(scene.angles, (std::vector<bool>{false, false, true}));
  const double a = parameter(spec, "a");
  for (const double phi : {0.0, 0.7, -2.1, 3.0}) {
    const double x = 1.3, y = -0.4;
    const std::vector<double> out = run_scene(scene, spec, 0.0, {x, y, phi}, {0.1, 0.2, 0.3});
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
  const std::vector<nhdyn::SceneSize> sizes = nhdyn::calc_scene_sizes(scene, spec_parameters(spec), spec.name);
  EXPECT_DOUBLE_EQ(sizes[static_cast<std::size_t>(wheel)].size[0], r);
  EXPECT_EQ(scene.shapes[static_cast<std::size_t>(wheel)].axis, 1);
  const double x = 0.4, y = -1.1, psi = 0.9, theta = 0.35, phi = 2.0;
  const std::vector<double> out = run_scene(scene, spec, 0.0, {x, y, psi, theta, phi}, {0, 0, 0, 0, 0});
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
  std::array<double, 3> semi = sizes[static_cast<std::size_t>(body)].size;
  std::sort(semi.begin(), semi.end());
  EXPECT_NEAR(semi[2], std::sqrt(5.0) / 2 * r, 1e-14);
  EXPECT_NEAR(semi[1], std::sqrt(5.0) / 2 * r, 1e-14);
  EXPECT_NEAR(semi[0], 0.1 * std::sqrt(5.0) / 2 * r, 1e-14);
  // psi, theta and phi are angles; x and y lengths.
  EXPECT_EQ(scene.angles, (std::vector<bool>{false, false, true, true, true}));
}

// Parameters are data: the scene is compiled once with the parameters symbolic, and the report
// draws the values of the Model it is given. The spec keeps r = 0.2; the Model's r is set to 0.35
// after compiling, and the page's wheel, body and centre follow 0.35.
TEST(Visual, SceneFollowsTheModelsParametersWithoutRecompiling) {
  const nhdyn::symbolic::Spec spec = nhdyn::load_model_file(example("rolling_disk_bodies.toml"));
  nhdyn::Model model = nhdyn::symbolic::compile_model(spec);
  const double r = 0.35;
  ASSERT_NE(parameter(spec, "r"), r);
  nhdyn::set_parameter(model, "r", r);
  const nhdyn::symbolic::VisualScene scene = nhdyn::symbolic::compile_visual(spec);
  const std::vector<nhdyn::SceneSize> sizes = nhdyn::calc_scene_sizes(scene, model.parameters, model.name);
  for (std::size_t i = 0; i < scene.shapes.size(); ++i) {
    if (scene.shapes[i].kind == VisualKind::wheel) {
      EXPECT_DOUBLE_EQ(sizes[i].size[0], r);
    }
    if (scene.shapes[i].kind == VisualKind::body) {
      std::array<double, 3> semi = sizes[i].size;
      std::sort(semi.begin(), semi.end());
      EXPECT_NEAR(semi[2], std::sqrt(5.0) / 2 * r, 1e-14);
    }
  }

  // A run of three rows through write_model_report, the function both commands call.
  nhdyn::CsvTable table;
  table.header = nhdyn::make_result_columns(model).all;
  const std::vector<std::array<double, 5>> states = {{0, 0, 0, 0.3, 0}, {0.4, -1.1, 0.9, 0.35, 2.0}, {-2, 1, -2.5, -0.6, 7}};
  for (std::size_t k = 0; k < states.size(); ++k) {
    std::vector<double> row(table.header.size(), 0.0);
    row[0] = 0.5 * static_cast<double>(k);
    for (int i = 0; i < 5; ++i) row[static_cast<std::size_t>(table.column(model.coordinates[static_cast<std::size_t>(i)]))] = states[k][static_cast<std::size_t>(i)];
    table.rows.push_back(row);
  }
  const fs::path html = fs::temp_directory_path() / ("nhdyn_report_parameters_" + std::to_string(::getpid()) + ".html");
  nhdyn::write_model_report(model, &spec, table, "disk", {}, html);
  const std::string page = nhdyn::test::read_text(html);
  fs::remove(html);
  const ReportShape wheel = report_shape(page, "wheel", "disk");
  ASSERT_GE(wheel.offset, 0) << "no wheel in the page";
  ASSERT_EQ(wheel.size.size(), 3u);
  EXPECT_NEAR(wheel.size[0], r, 1e-6);
  const std::vector<double> values = report_scene_values(page);
  const int stride = report_scene_stride(page);
  ASSERT_EQ(values.size(), states.size() * static_cast<std::size_t>(stride));
  for (std::size_t k = 0; k < states.size(); ++k) {
    const double x = states[k][0], y = states[k][1], psi = states[k][2], theta = states[k][3];
    const double* c = values.data() + k * static_cast<std::size_t>(stride) + wheel.offset;
    EXPECT_NEAR(c[0], x + r * std::sin(theta) * std::sin(psi), 1e-5);  // six significant digits in the page
    EXPECT_NEAR(c[1], y - r * std::sin(theta) * std::cos(psi), 1e-5);  // six significant digits in the page
    EXPECT_NEAR(c[2], r * std::cos(theta), 1e-5);  // six significant digits in the page
  }
}

// A [visual] table in a derived parameter (h = L/2): setting L re-evaluates h, and the point's
// place and radius follow; a radius the parameters make negative is refused naming the item.
TEST(Visual, DerivedParametersAndBadSizesFromTheRunsValues) {
  const nhdyn::symbolic::Spec spec = nhdyn::load_model_string(R"toml(
name = "dot"
coordinates = ["x", "y"]
kinetic_energy = "m/2*(x'^2 + y'^2)"
[parameters]
m = 1.0
L = 1.0
h = "L/2"
[visual]
points = [{ name = "p", position = ["x + h", "y - h^2"], radius = "h/10" }]
)toml",
                                                              "dot.toml");
  const nhdyn::symbolic::VisualScene scene = nhdyn::symbolic::compile_visual(spec);
  nhdyn::Model model = nhdyn::symbolic::compile_model(spec);
  nhdyn::set_parameter(model, "L", 3.0);
  const double h = 1.5;
  EXPECT_DOUBLE_EQ(nhdyn::calc_scene_sizes(scene, model.parameters, model.name)[0].size[0], h / 10);
  std::vector<double> values;
  for (const nhdyn::Parameter& p : model.parameters) values.push_back(p.value);
  const nhdyn::Tape program = scene.tape.bind(values.data(), values.size());
  std::vector<double> registers(static_cast<std::size_t>(program.registers())), out(3);
  const double q[2] = {0.25, -0.75}, v[2] = {0, 0};
  program.run(0.0, q, v, registers.data(), out.data());
  EXPECT_DOUBLE_EQ(out[0], 0.25 + h);
  EXPECT_DOUBLE_EQ(out[1], -0.75 - h * h);

  nhdyn::set_parameter(model, "L", -1.0);
  try {
    nhdyn::calc_scene_sizes(scene, model.parameters, model.name);
    ADD_FAILURE() << "a negative radius was drawn";
  } catch (const nhdyn::InputError& e) {
    const std::string m = e.what();
    EXPECT_TRUE(nhdyn::test::contains(m, "dot.toml:10:")) << m;
    EXPECT_TRUE(nhdyn::test::contains(m, "point 'p'")) << m;
    EXPECT_TRUE(nhdyn::test::contains(m, "-0.05")) << m;
  }
  // Another model's values are refused, naming both lists.
  std::vector<nhdyn::Parameter> other = model.parameters;
  other.pop_back();
  EXPECT_THROW(nhdyn::calc_scene_sizes(scene, other, model.name), nhdyn::InputError);
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

// The PNG panels' rules in the page: an angle known by its name (phi, not used in sin or cos
// here) gets the angles' panel, and a column constant to round-off beside others of its role is
// drawn flat at its level and labelled so, not magnified into noise.
TEST(Report, AnglesByNameAndRoundOffDrawnFlat) {
  const nhdyn::Model model = nhdyn::symbolic::compile_model(nhdyn::load_model_string(
      "name = \"spinner\"\ncoordinates = [\"x\", \"phi\"]\nkinetic_energy = \"x'^2/2 + phi'^2/2\"\n", "spinner.toml"));
  nhdyn::CsvTable table;
  table.header = nhdyn::make_result_columns(model).all;
  for (int r = 0; r < 11; ++r) {
    std::vector<double>& row = table.rows.emplace_back(table.header.size(), 0.0);
    row[0] = 0.1 * r;                                // t
    row[1] = 2.0 * row[0];                           // x: the motion
    row[2] = 1e-12 * std::sin(7.0 * r);              // phi: noise of 1e-12 about 0
  }
  const fs::path html = fs::temp_directory_path() / "nhdyn_report_rules.html";
  nhdyn::write_model_report(model, static_cast<const nhdyn::symbolic::ModelDescription*>(nullptr), table, "spinner",
                            {}, html);
  std::ifstream in(html);
  std::stringstream page;
  page << in.rdbuf();
  fs::remove(html);
  const std::string text = page.str();
  EXPECT_NE(text.find("{\"title\":\"coordinates\",\"log\":false,\"series\":[{\"name\":\"x\","), std::string::npos);
  const std::size_t angles = text.find("{\"title\":\"angles [rad]\",\"log\":false,\"series\":[{\"name\":\"phi "
                                       "(constant to round-off, ");
  ASSERT_NE(angles, std::string::npos) << text.substr(text.find("\"plots\""), 600);
  // Drawn at one level: every value of the series is the same number.
  const std::size_t v = text.find("\"v\":[", angles) + 5;
  const std::string values = text.substr(v, text.find(']', v) - v);
  const std::string first = values.substr(0, values.find(','));
  EXPECT_EQ(values, [&] {
    std::string same = first;
    for (int r = 1; r < 11; ++r) same += "," + first;
    return same;
  }());
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

// `nhdyn report -o` into a directory that does not exist: refused (exit 2) naming the path, before
// the model is compiled or the CSV read (the CSV named here does not exist either).
TEST_F(Cli, UnwritableReportOutputIsRefusedFirst) {
  const nhdyn::test::CliOutcome run = nhdyn::test::run_nhdyn(
      "report " + (dir / "none.csv").string() + " --model " + example("sled.toml").string() + " -o " +
          (dir / "missing" / "r.html").string(),
      dir);
  EXPECT_EQ(run.exit_code, 2) << run.out;
  EXPECT_TRUE(nhdyn::test::contains(run.out, (dir / "missing").string())) << run.out;
  EXPECT_FALSE(nhdyn::test::contains(run.out, "none.csv")) << "the CSV was read first: " << run.out;
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

// `--set` on the command line: the report of simulate and of `nhdyn report` draw the run's values,
// checked against the closed form of the wheel's centre on every row of the CSV, and the sled's
// centre of mass at x + a cos(phi) with the a that was set.
TEST_F(Cli, SetParametersAreDrawnWithTheRunsValues) {
  const fs::path csv = dir / "disk.csv", a = dir / "a.html", b = dir / "b.html";
  const double r = 0.35;
  nhdyn::test::CliOutcome run = nhdyn::test::run_nhdyn(
      "simulate " + example("rolling_disk_bodies.toml").string() + " --set r=0.35 --t-end 1 -q -o " + csv.string() +
          " --html " + a.string(),
      dir);
  ASSERT_EQ(run.exit_code, 0) << run.out;
  run = nhdyn::test::run_nhdyn("report " + csv.string() + " --model " + example("rolling_disk_bodies.toml").string() +
                                   " --set r=0.35 -q -o " + b.string(),
                               dir);
  ASSERT_EQ(run.exit_code, 0) << run.out;
  const nhdyn::CsvTable table = nhdyn::load_csv(csv);
  ASSERT_GT(table.rows.size(), 10u);
  for (const fs::path& html : {a, b}) {
    const std::string page = nhdyn::test::read_text(html);
    const ReportShape wheel = report_shape(page, "wheel", "disk");
    ASSERT_GE(wheel.offset, 0) << html;
    EXPECT_NEAR(wheel.size.at(0), r, 1e-6) << html;
    const ReportShape body = report_shape(page, "body", "disk");
    ASSERT_EQ(body.size.size(), 3u);
    EXPECT_NEAR(*std::max_element(body.size.begin(), body.size.end()), std::sqrt(5.0) / 2 * r, 1e-6) << html;
    const std::vector<double> values = report_scene_values(page);
    const std::size_t stride = static_cast<std::size_t>(report_scene_stride(page));
    ASSERT_EQ(values.size(), table.rows.size() * stride) << html;
    for (std::size_t k = 0; k < table.rows.size(); ++k) {
      const std::vector<double>& row = table.rows[k];
      const double x = row[1], y = row[2], psi = row[3], theta = row[4];
      const double* c = values.data() + k * stride + wheel.offset;
      ASSERT_NEAR(c[0], x + r * std::sin(theta) * std::sin(psi), 1e-5) << html << " row " << k;
      ASSERT_NEAR(c[1], y - r * std::sin(theta) * std::cos(psi), 1e-5) << html << " row " << k;
      ASSERT_NEAR(c[2], r * std::cos(theta), 1e-5) << html << " row " << k;
    }
  }

  const fs::path sled_csv = dir / "sled.csv", sled = dir / "sled.html";
  run = nhdyn::test::run_nhdyn("simulate " + example("sled.toml").string() + " --set a=0.3 --t-end 1 -q -o " +
                                   sled_csv.string() + " --html " + sled.string(),
                               dir);
  ASSERT_EQ(run.exit_code, 0) << run.out;
  const nhdyn::CsvTable sled_table = nhdyn::load_csv(sled_csv);
  const std::string page = nhdyn::test::read_text(sled);
  const ReportShape mass = report_shape(page, "sphere", "centre of mass");
  ASSERT_GE(mass.offset, 0);
  const std::vector<double> values = report_scene_values(page);
  const std::size_t stride = static_cast<std::size_t>(report_scene_stride(page));
  ASSERT_EQ(values.size(), sled_table.rows.size() * stride);
  for (std::size_t k = 0; k < sled_table.rows.size(); ++k) {
    const double x = sled_table.rows[k][1], y = sled_table.rows[k][2], phi = sled_table.rows[k][3];
    ASSERT_NEAR(values[k * stride + mass.offset], x + 0.3 * std::cos(phi), 1e-5) << "row " << k;
    ASSERT_NEAR(values[k * stride + mass.offset + 1], y + 0.3 * std::sin(phi), 1e-5) << "row " << k;
  }
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
  // The provenance header names the run's model first (io/provenance.hpp) ...
  EXPECT_NE(err.find("was written by a run of 'appell' from "), std::string::npos) << err;
  EXPECT_FALSE(fs::exists(dir / "r.html"));
  // ... and a CSV without one is told by its columns.
  std::string rows;
  {
    std::ifstream in(csv);
    for (std::string line; std::getline(in, line);)
      if (!line.starts_with("#")) rows += line + "\n";
  }
  std::ofstream(csv) << rows;
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

// ---- [[contacts]]: each shape on its body and each ground, as the run's parameters make them ----

namespace {

// The index of the scene's shape of this kind and name, or -1.
int find_shape(const nhdyn::symbolic::VisualScene& scene, VisualKind kind, const std::string& name) {
  for (std::size_t i = 0; i < scene.shapes.size(); ++i)
    if (scene.shapes[i].kind == kind && scene.shapes[i].name == name) return static_cast<int>(i);
  return -1;
}

// The rattleback's ellipsoid: its semi-axes are the parameters a, b, c of the run (a set after
// compiling), at the body frame's origin (x, y, z) and turning with it (the body's rotation, its centre of
// mass being below the shape's centre); the body is drawn by it (the page hides its ellipsoid of
// inertia); the contact point's track is NAME_X, NAME_Y, NAME_Z.
TEST(ContactScene, EllipsoidHasTheRunsSemiAxesAndTurnsWithItsBody) {
  const nhdyn::symbolic::Spec spec = nhdyn::load_model_file(example("rattleback.toml"));
  nhdyn::Model model = nhdyn::symbolic::compile_model(spec);
  nhdyn::set_parameter(model, "a", 0.23);
  const nhdyn::symbolic::VisualScene scene = nhdyn::symbolic::compile_visual(spec);
  const int shape = find_shape(scene, VisualKind::ellipsoid, "rattleback");
  const int body = find_shape(scene, VisualKind::body, "rattleback");
  const int track = find_shape(scene, VisualKind::track, "rattleback");
  ASSERT_GE(shape, 0);
  ASSERT_GE(body, 0);
  ASSERT_GE(track, 0);
  EXPECT_EQ(scene.shapes[static_cast<std::size_t>(shape)].body, "rattleback");
  const std::vector<nhdyn::SceneSize> sizes = nhdyn::calc_scene_sizes(scene, model.parameters, model.name);
  const std::array<double, 3> semi = sizes[static_cast<std::size_t>(shape)].size;
  EXPECT_EQ(semi[0], 0.23);
  EXPECT_EQ(semi[1], parameter(spec, "b"));
  EXPECT_EQ(semi[2], parameter(spec, "c"));
  const std::vector<double> q = {0.1, -0.2, 0.03, 0.7, 0.2, -0.1}, v(q.size(), 0.0);
  ASSERT_EQ(static_cast<int>(q.size()), spec.n());
  const std::vector<double> out = run_scene(scene, spec, 0.0, q, v);
  const int s = scene.shapes[static_cast<std::size_t>(shape)].offset, b = scene.shapes[static_cast<std::size_t>(body)].offset;
  for (int k = 3; k < 12; ++k) EXPECT_EQ(out[static_cast<std::size_t>(s + k)], out[static_cast<std::size_t>(b + k)]) << k;
  for (int k = 0; k < 3; ++k) EXPECT_EQ(out[static_cast<std::size_t>(s + k)], q[static_cast<std::size_t>(k)]);  // the frame's origin
}

// A ball over a bump of terrain, run by the command line: the page has the ball (a sphere drawn
// as an ellipsoid of three equal semi-axes r), the terrain's mesh and the track, whose positions
// are the CSV's columns ball_X, ball_Y, ball_Z; the mesh's heights are h(X, Y) at its vertices to
// round-off, over a region that holds the whole track.
TEST_F(Cli, BallOverBumpDrawsTheTerrainAndTheTrack) {
  std::string out, err;
  const fs::path csv = dir / "bump.csv", html = dir / "bump.html";
  ASSERT_EQ(run("simulate " + example("ball_over_bump.toml").string() + " --t-end 0.5 -o " + csv.string() +
                    " --html " + html.string() + " -q",
                out, err, dir),
            0)
      << err;
  const std::string page = nhdyn::test::read_text(html);
  const nhdyn::CsvTable table = nhdyn::load_csv(csv);
  const nhdyn::symbolic::Spec spec = nhdyn::load_model_file(example("ball_over_bump.toml"));
  const double r = parameter(spec, "r"), H = parameter(spec, "H"), w = parameter(spec, "w");
  const ReportShape ball = report_shape(page, "ellipsoid", "ball");
  ASSERT_GE(ball.offset, 0) << "no ball in the page";
  EXPECT_EQ(ball.size, (std::vector<double>{r, r, r}));
  const ReportShape track = report_shape(page, "track", "ball");
  ASSERT_GE(track.offset, 0) << "no track in the page";
  EXPECT_GE(report_shape(page, "terrain", "ball").offset, 0) << "no terrain in the page";
  EXPECT_NE(page.find("\"mesh\":{\"v\":", page.find("{\"kind\":\"terrain\"")), std::string::npos);
  const std::vector<double> values = report_scene_values(page);
  const std::size_t stride = static_cast<std::size_t>(report_scene_stride(page));
  ASSERT_EQ(values.size(), table.rows.size() * stride) << "every row is a frame";
  const int X = table.column("ball_X"), Y = table.column("ball_Y"), Z = table.column("ball_Z");
  ASSERT_GE(X, 0);
  for (std::size_t f = 0; f < table.rows.size(); ++f)
    for (int k = 0; k < 3; ++k) {
      const double column = table.rows[f][static_cast<std::size_t>((k == 0 ? X : k == 1 ? Y : Z))];
      EXPECT_NEAR(values[f * stride + static_cast<std::size_t>(track.offset + k)], column, 1e-6 * std::max(1.0, std::abs(column)));
    }

  // The mesh itself, from the library at full precision.
  const nhdyn::symbolic::VisualScene scene = nhdyn::symbolic::compile_visual(spec);
  const int terrain = find_shape(scene, VisualKind::terrain, "ball");
  ASSERT_GE(terrain, 0);
  const std::vector<nhdyn::SceneMesh> meshes =
      nhdyn::calc_scene_meshes(scene, spec_parameters(spec), values, stride, spec.name);
  const nhdyn::SceneMesh& mesh = meshes[static_cast<std::size_t>(terrain)];
  ASSERT_GE(mesh.vertices.size(), 3u * 81);
  double lo[2] = {1e300, 1e300}, hi[2] = {-1e300, -1e300};
  for (std::size_t k = 0; k < mesh.vertices.size(); k += 3) {
    const double x = mesh.vertices[k], y = mesh.vertices[k + 1];
    EXPECT_NEAR(mesh.vertices[k + 2], H * std::exp(-(x * x + y * y) / (w * w)), 4e-16 * H);
    lo[0] = std::min(lo[0], x), lo[1] = std::min(lo[1], y), hi[0] = std::max(hi[0], x), hi[1] = std::max(hi[1], y);
  }
  for (const std::vector<double>& row : table.rows) {
    EXPECT_LT(lo[0], row[static_cast<std::size_t>(X)]);
    EXPECT_GT(hi[0], row[static_cast<std::size_t>(X)]);
    EXPECT_LT(lo[1], row[static_cast<std::size_t>(Y)]);
    EXPECT_GT(hi[1], row[static_cast<std::size_t>(Y)]);
  }
  for (const int i : mesh.triangles) EXPECT_LT(static_cast<std::size_t>(3 * i), mesh.vertices.size());
}

// A ball in a bowl: the bowl's mesh lies on the sphere of radius Rb about (0, 0, Rb) to round-off
// and covers the ball's contact point wherever it goes; the ball's radius is the run's r.
TEST(ContactScene, BowlIsAMeshOfItsSphereAroundTheMotion) {
  const nhdyn::symbolic::Spec spec = nhdyn::load_model_file(example("ball_in_bowl.toml"));
  nhdyn::Model model = nhdyn::symbolic::compile_model(spec);
  nhdyn::set_parameter(model, "r", 0.08);
  const nhdyn::symbolic::VisualScene scene = nhdyn::symbolic::compile_visual(spec);
  const int ball = find_shape(scene, VisualKind::ellipsoid, "ball"), bowl = find_shape(scene, VisualKind::surface, "ball");
  const int track = find_shape(scene, VisualKind::track, "ball");
  ASSERT_GE(ball, 0);
  ASSERT_GE(bowl, 0);
  ASSERT_GE(track, 0);
  EXPECT_EQ(nhdyn::calc_scene_sizes(scene, model.parameters, model.name)[static_cast<std::size_t>(ball)].size,
            (std::array<double, 3>{0.08, 0.08, 0.08}));
  // Frames of the ball's centre on the sphere of radius Rb - r about the bowl's centre.
  const double Rb = parameter(spec, "Rb"), r = 0.08;
  std::vector<double> values;
  std::vector<double> parameters;
  for (const nhdyn::Parameter& p : model.parameters) parameters.push_back(p.value);
  const nhdyn::Tape program = scene.tape.bind(parameters.data(), parameters.size());
  std::vector<double> registers(static_cast<std::size_t>(program.registers())), out(static_cast<std::size_t>(program.outputs()));
  std::vector<std::array<double, 3>> contact;
  for (const double angle : {0.0, 0.2, -0.3}) {
    const std::vector<double> q = {(Rb - r) * std::sin(angle), 0.0, Rb - (Rb - r) * std::cos(angle), 0.3, 0.1, angle},
                              v(q.size(), 0.0);
    program.run(0.0, q.data(), v.data(), registers.data(), out.data());
    values.insert(values.end(), out.begin(), out.end());
    const double* p = out.data() + scene.shapes[static_cast<std::size_t>(track)].offset;
    contact.push_back({p[0], p[1], p[2]});
  }
  const nhdyn::SceneMesh mesh = nhdyn::calc_scene_meshes(scene, model.parameters, values, out.size(), model.name)[static_cast<std::size_t>(bowl)];
  ASSERT_FALSE(mesh.vertices.empty());
  for (std::size_t k = 0; k < mesh.vertices.size(); k += 3)
    EXPECT_NEAR(std::hypot(mesh.vertices[k], mesh.vertices[k + 1], mesh.vertices[k + 2] - Rb), Rb, 1e-14);
  // Every contact point is on the bowl, and within the cap: a vertex is near it, and the cap
  // reaches beyond it (higher up the wall).
  double highest = 0.0;
  for (std::size_t k = 0; k < mesh.vertices.size(); k += 3) highest = std::max(highest, mesh.vertices[k + 2]);
  for (const auto& p : contact) {
    EXPECT_NEAR(std::hypot(p[0], p[1], p[2] - Rb), Rb, 1e-14) << "the contact point is on the bowl";
    double nearest = 1e300;
    for (std::size_t k = 0; k < mesh.vertices.size(); k += 3)
      nearest = std::min(nearest, std::hypot(mesh.vertices[k] - p[0], mesh.vertices[k + 1] - p[1], mesh.vertices[k + 2] - p[2]));
    EXPECT_LT(nearest, 0.05 * Rb);
    EXPECT_LT(p[2], highest);
  }
}

// A ball in the elliptic paraboloid (a surface that is not a sphere): the bowl's mesh, sampled
// over its tangent plane, lies on Z = X^2/(2 rho1) + Y^2/(2 rho2) to round-off and holds the
// contact points.
TEST(ContactScene, ParaboloidIsAMeshOfItsSurfaceAroundTheMotion) {
  const nhdyn::symbolic::Spec spec = nhdyn::load_model_file(example("ball_in_paraboloid.toml"));
  const nhdyn::Model model = nhdyn::symbolic::compile_model(spec);
  const nhdyn::symbolic::VisualScene scene = nhdyn::symbolic::compile_visual(spec);
  const int bowl = find_shape(scene, VisualKind::surface, "ball"), track = find_shape(scene, VisualKind::track, "ball");
  ASSERT_GE(bowl, 0);
  ASSERT_GE(track, 0);
  const double rho1 = parameter(spec, "rho1"), rho2 = parameter(spec, "rho2"), r = parameter(spec, "r");
  std::vector<double> parameters;
  for (const nhdyn::Parameter& p : model.parameters) parameters.push_back(p.value);
  const nhdyn::Tape program = scene.tape.bind(parameters.data(), parameters.size());
  std::vector<double> registers(static_cast<std::size_t>(program.registers())), out(static_cast<std::size_t>(program.outputs()));
  std::vector<double> values;
  std::vector<std::array<double, 3>> contact;
  // States on the contact: U on the bowl, the centre at r along its normal, the angles 0.
  for (const auto& [X, Y] : std::vector<std::pair<double, double>>{{0.0, 0.0}, {0.05, -0.02}, {-0.03, 0.04}}) {
    const double Z = X * X / (2 * rho1) + Y * Y / (2 * rho2);
    const double nx = -X / rho1, ny = -Y / rho2, length = std::sqrt(nx * nx + ny * ny + 1);
    const std::vector<double> q = {X + r * nx / length, Y + r * ny / length, Z + r / length, 0, 0, 0, X, Y, Z},
                              v(q.size(), 0.0);
    program.run(0.0, q.data(), v.data(), registers.data(), out.data());
    values.insert(values.end(), out.begin(), out.end());
    const double* p = out.data() + scene.shapes[static_cast<std::size_t>(track)].offset;
    EXPECT_NEAR(p[0], X, 1e-15);
    EXPECT_NEAR(p[2], Z, 1e-15);
    contact.push_back({p[0], p[1], p[2]});
  }
  const nhdyn::SceneMesh mesh =
      nhdyn::calc_scene_meshes(scene, model.parameters, values, out.size(), model.name)[static_cast<std::size_t>(bowl)];
  ASSERT_FALSE(mesh.vertices.empty());
  for (std::size_t k = 0; k < mesh.vertices.size(); k += 3) {
    const double X = mesh.vertices[k], Y = mesh.vertices[k + 1];
    EXPECT_NEAR(mesh.vertices[k + 2], X * X / (2 * rho1) + Y * Y / (2 * rho2), 1e-14);
  }
  for (const auto& p : contact) {
    double nearest = 1e300;
    for (std::size_t k = 0; k < mesh.vertices.size(); k += 3)
      nearest = std::min(nearest, std::hypot(mesh.vertices[k] - p[0], mesh.vertices[k + 1] - p[1], mesh.vertices[k + 2] - p[2]));
    EXPECT_LT(nearest, 0.02);
  }
  for (const int i : mesh.triangles) EXPECT_LT(static_cast<std::size_t>(3 * i), mesh.vertices.size());
}

// examples/ball_over_bump.toml with `from` replaced by `to`, written as NAME.toml and run for 0.2 s
// with --html: its spec, its page and the terrain's mesh at full precision from the page's frames.
struct BumpVariant {
  bool ran = false;
  std::string err;
  nhdyn::symbolic::Spec spec;
  std::string page;
  nhdyn::SceneMesh terrain;
};

BumpVariant run_bump_variant(const fs::path& dir, const std::string& from, const std::string& to, const std::string& name) {
  BumpVariant v;
  std::string text = nhdyn::read_model_text(example("ball_over_bump.toml"));
  if (text.find(from) == std::string::npos) {
    v.err = "no '" + from + "' in ball_over_bump.toml";
    return v;
  }
  text.replace(text.find(from), from.size(), to);
  const fs::path model = dir / (name + ".toml"), csv = dir / (name + ".csv"), html = dir / (name + ".html");
  std::ofstream(model) << text;
  std::string out;
  if (run("simulate " + model.string() + " --t-end 0.2 -o " + csv.string() + " --html " + html.string() + " -q", out,
          v.err, dir) != 0)
    return v;
  v.page = nhdyn::test::read_text(html);
  v.spec = nhdyn::load_model_file(model);
  const nhdyn::symbolic::VisualScene scene = nhdyn::symbolic::compile_visual(v.spec);
  const int index = find_shape(scene, VisualKind::terrain, "ball");
  if (index < 0) {
    v.err = "no terrain in the scene";
    return v;
  }
  v.terrain = nhdyn::calc_scene_meshes(scene, spec_parameters(v.spec), report_scene_values(v.page),
                                       static_cast<std::size_t>(report_scene_stride(v.page)),
                                       v.spec.name)[static_cast<std::size_t>(index)];
  v.ran = true;
  return v;
}

// A terrain undefined over part of the drawn box (sqrt(X + 0.1), a term too small to move the
// ball, is not real for X < -0.1, inside the box's margin): no triangle there, rather than a
// ground drawn at 0; every triangle's vertices are finite and the terrain's value.
TEST_F(Cli, TerrainUndefinedInPartOfTheBoxIsLeftOutThere) {
  const BumpVariant v = run_bump_variant(dir, "terrain = \"H*exp(-(X^2 + Y^2)/w^2)\"",
                                         "terrain = \"H*exp(-(X^2 + Y^2)/w^2) + 1e-12*sqrt(X + 0.1)\"", "half");
  ASSERT_TRUE(v.ran) << v.err;
  const std::string& page = v.page;
  const nhdyn::SceneMesh& mesh = v.terrain;
  const double H = parameter(v.spec, "H"), w = parameter(v.spec, "w");
  int undefined = 0;
  for (std::size_t k = 0; k < mesh.vertices.size(); k += 3) undefined += !std::isfinite(mesh.vertices[k + 2]);
  EXPECT_GT(undefined, 0) << "the box reaches X < -0.1";
  ASSERT_FALSE(mesh.triangles.empty());
  for (const int i : mesh.triangles) {
    const std::size_t k = 3 * static_cast<std::size_t>(i);
    const double x = mesh.vertices[k], y = mesh.vertices[k + 1];
    ASSERT_GE(x, -0.1);
    EXPECT_NEAR(mesh.vertices[k + 2], H * std::exp(-(x * x + y * y) / (w * w)) + 1e-12 * std::sqrt(x + 0.1), 4e-16 * H);
  }
  // The page carries those vertices as null (no number made up for them).
  EXPECT_NE(page.find("null", page.find("{\"kind\":\"terrain\"")), std::string::npos);
}

// The ball over the bump written as an implicit sphere: the terrain's margin around the track is
// four times the shape's half extent (its mesh's), 4 r = 0.2 m, as for the closed-form ball,
// not a length of 1 m.
TEST_F(Cli, TerrainUnderAnImplicitShapeHasTheShapesMargin) {
  const BumpVariant v =
      run_bump_variant(dir, "shape = { sphere = \"r\" }", "shape = { surface = \"X^2 + Y^2 + Z^2 - r^2\" }", "implicit");
  ASSERT_TRUE(v.ran) << v.err;
  const nhdyn::SceneMesh& mesh = v.terrain;
  const double r = parameter(v.spec, "r");
  const nhdyn::CsvTable table = nhdyn::load_csv(dir / "implicit.csv");
  const int X = table.column("ball_X");
  ASSERT_GE(X, 0);
  double lo = 1e300, hi = -1e300, path_lo = 1e300, path_hi = -1e300;
  for (std::size_t k = 0; k < mesh.vertices.size(); k += 3) lo = std::min(lo, mesh.vertices[k]), hi = std::max(hi, mesh.vertices[k]);
  for (const std::vector<double>& row : table.rows)
    path_lo = std::min(path_lo, row[static_cast<std::size_t>(X)]), path_hi = std::max(path_hi, row[static_cast<std::size_t>(X)]);
  ASSERT_LT(path_hi - path_lo, 3 * 4 * r);  // the margin is then 4 r, not a third of the path
  EXPECT_NEAR(path_lo - lo, 4 * r, 1e-3 * r);
  EXPECT_NEAR(hi - path_hi, 4 * r, 1e-3 * r);
}

// An implicit shape (the rattleback's ellipsoid written as f = 0): its mesh lies on f = 0 to
// round-off, with the run's semi-axes, in the body's axes about the shape's centre.
TEST(ContactScene, ImplicitShapeIsAMeshOfItsZeroSet) {
  std::string text = nhdyn::read_model_text(example("rattleback.toml"));
  const std::string ellipsoid = "shape = { ellipsoid = [\"a\", \"b\", \"c\"] }";
  ASSERT_NE(text.find(ellipsoid), std::string::npos);
  text.replace(text.find(ellipsoid), ellipsoid.size(), "shape = { surface = \"X^2/a^2 + Y^2/b^2 + Z^2/c^2 - 1\" }");
  const nhdyn::symbolic::Spec spec = nhdyn::load_model_string(text, "rattleback_surface.toml");
  nhdyn::Model model = nhdyn::symbolic::compile_model(spec);
  const double a = 0.21;
  nhdyn::set_parameter(model, "a", a);
  const double b = parameter(spec, "b"), c = parameter(spec, "c");
  const nhdyn::symbolic::VisualScene scene = nhdyn::symbolic::compile_visual(spec);
  const int solid = find_shape(scene, VisualKind::solid, "rattleback");
  ASSERT_GE(solid, 0);
  const nhdyn::SceneMesh mesh = nhdyn::calc_scene_meshes(scene, model.parameters, {}, 0, model.name)[static_cast<std::size_t>(solid)];
  ASSERT_GE(mesh.vertices.size(), 3u * 100);
  double reach[3] = {0, 0, 0};
  for (std::size_t k = 0; k < mesh.vertices.size(); k += 3) {
    const double x = mesh.vertices[k], y = mesh.vertices[k + 1], z = mesh.vertices[k + 2];
    EXPECT_NEAR(x * x / (a * a) + y * y / (b * b) + z * z / (c * c), 1.0, 1e-13);
    for (int i = 0; i < 3; ++i) reach[i] = std::max(reach[i], std::abs(mesh.vertices[k + static_cast<std::size_t>(i)]));
  }
  EXPECT_NEAR(reach[2], c, 1e-14);  // the poles are vertices
  EXPECT_NEAR(reach[0], a, 1e-14);  // and the ends of x (azimuth 0, polar pi/2)
}

// An implicit shape whose frame origin lies outside it (a ball of radius r centred 0.3 below the
// origin): the report finds a point inside by descending f and draws the whole sphere from there.
TEST(ContactScene, ImplicitShapeOffItsFramesOriginIsDrawnFromAPointInside) {
  const std::string text = R"(name = "offset-ball"
coordinates = ["x", "y", "z", "psi", "theta", "phi", "px", "py", "pz"]
gravity = [0, 0, "-g"]
[parameters]
m = 1.0
r = 0.1
g = 9.81
[[frames]]
name = "ball"
translation = ["x", "y", "z"]
rotations = [["z", "psi"], ["x", "theta"], ["y", "phi"]]
[[bodies]]
name = "ball"
frame = "ball"
mass = "m"
com = [0, 0, -0.3]
inertia = ["2/5*m*r^2", "2/5*m*r^2", "2/5*m*r^2"]
[[contacts]]
name = "foot"
body = "ball"
shape = { surface = "X^2 + Y^2 + (Z + 0.3)^2 - r^2", coordinates = ["px", "py", "pz"] }
[initial]
position = { x = 0, y = 0, z = 0.4, psi = 0, theta = 0, phi = 0, px = 0, py = 0, pz = -0.4 }
velocity = { x = 0.4, phi = 1 }
)";
  const nhdyn::symbolic::Spec spec = nhdyn::load_model_string(text, "offset_ball.toml");
  nhdyn::Model model = nhdyn::symbolic::compile_model(spec);
  const double r = 0.12;
  nhdyn::set_parameter(model, "r", r);
  const nhdyn::symbolic::VisualScene scene = nhdyn::symbolic::compile_visual(spec);
  const int solid = find_shape(scene, VisualKind::solid, "foot");
  ASSERT_GE(solid, 0);
  const nhdyn::SceneMesh mesh = nhdyn::calc_scene_meshes(scene, model.parameters, {}, 0, model.name)[static_cast<std::size_t>(solid)];
  ASSERT_GE(mesh.vertices.size(), 3u * 100);
  double lo[3] = {1e9, 1e9, 1e9}, hi[3] = {-1e9, -1e9, -1e9};
  for (std::size_t k = 0; k < mesh.vertices.size(); k += 3) {
    const double x = mesh.vertices[k], y = mesh.vertices[k + 1], z = mesh.vertices[k + 2];
    EXPECT_NEAR(std::sqrt(x * x + y * y + (z + 0.3) * (z + 0.3)), r, 1e-12);
    for (std::size_t i = 0; i < 3; ++i) {
      lo[i] = std::min(lo[i], mesh.vertices[k + i]);
      hi[i] = std::max(hi[i], mesh.vertices[k + i]);
    }
  }
  // The whole sphere, not a cap: its extent is 2r along each axis (to the mesh's resolution).
  for (std::size_t i = 0; i < 3; ++i) EXPECT_NEAR(hi[i] - lo[i], 2 * r, 0.02 * r) << i;
  EXPECT_NEAR(0.5 * (hi[2] + lo[2]), -0.3, 0.01 * r);
}

// The round tyre: the torus's radii are the run's R and r, about the wheel's axle y.
TEST(ContactScene, TorusHasTheRunsRadiiAboutItsAxle) {
  const nhdyn::symbolic::Spec spec =
      nhdyn::load_model_file(fs::path(NHDYN_SOURCE_DIR) / "docs" / "gallery" / "torus_wheel.toml");
  nhdyn::Model model = nhdyn::symbolic::compile_model(spec);
  nhdyn::set_parameter(model, "R", 0.3);
  const nhdyn::symbolic::VisualScene scene = nhdyn::symbolic::compile_visual(spec);
  const int torus = find_shape(scene, VisualKind::torus, "tyre");
  ASSERT_GE(torus, 0);
  EXPECT_EQ(scene.shapes[static_cast<std::size_t>(torus)].axis, 1);
  EXPECT_EQ(nhdyn::calc_scene_sizes(scene, model.parameters, model.name)[static_cast<std::size_t>(torus)].size,
            (std::array<double, 3>{0.3, parameter(spec, "r"), 0.0}));
  EXPECT_GE(find_shape(scene, VisualKind::track, "tyre"), 0);
}

// ---- Plane grounds: a tilted plane in its own axes, a turntable turned through its angle ----

// docs/gallery/ball_on_incline.toml, its plane's normal written with length 2 (the scene
// normalizes it), run for 1.2 s with --html: the page has one plane, at the origin, whose third
// axis is (-sin alpha, 0, cos alpha) on every frame, its axes orthonormal; the ball's centre is r
// above that plane all along, on the closed form's parabola C(0) + u0 t e_y + 5/14 g sin(alpha)
// t^2 d, d = (-cos alpha, 0, -sin alpha) down the slope.
TEST_F(Cli, InclineIsDrawnInItsOwnPlaneUnderTheBall) {
  std::string text = nhdyn::test::read_text(fs::path(NHDYN_SOURCE_DIR) / "docs" / "gallery" / "ball_on_incline.toml");
  const std::string written = R"m(plane = ["-sin(alpha)", 0, "cos(alpha)"])m";
  ASSERT_NE(text.find(written), std::string::npos);
  text.replace(text.find(written), written.size(), R"m(plane = ["-2*sin(alpha)", 0, "2*cos(alpha)"])m");
  std::ofstream(dir / "incline.toml") << text;
  const fs::path csv = dir / "incline.csv", html = dir / "incline.html";
  const nhdyn::test::CliOutcome run = nhdyn::test::run_nhdyn(
      "simulate incline.toml --t-end 1.2 -q -o " + csv.string() + " --html " + html.string(), dir);
  ASSERT_EQ(run.exit_code, 0) << run.out;
  const std::string page = nhdyn::test::read_text(html);
  const nhdyn::CsvTable table = nhdyn::load_csv(csv);
  const ReportShape plane = report_shape(page, "plane", "ball"), ball = report_shape(page, "ellipsoid", "ball");
  ASSERT_GE(plane.offset, 0) << "no plane in the page";
  ASSERT_GE(ball.offset, 0);
  const std::size_t first = page.find("{\"kind\":\"plane\"");
  EXPECT_EQ(page.find("{\"kind\":\"plane\"", first + 1), std::string::npos) << "the plane is drawn once";
  EXPECT_EQ(page.find("\"turns\""), std::string::npos) << "a fixed plane does not turn";
  const nhdyn::symbolic::Spec spec = nhdyn::load_model_string(text, "incline.toml");
  const double alpha = parameter(spec, "alpha"), r = parameter(spec, "r"), g = parameter(spec, "g"),
               u0 = parameter(spec, "u0");
  const std::array<double, 3> n = {-std::sin(alpha), 0.0, std::cos(alpha)}, d = {-std::cos(alpha), 0.0, -std::sin(alpha)};
  const std::vector<double> values = report_scene_values(page);
  const std::size_t stride = static_cast<std::size_t>(report_scene_stride(page));
  ASSERT_EQ(values.size(), table.rows.size() * stride);
  for (std::size_t f = 0; f < table.rows.size(); ++f) {
    const double* o = values.data() + f * stride + plane.offset;
    const double* R = o + 3;
    for (int k = 0; k < 3; ++k) EXPECT_EQ(o[k], 0.0);
    for (int i = 0; i < 3; ++i) EXPECT_NEAR(R[3 * i + 2], n[static_cast<std::size_t>(i)], 1e-6) << "frame " << f;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) {
        const double dot = R[i] * R[j] + R[3 + i] * R[3 + j] + R[6 + i] * R[6 + j];
        EXPECT_NEAR(dot, i == j ? 1.0 : 0.0, 2e-6) << "columns " << i << ", " << j;
      }
    const double* C = values.data() + f * stride + ball.offset;
    EXPECT_NEAR(R[2] * C[0] + R[5] * C[1] + R[8] * C[2], r, 1e-5) << "the ball is on the drawn plane, frame " << f;
    const double t = table.rows[f][0], down = 5.0 / 14 * g * std::sin(alpha) * t * t;
    const std::array<double, 3> expected = {r * n[0] + down * d[0], u0 * t, r * n[2] + down * d[2]};
    for (std::size_t k = 0; k < 3; ++k)
      EXPECT_NEAR(C[k], expected[k], 1e-5 * std::max(1.0, std::abs(expected[k]))) << "frame " << f << ", component " << k;
  }
}

// Several contacts on one plane draw it once; a level plane that does not turn is the scene's
// grid in z = 0, and is drawn as a plane item only beside a tilted one (the page then draws no
// other grid); a scene whose grounds are all level draws none (its report as before).
TEST(ContactScene, EachGroundPlaneIsDrawnOnce) {
  std::string text = R"m(name = "three-balls"
coordinates = ["x1", "y1", "z1", "a1", "b1", "c1", "x2", "y2", "z2", "a2", "b2", "c2", "x3", "y3", "z3", "a3", "b3", "c3"]
gravity = [0, 0, "-g"]

[parameters]
m = 0.1
r = 0.05
g = 9.81
alpha = 0.3
)m";
  const char* const grounds[3] = {R"m(ground = { plane = ["-sin(alpha)", 0, "cos(alpha)"] })m",
                                  R"m(ground = { plane = ["-sin(alpha)", 0, "cos(alpha)"] })m", R"m(ground = "plane")m"};
  for (int k = 1; k <= 3; ++k)
    text += fmt::format(R"m(
[[frames]]
name = "ball{0}"
translation = ["x{0}", "y{0}", "z{0}"]
rotations = [["x", "a{0}"], ["y", "b{0}"], ["z", "c{0}"]]

[[bodies]]
name = "ball{0}"
frame = "ball{0}"
mass = "m"
inertia = ["2/5*m*r^2", "2/5*m*r^2", "2/5*m*r^2"]

[[contacts]]
name = "ball{0}"
body = "ball{0}"
shape = {{ sphere = "r" }}
{1}
)m",
                        k, grounds[k - 1]);
  const nhdyn::symbolic::Spec spec = nhdyn::load_model_string(text, "three.toml");
  const nhdyn::symbolic::VisualScene scene = nhdyn::symbolic::compile_visual(spec);
  std::vector<std::string> planes;
  for (const nhdyn::symbolic::VisualShape& shape : scene.shapes)
    if (shape.kind == VisualKind::plane) planes.push_back(shape.name);
  EXPECT_EQ(planes, (std::vector<std::string>{"ball1", "ball3"}));
  const std::vector<double> out = run_scene(scene, spec, 0.0, std::vector<double>(18, 0.0), std::vector<double>(18, 0.0));
  const double* level = out.data() + scene.shapes[static_cast<std::size_t>(find_shape(scene, VisualKind::plane, "ball3"))].offset;
  EXPECT_EQ(std::vector<double>(level, level + 12), (std::vector<double>{0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1}));

  for (const char* const level_only : {"rattleback.toml", "rolling_disk_hop_wheel.toml"}) {
    const nhdyn::symbolic::VisualScene flat = nhdyn::symbolic::compile_visual(nhdyn::load_model_file(example(level_only)));
    for (const nhdyn::symbolic::VisualShape& shape : flat.shapes) EXPECT_NE(shape.kind, VisualKind::plane) << level_only;
  }
}

// examples/ball_on_turntable.toml with `from` replaced by `to` (nothing replaced when empty), run
// for 1 s with --html from `dir`.
struct TurntableRun {
  nhdyn::test::CliOutcome run;
  std::string page;
  nhdyn::CsvTable table;
};
TurntableRun run_turntable(const fs::path& dir, const std::vector<std::pair<std::string, std::string>>& edits) {
  std::string text = nhdyn::test::read_text(example("ball_on_turntable.toml"));
  for (const auto& [from, to] : edits) {
    const std::size_t at = text.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    if (at != std::string::npos) text.replace(at, from.size(), to);
  }
  std::ofstream(dir / "table.toml") << text;
  TurntableRun out;
  out.run = nhdyn::test::run_nhdyn("simulate table.toml --t-end 1.2 -q -o table.csv --html table.html", dir);
  if (out.run.exit_code == 0) {
    out.page = nhdyn::test::read_text(dir / "table.html");
    out.table = nhdyn::load_csv(dir / "table.csv");
  }
  return out;
}

// The table's angle at two frames: theta = atan2 of its first axis (R's first column, its normal
// being z), against the integral of its rate from 0: Omega t for the example's constant rate,
// Omega sin t for the rate Omega cos t; the normal stays (0, 0, 1).
void check_table_angle(const TurntableRun& turntable, const std::function<double(double)>& angle) {
  ASSERT_EQ(turntable.run.exit_code, 0) << turntable.run.out;
  const std::string& page = turntable.page;
  const ReportShape plane = report_shape(page, "plane", "ball");
  ASSERT_GE(plane.offset, 0) << "no plane in the page";
  EXPECT_NE(page.find("\"turns\":true", page.find("{\"kind\":\"plane\"")), std::string::npos);
  const std::vector<double> values = report_scene_values(page);
  const std::size_t stride = static_cast<std::size_t>(report_scene_stride(page));
  ASSERT_EQ(values.size(), turntable.table.rows.size() * stride);
  for (const std::size_t f : {std::size_t{30}, std::size_t{110}}) {
    const double t = turntable.table.rows.at(f)[0];
    const double* R = values.data() + f * stride + plane.offset + 3;
    const double theta = std::atan2(R[3], R[0]);
    EXPECT_NEAR(std::remainder(theta - angle(t), 2 * M_PI), 0.0, 2e-5) << "t = " << t;
    EXPECT_NEAR(R[8], 1.0, 1e-12);
    EXPECT_NEAR(R[2], 0.0, 1e-12);
    EXPECT_NEAR(R[5], 0.0, 1e-12);
  }
}

TEST_F(Cli, TurntableTurnsThroughTheIntegralOfItsRate) {
  const double Omega = 3.0;
  check_table_angle(run_turntable(dir, {}), [&](double t) { return Omega * t; });
  // Omega cos t: the same at t = 0, where the initial velocities are written for Omega.
  check_table_angle(run_turntable(dir, {{"angular_velocity = \"Omega\"", "angular_velocity = \"Omega*cos(t)\""}}),
                    [&](double t) { return Omega * std::sin(t); });
}

// A rate that the run never evaluates undefined (before a start at t0 = 1), while the table's
// angle integrates it from 0: the report is refused naming the contact and the time, and not
// written.
TEST_F(Cli, TurntableRateUndefinedBeforeTheRunIsRefused) {
  const TurntableRun turntable = run_turntable(
      dir, {{"angular_velocity = \"Omega\"", "angular_velocity = \"Omega + 0.001*sqrt(t - 0.5)\""},
            {"[initial]\n", "[initial]\nt0 = 1\n"},
            {"a = \"(Omega*x0 - u0)/r\"", "a = \"((Omega + 0.001*sqrt(0.5))*x0 - u0)/r\""}});
  EXPECT_EQ(turntable.run.exit_code, 2) << turntable.run.out;
  EXPECT_TRUE(nhdyn::test::contains(turntable.run.out, "table.toml:")) << turntable.run.out;
  EXPECT_TRUE(nhdyn::test::contains(turntable.run.out, "contact 'ball' of 'ball-on-turntable': its ground's "
                                                       "angular_velocity is NaN at t = "))
      << turntable.run.out;
  EXPECT_TRUE(nhdyn::test::contains(turntable.run.out, "the integral of the rate from t = 0")) << turntable.run.out;
  EXPECT_FALSE(fs::exists(dir / "table.html"));
}

}  // namespace
