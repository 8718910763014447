// The gnuplot runner of the plots (plot.hpp, xy_plot.hpp): runs the external `gnuplot` program on a
// script, without a shell, and puts its picture in place only when it succeeded. Last step of a
// plot, after plot_csv.hpp has read the CSV and plot.cpp has written the script.
// Internal: used by io/plot.cpp, not part of the public API (nhdyn/nhdyn.hpp).
#pragma once

#include <filesystem>
#include <functional>
#include <string>

namespace nhdyn {

// Draws a picture into `png` with gnuplot: writes the script that `script(output)` returns (into a
// temporary file next to `png`; `output` is the temporary file the script must draw into), runs
// `gnuplot -d` on it (stdin and stdout on /dev/null, stderr captured), and, when gnuplot exited 0
// and wrote an image, writes that image through an AtomicFile onto `png` (io/atomic_file.hpp: a
// link is written through, a device or pipe written straight, an existing file keeps its mode, a
// protected input is never replaced). Nothing is left behind on failure. `absolute_png` is `png`
// made absolute; `csv` is named in the error messages. Throws FileError when `png` is a directory
// or an input of the run, gnuplot is missing or has no PNG terminal, the directory cannot be
// written, or gnuplot fails (the message quotes the tail of its stderr).
void render_with_gnuplot(const std::filesystem::path& png, const std::filesystem::path& absolute_png,
                         const std::filesystem::path& csv,
                         const std::function<std::string(const std::filesystem::path& output)>& script);

}  // namespace nhdyn
