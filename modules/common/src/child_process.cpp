#include <paco/common/child_process.h>

#include <paco/common/error.h>
#include <paco/common/progress.h>

#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <exception>

#include <dlfcn.h>
#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <unistd.h>

namespace paco {
namespace {

// The child's message starts with one of these tags.
constexpr char kResultTag = 'R';
constexpr char kErrorTag = 'E';

void writeAll(int fd, const std::string& bytes) {
  std::size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = ::write(fd, bytes.data() + done, bytes.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return;  // the parent is gone; nothing useful left to do
    done += static_cast<std::size_t>(n);
  }
}

// libgomp is not fork-safe: the child inherits the bookkeeping of the caller's OpenMP thread pool
// but not its threads, so its first parallel region waits forever. LibTorch fills that pool, and
// CBC reaches a parallel region through LAPACK and the OpenMP build of OpenBLAS, which follows
// omp_get_max_threads(). One thread in the child avoids the pool. Looked up at run time so that
// paco_common needs no OpenMP of its own; absent OpenMP, there is nothing to do.
void useOneOpenMpThread() {
  using SetNumThreads = void (*)(int);
  if (void* symbol = ::dlsym(RTLD_DEFAULT, "omp_set_num_threads")) reinterpret_cast<SetNumThreads>(symbol)(1);
}

[[noreturn]] void runChild(int fd, int stderr_fd, const std::function<std::string()>& work) {
  // What the work writes to stderr (a solver's failed assertion, say) goes to the parent, which
  // quotes it in the error or passes it on.
  if (::dup2(stderr_fd, STDERR_FILENO) >= 0) ::close(stderr_fd);
  useOneOpenMpThread();
  std::string message;
  int code = 0;
  try {
    message = kResultTag + work();
  } catch (const std::exception& e) {
    message = kErrorTag + std::string(e.what());
    code = 3;
  } catch (...) {
    message = kErrorTag + std::string("unknown exception");
    code = 3;
  }
  std::fflush(stderr);
  writeAll(fd, message);
  ::close(fd);
  ::_exit(code);
}

// The most of the child's stderr held back until it ends (the last words are the useful ones);
// anything before it is passed on to the caller's stderr as it comes.
constexpr std::size_t kHeldErrorOutput = 16384;

// Reads what is there into `into`; false at end of file or on an error (not when interrupted or,
// on a non-blocking pipe, when nothing is there yet). With `hold` > 0, all but the last `hold`
// bytes go on to the caller's stderr.
bool readSome(int fd, std::string& into, std::size_t hold) {
  char buffer[65536];
  const ssize_t n = ::read(fd, buffer, sizeof(buffer));
  if (n > 0) {
    into.append(buffer, static_cast<std::size_t>(n));
    if (hold > 0 && into.size() > hold) {
      writeAll(STDERR_FILENO, into.substr(0, into.size() - hold));
      into.erase(0, into.size() - hold);
    }
    return true;
  }
  return n < 0 && (errno == EINTR || errno == EAGAIN);
}

std::string lastLine(const std::string& text) {
  const std::size_t end = text.find_last_not_of(" \t\r\n");
  if (end == std::string::npos) return {};
  const std::size_t newline = text.find_last_of('\n', end);
  const std::size_t start = newline == std::string::npos ? 0 : newline + 1;
  return text.substr(start, end + 1 - start);
}

}  // namespace

ChildProcessResult runInChildProcess(const std::function<std::string()>& work, double timeout_seconds) {
  int fds[2], err_fds[2];
  if (::pipe2(fds, O_CLOEXEC) != 0)
    throw Error(std::string("cannot create a pipe for a child process: ") + std::strerror(errno));
  if (::pipe2(err_fds, O_CLOEXEC) != 0) {
    const int e = errno;
    ::close(fds[0]);
    ::close(fds[1]);
    throw Error(std::string("cannot create a pipe for a child process: ") + std::strerror(e));
  }
  // The child inherits the stdio buffers: flush them first, or output still buffered here would
  // be written twice if the child flushes (CBC does).
  std::fflush(nullptr);
  const pid_t pid = ::fork();
  if (pid < 0) {
    const int e = errno;
    for (int fd : {fds[0], fds[1], err_fds[0], err_fds[1]}) ::close(fd);
    throw Error(std::string("cannot start a child process (fork): ") + std::strerror(e) +
                "; free some memory or lower --jobs");
  }
  if (pid == 0) {
    ::close(fds[0]);
    ::close(err_fds[0]);
    runChild(fds[1], err_fds[1], work);
  }
  ::close(fds[1]);
  ::close(err_fds[1]);
  // Never block on stderr: a process the work started may hold it open after the child is gone.
  ::fcntl(err_fds[0], F_SETFL, ::fcntl(err_fds[0], F_GETFL) | O_NONBLOCK);

  ChildProcessResult result;
  std::string received;
  const auto started = std::chrono::steady_clock::now();
  bool result_open = true, stderr_open = true;
  while (result_open) {
    pollfd p[2] = {{fds[0], POLLIN, 0}, {err_fds[0], POLLIN, 0}};
    const int ready = ::poll(p, stderr_open ? 2 : 1, 100);  // wake up regularly to check the clock and Ctrl-C
    if (ready > 0) {
      if (stderr_open && (p[1].revents & (POLLIN | POLLHUP | POLLERR)))
        stderr_open = readSome(err_fds[0], result.error_output, kHeldErrorOutput);
      if (p[0].revents & (POLLIN | POLLHUP | POLLERR)) result_open = readSome(fds[0], received, 0);
      if (!result_open) break;  // end of file: the child is done (or dead)
    } else if (ready < 0 && errno != EINTR) {
      break;
    }
    const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
    if (timeout_seconds > 0.0 && elapsed > timeout_seconds) result.timed_out = true;
    if (interruptRequested()) result.interrupted = true;
    if (result.timed_out || result.interrupted) {
      ::kill(pid, SIGKILL);
      break;
    }
  }
  ::close(fds[0]);
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  // The child is gone: read the rest of its stderr (up to end of file, or until nothing more
  // comes for a moment).
  while (stderr_open) {
    pollfd p{err_fds[0], POLLIN, 0};
    const int ready = ::poll(&p, 1, 100);
    if (ready == 0 || (ready < 0 && errno != EINTR)) break;
    if (ready > 0) stderr_open = readSome(err_fds[0], result.error_output, kHeldErrorOutput);
  }
  ::close(err_fds[0]);

  bool crashed = false;
  if (result.timed_out) {
    result.error = "the child process ran over its time limit of " + std::to_string(timeout_seconds) + " s and was killed";
  } else if (result.interrupted) {
    result.error = "interrupted";
  } else if (WIFSIGNALED(status)) {
    const int signal_number = WTERMSIG(status);
    result.error = "the child process was killed by signal " + std::to_string(signal_number) + " (" +
                   ::strsignal(signal_number) + ")";
    crashed = true;
  } else if (!received.empty() && received[0] == kErrorTag) {
    result.error = received.substr(1);
  } else if (!WIFEXITED(status) || WEXITSTATUS(status) != 0 || received.empty() || received[0] != kResultTag) {
    result.error = "the child process ended without a result (exit status " +
                   std::to_string(WIFEXITED(status) ? WEXITSTATUS(status) : -1) + ")";
    crashed = true;
  } else {
    result.ok = true;
    result.output = received.substr(1);
  }
  const std::string last_words = lastLine(result.error_output);
  if (crashed && !last_words.empty()) {
    result.error += " after writing \"" + last_words + "\"";
  } else {
    writeAll(STDERR_FILENO, result.error_output);  // not quoted in the error: pass it on
  }
  return result;
}

}  // namespace paco
