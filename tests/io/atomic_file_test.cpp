// AtomicFile's two steps (io/atomic_file.hpp): finish() does all that can fail for want of space,
// publish() only the rename, so that a writer of several files finishes them all before any
// appears. The failure is a real one: the file-size limit of the process (RLIMIT_FSIZE, with
// SIGXFSZ ignored) makes the kernel refuse the bytes past it with EFBIG, as a full disk refuses
// them with ENOSPC, at the flush of the last buffered bytes.
#include <gtest/gtest.h>
#include <pthread.h>
#include <signal.h>
#include <sys/resource.h>
#include <unistd.h>

#include "support/address_sanitizer.hpp"

#include <fmt/format.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "nhdyn/core/error.hpp"
#include "nhdyn/io/atomic_file.hpp"
#include "nhdyn/io/csv.hpp"

namespace {

namespace fs = std::filesystem;

// A fresh directory per test, removed after it.
class AtomicFileSteps : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::path(::testing::TempDir()) /
           ("nhdyn_atomic_" + std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  // The names in the directory, temporaries included.
  std::vector<std::string> entries() const {
    std::vector<std::string> names;
    for (const auto& e : fs::directory_iterator(dir_)) names.push_back(e.path().filename().string());
    return names;
  }
  static std::string read(const fs::path& path) {
    std::ifstream in(path, std::ios::binary);
    std::ostringstream out;
    out << in.rdbuf();
    return out.str();
  }

  fs::path dir_;
};

// While it lives, the process may write files of at most `bytes` bytes; writes past it fail with
// EFBIG instead of raising SIGXFSZ.
class FileSizeLimit {
 public:
  explicit FileSizeLimit(rlim_t bytes) {
    ::getrlimit(RLIMIT_FSIZE, &saved_);
    old_handler_ = ::signal(SIGXFSZ, SIG_IGN);
    rlimit limit = saved_;
    limit.rlim_cur = bytes;
    ok_ = ::setrlimit(RLIMIT_FSIZE, &limit) == 0;
  }
  ~FileSizeLimit() {
    ::setrlimit(RLIMIT_FSIZE, &saved_);
    ::signal(SIGXFSZ, old_handler_);
  }
  FileSizeLimit(const FileSizeLimit&) = delete;
  FileSizeLimit& operator=(const FileSizeLimit&) = delete;
  bool ok() const { return ok_; }

