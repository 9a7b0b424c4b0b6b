#pragma once
// Background work beside the sample thread: the lockstep model's rebuilds (ModelBuilder) and
// identification's fits (identify::Identifier) run milliseconds to seconds on threads of their
// own. Woken as ordinary threads, Linux may start them on the sample thread's CPU at once,
// preempting it until the load balancer moves one of them: through a speed ramp at 333.3 kHz a
// revolution's record then came 1.6–4.2 ms after its block (its CPU time 26–35 µs; the rest
// off the CPU, the build running in its place), where the others take tens of µs. As batch work
// (SCHED_BATCH) their wake-ups never preempt a running thread; they take the same share of the
// CPU over time.

namespace millwatch::monitor {

/// Marks the calling thread as batch work (Linux: SCHED_BATCH, nice unchanged). Returns whether
/// the system took it (elsewhere, or refused: the thread runs as before).
bool make_this_thread_batch();

}  // namespace millwatch::monitor
