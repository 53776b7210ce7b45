#include "runtime/interrupt.h"

#include <atomic>
#include <cstring>
#include <ctime>

#include <unistd.h>

#include "runtime/atomic_file.h"

namespace {

volatile std::sig_atomic_t g_signal = 0;
std::atomic<int> g_count{0};
// When the first signal came, in ns of CLOCK_MONOTONIC; 0 until it is known. Any thread may run a
// handler (the device threads too), so a second signal can be handled before the first has set it.
std::atomic<int64_t> g_first_ns{0};
char g_lost[1024];  // the whole hard-exit message, prepared before any signal can come

void say(const char* text) {
  ssize_t ignored = ::write(STDERR_FILENO, text, std::strlen(text));
  (void)ignored;
}

int64_t now_ns() {
  timespec now{};
  clock_gettime(CLOCK_MONOTONIC, &now);
  return int64_t(now.tv_sec) * 1000000000 + now.tv_nsec;
}

// Only async-signal-safe calls: write, clock_gettime, unlink, _exit.
void on_stop_signal(int signal) {
  int count = ++g_count;
  if (count == 1) {
    g_signal = signal;
    g_first_ns.store(now_ns());
    say("\npathcl: stopping to write what is rendered so far (interrupt twice more to exit at once without it)\n");
    return;
  }
  int64_t first = g_first_ns.load();
  if (count == 2 && (first == 0 || double(now_ns() - first) * 1e-9 <= kStopGraceSeconds)) {
    say("pathcl: still stopping and writing what is rendered; interrupt once more to exit at once without it\n");
    return;
  }
  remove_partial_files_now();
  say(g_lost);
  _exit(128 + signal);
}

}  // namespace

void install_stop_handlers(const std::string& lost) {
  std::string text = "pathcl: interrupted again, exiting at once: " + lost + "\n";
  std::strncpy(g_lost, text.c_str(), sizeof g_lost - 1);
  struct sigaction action {};
  action.sa_handler = on_stop_signal;
  sigemptyset(&action.sa_mask);
  // A handler blocks both signals in its thread; other threads may still run one at the same time.
  sigaddset(&action.sa_mask, SIGINT);
  sigaddset(&action.sa_mask, SIGTERM);
  action.sa_flags = SA_RESTART;  // the writes in progress continue after a counted signal
  sigaction(SIGINT, &action, nullptr);
  sigaction(SIGTERM, &action, nullptr);
}

const volatile std::sig_atomic_t* stop_signal() { return &g_signal; }
