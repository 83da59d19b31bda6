#pragma once
// Helpers for paco's tests: a temporary folder removed at the end, and the shared data folder
// (../shared next to the checkout) that tests may use only when present.
#include <sys/types.h>

#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace paco::test {

/// A fresh empty folder under the system temp dir, removed with everything in it on destruction.
class TempDir {
 public:
  TempDir();
  ~TempDir();
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  const std::filesystem::path& path() const { return path_; }
  std::string file(const std::string& name) const { return (path_ / name).string(); }

 private:
  std::filesystem::path path_;
};

/// Writes `bytes` to `path` verbatim (for malformed-file tests).
void writeBytes(const std::string& path, const std::string& bytes);
/// Reads a whole file.
std::string readBytes(const std::string& path);

/// The project's shared data folder (PACO_SHARED_DIR, else ../shared beside the source tree),
/// or nothing when it is absent: tests that need it call GTEST_SKIP() then.
std::optional<std::filesystem::path> sharedDataDir();

/// Path of a built tool (e.g. "paco_segment") in the build tree.
std::string toolPath(const std::string& name);

/// Runs a shell command, returns its exit status, and captures stdout+stderr into `output`.
int runCommand(const std::string& command, std::string* output = nullptr);

/// `s` in single quotes, for a path in a runCommand command line (test paths hold no quote).
inline std::string quoted(const std::string& s) { return "'" + s + "'"; }

/// A tool started in the background (`args[0]` is its path), its stdout and stderr both into
/// `log_path`: for tests that signal a running tool as a user's Ctrl-C would. The destructor
/// kills and reaps it if it still runs.
class BackgroundTool {
 public:
  BackgroundTool(const std::vector<std::string>& args, const std::string& log_path);
  ~BackgroundTool();
  BackgroundTool(const BackgroundTool&) = delete;
  BackgroundTool& operator=(const BackgroundTool&) = delete;
  /// Polls `ready` until it holds (true), the tool ends or `timeout_seconds` pass (false).
  bool waitUntil(const std::function<bool()>& ready, double timeout_seconds);
  /// Sends `signal` (unless the tool already ended) and waits for the end: the exit code, or
  /// minus the signal's number when a signal ended it (a shell would report 128 + it).
  int signalAndWait(int signal);

 private:
  bool running();
  pid_t pid_ = -1;
  int status_ = 0;
  bool ended_ = false;
};

}  // namespace paco::test
