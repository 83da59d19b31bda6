#include <paco/common/progress.h>

#include <gtest/gtest.h>

#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <string>
#include <thread>

TEST(ProgressBar, FormatsDurations) {
  EXPECT_EQ(paco::ProgressBar::formatDuration(1.25), "1.2 s");
  EXPECT_EQ(paco::ProgressBar::formatDuration(184), "3 min 04 s");
  EXPECT_EQ(paco::ProgressBar::formatDuration(7500), "2 h 05 min");
  EXPECT_EQ(paco::ProgressBar::formatDuration(NAN), "?");
}

TEST(ProgressBar, WritesCountRateAndFinalLineToNonTerminal) {
  std::FILE* f = std::tmpfile();
  ASSERT_NE(f, nullptr);
  {
    paco::ProgressBar bar("work", 4, f);
    bar.setStatus("loss 0.5");
    for (int i = 0; i < 4; ++i) bar.advance();
  }
  std::rewind(f);
  char buf[4096] = {0};
  const std::size_t n = std::fread(buf, 1, sizeof buf - 1, f);
  std::fclose(f);
  const std::string text(buf, n);
  EXPECT_NE(text.find("work ["), std::string::npos);
  EXPECT_NE(text.find("4/4 100%"), std::string::npos);
  EXPECT_NE(text.find("/s in "), std::string::npos);
  EXPECT_NE(text.find("loss 0.5"), std::string::npos);
}

// Into a log, a line every 10 % and one whenever the interval has passed since the last line.
TEST(ProgressBar, WritesALineToANonTerminalWhenTheIntervalHasPassed) {
  std::FILE* f = std::tmpfile();
  ASSERT_NE(f, nullptr);
  {
    paco::ProgressBar bar("work", 1000, f, /*log_interval=*/0.5);
    bar.advance();  // the 0 % line
    bar.advance();  // same tenth, too soon: no line
    std::this_thread::sleep_for(std::chrono::milliseconds(600));
    bar.advance();  // same tenth, the interval passed: a line
    bar.advance();  // too soon again
  }  // the final line
  std::rewind(f);
  char buf[4096] = {0};
  const std::size_t n = std::fread(buf, 1, sizeof buf - 1, f);
  std::fclose(f);
  const std::string text(buf, n);
  EXPECT_EQ(std::count(text.begin(), text.end(), '\n'), 3) << text;
  EXPECT_NE(text.find(" 1/1000 "), std::string::npos) << text;
  EXPECT_NE(text.find(" 3/1000 "), std::string::npos) << text;
  EXPECT_EQ(text.find(" 2/1000 "), std::string::npos) << text;
  EXPECT_NE(text.find(" 4/1000 "), std::string::npos) << text;
}

// A second Ctrl-C ends the process with 130 at once, writing the note first (in a child process,
// since it ends the process).
TEST(InterruptGuard, ASecondSigintEndsTheProcessAfterWritingTheNote) {
  int pipe_ends[2];
  ASSERT_EQ(pipe(pipe_ends), 0);
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    close(pipe_ends[0]);
    paco::InterruptGuard guard;
    paco::setHardInterruptNote(pipe_ends[1], "stopped hard\n");
    std::raise(SIGINT);  // sets the flag
    std::raise(SIGINT);  // ends the process
    _exit(1);
  }
  close(pipe_ends[1]);
  char buffer[64] = {};
  const ssize_t n = read(pipe_ends[0], buffer, sizeof buffer - 1);
  close(pipe_ends[0]);
  int status = 0;
  ASSERT_EQ(waitpid(child, &status, 0), child);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 130);
  EXPECT_EQ(std::string(buffer, n > 0 ? static_cast<std::size_t>(n) : 0), "stopped hard\n");
}

TEST(InterruptGuard, SigintSetsFlagInsteadOfKilling) {
  paco::setInterruptRequested(false);
  {
    paco::InterruptGuard guard;
    std::raise(SIGINT);
    EXPECT_TRUE(paco::interruptRequested());
  }
  paco::setInterruptRequested(false);
}
