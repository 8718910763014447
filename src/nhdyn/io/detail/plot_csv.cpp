// Reading a plot's CSV (plot_csv.hpp): the header and first row through csv.hpp's record reader,
// the row count from newlines (counted or sampled), the ranges by one streaming pass.
#include "nhdyn/io/detail/plot_csv.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <fstream>
#include <system_error>

#include "nhdyn/core/error.hpp"
#include "nhdyn/io/csv.hpp"

namespace nhdyn {
namespace {
namespace fs = std::filesystem;
}  // namespace

namespace plot_csv {  // named: the io sources are one unity build

std::string errno_text(int err) { return std::error_code(err, std::generic_category()).message(); }

std::string trim(std::string_view s) {
  const auto blank = [](char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\n'; };
  while (!s.empty() && blank(s.front())) s.remove_prefix(1);
  while (!s.empty() && blank(s.back())) s.remove_suffix(1);
  return std::string(s);
}

// Number of data rows after byte `data_start` of a file of `size` bytes: counted in a small
// file, estimated in a large one from the mean length of the rows in three 64 KiB windows (at
// 1/4, 1/2 and 3/4 of the rows), as reading a million rows only to count them would cost
// more than the thinning saves. Not from the first rows alone: they are short ("0,1,0,...")
// and would overestimate the count tenfold.
std::uintmax_t count_rows(std::istream& in, std::uintmax_t data_start, std::uintmax_t size) {
  constexpr std::uintmax_t window = 1 << 16;
  std::vector<char> buffer(window);
  const auto newlines_in = [&](std::uintmax_t from, std::uintmax_t length) {
    in.clear();
    in.seekg(static_cast<std::streamoff>(from));
    std::uintmax_t newlines = 0;
    while (length > 0 && in) {
      in.read(buffer.data(), static_cast<std::streamsize>(std::min(length, window)));
      const auto got = static_cast<std::uintmax_t>(in.gcount());
      if (got == 0) break;
      newlines += static_cast<std::uintmax_t>(
          std::count(buffer.begin(), buffer.begin() + static_cast<std::ptrdiff_t>(got), '\n'));
      length -= got;
    }
    return newlines;
  };
  if (size <= data_start) return 1;
  const std::uintmax_t body = size - data_start;
  if (body <= 4 * window) return std::max<std::uintmax_t>(1, newlines_in(data_start, body));
  std::uintmax_t sampled = 0;
  for (std::uintmax_t quarter = 1; quarter <= 3; ++quarter) {
    sampled += newlines_in(data_start + body / 4 * quarter, window);
  }
  return std::max<std::uintmax_t>(1, body / (3 * window) * sampled);
}

}  // namespace plot_csv

CsvHead read_csv_head(const fs::path& csv) {
  errno = 0;
  std::ifstream in(csv, std::ios::binary);
  if (!in) {
    const int err = errno;
    throw FileError(fmt::format("cannot read the CSV file '{}' to plot ({}); check the path",
                                csv.string(), err != 0 ? plot_csv::errno_text(err) : "open failed"));
  }
  std::string header;
  std::string row;
  // Comment lines before the header (the provenance of io/provenance.hpp) are skipped here and,
  // counted in header_lines, by gnuplot's `skip`.
  int comment_lines = 0;
  while (read_csv_record(in, header) && header.starts_with('#')) ++comment_lines;
  if (!in || plot_csv::trim(header).empty() || header.starts_with('#')) {
    throw InputError(fmt::format(
        "the CSV file '{}' has no header row; expected column names on its first line, as "
        "nhdyn writes them",
        csv.string()));
  }
  const std::streamoff data_start = in.tellg();
  if (!read_csv_record(in, row) || plot_csv::trim(row).empty()) {
    throw InputError(fmt::format(
        "the CSV file '{}' has a header but no data rows; there is nothing to plot (did the "
        "run stop before its first output?)",
        csv.string()));
  }
  if (header.starts_with("\xEF\xBB\xBF")) header.erase(0, 3);  // UTF-8 byte order mark

  CsvHead head;
  head.header_lines = comment_lines + 1 + static_cast<int>(std::count(header.begin(), header.end(), '\n'));
  head.names = split_csv_record(header);
  head.first_row = split_csv_record(row);
  for (std::string& field : head.first_row) field = plot_csv::trim(field);
  std::error_code ec;
  const std::uintmax_t size = fs::file_size(csv, ec);
  head.rows =
      ec || data_start < 0 ? 1 : plot_csv::count_rows(in, static_cast<std::uintmax_t>(data_start), size);
  return head;
}

// 1-based gnuplot column index of `name`; `role` says which list of the request named it.
int column_of(const CsvHead& head, const fs::path& csv, const std::string& name,
              std::string_view role) {
  for (std::size_t i = 0; i < head.names.size(); ++i) {
    if (head.names[i] == name) return static_cast<int>(i) + 1;
  }
  constexpr std::size_t shown = 40;
  std::string known;
  for (std::size_t i = 0; i < head.names.size() && i < shown; ++i) {
    known += (i == 0 ? "" : ", ") + head.names[i];
  }
  if (head.names.size() > shown) known += fmt::format(", ... ({} in all)", head.names.size());
  throw InputError(fmt::format(
      "cannot plot {} column '{}': the CSV file '{}' has no column of that name; its columns "
      "are {}; use one of these names",
      role, name, csv.string(), known));
}

// Reads every `stride`-th data row (as gnuplot's `every` does) and returns the range of each
// 1-based column in `indices`. Fields that are not numbers are skipped (gnuplot skips them too).
std::vector<ColumnRange> read_column_ranges(const fs::path& csv, int header_lines, const std::vector<int>& indices,
                                            std::uintmax_t stride) {
  std::vector<ColumnRange> out(indices.size());
  std::ifstream in(csv, std::ios::binary);
  if (!in) {
    throw FileError(fmt::format("cannot read the CSV file '{}' to plot ({}); check the path", csv.string(),
                                plot_csv::errno_text(errno)));
  }
  std::string line;
  for (int i = 0; i < header_lines && std::getline(in, line); ++i) {
  }
  int widest = 0;
  for (int index : indices) widest = std::max(widest, index);
  std::vector<std::string_view> fields;
  std::uintmax_t row = 0;
  while (std::getline(in, line)) {
    if (row++ % stride != 0) continue;
    fields.clear();
    std::string_view rest(line);
    while (static_cast<int>(fields.size()) < widest) {
      const std::size_t comma = rest.find(',');
      fields.push_back(rest.substr(0, comma));
      if (comma == std::string_view::npos) break;
      rest.remove_prefix(comma + 1);
    }
    for (std::size_t k = 0; k < indices.size(); ++k) {
      const auto i = static_cast<std::size_t>(indices[k] - 1);
      if (i >= fields.size()) continue;
      std::string_view field = fields[i];
      while (!field.empty() && (field.front() == ' ' || field.front() == '+')) field.remove_prefix(1);
      while (!field.empty() && (field.back() == ' ' || field.back() == '\r')) field.remove_suffix(1);
      double value = 0.0;
      const auto [end, err] = std::from_chars(field.data(), field.data() + field.size(), value);
      if (err != std::errc{} || end != field.data() + field.size() || !std::isfinite(value)) continue;
      ColumnRange& r = out[k];
      r.min = std::isnan(r.min) ? value : std::min(r.min, value);
      r.max = std::isnan(r.max) ? value : std::max(r.max, value);
      const double a = std::abs(value);
      r.max_abs = std::isnan(r.max_abs) ? a : std::max(r.max_abs, a);
      if (a > 0.0) r.min_abs_positive = std::isnan(r.min_abs_positive) ? a : std::min(r.min_abs_positive, a);
    }
  }
  return out;
}

}  // namespace nhdyn
