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

[[noreturn]] void runChild(int fd, const std::function<std::string()>& work) {
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
  writeAll(fd, message);
  ::close(fd);
  ::_exit(code);
}

}  // namespace

ChildProcessResult runInChildProcess(const std::function<std::string()>& work, double timeout_seconds) {
  int fds[2];
  if (::pipe2(fds, O_CLOEXEC) != 0)
    throw Error(std::string("cannot create a pipe for a child process: ") + std::strerror(errno));
  // The child inherits the stdio buffers: flush them first, or output still buffered here would
  // be written twice if the child flushes (CBC does).
  std::fflush(nullptr);
  const pid_t pid = ::fork();
  if (pid < 0) {
    const int e = errno;
    ::close(fds[0]);
    ::close(fds[1]);
    throw Error(std::string("cannot start a child process (fork): ") + std::strerror(e) +
                "; free some memory or lower --jobs");
  }
  if (pid == 0) {
    ::close(fds[0]);
    runChild(fds[1], work);
  }
  ::close(fds[1]);

  ChildProcessResult result;
  std::string received;
  const auto started = std::chrono::steady_clock::now();
  char buffer[65536];
  for (;;) {
    pollfd p{fds[0], POLLIN, 0};
    const int ready = ::poll(&p, 1, 100);  // wake up regularly to check the clock and Ctrl-C
    if (ready > 0) {
      const ssize_t n = ::read(fds[0], buffer, sizeof(buffer));
      if (n > 0) {
        received.append(buffer, static_cast<std::size_t>(n));
        continue;
      }
      if (n == 0) break;  // end of file: the child is done (or dead)
      if (errno != EINTR && errno != EAGAIN) break;
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
  if (result.timed_out) {
    result.error = "the child process ran over its time limit of " + std::to_string(timeout_seconds) + " s and was killed";
  } else if (result.interrupted) {
    result.error = "interrupted";
  } else if (WIFSIGNALED(status)) {
    const int signal_number = WTERMSIG(status);
    result.error = "the child process was killed by signal " + std::to_string(signal_number) + " (" +
                   ::strsignal(signal_number) + ")";
  } else if (!received.empty() && received[0] == kErrorTag) {
    result.error = received.substr(1);
  } else if (!WIFEXITED(status) || WEXITSTATUS(status) != 0 || received.empty() || received[0] != kResultTag) {
    result.error = "the child process ended without a result (exit status " +
                   std::to_string(WIFEXITED(status) ? WEXITSTATUS(status) : -1) + ")";
  } else {
    result.ok = true;
    result.output = received.substr(1);
  }
  return result;
}

}  // namespace paco
