#include "stop_signal.h"

#include <csignal>

namespace skerry::cli {

namespace {

// Only lock-free atomics and sig_atomic_t are safe to touch from a handler.
std::atomic<bool> g_stop{false};
volatile std::sig_atomic_t g_signal = 0;
static_assert(std::atomic<bool>::is_always_lock_free, "the stop flag is set in a signal handler");

struct sigaction g_previous_int, g_previous_term;

extern "C" void OnStopSignal(int signal_number) {
  g_signal = signal_number;
  g_stop.store(true);
}

void Install(int signal_number, struct sigaction* previous) {
  struct sigaction action = {};
  action.sa_handler = OnStopSignal;
  sigemptyset(&action.sa_mask);
  // One-shot: the handler resets to the default, so a second Ctrl-C ends the process.
  action.sa_flags = SA_RESETHAND | SA_RESTART;
  sigaction(signal_number, &action, previous);
}

}  // namespace

StopSignal::StopSignal() {
  g_stop.store(false);
  g_signal = 0;
  Install(SIGINT, &g_previous_int);
  Install(SIGTERM, &g_previous_term);
}

StopSignal::~StopSignal() {
  sigaction(SIGINT, &g_previous_int, nullptr);
  sigaction(SIGTERM, &g_previous_term, nullptr);
}

const std::atomic<bool>* StopSignal::flag() const { return &g_stop; }

int StopSignal::signal_number() const { return static_cast<int>(g_signal); }

const char* StopSignal::signal_name() const {
  switch (signal_number()) {
    case SIGINT:
      return "SIGINT";
    case SIGTERM:
      return "SIGTERM";
    default:
      return "";
  }
}

}  // namespace skerry::cli
