#pragma once
// The diagnosis's catalogue of candidate effects (millwatch issue 8, item 2): each with its name,
// the residual signature that suggests it, and the extension that represents it — a ModelConfig
// effect fitted through identify::WindowFitter, or a term of the measurement chain fitted by
// linear least squares on the record (drift, hum), or the spindle's actual speed — with its free
// parameters.

#include <span>
#include <string>
#include <string_view>

namespace millwatch::diagnose {

enum class CandidateKind {
  kModelEffect,       ///< a ModelConfig effect, refitted on the synchronous average
  kMeasurementChain,  ///< a term added to the measured signal (drift, hum)
  kSpindle,           ///< the model's time base: the actual spindle speed
  kTimeVarying,       ///< the model changes over the record (a trend, a step)
};

struct CandidateInfo {
  std::string_view name;  ///< exact name (report.json's named_effects)
  CandidateKind kind;
  std::string_view signature;   ///< what in the residual suggests it
  std::string_view extension;   ///< what is added to the model
  std::string_view parameters;  ///< its free parameters
};

/// Every candidate, in the order they are scored.
[[nodiscard]] std::span<const CandidateInfo> catalogue();
/// The entry of a name (nullptr: none).
[[nodiscard]] const CandidateInfo* find_candidate(std::string_view name);

}  // namespace millwatch::diagnose
