#include "nhdyn/io/csv.hpp"

#include <fmt/compile.h>
#include <fmt/format.h>

#include <algorithm>
#include <condition_variable>
#include <cstdlib>
#include <exception>
#include <fstream>
#include <mutex>
#include <sstream>
#include <system_error>
#include <thread>

#include "nhdyn/core/detail/characters.hpp"
#include "nhdyn/core/detail/signals.hpp"
#include "nhdyn/core/error.hpp"

namespace nhdyn {
namespace {

std::string quote_if_needed(const std::string& name) {
  if (name.find_first_of(",\"\n") == std::string::npos) return name;
  std::string out = "\"";
  for (char c : name) {
    if (c == '"') out += '"';
    out += c;
  }
  return out + "\"";
}

// Formatted text is written to the file in pieces of about this size.
constexpr std::size_t kFlushBytes = std::size_t{1} << 15;
// A table that has passed this much text starts its formatting thread (CsvWriter::Formatter): by
// then the thread's start and end (about 0.1 ms) cost a fifth of the formatting so far at most, and
// a short table never pays them.
constexpr std::size_t kBesideBytes = std::size_t{1} << 18;
// Numbers per block handed to the formatting thread (at least one row).
constexpr std::size_t kBlockValues = std::size_t{1} << 13;

// Appends `rows` rows of `columns` values to `text`, each value in its shortest round-trip form.
void format_rows(const double* values, std::size_t rows, std::size_t columns, std::string& text) {
  // Each value into a stack buffer first: appending through a back_inserter costs a capacity check
  // per character, twice the formatting itself on an 89-column row.
  char cell[40];  // the shortest round-trip form of a double takes at most 24 characters
  for (std::size_t r = 0; r < rows; ++r) {
    for (std::size_t i = 0; i < columns; ++i) {
      if (i) text += ',';
      char* end = fmt::format_to(cell, FMT_COMPILE("{}"), *values++);
      text.append(cell, end);
    }
    text += '\n';
  }
}

}  // namespace

// The thread that formats and writes the blocks of rows write_row collects. One block is with it
// at a time (`full`); the writer fills the next meanwhile and waits only when it has filled that
// too: the memory stays two blocks, and the file gets the rows in their order.
struct CsvWriter::Formatter {
  std::mutex mutex;
  std::condition_variable wake;  // the thread waits for a block or the stop
  std::condition_variable idle;  // the writer waits for the thread to be done with its block
  std::vector<double> block;     // the thread's, while `full`
  bool full = false;
  bool stop = false;
  std::exception_ptr error;      // what formatting or writing threw, for the writer to rethrow
  std::thread thread;

