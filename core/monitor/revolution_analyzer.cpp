#include "core/monitor/revolution_analyzer.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "core/monitor/residual_sums.hpp"
#include "core/monitor/sector_walk.hpp"

namespace millwatch::monitor {
namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;

/// Template angle of event k (0..flutes) of a revolution.
double event_angle(const ToothEventTemplate& t, const RevolutionEvents& e, int k) {
  const double turn = static_cast<double>(e.turn);
  return k < t.flutes ? t.event_rad[static_cast<std::size_t>(k)] + kTwoPi * turn
                      : t.event_rad[0] + kTwoPi * (turn + 1.0);
}

}  // namespace

AngleMap angle_map(const RevolutionEvents& e, const ToothEventTemplate& t) {
  int used = 0;
  for (int k = 0; k <= e.flutes; ++k) {
    used += e.found[static_cast<std::size_t>(k)] ? 1 : 0;
  }
  const bool all = used < 2;
  // Centred sums for a well-conditioned fit.
  const double n0 = e.event_sample[0];
  double sx = 0.0, sy = 0.0, sxx = 0.0, sxy = 0.0, count = 0.0;
  for (int k = 0; k <= e.flutes; ++k) {
    if (!all && !e.found[static_cast<std::size_t>(k)]) {
      continue;
    }
    const double x = e.event_sample[static_cast<std::size_t>(k)] - n0;
    const double y = event_angle(t, e, k);
    sx += x;
    sy += y;
    sxx += x * x;
    sxy += x * y;
    count += 1.0;
  }
  const double denominator = count * sxx - sx * sx;
  AngleMap m;
  if (denominator <= 0.0) {
    // Degenerate: one revolution between the first and last event.
    const double span = e.event_sample[static_cast<std::size_t>(e.flutes)] - n0;
    m.slope_rad_per_sample = span > 0.0 ? kTwoPi / span : 0.0;
    m.intercept_rad = event_angle(t, e, 0) - m.slope_rad_per_sample * n0;
    return m;
  }
  m.slope_rad_per_sample = (count * sxy - sx * sy) / denominator;
  if (e.period_samples > 0.0) {
    // The slope from the tracker's filtered period: a slope fitted to each revolution's own
    // events carries their noise, and stretches or shrinks that revolution's waveform in the
    // synchronous average (a smear that grows as k² in harmonic k).
    m.slope_rad_per_sample = kTwoPi / e.period_samples;
  }
  m.intercept_rad = (sy - m.slope_rad_per_sample * sx) / count - m.slope_rad_per_sample * n0;
  return m;
}

double measured_rpm(const RevolutionEvents& e, const RevolutionMeasurement& m,
                    double sample_rate_hz) {
  // A revolution whose closing CE1 event was not found coasts on the events' filter: its period
  // is the filter's prediction, not a measurement (the revolutions the events take to give up
  // on a cut that ended or changed), so it states no speed.
  if (!e.found[static_cast<std::size_t>(e.flutes)]) {
    return 0.0;
  }
  if (e.period_samples > 0.0) {
    return 60.0 * sample_rate_hz / e.period_samples;
  }
  return m.period_s > 0.0 ? 60.0 / m.period_s : 0.0;
}

RevolutionAnalyzer::RevolutionAnalyzer(const MonitorConfig& config,
                                       std::size_t max_revolution_samples)
    : sample_rate_hz_(config.sample_rate_hz),
      search_fraction_(config.search_fraction_of_pitch),
      sectors_(std::clamp(config.residual_sectors, 1, kMaxSectors)) {
  model_rows_.assign(kModelRow * max_revolution_samples, 0.0);
}

void RevolutionAnalyzer::analyze(const RevolutionEvents& events, const ToothEventTemplate& tmpl,
                                 const SampleRing& ring, const Lockstep* model,
                                 RevolutionRecord& out) {
  out.event_kind = tmpl.kind;
  RevolutionMeasurement& m = out.measured;
  m.flutes = events.flutes;
  m.sequence = events.sequence;
  m.event_sample = events.event_sample;
  m.boundary_sample = events.boundary_sample;
  m.valid = events.valid;
  m.bounded = events.bounded;
  measure_revolution([&](std::int64_t s) { return ring.row(s); }, sample_rate_hz_, m);
  out.spindle_rpm = measured_rpm(events, m, sample_rate_hz_);

  if (model != nullptr) {
    analyze_model(events, tmpl, ring, *model, out);
  } else {
    out.model_valid = false;
    out.sectors = 0;
  }
}

