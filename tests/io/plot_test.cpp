// write_plot against the real gnuplot (installed in CI): the picture is a PNG of the promised
// size, names that are not in the CSV header are refused by name, and a failed plot leaves
// neither a partial image nor a temporary file behind.
#include "nhdyn/io/plot.hpp"
#include "nhdyn/io/xy_plot.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <random>
#include <set>
#include <string>

#include "nhdyn/core/error.hpp"

namespace nhdyn {
namespace {

namespace fs = std::filesystem;

std::string read_bytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

std::set<std::string> entries(const fs::path& dir) {
  std::set<std::string> names;
  for (const auto& entry : fs::directory_iterator(dir)) names.insert(entry.path().filename());
  return names;
}

std::uint32_t big_endian_u32(const std::string& bytes, std::size_t at) {
  std::uint32_t value = 0;
  for (std::size_t i = 0; i < 4; ++i) {
    value = (value << 8) | static_cast<unsigned char>(bytes.at(at + i));
  }
  return value;
}

class PlotTest : public ::testing::Test {
 protected:
  void SetUp() override {
    // An apostrophe and a space in the directory name exercise the quoting of file names.
    std::random_device random;
    dir_ = fs::temp_directory_path() /
           fmt::format("nhdyn plot's test {}-{:08x}", ::getpid(), random());
    fs::create_directories(dir_);
    csv_ = dir_ / "sled.csv";
  }
  void TearDown() override {
    std::error_code ignored;
    fs::remove_all(dir_, ignored);
  }

  // A planar sled on the unit circle: x = cos t, y = sin t, phi = t over t in [0, 10].
  // Residuals are exactly zero in the first row (and every 7th row of the velocity residual),
  // as a run that starts on its constraints writes them.
  void write_sled_csv(int rows) const {
    std::ofstream out(csv_);
    out << "t,x,y,phi,x',R_x,residual_vel_blade,residual_pos,E\n";
    for (int i = 0; i < rows; ++i) {
      const double t = 10.0 * i / (rows - 1);
      const double residual_vel = (i == 0 || i == rows / 2) ? 0.0 : 1e-14 * (1.0 + t);
      out << fmt::format("{},{},{},{},{},{},{},{},{}\n", t, std::cos(t), std::sin(t), t,
                         -std::sin(t), std::sin(3.0 * t), residual_vel, 1e-12 * t, 1.0 + 1e-10 * t);
    }
  }

  PlotRequest sled_request() const {
    PlotRequest request;
    request.title = "sled — sanh, dopri5";
    request.csv = csv_;
    request.coordinates = {"x", "y", "phi", "x'"};
    request.reactions = {"R_x"};
    request.residuals = {"residual_vel_blade", "residual_pos"};
    request.path = std::pair<std::string, std::string>{"x", "y"};
    request.energy = "E";
    return request;
  }

  // A PNG signature, the promised size in its IHDR chunk, and more than a blank canvas.
  static void expect_png(const fs::path& png) {
    ASSERT_TRUE(fs::exists(png));
    const std::string bytes = read_bytes(png);
    ASSERT_GT(bytes.size(), 24u);
    EXPECT_EQ(bytes.substr(0, 8), std::string("\x89PNG\r\n\x1a\n"));
    EXPECT_EQ(bytes.substr(12, 4), "IHDR");
    // The canvas grows with the grid of panels: at least one panel of about 600 x 340 px.
    EXPECT_GE(big_endian_u32(bytes, 16), 600u);
    EXPECT_GE(big_endian_u32(bytes, 20), 400u);
    EXPECT_GT(bytes.size(), 8000u);
  }

