// AtomicFile's two steps (io/atomic_file.hpp): finish() does all that can fail for want of space,
// publish() only the rename, so that a writer of several files finishes them all before any
// appears. The failure is a real one: the file-size limit of the process (RLIMIT_FSIZE, with
// SIGXFSZ ignored) makes the kernel refuse the bytes past it with EFBIG, as a full disk refuses
// them with ENOSPC, at the flush of the last buffered bytes.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/resource.h>

#include <filesystem>
#include <fstream>
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