void RevolutionAnalyzer::analyze_model(const RevolutionEvents& events,
                                       const ToothEventTemplate& tmpl, const SampleRing& ring,
                                       const Lockstep& model, RevolutionRecord& out) {
  out.model_valid = false;
  out.sectors = 0;
  const AngleMap map = angle_map(events, tmpl);
  if (model.aligned() && (kept_.turns >= kKeptTurns && kept_.holds(model.revision(), tmpl)
                              ? model_revolution_again(events, map, model, out)
                              : model_revolution(events, tmpl, map, model, out))) {
    out.model_offset_rad = model.offset_rad();
    residuals(out.measured, ring, map, out);
  }
}

void RevolutionAnalyzer::add_to_average(const RevolutionEvents& events,
                                        const ToothEventTemplate& tmpl, const SampleRing& ring,
                                        SyncAverage& sync) const {
  const AngleMap map = angle_map(events, tmpl);
  const auto from = static_cast<std::int64_t>(std::ceil(events.event_sample[0]));
  const auto to = static_cast<std::int64_t>(
                      std::ceil(events.event_sample[static_cast<std::size_t>(events.flutes)])) -
                  1;
  const double turn_rad = kTwoPi * static_cast<double>(events.turn);
  const std::int64_t first = std::max(from, ring.oldest());
  const std::int64_t last = std::min(to, ring.newest());
  if (last >= first) {
    // The spindle angle within this turn, in bins: the map is a line.
    const double bins_per_rad = sync.bins() / kTwoPi;
    // The ring's rows: fx, fy, fz and fx² + fy².
    sync.add_line_rows(static_cast<std::size_t>(last - first + 1),
                       (map.at(static_cast<double>(first)) - turn_rad) * bins_per_rad,
                       map.slope_rad_per_sample * bins_per_rad,
                       [rows = ring.rows(), first](std::size_t i) {
                         return rows.row(first + static_cast<std::int64_t>(i));
                       });
  }
  sync.end_revolution();
}

bool RevolutionAnalyzer::model_revolution(const RevolutionEvents& events,
                                          const ToothEventTemplate& tmpl, const AngleMap& map,
                                          const Lockstep& model, RevolutionRecord& out) {
  // Only a turn whose own events were all found: a predicted one would set the searches and
  // windows of every later turn.
  if (keep_ && events.valid && events.bounded) {
    KeptModelRevolution& k = kept_;
    if (!k.holds(model.revision(), tmpl)) {
      k.revision = model.revision();
      k.tmpl = tmpl;
      k.turns = 0;
    }
    if (k.turns < kKeptTurns) {
      // This turn's model revolution once more, moved by a fraction of a sample so that the
      // model's event 0 falls at the sub-sample phase (t + ½)/8 on the kept one's t-th turn:
      // what is kept then stands for every phase alike (a turn's own phase may move slowly).
      const double phase = (k.turns + 0.5) / kKeptTurns;
      double shift = events.event_sample[0] - phase;
      shift -= std::floor(shift);
      if (measure_model(events, tmpl, map, model, shift, shifted_) && shifted_.valid) {
        remember_model_revolution(events, map, shifted_);
      }
    }
  }
  return measure_model(events, tmpl, map, model, 0.0, out.model);
}