  void run(AtomicFile& file, std::size_t columns) {
    std::string text;
    std::unique_lock lock(mutex);
    for (;;) {
      wake.wait(lock, [this] { return full || stop; });
      if (!full) return;
      lock.unlock();
      try {
        text.clear();
        format_rows(block.data(), block.size() / columns, columns, text);
        file.write(text);  // a failed write is kept by the file and reported by finish()
      } catch (...) {
        error = std::current_exception();
      }
      lock.lock();
      full = false;
      idle.notify_one();
    }
  }
};

CsvWriter::CsvWriter(const std::filesystem::path& target, const std::vector<std::string>& columns,
                     const std::string& preamble, bool beside)
    : file_(target), columns_(columns.size()), beside_(beside) {
  std::string header = preamble;
  for (std::size_t i = 0; i < columns.size(); ++i) {
    if (i) header += ',';
    header += quote_if_needed(columns[i]);
  }
  header += '\n';
  file_.write(header);
  buffer_.reserve(2 * kFlushBytes);
}

CsvWriter::~CsvWriter() {
  if (!formatter_) return;
  {
    const std::lock_guard lock(formatter_->mutex);
    formatter_->stop = true;
  }
  formatter_->wake.notify_one();
  formatter_->thread.join();
}

void CsvWriter::write_row(std::span<const double> values) {
  if (values.size() != columns_)
    throw std::logic_error(fmt::format("CsvWriter: a row of {} values for {} columns", values.size(), columns_));
  if (formatter_) {
    block_.insert(block_.end(), values.begin(), values.end());
    if (block_.size() >= kBlockValues) hand_over();
    return;
  }
  format_rows(values.data(), 1, columns_, buffer_);
  if (buffer_.size() > kFlushBytes) {
    text_written_ += buffer_.size();
    file_.write(buffer_);
    buffer_.clear();
    // A long table goes on being formatted beside the run, where there is a core for it. A device
    // or pipe is written by the caller's thread alone, as the caller's other output is.
    if (beside_ && text_written_ >= kBesideBytes && !file_.straight() && columns_ > 0 &&
        std::thread::hardware_concurrency() > 1)
      start_formatter();
  }
}

void CsvWriter::start_formatter() {
  beside_ = false;  // one attempt: a thread refused (a limit on threads or memory) is not asked for again
  auto formatter = std::make_unique<Formatter>();
  block_.reserve(kBlockValues + columns_);
  formatter->block.reserve(kBlockValues + columns_);
  Formatter* f = formatter.get();
  try {
    formatter->thread = thread_without_stopping_signals([this, f] { f->run(file_, columns_); });
  } catch (const std::system_error&) {
    return;  // the rows go on being formatted on the caller's thread
  }
  formatter_ = std::move(formatter);
  buffer_.shrink_to_fit();  // no longer used
}

void CsvWriter::hand_over() {
  Formatter& f = *formatter_;
  std::unique_lock lock(f.mutex);
  f.idle.wait(lock, [&f] { return !f.full; });
  if (f.error) std::rethrow_exception(f.error);
  std::swap(f.block, block_);
  block_.clear();
  f.full = true;
  lock.unlock();
  f.wake.notify_one();
}

void CsvWriter::drain() {
  if (formatter_) {
    if (!block_.empty()) hand_over();
    Formatter& f = *formatter_;
    std::unique_lock lock(f.mutex);
    f.idle.wait(lock, [&f] { return !f.full; });
    if (f.error) std::rethrow_exception(f.error);
  }
  file_.write(buffer_);
  buffer_.clear();
}

std::string CsvWriter::written() {
  drain();
  return file_.written();
}

void CsvWriter::finish() {
  drain();
  file_.finish();
}

void CsvWriter::commit() {
  finish();
  publish();
}

int CsvTable::column(const std::string& name) const {
  for (std::size_t i = 0; i < header.size(); ++i)
    if (header[i] == name) return static_cast<int>(i);
  return -1;
}

namespace {

// A line of a CSV longer than this is refused: a row of 10 000 bodies' states is a few MB, and
// a file without line ends (a device such as /dev/zero) would otherwise be read into memory to
// its end, which never comes.
constexpr std::size_t kMaxCsvLine = std::size_t{64} << 20;

// std::getline with that bound: the next line without its '\n', false at the end of the input.
bool read_bounded_line(std::istream& in, std::string& line, const std::filesystem::path& path, long line_number) {
  line.clear();
  std::streambuf* buffer = in.rdbuf();
  bool any = false;
  for (int c = buffer->sbumpc(); c != std::char_traits<char>::eof(); c = buffer->sbumpc()) {
    any = true;
    if (c == '\n') return true;
    line.push_back(static_cast<char>(c));
    if (line.size() > kMaxCsvLine)
      throw FileError(fmt::format("{}:{}: a line longer than {} MB; is '{}' a CSV file?", path.string(), line_number,
                                  kMaxCsvLine >> 20, path.string()));
  }
  return any;
}

}  // namespace

CsvTable load_csv(const std::filesystem::path& path) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec))
    throw FileError(fmt::format("'{}' is a directory; expected a CSV file", path.string()));
  std::ifstream in(path);
  if (!in) throw FileError(fmt::format("cannot read '{}'", path.string()));
  CsvTable table;
  std::string line;
  long line_number = 0;
  // Comment lines before the header (the reason line of nhdyn's own FILE.partial.csv) are skipped,
  // and a UTF-8 byte-order mark (spreadsheet exports) is not part of the first name.
  bool header = false;
  while (read_bounded_line(in, line, path, line_number + 1)) {
    ++line_number;
    if (line_number == 1 && line.rfind("\xEF\xBB\xBF", 0) == 0) line.erase(0, 3);
    if (!line.empty() && line[0] == '#') {
      table.comments.push_back(line.substr(1));
      continue;
    }
    header = true;
    break;
  }
  if (!header) throw FileError(fmt::format("'{}' is empty; expected a header row", path.string()));
  table.header = split_csv_record(line);
  while (read_bounded_line(in, line, path, line_number + 1)) {
    ++line_number;
    if (line.empty()) continue;
    std::vector<double> row;
    row.reserve(table.header.size());
    const char* p = line.c_str();
    while (*p) {
      char* end = nullptr;
      const double value = std::strtod(p, &end);
      if (end == p)
        throw FileError(fmt::format("{}:{}: not a number at column {}", path.string(), line_number, row.size() + 1));
      // strtod reads hexadecimal too (0x10 as 16); a table of nhdyn's, or a user's, is decimal.
      if (std::find_if(p, static_cast<const char*>(end), [](char c) { return c == 'x' || c == 'X'; }) != end)
        throw FileError(fmt::format("{}:{}: '{}' at column {} is not a decimal number", path.string(), line_number,
                                    std::string(p, static_cast<const char*>(end)), row.size() + 1));
      row.push_back(value);
      p = end;
      if (*p == ',') ++p;
      else if (*p == '\r') ++p;
      else if (*p) {
        // Named as the expression readers name it: its code point, what it is, what to write.
        throw FileError(fmt::format("{}:{}: unexpected character {}", path.string(), line_number,
                                    describe_character(line, static_cast<std::size_t>(p - line.c_str()))));
      }
    }
    if (row.size() != table.header.size())
      throw FileError(fmt::format("{}:{}: {} values for {} columns", path.string(), line_number, row.size(),
                                  table.header.size()));
    table.rows.push_back(std::move(row));
  }
  return table;
}

std::vector<std::string> split_csv_record(std::string_view record) {
  std::vector<std::string> fields;
  std::string field;
  bool quoted = false;
  for (std::size_t i = 0; i < record.size(); ++i) {
    const char c = record[i];
    if (quoted) {
      if (c == '"' && i + 1 < record.size() && record[i + 1] == '"') {
        field += record[++i];
      } else if (c == '"') {
        quoted = false;
      } else {
        field += c;
      }
    } else if (c == '"') {
      quoted = true;
    } else if (c == ',') {
      fields.push_back(std::move(field));
      field.clear();
    } else if (c != '\r') {
      field += c;
    }
  }
  fields.push_back(std::move(field));
  return fields;
}

// Reads one CSV record: a line, continued over newlines that sit inside double quotes.
bool read_csv_record(std::istream& in, std::string& record) {
  if (!std::getline(in, record)) return false;
  std::string more;
  while (std::count(record.begin(), record.end(), '"') % 2 == 1 && std::getline(in, more)) {
    record += '\n';
    record += more;
  }
  return true;
}

}  // namespace nhdyn
