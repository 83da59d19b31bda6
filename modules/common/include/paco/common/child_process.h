#pragma once
// Usage:
//   paco::ChildProcessResult r = paco::runInChildProcess([&] { return solveAndSerialise(); }, 60.0);
//   if (!r.ok) fail(r.error);            // e.g. "killed by signal 6 (Aborted) after writing \"...\""
//   use(r.output);
//
// Runs work that may abort the whole process (a third-party solver's failed assertion, as COIN-OR
// Clp's ClpNonLinearCost.cpp:1064 does on some degenerate programs) in a forked child, so that a
// crash fails one call instead of killing the caller (a long evaluation, a user's program).
#include <functional>
#include <string>

namespace paco {

struct ChildProcessResult {
  bool ok = false;           ///< the work returned normally; `output` holds what it returned
  std::string output;        ///< the work's return value (bytes), passed back through a pipe
  std::string error;         ///< why not ok: the work's exception, the signal that killed it, ...
  bool timed_out = false;    ///< killed after `timeout_seconds`
  bool interrupted = false;  ///< killed because paco::interruptRequested() became true
  /// The last 16 KB the work wrote to stderr, held back until the child ended (anything before
  /// them went on to the caller's stderr as it came). When the child crashed, their last line ends
  /// `error` (a solver's failed assertion, say); otherwise they are passed on to the caller's
  /// stderr too, as if the work had run in the caller.
  std::string error_output;
};

/// Forks; the child runs `work` and sends its result back, the parent waits for it (at most
/// `timeout_seconds` of wall time, then kills the child; <= 0: no limit) and watches
/// paco::interruptRequested(). The child leaves with _exit, so no destructor or atexit handler of
/// the parent's state runs twice. `work` runs on a copy of the memory: its side effects other
/// than the returned bytes are lost, and it must not rely on other threads (only the forking
/// thread exists in the child; OpenMP runs on one thread there, since libgomp's pool does not
/// survive fork). An exception from `work` becomes `error`. Throws paco::Error only
/// when the child cannot be created.
ChildProcessResult runInChildProcess(const std::function<std::string()>& work, double timeout_seconds);

}  // namespace paco