bool RevolutionAnalyzer::measure_model(const RevolutionEvents& measured,
                                       const ToothEventTemplate& tmpl, const AngleMap& measured_map,
                                       const Lockstep& model, double shift,
                                       RevolutionMeasurement& mm) {
  // The rows hold the model at the angles of samples s + shift: the events move by −shift in
  // them, and back after.
  RevolutionEvents events = measured;
  for (std::size_t k = 0; k <= static_cast<std::size_t>(measured.flutes); ++k) {
    events.event_sample[k] -= shift;
    events.boundary_sample[k] -= shift;
  }
  AngleMap map = measured_map;
  map.intercept_rad += shift * map.slope_rad_per_sample;
  const int flutes = events.flutes;
  const auto n = static_cast<std::size_t>(flutes);
  const double span = events.event_sample[n] - events.event_sample[0];
  const double pitch = span / flutes;
  const auto half = static_cast<std::int64_t>(std::ceil(search_fraction_ * pitch));
  const int fit = std::max(2, static_cast<int>(std::lround(pitch / 7.0)));
  const std::int64_t pad = half + 3 * fit + 2;
  first_ = static_cast<std::int64_t>(
               std::floor(std::min(events.boundary_sample[0], events.event_sample[0]))) -
           pad;
  const std::int64_t last = static_cast<std::int64_t>(std::ceil(events.event_sample[n])) + pad;
  if (last - first_ + 1 > static_cast<std::int64_t>(model_rows_.size() / kModelRow) ||
      !(span > 0.0)) {
    return false;
  }
  model.forces_on_line(map.at(static_cast<double>(first_)), map.slope_rad_per_sample,
                       static_cast<std::size_t>(last - first_ + 1), model_rows_.data());
  const auto row = [&](std::int64_t s) { return model_row(s); };
  const auto detect = [&](std::int64_t s) { return model_row(s)[3]; };
  // Where the model's force pauses between the flutes, its valleys are the pauses' middles
  // (find_quiet_middle()); the quiet level is the tooth-event template's, on the resultant.
  double quiet = -1.0;
  if (tmpl.kind == ToothEventKind::kValley) {
    double lowest = detect(first_), highest = lowest;
    for (std::int64_t s = first_ + 1; s <= last; ++s) {
      lowest = std::min(lowest, detect(s));
      highest = std::max(highest, detect(s));
    }
    if (highest > lowest) {
      const double floor = std::sqrt(std::max(0.0, lowest));
      const double level = floor + kQuietFraction * (std::sqrt(highest) - floor);
      quiet = level * level;
    }
  }
  mm.flutes = flutes;
  mm.sequence = events.sequence;
  mm.valid = true;
  for (int k = 0; k <= flutes; ++k) {
    const auto uk = static_cast<std::size_t>(k);
    const double lead = events.event_sample[uk] - events.boundary_sample[uk];
    EventSearch e;
    if (tmpl.kind == ToothEventKind::kCentroid) {
      const double next_lead =
          k < flutes ? events.event_sample[uk + 1] - events.boundary_sample[uk + 1] : lead;
      const double to = k < flutes ? events.event_sample[uk + 1] - next_lead
                                   : events.event_sample[uk] + pitch - lead;
      e = find_centroid(detect, first_, last, events.boundary_sample[uk], to);
    } else {
      if (quiet >= 0.0) {
        e = find_quiet_middle(detect, first_, last, events.event_sample[uk], half, quiet,
                              kQuietPitch * pitch);
      }
      if (e.status != EventSearch::Status::kFound) {
        e = find_valley(detect, first_, last, events.event_sample[uk], half, fit);
      }
    }
    const bool found = e.status == EventSearch::Status::kFound;
    mm.event_sample[uk] = found ? e.position : events.event_sample[uk];
    mm.boundary_sample[uk] = mm.event_sample[uk] - lead;
    mm.valid = mm.valid && found;
  }
  // A pulse's window opens its lead before the centroid: a model pulse far earlier than the
  // measured one would open it before the rows computed (none of the measured revolution's).
  if (std::ceil(mm.boundary_sample[0]) < static_cast<double>(first_) ||
      std::floor(mm.boundary_sample[n]) > static_cast<double>(last)) {
    return false;
  }
  measure_revolution(row, sample_rate_hz_, mm);
  for (std::size_t k = 0; k <= n; ++k) {
    mm.event_sample[k] += shift;
    mm.boundary_sample[k] += shift;
  }
  return true;
}

void RevolutionAnalyzer::remember_model_revolution(const RevolutionEvents& events,
                                                   const AngleMap& map,
                                                   const RevolutionMeasurement& mm) {
  KeptModelRevolution& k = kept_;
  const auto t = static_cast<std::size_t>(k.turns);
  const double turn_rad = kTwoPi * static_cast<double>(events.turn);
  for (std::size_t j = 0; j <= static_cast<std::size_t>(mm.flutes); ++j) {
    k.event_rad[t][j] = map.at(mm.event_sample[j]) - turn_rad;
    k.boundary_rad[t][j] = map.at(mm.boundary_sample[j]) - turn_rad;
  }
  k.measured[t] = mm;
  if (++k.turns == kKeptTurns) {
    k.keep();
  }
}

