#include <paco/common/child_process.h>
#include <paco/common/progress.h>

#include <gtest/gtest.h>
#include <test_support.h>

#include <chrono>
#include <cstdlib>
#include <stdexcept>
#include <thread>
#include <vector>

#include <omp.h>

TEST(ChildProcess, ReturnsTheBytesOfTheWork) {
  const std::string big(200000, 'x');  // larger than a pipe buffer
  const paco::ChildProcessResult r = paco::runInChildProcess([&] { return std::string("ok:") + big; }, 30.0);
  ASSERT_TRUE(r.ok) << r.error;
  EXPECT_EQ(r.output, "ok:" + big);
  EXPECT_TRUE(r.error.empty());
}

TEST(ChildProcess, AnAbortFailsTheCallNotTheCaller) {
  const paco::ChildProcessResult r = paco::runInChildProcess([]() -> std::string { std::abort(); }, 30.0);
  EXPECT_FALSE(r.ok);
  EXPECT_NE(r.error.find("signal 6"), std::string::npos) << r.error;
}

// COIN-OR Clp's failed assertion is written to stderr just before the abort. The caller's user
// should read it in the error, not as a stray line that looks as if the whole program crashed.
TEST(ChildProcess, TheLastLineACrashingChildWroteEndsTheErrorAndIsNotPrinted) {
  testing::internal::CaptureStderr();
  const paco::ChildProcessResult r = paco::runInChildProcess(
      []() -> std::string {
        std::fputs("solver: starting\n", stderr);
        std::fputs("solver: lib.cpp:12: Assertion `a <= b' failed.\n", stderr);
        std::abort();
      },
      30.0);
  const std::string printed = testing::internal::GetCapturedStderr();
  EXPECT_FALSE(r.ok);
  EXPECT_EQ(r.error, "the child process was killed by signal 6 (Aborted) after writing \"solver: lib.cpp:12: "
                     "Assertion `a <= b' failed.\"");
  EXPECT_EQ(r.error_output, "solver: starting\nsolver: lib.cpp:12: Assertion `a <= b' failed.\n");
  EXPECT_EQ(printed, "");
}

TEST(ChildProcess, WhatASucceedingChildWritesToStderrIsPassedOn) {
  const std::string many_lines(100000, '.');  // more than a pipe holds: read while the child runs
  testing::internal::CaptureStderr();
  const paco::ChildProcessResult r = paco::runInChildProcess(
      [&] {
        std::fputs("solver: a warning\n", stderr);
        std::fputs(many_lines.c_str(), stderr);
        return std::string("solved");
      },
      30.0);
  const std::string printed = testing::internal::GetCapturedStderr();
  ASSERT_TRUE(r.ok) << r.error;
  EXPECT_EQ(r.output, "solved");
  EXPECT_EQ(printed, "solver: a warning\n" + many_lines);
  EXPECT_EQ(r.error_output, printed.substr(printed.size() - 16384));  // the last 16 KB
}

TEST(ChildProcess, AnExceptionBecomesTheError) {
  const paco::ChildProcessResult r =
      paco::runInChildProcess([]() -> std::string { throw std::runtime_error("degenerate program"); }, 30.0);
  EXPECT_FALSE(r.ok);
  EXPECT_EQ(r.error, "degenerate program");
}

TEST(ChildProcess, WorkOverTheTimeLimitIsKilled) {
  const auto started = std::chrono::steady_clock::now();
  const paco::ChildProcessResult r = paco::runInChildProcess(
      [] {
        std::this_thread::sleep_for(std::chrono::seconds(30));
        return std::string("too late");
      },
      0.3);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  EXPECT_FALSE(r.ok);
  EXPECT_TRUE(r.timed_out);
  EXPECT_LT(seconds, 10.0);
}

TEST(ChildProcess, AnInterruptKillsTheChild) {
  paco::setInterruptRequested(true);
  const paco::ChildProcessResult r = paco::runInChildProcess(
      [] {
        std::this_thread::sleep_for(std::chrono::seconds(30));
        return std::string("too late");
      },
      0.0);
  paco::setInterruptRequested(false);
  EXPECT_FALSE(r.ok);
  EXPECT_TRUE(r.interrupted);
}

TEST(ChildProcess, BufferedOutputOfTheCallerIsNotRepeatedByTheChild) {
  paco::test::TempDir dir;
  const std::string path = dir.file("out.txt");
  FILE* file = std::fopen(path.c_str(), "w");
  ASSERT_NE(file, nullptr);
  std::fputs("once\n", file);  // still in the stdio buffer at the fork
  const paco::ChildProcessResult r = paco::runInChildProcess(
      [&] {
        std::fflush(file);  // as a solver flushing its log would
        return std::string("done");
      },
      30.0);
  std::fclose(file);
  ASSERT_TRUE(r.ok) << r.error;
  EXPECT_EQ(paco::test::readBytes(path), "once\n");
}

// libgomp's thread pool does not survive fork(): once the caller has used it (LibTorch does), a
// parallel region in the child waits forever for threads that are not there. CBC reaches one
// through LAPACK -> OpenMP OpenBLAS; this hung paco's PolyFit at random.
TEST(ChildProcess, OpenMpWorkInTheChildAfterTheCallerUsedOpenMp) {
  omp_set_num_threads(2);
  std::vector<double> values(1000, 1.0);
  double sum = 0.0;
#pragma omp parallel for reduction(+ : sum)
  for (int i = 0; i < 1000; ++i) sum += values[static_cast<std::size_t>(i)];
  ASSERT_EQ(sum, 1000.0);
  const paco::ChildProcessResult r = paco::runInChildProcess(
      [&] {
        double child_sum = 0.0;
#pragma omp parallel for reduction(+ : child_sum)
        for (int i = 0; i < 1000; ++i) child_sum += 2.0 * values[static_cast<std::size_t>(i)];
        return std::to_string(child_sum);
      },
      20.0);
  EXPECT_FALSE(r.timed_out) << "the child hung in an OpenMP parallel region";
  ASSERT_TRUE(r.ok) << r.error;
  EXPECT_EQ(std::stod(r.output), 2000.0);
  EXPECT_EQ(omp_get_max_threads(), 2);  // the caller keeps its threads
}
