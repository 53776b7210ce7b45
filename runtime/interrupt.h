// Stopping a render on SIGINT or SIGTERM without losing it. The first signal asks the render to stop
// at its next horizon; the image so far and the checkpoint are then written, whatever signals follow:
// GNU timeout, shells and process managers send a signal to the process and then to its group, and an
// impatient user presses Ctrl-C twice. Only a third signal, or a second one more than
// kStopGraceSeconds after the first, ends the process at once: it removes the temporary files being
// written (runtime/atomic_file.h, so nothing partial is left), prints what is lost and exits with
// 128 + the signal number.
#pragma once
#include <csignal>
#include <string>

constexpr double kStopGraceSeconds = 5;

// Installs the handlers. `lost` completes the hard exit's message "pathcl: interrupted again, exiting
// at once: LOST", e.g. "out.exr is not written; the checkpoint state.ck holds the render as of its
// last save".
void install_stop_handlers(const std::string& lost);
// The signal number of the first SIGINT or SIGTERM since install_stop_handlers, or 0.
const volatile std::sig_atomic_t* stop_signal();
