// Every gallery example, and the models built from bodies, also run from the command line as
// their pages say:
// `nhdyn simulate examples/<name>.toml -o FILE.csv` exits 0 and writes the CSV with the model's
// coordinates in its header and one row per output time.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <utility>

namespace {

namespace fs = std::filesystem;

TEST(GalleryCli, EveryExampleRunsFromTheCommandLine) {
  const fs::path dir = fs::temp_directory_path() / ("nhdyn-gallery-" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const std::pair<std::string, std::string> examples[] = {{"chaplygin_sleigh", "t,x,y,phi,"},
                                                          {"knife_edge", "t,x,y,phi,"},
                                                          {"pendulum_cartesian", "t,x,y,"},
                                                          {"hoop_bead", "t,x,y,z,"},
                                                          {"double_pendulum", "t,x1,y1,x2,y2,"},
                                                          {"rolling_disk", "t,x,y,psi,theta,phi,"},
                                                          {"slider_crank", "t,alpha,beta,x,"},
                                                          {"diff_drive", "t,x,y,theta,phi_r,phi_l,"},
                                                          // built from bodies (docs/multibody.md)
                                                          {"rolling_disk_bodies", "t,x,y,psi,theta,phi,"},
                                                          {"whipple_bicycle", "t,x,y,psi,phi,theta,delta,thetaR,thetaF,"}};
  for (const auto& [name, header] : examples) {
    const fs::path csv = dir / (name + ".csv");
    const std::string command = std::string("'") + NHDYN_CLI_PATH + "' simulate '" + NHDYN_SOURCE_DIR +
                                "/examples/" + name + ".toml' --t-end 1 --output-step 0.1 -q -o '" +
                                csv.string() + "'";
    EXPECT_EQ(std::system(command.c_str()), 0) << command;
    std::ifstream in(csv);
    std::string line;
    while (std::getline(in, line) && line.starts_with('#')) {
    }  // the provenance header (io/provenance.hpp)
    EXPECT_EQ(line.rfind(header, 0), 0u) << line;
    int rows = 0;
    while (std::getline(in, line)) ++rows;
    EXPECT_EQ(rows, 11) << name;  // t = 0, 0.1, ..., 1
  }
  fs::remove_all(dir);
}

}  // namespace