void RevolutionAnalyzer::KeptModelRevolution::keep() {
  // The mean of the middle half of the turns' values: the phases' mean, without a search that
  // went astray.
  const auto middle_mean = [](const auto& value) {
    std::array<double, kKeptTurns> v{};
    for (std::size_t t = 0; t < v.size(); ++t) {
      v[t] = value(t);
    }
    std::sort(v.begin(), v.end());
    double sum = 0.0;
    for (std::size_t t = v.size() / 4; t < v.size() - v.size() / 4; ++t) {
      sum += v[t];
    }
    return sum / static_cast<double>(v.size() - 2 * (v.size() / 4));
  };
  const auto n = static_cast<std::size_t>(tmpl.flutes);
  kept = RevolutionMeasurement{};
  kept.flutes = tmpl.flutes;
  for (std::size_t j = 0; j < n; ++j) {
    kept_event_rad[j] = middle_mean([&](std::size_t t) { return event_rad[t][j]; });
    kept_boundary_rad[j] = middle_mean([&](std::size_t t) { return boundary_rad[t][j]; });
    for (std::size_t c = 0; c < 3; ++c) {
      kept.peak_N[j][c] = middle_mean([&](std::size_t t) { return measured[t].peak_N[j][c]; });
      kept.range_N[j][c] = middle_mean([&](std::size_t t) { return measured[t].range_N[j][c]; });
    }
    kept.peak_resultant_N[j] =
        middle_mean([&](std::size_t t) { return measured[t].peak_resultant_N[j]; });
  }
  kept.delta_fy_N = middle_mean([&](std::size_t t) { return measured[t].delta_fy_N; });
  // The model repeats: its event N is its event 0 a turn on (found on samples at another
  // sub-sample phase, it would put each later period off by that search's rounding).
  kept_event_rad[n] = kept_event_rad[0] + kTwoPi;
  kept_boundary_rad[n] = kept_boundary_rad[0] + kTwoPi;
  kept.valid = true;
  kept.bounded = true;
}

bool RevolutionAnalyzer::model_revolution_again(const RevolutionEvents& events, const AngleMap& map,
                                                const Lockstep& model, RevolutionRecord& out) {
  if (!(map.slope_rad_per_sample > 0.0)) {
    return false;
  }
  RevolutionMeasurement& mm = out.model;
  mm = kept_.kept;
  mm.sequence = events.sequence;
  // The model's events where this revolution's angle map puts their angles; its forces are
  // those of any turn (the model repeats), its periods follow this revolution's speed.
  const double turn_rad = kTwoPi * static_cast<double>(events.turn);
  const auto ux = static_cast<std::size_t>(mm.flutes);
  for (std::size_t k = 0; k <= ux; ++k) {
    mm.event_sample[k] = map.sample_at(kept_.kept_event_rad[k] + turn_rad);
    mm.boundary_sample[k] = map.sample_at(kept_.kept_boundary_rad[k] + turn_rad);
  }
  measure_periods(sample_rate_hz_, mm);
  // The rows the residuals read: the measured revolution's windows.
  const RevolutionMeasurement& m = out.measured;
  first_ = static_cast<std::int64_t>(std::ceil(m.boundary_sample[0]));
  const auto last = static_cast<std::int64_t>(std::floor(m.boundary_sample[ux]));
  if (last < first_ ||
      last - first_ + 1 > static_cast<std::int64_t>(model_rows_.size() / kModelRow)) {
    mm.valid = false;
    return false;
  }
  model.forces_on_line(map.at(static_cast<double>(first_)), map.slope_rad_per_sample,
                       static_cast<std::size_t>(last - first_ + 1), model_rows_.data());
  return true;
}

