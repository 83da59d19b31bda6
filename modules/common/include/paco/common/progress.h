#pragma once
// Usage:
//   paco::InterruptGuard guard;                 // Ctrl-C sets a flag instead of killing
//   paco::ProgressBar bar("segment", total);
//   for (...) { if (paco::interruptRequested()) break; work(); bar.advance(); }
//   bar.finish();
#include <chrono>
#include <cstddef>
#include <cstdio>
#include <mutex>
#include <string>

namespace paco {

/// A one-line terminal progress bar with count, rate and ETA. Thread-safe; redraws at most
/// ~10 times a second. On a non-terminal stream (a log file) it prints a line every 10 % instead,
/// and at least every `log_interval` seconds while work goes on, so that an hour-long pass does
/// not sit silent in its log between two tenths.
class ProgressBar {
 public:
  ProgressBar(std::string label, std::size_t total, std::FILE* stream = stderr, double log_interval = 60.0);
  ~ProgressBar();
  void advance(std::size_t steps = 1);
  /// A short free-form status shown after the counters, e.g. "loss 0.31".
  void setStatus(const std::string& status);
  void finish();

  /// "1.2 s", "3 min 04 s", "2 h 05 min".
  static std::string formatDuration(double seconds);

 private:
  void draw(bool final);
  std::string label_;
  std::size_t total_;
  std::size_t done_ = 0;
  std::FILE* stream_;
  bool is_terminal_;
  double log_interval_;
  bool finished_ = false;
  int last_decile_ = -1;
  std::string status_;
  std::chrono::steady_clock::time_point start_, last_draw_;
  std::mutex mutex_;
};

/// While alive, SIGINT and SIGTERM set a flag (interruptRequested()) instead of ending the
/// process, so long work can save its state and stop cleanly. A second Ctrl-C ends the process.
class InterruptGuard {
 public:
  InterruptGuard();
  ~InterruptGuard();
  InterruptGuard(const InterruptGuard&) = delete;
  InterruptGuard& operator=(const InterruptGuard&) = delete;
};

bool interruptRequested();
/// For tests and for code that stops work itself.
void setInterruptRequested(bool requested);
/// Before a second Ctrl-C (or SIGTERM) ends the process at once, it writes `text` to the file
/// descriptor `fd` (write(2) is all a signal handler may do): a line in a journal, say, that tells
/// the next run why the work in flight never finished. `fd` < 0: nothing. `text` must outlive the
/// setting (a string literal).
void setHardInterruptNote(int fd, const char* text);

}  // namespace paco
