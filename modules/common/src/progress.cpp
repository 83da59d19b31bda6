#include <paco/common/progress.h>

#include <atomic>
#include <cmath>
#include <csignal>
#include <cstdlib>
#include <unistd.h>

namespace paco {

namespace {
std::atomic<bool> g_interrupt_requested{false};
std::atomic<int> g_guards{0};
struct sigaction g_old_int, g_old_term;

std::atomic<int> g_note_fd{-1};
std::atomic<const char*> g_note_text{nullptr};

extern "C" void onInterruptSignal(int) {
  // A second Ctrl-C while the first is being honoured ends the process at once.
  if (g_interrupt_requested.exchange(true)) {
    const int fd = g_note_fd.load();
    const char* text = g_note_text.load();
    if (fd >= 0 && text) {
      std::size_t length = 0;
      while (text[length]) ++length;  // strlen is not async-signal-safe by the letter of POSIX
      [[maybe_unused]] const ssize_t written = ::write(fd, text, length);
    }
    std::_Exit(130);
  }
}
}  // namespace

void setHardInterruptNote(int fd, const char* text) {
  g_note_fd.store(-1);  // never a new fd with the old text, or the reverse
  g_note_text.store(text);
  g_note_fd.store(fd);
}

bool interruptRequested() { return g_interrupt_requested.load(); }
void setInterruptRequested(bool requested) { g_interrupt_requested.store(requested); }

InterruptGuard::InterruptGuard() {
  if (g_guards++ > 0) return;
  struct sigaction action {};
  action.sa_handler = onInterruptSignal;
  sigemptyset(&action.sa_mask);
  sigaction(SIGINT, &action, &g_old_int);
  sigaction(SIGTERM, &action, &g_old_term);
}

InterruptGuard::~InterruptGuard() {
  if (--g_guards > 0) return;
  sigaction(SIGINT, &g_old_int, nullptr);
  sigaction(SIGTERM, &g_old_term, nullptr);
}

ProgressBar::ProgressBar(std::string label, std::size_t total, std::FILE* stream, double log_interval)
    : label_(std::move(label)), total_(total), stream_(stream),
      is_terminal_(isatty(fileno(stream)) != 0), log_interval_(log_interval),
      start_(std::chrono::steady_clock::now()), last_draw_(start_) {}

ProgressBar::~ProgressBar() { finish(); }

void ProgressBar::advance(std::size_t steps) {
  std::lock_guard<std::mutex> lock(mutex_);
  done_ += steps;
  draw(false);
}

void ProgressBar::setStatus(const std::string& status) {
  std::lock_guard<std::mutex> lock(mutex_);
  status_ = status;
}

void ProgressBar::finish() {
  std::lock_guard<std::mutex> lock(mutex_);
  if (finished_) return;
  draw(true);
  finished_ = true;
}

std::string ProgressBar::formatDuration(double seconds) {
  char buf[64];
  if (!std::isfinite(seconds) || seconds < 0) return "?";
  if (seconds < 60) std::snprintf(buf, sizeof buf, "%.1f s", seconds);
  else if (seconds < 3600)
    std::snprintf(buf, sizeof buf, "%d min %02d s", static_cast<int>(seconds) / 60, static_cast<int>(seconds) % 60);
  else
    std::snprintf(buf, sizeof buf, "%d h %02d min", static_cast<int>(seconds) / 3600,
                  (static_cast<int>(seconds) % 3600) / 60);
  return buf;
}

void ProgressBar::draw(bool final) {
  if (finished_) return;
  const auto now = std::chrono::steady_clock::now();
  const double elapsed = std::chrono::duration<double>(now - start_).count();
  const double fraction = total_ > 0 ? std::min(1.0, static_cast<double>(done_) / static_cast<double>(total_)) : 1.0;
  if (is_terminal_) {
    if (!final && std::chrono::duration<double>(now - last_draw_).count() < 0.1) return;
  } else {
    const int decile = static_cast<int>(fraction * 10);
    const bool overdue = std::chrono::duration<double>(now - last_draw_).count() >= log_interval_;
    if (!final && decile == last_decile_ && !overdue) return;
    last_decile_ = decile;
  }
  last_draw_ = now;
  const double rate = elapsed > 0 ? static_cast<double>(done_) / elapsed : 0.0;
  const double eta = rate > 0 ? static_cast<double>(total_ - std::min(done_, total_)) / rate : NAN;
  constexpr int width = 28;
  const int filled = static_cast<int>(fraction * width);
  std::string bar(static_cast<std::size_t>(filled), '#');
  bar.resize(width, '.');
  std::fprintf(stream_, "%s%s [%s] %zu/%zu %3.0f%% %.1f/s %s %s%s%s", is_terminal_ ? "\r\033[K" : "",
               label_.c_str(), bar.c_str(), done_, total_, 100.0 * fraction, rate,
               final ? "in" : "ETA", formatDuration(final ? elapsed : eta).c_str(),
               status_.empty() ? "" : " | ", status_.c_str());
  if (!is_terminal_ || final) std::fputc('\n', stream_);
  std::fflush(stream_);
}

}  // namespace paco