 private:
  rlimit saved_{};
  void (*old_handler_)(int) = SIG_DFL;
  bool ok_ = false;
};

TEST_F(AtomicFileSteps, FinishLeavesTheTargetAloneAndPublishRenames) {
  const fs::path target = dir_ / "a.txt";
  std::ofstream(target) << "old\n";
  nhdyn::AtomicFile file(target);
  file.write("new\n");
  file.finish();
  EXPECT_EQ(read(target), "old\n");  // finished, not yet in place
  EXPECT_EQ(entries().size(), 2U);   // the target and the closed temporary
  file.publish();
  EXPECT_EQ(read(target), "new\n");
  EXPECT_EQ(entries(), std::vector<std::string>{"a.txt"});
  EXPECT_THROW(file.publish(), std::logic_error);
}

// What a failed run leaves in FILE.partial.csv: the table's bytes so far, read back from its
// temporary (the rows still in the writer's buffer included), while the target keeps its content.
TEST_F(AtomicFileSteps, TheBytesWrittenSoFarAreReadBackFromTheTemporary) {
  const fs::path target = dir_ / "t.csv";
  std::ofstream(target) << "old\n";
  nhdyn::CsvWriter table(target, {"t", "x"}, "# made by a test\n");
  const std::vector<double> row = {0.5, -1e-300};
  table.write_row(row);
  EXPECT_EQ(table.written(), "# made by a test\nt,x\n0.5,-1e-300\n");
  for (int i = 0; i < 3000; ++i) table.write_row(row);  // past the writer's 32 KiB buffer
  const std::string text = table.written();
  EXPECT_EQ(text.size(), 21U + 3001U * 12U);  // the preamble and header, 3001 rows
  EXPECT_EQ(text.substr(text.size() - 24), "0.5,-1e-300\n0.5,-1e-300\n");
  EXPECT_EQ(read(target), "old\n");
  table.finish();
  table.publish();
  EXPECT_EQ(read(target), text);
  nhdyn::AtomicFile finished(dir_ / "u.txt");
  finished.write("x");
  finished.finish();
  EXPECT_EQ(finished.written(), "");
}

// Rows of `columns` numbers of every kind: long fractions, integers, negative zero, the extremes,
// subnormals, infinities and NaN, so that each row's text has its own length.
std::vector<std::vector<double>> varied_rows(int rows, int columns) {
  std::mt19937_64 random(7);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  const double special[] = {0.0, -0.0, 1.0, -70.0, 1e-300, 4.9e-324, std::numeric_limits<double>::max(),
                            std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity(),
                            std::numeric_limits<double>::quiet_NaN(), 1e16, 1e-5, 0.0001, 123456789012345678.0};
  std::vector<std::vector<double>> out(static_cast<std::size_t>(rows));
  for (int r = 0; r < rows; ++r)
    for (int c = 0; c < columns; ++c) {
      const auto k = static_cast<std::size_t>(random() % 20);
      out[static_cast<std::size_t>(r)].push_back(k < std::size(special) ? special[k]
                                                                         : uniform(random) * std::pow(10.0, r % 40 - 20));
    }
  return out;
}

// The text of `rows` as a CSV under the header "a,b,...", each number as fmt prints it.
std::string expected_text(const std::vector<std::vector<double>>& rows, const std::string& header) {
  std::string text = header;
  for (const std::vector<double>& row : rows) {
    for (std::size_t i = 0; i < row.size(); ++i) text += (i ? "," : "") + fmt::format("{}", row[i]);
    text += "\n";
  }
  return text;
}

TEST_F(AtomicFileSteps, ALongTableFormattedBesideTheRunHasTheBytesOfEachRowInOrder) {
  // 12000 rows of 7 and 40 of 3000 columns (each past the first 256 KiB, where the formatting
  // thread takes over, with blocks of many rows and of a few), with the bytes read back in the
  // middle of the run, the thread at work, as a failed run reads them.
  for (const int columns : {7, 3000}) {
    const int rows = columns == 7 ? 12000 : 40;
    const fs::path target = dir_ / "long.csv";
    std::vector<std::string> names;
    std::string header;
    for (int c = 0; c < columns; ++c) {
      names.push_back("c" + std::to_string(c));
      header += (c ? "," : "") + names.back();
    }
    header += "\n";
    const std::vector<std::vector<double>> table = varied_rows(rows, columns);
    nhdyn::CsvWriter writer(target, names, "# preamble\n");
    const std::vector<std::vector<double>> first(table.begin(), table.begin() + rows / 2);
    for (const std::vector<double>& row : first) writer.write_row(row);
    EXPECT_EQ(writer.written(), "# preamble\n" + expected_text(first, header)) << columns << " columns";
    for (int r = rows / 2; r < rows; ++r) writer.write_row(table[static_cast<std::size_t>(r)]);
    writer.commit();
    const std::string text = read(target);
    EXPECT_EQ(text, "# preamble\n" + expected_text(table, header)) << columns << " columns";
    // And every finite number reads back to the same double.
    const nhdyn::CsvTable back = nhdyn::load_csv(target);
    ASSERT_EQ(back.rows.size(), table.size());
    for (std::size_t r = 0; r < table.size(); ++r)
      for (std::size_t c = 0; c < table[r].size(); ++c) {
        if (!std::isfinite(table[r][c])) continue;
        ASSERT_EQ(back.rows[r][c], table[r][c]) << "row " << r << " column " << c;
      }
  }
}

TEST_F(AtomicFileSteps, ALongTableNotCommittedLeavesNothingWhileItsRowsAreBeingFormatted) {
  const fs::path target = dir_ / "long.csv";
  std::ofstream(target) << "old\n";
  {
    nhdyn::CsvWriter writer(target, {"a", "b", "c"});
    for (const std::vector<double>& row : varied_rows(20000, 3)) writer.write_row(row);
  }  // destroyed without commit, blocks perhaps still with the formatting thread
  EXPECT_EQ(entries(), std::vector<std::string>{"long.csv"});
  EXPECT_EQ(read(target), "old\n");
}

TEST_F(AtomicFileSteps, ALongTableThatDoesNotFitFailsWholeAtItsFinish) {
  // The formatting thread's writes pass the file-size limit: finish() reports it and nothing
  // appears, as for a table written by the caller's thread.
  const fs::path target = dir_ / "long.csv";
  const std::vector<std::vector<double>> table = varied_rows(20000, 5);
  nhdyn::CsvWriter writer(target, {"a", "b", "c", "d", "e"});
  {
    const FileSizeLimit limit(600000);
    ASSERT_TRUE(limit.ok());
    for (const std::vector<double>& row : table) writer.write_row(row);
    try {
      writer.finish();
      ADD_FAILURE() << "a table past the file-size limit was finished";
    } catch (const nhdyn::FileError& e) {
      EXPECT_NE(std::string(e.what()).find("long.csv"), std::string::npos) << e.what();
    }
  }
  EXPECT_TRUE(entries().empty());
}

// The process's virtual memory size now (VmSize of /proc/self/status), in bytes; 0 if unknown.
rlim_t virtual_memory_size() {
  std::ifstream in("/proc/self/status");
  std::string line;
  while (std::getline(in, line))
    if (line.rfind("VmSize:", 0) == 0) return static_cast<rlim_t>(std::stoull(line.substr(7))) * 1024;
  return 0;
}

TEST_F(AtomicFileSteps, ALongTableIsFormattedOnTheCallersThreadWhereNoThreadCanStart) {
#ifdef NHDYN_ADDRESS_SANITIZER
  GTEST_SKIP() << "AddressSanitizer reserves more address space than the limit this test sets";
#else
  // An address-space limit a few megabytes above what the process uses leaves no room for a
  // thread's stack (8 MiB): the writer formats every row itself, and the table is whole.
  const fs::path target = dir_ / "long.csv";
  const std::vector<std::vector<double>> table = varied_rows(30000, 2);
  nhdyn::CsvWriter writer(target, {"a", "b"});
  rlimit saved{};
  ::getrlimit(RLIMIT_AS, &saved);
  const rlim_t used = virtual_memory_size();
  ASSERT_GT(used, 0U);
  rlimit limit = saved;
  limit.rlim_cur = used + (rlim_t{4} << 20);
  ASSERT_EQ(::setrlimit(RLIMIT_AS, &limit), 0);
  for (const std::vector<double>& row : table) writer.write_row(row);
  ::setrlimit(RLIMIT_AS, &saved);
  writer.commit();
  EXPECT_EQ(read(target), expected_text(table, "a,b\n"));
#endif
}

TEST_F(AtomicFileSteps, TheFormattingThreadLeavesTheStoppingSignalsToTheCaller) {
  // A caller that holds SIGUSR1 (as a foreground compile holds the stopping signals) receives one
  // sent to the process while the formatting thread lives: the thread blocks them all. Were it not
  // to, the signal would be delivered to it and end the process.
  const fs::path target = dir_ / "long.csv";
  nhdyn::CsvWriter writer(target, {"a", "b", "c"});
  for (const std::vector<double>& row : varied_rows(30000, 3)) writer.write_row(row);
  sigset_t usr1, old;
  sigemptyset(&usr1);
  sigaddset(&usr1, SIGUSR1);
  ASSERT_EQ(::pthread_sigmask(SIG_BLOCK, &usr1, &old), 0);
  ASSERT_EQ(::kill(::getpid(), SIGUSR1), 0);
  const timespec wait{2, 0};
  const int received = ::sigtimedwait(&usr1, nullptr, &wait);
  ::pthread_sigmask(SIG_SETMASK, &old, nullptr);
  EXPECT_EQ(received, SIGUSR1);
  writer.commit();
  EXPECT_TRUE(fs::exists(target));
}

TEST_F(AtomicFileSteps, AFinishedFileNotPublishedLeavesNothing) {
  {
    nhdyn::AtomicFile file(dir_ / "a.txt");
    file.write("rows\n");
    file.finish();
  }
  EXPECT_TRUE(entries().empty());
}

TEST_F(AtomicFileSteps, TheLastFlushFailingRemovesTheTemporaryAndNamesTheFile) {
  const fs::path target = dir_ / "big.csv";
  {
    nhdyn::AtomicFile file(target);
    // 3000 bytes stay in the stream's buffer (4096 bytes for a file here), so that the refusal
    // comes at finish()'s flush, not at write().
    file.write(std::string(3000, 'x'));
    const FileSizeLimit limit(1024);
    ASSERT_TRUE(limit.ok());
    try {
      file.finish();
      FAIL() << "finish() succeeded past the file-size limit";
    } catch (const nhdyn::FileError& e) {
      EXPECT_NE(std::string(e.what()).find("writing '" + target.string() + "' failed (disk full?); nothing was written"),
                std::string::npos)
          << e.what();
    }
  }
  EXPECT_TRUE(entries().empty());
}

TEST_F(AtomicFileSteps, FilesFinishedTogetherAppearTogetherOrNotAtAll) {
  // What RunFiles::commit (apps/nhdyn/run_files.cpp) does with a command's files: all finished,
  // then all published. The first is small and finishes; the second cannot be written whole, so
  // the first never appears either (committed one after the other, it would have).
  const fs::path first = dir_ / "run.csv", second = dir_ / "run-events.csv";
  {
    nhdyn::CsvWriter table(first, {"t", "x"});
    const std::vector<double> row = {0.0, 1.0};
    table.write_row(row);
    nhdyn::AtomicFile events(second);
    events.write(std::string(3000, 'e'));
    const FileSizeLimit limit(1024);
    ASSERT_TRUE(limit.ok());
    table.finish();
    EXPECT_THROW(events.finish(), nhdyn::FileError);
  }
  EXPECT_TRUE(entries().empty());
  // And with room for both, both appear, whole.
  {
    nhdyn::CsvWriter table(first, {"t", "x"});
    const std::vector<double> row = {0.0, 1.0};
    table.write_row(row);
    nhdyn::AtomicFile events(second);
    events.write(std::string(3000, 'e'));
    table.finish();
    events.finish();
    EXPECT_TRUE(entries().size() == 2U && !fs::exists(first) && !fs::exists(second));
    table.publish();
    events.publish();
  }
  EXPECT_EQ(read(first), "t,x\n0,1\n");
  EXPECT_EQ(read(second), std::string(3000, 'e'));
}

TEST_F(AtomicFileSteps, ADeviceIsFinishedByItsFlush) {
  // Written straight (no temporary): /dev/full takes the bytes into the stream's buffer and
  // refuses them at the flush with ENOSPC, named in the message.
  nhdyn::AtomicFile file("/dev/full");
  file.write("a row\n");
  try {
    file.finish();
    FAIL() << "finish() on /dev/full succeeded";
  } catch (const nhdyn::FileError& e) {
    EXPECT_NE(std::string(e.what()).find("writing '/dev/full' failed: No space left on device"), std::string::npos)
        << e.what();
  }
}

}  // namespace
