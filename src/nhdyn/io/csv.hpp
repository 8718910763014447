// CSV output of a simulation: a header row naming every column, then one row of numbers per
// output time, written through an AtomicFile so that a failed run leaves no partial file.
// Numbers are printed in the shortest form that reads back to the same double.
//
// A long table is formatted on a thread of its own: once the rows written pass 256 KB of text (and
// the machine has a second core, and the target is a regular file), write_row only copies the
// numbers into a block that the thread formats and writes while the run goes on. The bytes are the
// same; the shortest form of a double costs about 35 ns, a third of an output row's cost on a
// small model (docs/performance.md). The thread holds no stopping signal (core/detail/signals.hpp);
// where no thread can be started, the caller's thread formats every row as before.
#pragma once

#include <filesystem>
#include <istream>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "nhdyn/io/atomic_file.hpp"

namespace nhdyn {

class CsvWriter {
 public:
  // Opens the temporary file at once (FileError if the target cannot be written) and writes the
  // header, after `preamble` (comment lines, each starting with '#' and ending in '\n': the
  // provenance header of io/provenance.hpp). Names containing a comma or a quote are quoted.
  // `beside` false: every row formatted on the caller's thread (a writer among many busy threads,
  // such as a batch's, gains nothing from one more).
  CsvWriter(const std::filesystem::path& target, const std::vector<std::string>& columns,
            const std::string& preamble = {}, bool beside = true);
  ~CsvWriter();  // uncommitted: the formatting thread stopped, the temporary removed
  CsvWriter(const CsvWriter&) = delete;
  CsvWriter& operator=(const CsvWriter&) = delete;

  void write_row(std::span<const double> values);  // values.size() must equal the column count
  void commit();                                  // the file appears whole, or FileError
  // The preamble, header and rows written so far, as the file holds them (AtomicFile::written).
  std::string written();
  // commit() in its two steps (AtomicFile::finish, publish), for a group of files that appear
  // together: the rows written and the temporary closed (FileError if any of it failed), then the
  // rename.
  void finish();
  void publish() { file_.publish(); }
  std::size_t columns() const { return columns_; }

 private:
  struct Formatter;  // the formatting thread and the block it is given (csv.cpp)
  void start_formatter();
  void hand_over();  // block_ to the formatter, once it is done with the one before
  void drain();      // every row written is in the file (the formatter idle, buffer_ empty)

  AtomicFile file_;
  std::size_t columns_;
  std::string buffer_;          // formatted rows not yet written to file_ (no formatter)
  std::vector<double> block_;   // rows not yet formatted (with a formatter)
  std::size_t text_written_ = 0;  // bytes of rows written by the caller's thread
  bool beside_;                 // a formatting thread may still be started
  std::unique_ptr<Formatter> formatter_;
};

// Reads a CSV written by CsvWriter (header and numeric rows); for tests and comparisons.
struct CsvTable {
  std::vector<std::string> header;
  std::vector<std::vector<double>> rows;
  // The comment lines before the header, without their '#' (the provenance of io/provenance.hpp,
  // the reason line of a FILE.partial.csv).
  std::vector<std::string> comments;
  int column(const std::string& name) const;  // index, or -1
};
CsvTable load_csv(const std::filesystem::path& path);  // throws FileError naming file and line

// Splits a CSV record on commas, as CsvWriter quotes it: a field in double quotes may hold
// commas, newlines and doubled quotes ("" -> "). Carriage returns outside quotes are dropped.
std::vector<std::string> split_csv_record(std::string_view record);
// Reads one CSV record into `record`: a line, continued over newlines that sit inside double
// quotes (a quoted column name may hold one). False at the end of the input.
bool read_csv_record(std::istream& in, std::string& record);

}  // namespace nhdyn