  fs::path dir_;
  fs::path csv_;
};

TEST_F(PlotTest, GnuplotIsAvailable) { EXPECT_TRUE(gnuplot_available()); }

TEST_F(PlotTest, DrawsEveryPanelIntoAPng) {
  write_sled_csv(400);
  const fs::path png = dir_ / "sled.png";
  write_plot(sled_request(), png);
  expect_png(png);
  // Nothing but the CSV and the picture: the script and the temporary image are gone.
  EXPECT_EQ(entries(dir_), (std::set<std::string>{"sled.csv", "sled.png"}));
}

// Events on every time axis and on the path, named in the legend; a name with a quote and more
// events than get labels reach gnuplot as text.
TEST_F(PlotTest, DrawsTheEvents) {
  write_sled_csv(400);
  PlotRequest request = sled_request();
  for (int k = 0; k < 3; ++k) {
    const double t = 1.0 + 3.0 * k;
    request.events.push_back(PlotEvent{"phi's turn", t, {{"x", std::cos(t)}, {"y", std::sin(t)}}});
  }
  const fs::path png = dir_ / "events.png";
  write_plot(request, png);
  expect_png(png);
  for (int k = 0; k < 20; ++k) request.events.push_back(PlotEvent{"tick", 0.5 * k});
  write_plot(request, png);
  expect_png(png);
  EXPECT_EQ(entries(dir_), (std::set<std::string>{"sled.csv", "events.png"}));
}

// The compare command's figure: given panels, one log range for all.
TEST_F(PlotTest, DrawsGivenPanelsWithOneLogRange) {
  write_sled_csv(200);
  PanelPlotRequest request;
  request.title = "panels";
  request.csv = csv_;
  request.panels = {PlotPanel{"a", PanelKind::log_abs, {"residual_vel_blade", "residual_pos"}, {"vel", "pos"}},
                    PlotPanel{"b", PanelKind::log_abs, {"residual_pos"}}};
  request.same_log_range = true;
  request.layout_columns = 2;
  const fs::path png = dir_ / "panels.png";
  write_panel_plot(request, png);
  expect_png(png);
  request.panels[0].labels = {"only one"};
  EXPECT_THROW(write_panel_plot(request, png), InputError);
  request.panels = {PlotPanel{"path", PanelKind::path, {"x"}}};
  EXPECT_THROW(write_panel_plot(request, png), InputError);
}

TEST_F(PlotTest, ReplacesAnExistingPicture) {
  write_sled_csv(50);
  const fs::path png = dir_ / "sled.png";
  std::ofstream(png) << "old";
  write_plot(sled_request(), png);
  expect_png(png);
}

TEST_F(PlotTest, DrawsASinglePanel) {
  write_sled_csv(100);
  PlotRequest request;
  request.title = "only coordinates";
  request.csv = csv_;
  request.coordinates = {"phi"};
  const fs::path png = dir_ / "one.png";
  write_plot(request, png);
  expect_png(png);
}

TEST_F(PlotTest, ResidualsThatAreAllZeroStillPlot) {
  // log |r| is undefined everywhere; the panel falls back to a linear scale instead of failing.
  {
    std::ofstream out(csv_);
    out << "t,residual_a,residual_b\n";
    for (int i = 0; i < 100; ++i) out << fmt::format("{},0,0\n", 0.01 * i);
  }
  PlotRequest request;
  request.csv = csv_;
  request.residuals = {"residual_a", "residual_b"};
  const fs::path png = dir_ / "zero.png";
  write_plot(request, png);
  expect_png(png);
}

TEST_F(PlotTest, TitleReachesGnuplotAsPlainText) {
  // Backquotes would run a command inside a double-quoted gnuplot string, @ would expand a
  // macro; the title must be drawn as written, and nothing run.
  write_sled_csv(50);
  PlotRequest request = sled_request();
  const fs::path marker = dir_ / "marker";
  request.title = fmt::format("it's `touch '{}'` @title \"quoted\" \\ a\nb_c", marker.string());
  const fs::path png = dir_ / "title.png";
  write_plot(request, png);
  expect_png(png);
  EXPECT_FALSE(fs::exists(marker));
}

TEST_F(PlotTest, LargeCsvIsDrawnThinned) {
  // Twice the rows drawn per curve (50000), so that every 3rd row is drawn: enough to take the
  // thinning path; more rows only make gnuplot read longer.
  write_sled_csv(100001);
  const fs::path png = dir_ / "large.png";
  write_plot(sled_request(), png);
  expect_png(png);
}

TEST_F(PlotTest, UnknownColumnThrowsInputErrorNamingIt) {
  write_sled_csv(20);
  const fs::path png = dir_ / "sled.png";
  for (int role = 0; role < 5; ++role) {
    PlotRequest request = sled_request();
    switch (role) {
      case 0:
        request.coordinates.push_back("theta_missing");
        break;
      case 1:
        request.reactions = {"theta_missing"};
        break;
      case 2:
        request.residuals.push_back("theta_missing");
        break;
      case 3:
        request.path->second = "theta_missing";
        break;
      default:
        request.energy = "theta_missing";
        break;
    }
    try {
      write_plot(request, png);
      ADD_FAILURE() << "no InputError for an unknown column (role " << role << ")";
    } catch (const InputError& e) {
      const std::string message = e.what();
      EXPECT_NE(message.find("'theta_missing'"), std::string::npos) << message;
      EXPECT_NE(message.find("sled.csv"), std::string::npos) << message;
      EXPECT_NE(message.find("residual_vel_blade"), std::string::npos) << message;  // the known
    }
  }
  EXPECT_EQ(entries(dir_), (std::set<std::string>{"sled.csv"}));
}

TEST_F(PlotTest, MissingDirectoryThrowsFileErrorAndLeavesNothing) {
  write_sled_csv(20);
  const fs::path missing = dir_ / "no such dir";
  try {
    write_plot(sled_request(), missing / "sled.png");
    ADD_FAILURE() << "no FileError for a missing directory";
  } catch (const FileError& e) {
    EXPECT_NE(std::string(e.what()).find("no such dir"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(fs::exists(missing));
  EXPECT_EQ(entries(dir_), (std::set<std::string>{"sled.csv"}));
}

TEST_F(PlotTest, GnuplotFailureKeepsTheOldPictureAndLeavesNoTemporary) {
  // Rows that are not numbers: gnuplot finds no valid point and stops ("x range is invalid").
  {
    std::ofstream out(csv_);
    out << "t,x\n";
    for (int i = 0; i < 10; ++i) out << "not,numbers\n";
  }
  const fs::path png = dir_ / "plot.png";
  std::ofstream(png) << "old picture";
  PlotRequest request;
  request.csv = csv_;
  request.coordinates = {"x"};
  try {
    write_plot(request, png);
    ADD_FAILURE() << "no FileError when gnuplot fails";
  } catch (const FileError& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find("gnuplot failed"), std::string::npos) << message;
    EXPECT_NE(message.find("range is invalid"), std::string::npos) << message;  // its stderr
  }
  EXPECT_EQ(read_bytes(png), "old picture");
  EXPECT_EQ(entries(dir_), (std::set<std::string>{"sled.csv", "plot.png"}));
}

TEST_F(PlotTest, PngThatIsADirectoryThrowsFileError) {
  write_sled_csv(20);
  fs::create_directory(dir_ / "out.png");
  EXPECT_THROW(write_plot(sled_request(), dir_ / "out.png"), FileError);
  EXPECT_TRUE(fs::is_empty(dir_ / "out.png"));
}

TEST_F(PlotTest, MissingCsvThrowsFileError) {
  PlotRequest request = sled_request();
  request.csv = dir_ / "absent.csv";
  try {
    write_plot(request, dir_ / "p.png");
    ADD_FAILURE() << "no FileError for a missing CSV";
  } catch (const FileError& e) {
    EXPECT_NE(std::string(e.what()).find("absent.csv"), std::string::npos) << e.what();
  }
  EXPECT_TRUE(fs::is_empty(dir_));
}

TEST_F(PlotTest, BadRequestsThrowInputError) {
  // Header only: nothing to draw.
  std::ofstream(csv_) << "t,x,y,phi,x',R_x,residual_vel_blade,residual_pos,E\n";
  EXPECT_THROW(write_plot(sled_request(), dir_ / "p.png"), InputError);
  // No panel asked for.
  write_sled_csv(20);
  PlotRequest empty;
  empty.csv = csv_;
  EXPECT_THROW(write_plot(empty, dir_ / "p.png"), InputError);
  // An energy column whose first value is not a number has no drift.
  std::ofstream(csv_) << "t,E\n0,nan\n1,2\n";
  PlotRequest energy;
  energy.csv = csv_;
  energy.energy = "E";
  EXPECT_THROW(write_plot(energy, dir_ / "p.png"), InputError);
  EXPECT_EQ(entries(dir_), (std::set<std::string>{"sled.csv"}));
}

// ---- write_xy_plot (studies) ------------------------------------------------------------------

class XyPlotTest : public PlotTest {
 protected:
  // Errors and residuals of two runs against the tolerance, as `nhdyn study error-relation`
  // writes them; one residual is 0 (no logarithm) in the last row.
  void write_study_csv() const {
    std::ofstream out(csv_);
    out << "tolerance,error_a,residual_a,error_b,residual_b\n";
    for (int k = 3; k <= 12; ++k) {
      const double tol = std::pow(10.0, -k);
      out << fmt::format("{},{},{},{},{}\n", tol, 5 * tol, tol, 1e-13, k == 12 ? 0.0 : 2e-13);
    }
  }
  static void expect_xy_png(const fs::path& png) {
    ASSERT_TRUE(fs::exists(png));
    const std::string bytes = read_bytes(png);
    ASSERT_GT(bytes.size(), 24u);
    EXPECT_EQ(bytes.substr(0, 8), std::string("\x89PNG\r\n\x1a\n"));
    EXPECT_EQ(big_endian_u32(bytes, 16), 1000u);
    EXPECT_EQ(big_endian_u32(bytes, 20), 700u);
    EXPECT_GT(bytes.size(), 8000u);
  }
};

TEST_F(XyPlotTest, DrawsCurvesAgainstOneColumn) {
  write_study_csv();
  XyPlotRequest request;
  request.title = "q'' and R: it's a test";  // apostrophes reach gnuplot as text
  request.csv = csv_;
  request.x = "tolerance";
  request.y = {"error_a", "residual_a", "error_b", "residual_b"};
  request.x_label = "rtol";
  request.y_label = "|q'' - q''_ref|";
  const fs::path png = dir_ / "study.png";
  write_xy_plot(request, png);
  expect_xy_png(png);
  EXPECT_EQ(entries(dir_), (std::set<std::string>{"sled.csv", "study.png"}));
}

TEST_F(XyPlotTest, DrawsEachCurveAgainstItsOwnColumnWithADiagonal) {
  write_study_csv();
  XyPlotRequest request;
  request.csv = csv_;
  request.y = {"error_a", "error_b"};
  request.x_of_curve = {"residual_a", "residual_b"};
  request.titles = {"run a", "run b's"};
  request.diagonal = true;
  const fs::path png = dir_ / "relation.png";
  write_xy_plot(request, png);
  expect_xy_png(png);
}

TEST_F(XyPlotTest, AllValuesWithoutALogarithmFallBackToALinearAxis) {
  {
    std::ofstream out(csv_);
    out << "x,y\n1,0\n2,0\n3,-1\n";
  }
  XyPlotRequest request;
  request.csv = csv_;
  request.x = "x";
  request.y = {"y"};
  const fs::path png = dir_ / "zero.png";
  write_xy_plot(request, png);
  expect_xy_png(png);
}

TEST_F(XyPlotTest, BadRequestsThrowInputErrorAndLeaveNothing) {
  write_study_csv();
  const fs::path png = dir_ / "bad.png";
  XyPlotRequest request;
  request.csv = csv_;
  request.x = "tolerance";
  EXPECT_THROW(write_xy_plot(request, png), InputError);  // no curve
  request.y = {"error_c"};
  try {
    write_xy_plot(request, png);
    ADD_FAILURE() << "an unknown column was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("'error_c'"), std::string::npos) << e.what();
  }
  request.y = {"error_a", "error_b"};
  request.x_of_curve = {"residual_a"};
  EXPECT_THROW(write_xy_plot(request, png), InputError);
  request.x_of_curve.clear();
  request.titles = {"only one"};
  EXPECT_THROW(write_xy_plot(request, png), InputError);
  EXPECT_EQ(entries(dir_), (std::set<std::string>{"sled.csv"}));
}

}  // namespace
}  // namespace nhdyn
