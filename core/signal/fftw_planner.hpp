#pragma once
// One lock for FFTW's planner, shared by every part of millwatch that makes or destroys plans.
//
// FFTW's planner is not thread-safe: fftw_plan_* and fftw_destroy_plan read and write global
// state (the planner's table of solved problems, the wisdom), so two threads planning at once
// can corrupt it. fftw_execute on distinct plans and fftw_malloc/fftw_free are thread-safe.
// Plans are made in more than one thread: millwatchd builds a reloaded pipeline (the spindle
// tracker's plan, the lockstep filter's) in its main thread and destroys retired ones there,
// the sample thread plans when the lockstep model meets a new speed or accumulation cycle
// length, and the identifier's worker thread (core/identify) when it evaluates the model
// through the measurement's filter (both model::PeriodicResponse) and takes the model's
// harmonics (signal::RealSpectrum, once per fit and grid); the replay's plots take their Welch
// spectra (welch_spectrum.hpp) while a model build may still run. So every fftw_plan_* and
// fftw_destroy_plan call in the project holds this lock; fftw_execute never does (the
// real-time path stays lock-free).
// (FFTW 3.3.5+'s fftw_make_planner_thread_safe() would need libfftw3_threads; one mutex is
// simpler and planning is rare.)

#include <mutex>

namespace millwatch::signal {

/// The process-wide mutex to hold around FFTW plan creation and destruction.
std::mutex& fftw_planner_mutex();

}  // namespace millwatch::signal
