// What a plot reads of its CSV (plot.hpp, xy_plot.hpp): the header names, the first data row, an
// estimate of the number of rows (for thinning), and the range of chosen columns over the drawn
// rows — each in one pass that stops early, never the whole table in memory (a run may write a
// million rows). Records are split as csv.hpp writes them (split_csv_record). Between the run's
// CSV and the script that plot.cpp writes for gnuplot.
// Internal: used by io/plot.cpp, not part of the public API (nhdyn/nhdyn.hpp).
#pragma once

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

namespace nhdyn {

struct CsvHead {
  std::vector<std::string> names;      // header row, in column order (column 1 = time)
  std::vector<std::string> first_row;  // fields of the first data row
  std::uintmax_t rows = 0;             // estimated number of data rows
  int header_lines = 1;                // lines taken by the header (a quoted name may hold \n)
};

// Reads the header and the first data row, and estimates the rows: counted in a small file,
// estimated in a large one from three 64 KiB windows. Throws FileError when `csv` cannot be read,
// InputError when it has no header or no data row.
CsvHead read_csv_head(const std::filesystem::path& csv);

// 1-based gnuplot column index of `name`; `role` says which list of the request named it. Throws
// InputError naming the column, the file and (up to 40 of) its columns.
int column_of(const CsvHead& head, const std::filesystem::path& csv, const std::string& name, std::string_view role);

// The range of a column over the drawn rows, for the panel rule and the shared log range.
struct ColumnRange {
  double min = NAN, max = NAN;    // finite values only
  double min_abs_positive = NAN;  // smallest nonzero |value|
  double max_abs = NAN;
};

// Reads every `stride`-th data row (as gnuplot's `every` does) and returns the range of each
// 1-based column in `indices`. Fields that are not numbers are skipped (gnuplot skips them too).
std::vector<ColumnRange> read_column_ranges(const std::filesystem::path& csv, int header_lines,
                                            const std::vector<int>& indices, std::uintmax_t stride);

}  // namespace nhdyn
