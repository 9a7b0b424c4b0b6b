#pragma once

namespace millwatch::shell {

/// What a system call interrupted by SIGINT or SIGTERM does once the handler has run.
enum class InterruptedCalls {
  restart,         ///< the call goes on (a read in the middle of a file is not cut short)
  return_at_once,  ///< the call returns EINTR, so a blocking wait ends with the signal
};

/// Sets the offline shell's stop flag on SIGINT and SIGTERM (Ctrl-C; `kill`), and clears it:
/// a command checks `stop_requested()` between steps and ends as it would at its input's end.
void install_stop_signals(InterruptedCalls calls = InterruptedCalls::restart);

/// Whether SIGINT or SIGTERM has arrived since `install_stop_signals`.
bool stop_requested();
/// The last of them to arrive (SIGINT, SIGTERM; 0: none).
int stop_signal();
/// The exit status of a command that stopped for it, with its output partial: 128 + the
/// signal's number, as a shell reports a command the signal ended (130 for SIGINT).
int interrupted_exit_status();
/// Whether `status` is such a command's (130 or 143).
bool is_interrupted_exit_status(int status);

}  // namespace millwatch::shell
