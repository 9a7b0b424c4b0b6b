#pragma once
// A model's exact periodic steady state as the window an identification fits: the truth of the
// fitter-alone tests and of bench/identify_benchmark, finer than the fitter's 720 steps (and,
// finer_window, its 5 helix discs), with no noise and no monitor; and the ideal low-pass they
// fit it through.

#include <complex>

#include "core/identify/window_fit.hpp"
#include "core/model/model_config.hpp"

namespace millwatch::test {

/// `truth`'s exact mean revolution on 1440 steps, as a 30-revolution window sampled exactly (no
/// bins shared between samples).
identify::MeasuredRevolution exact_window(const model::ModelConfig& truth);

/// exact_window() of `m` with 20 helix discs.
identify::MeasuredRevolution finer_window(const model::ModelConfig& m);

/// An ideal low-pass at 3.3 kHz (H = 1 below, 0 above).
std::complex<double> ideal_lowpass(double frequency_hz);

}  // namespace millwatch::test