void RevolutionAnalyzer::residuals(const RevolutionMeasurement& m, const SampleRing& ring,
                                   const AngleMap& map, RevolutionRecord& out) const {
  const auto n_flutes = static_cast<std::size_t>(m.flutes);
  const auto from = static_cast<std::int64_t>(std::ceil(m.boundary_sample[0]));
  const auto to = static_cast<std::int64_t>(std::floor(m.boundary_sample[n_flutes]));
  if (from < ring.oldest() || to > ring.newest() || to <= from) {
    return;
  }
  std::array<double, kMaxFlutes> flute_sum{};
  std::array<int, kMaxFlutes> flute_n{};
  std::array<double, kMaxSectors> sector_sum{};
  std::array<int, kMaxSectors> sector_n{};
  std::size_t flute = 0;
  // The angle within the turn, [0, 2π), from the first sample's on: the map is a line.
  double start_rad = map.at(static_cast<double>(from));
  start_rad -= kTwoPi * std::floor(start_rad / kTwoPi);
  // The revolution's sums, and the current flute's and sector's run sums (two sums of the same
  // terms, reset at their own edges): a run of samples in one flute window and one sector is
  // summed in registers (residual_sums.hpp), then added to its flute's and sector's sums.
  // The kernels read four doubles a row: the ring's rows (fx, fy, fz, Fx² + Fy²) and the model's.
  static_assert(kModelRow == 4);
  ResidualSums sums;
  double& run_flute_sum = sums.flute_sector_N2[0];
  double& run_sector_sum = sums.flute_sector_N2[1];
  std::size_t run_sector = 0;
  int run_sector_n = 0;
  int run_flute_n = 0;
  const auto rows = [rows = ring.rows()](std::int64_t n) { return rows.row(n); };
  // Samples [first, last], all in one sector and one flute window.
  const auto piece = [&](std::int64_t first, std::int64_t last) {
    add_residuals(rows, model_row(first), first, last, sums);
    const auto count = static_cast<int>(last - first + 1);
    run_flute_n += count;
    run_sector_n += count;
  };
  SectorWalk(start_rad, map.slope_rad_per_sample, from, sectors_)
      .runs(to, [&](std::int64_t first, std::int64_t last, int sector) {
        const auto k = static_cast<std::size_t>(sector);
        if (k != run_sector) {
          sector_sum[run_sector] += run_sector_sum;
          sector_n[run_sector] += run_sector_n;
          run_sector = k;
          run_sector_sum = 0.0;
          run_sector_n = 0;
        }
        // The flute windows: flute j + 1's from the first sample at or after its boundary.
        for (std::int64_t s = first; s <= last;) {
          if (flute + 1 < n_flutes && static_cast<double>(s) >= m.boundary_sample[flute + 1]) {
            flute_sum[flute] += run_flute_sum;
            flute_n[flute] += run_flute_n;
            run_flute_sum = 0.0;
            run_flute_n = 0;
            while (flute + 1 < n_flutes && static_cast<double>(s) >= m.boundary_sample[flute + 1]) {
              ++flute;
            }
          }
          std::int64_t end = last;
          if (flute + 1 < n_flutes) {
            const double edge = std::ceil(m.boundary_sample[flute + 1]);
            if (edge <= static_cast<double>(last)) {
              end = std::max(s, static_cast<std::int64_t>(edge) - 1);
            }
          }
          piece(s, end);
          s = end + 1;
        }
      });
  flute_sum[flute] += run_flute_sum;
  flute_n[flute] += run_flute_n;
  sector_sum[run_sector] += run_sector_sum;
  sector_n[run_sector] += run_sector_n;
  const auto count = static_cast<double>(to - from + 1);
  for (std::size_t a = 0; a < 3; ++a) {
    out.residual_rms_N[a] = std::sqrt(sums.sums_N2[a] / count);
  }
  out.measured_rms_N = std::sqrt(sums.sums_N2[3] / count);
  for (std::size_t j = 0; j < n_flutes; ++j) {
    out.residual_flute_rms_N[j] = flute_n[j] > 0 ? std::sqrt(flute_sum[j] / flute_n[j]) : 0.0;
  }
  out.sectors = sectors_;
  for (std::size_t s = 0; s < static_cast<std::size_t>(sectors_); ++s) {
    out.residual_sector_rms_N[s] = sector_n[s] > 0 ? std::sqrt(sector_sum[s] / sector_n[s]) : 0.0;
  }
  out.model_valid = true;
}

}  // namespace millwatch::monitor
