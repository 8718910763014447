#include "outputs.hpp"

#include <system_error>

#include "nhdyn/core/error.hpp"
#include "nhdyn/io/plot.hpp"

namespace nhdyn::cli {

void make_parent_directory(const std::filesystem::path& file) {
  if (!file.has_parent_path()) return;
  std::error_code ignored;
  std::filesystem::create_directories(file.parent_path(), ignored);
}

void check_plot_possible(const std::string& plot) {
  if (!plot.empty() && !gnuplot_available())
    throw FileError("--plot needs gnuplot, which is not installed: install it (apt-get install gnuplot-nox) "
                    "or run without --plot");
}

}  // namespace nhdyn::cli
