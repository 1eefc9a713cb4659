// Write failures are runtime failures (WriteError, exit 4) that name the file and the system's
// reason: a parent that is a file, a full disk seen only at close (/dev/full), a file-size
// limit (RLIMIT_FSIZE, as a nearly full disk or quota).

#include <gtest/gtest.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <clutterscope/datasets/bop.hpp>
#include <clutterscope/datasets/errors.hpp>
#include <clutterscope/datasets/files.hpp>
#include <cstdio>
#include <fstream>
#include <functional>

#include "bop_fixture_support.hpp"

namespace clutterscope::datasets {
namespace {

namespace fs = std::filesystem;
using testing::ScratchDir;
using testing::write_text;

// The message of the WriteError thrown by `action`; a test failure if none is thrown.
std::string write_error(const std::function<void()>& action) {
  try {
    action();
  } catch (const WriteError& error) {
    return error.what();
  } catch (const std::exception& error) {
    ADD_FAILURE() << "expected WriteError, got another exception: " << error.what();
    return "";
  }
  ADD_FAILURE() << "expected WriteError, nothing was thrown";
  return "";
}

TEST(WriteErrors, ParentThatIsAFileNamesTheFolderAndTheReason) {
  ScratchDir dir;
  write_text(dir.path() / "plain", "a file, not a folder\n");
  const fs::path target = dir.path() / "plain" / "out" / "objects.csv";
  EXPECT_EQ(write_error([&] { write_file_atomically(target, "rows\n"); }),
            "cannot write " + (dir.path() / "plain" / "out").string() + ": Not a directory");
}

TEST(WriteErrors, FullDiskSeenOnlyAtCloseIsAWriteError) {
  // /dev/full accepts the buffered write and fails the flush at close with ENOSPC.
  std::ofstream stream("/dev/full", std::ios::binary);
  ASSERT_TRUE(stream) << "/dev/full cannot be opened";
  stream << "a few bytes that stay in the buffer";
  ASSERT_TRUE(stream);
  EXPECT_EQ(write_error([&] { close_checked(stream, "/dev/full"); }),
            "cannot write /dev/full: No space left on device");
}

TEST(WriteErrors, FileSizeLimitIsAWriteErrorAndLeavesNoTemporaryFile) {
  ScratchDir dir;
  const fs::path target = dir.path() / "big.bin";
  // In a child process: the limit and the ignored SIGXFSZ must not reach the test runner. The
  // child exits 0 when the WriteError names the file and EFBIG and no temporary file is left.
  const pid_t pid = ::fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    ::signal(SIGXFSZ, SIG_IGN);
    const rlimit limit{4096, 4096};
    ::setrlimit(RLIMIT_FSIZE, &limit);
    try {
      write_file_atomically(target, std::string(1 << 16, 'x'));
    } catch (const WriteError& error) {
      const bool named =
          std::string(error.what()) == "cannot write " + target.string() + ": File too large";
      std::_Exit(named ? (fs::is_empty(dir.path()) ? 0 : 3) : 2);
    }
    std::_Exit(1);
  }
  int status = 0;
  ASSERT_EQ(::waitpid(pid, &status, 0), pid);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 0)
      << "1: nothing thrown, 2: another message, 3: a temporary file was left";
}

}  // namespace
}  // namespace clutterscope::datasets
