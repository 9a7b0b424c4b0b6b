#include "shell/run_recorder.hpp"

#include <charconv>
#include <cmath>
#include <numbers>

namespace millwatch::shell {
namespace {

constexpr std::size_t kMaxRowsKept = 200000;

void append_number(std::string& s, double v) {
  if (!std::isfinite(v)) {
    return;  // empty field (CSV) — JSON writers check first
  }
  char text[32];
  const auto r = std::to_chars(text, text + sizeof text, v);
  s.append(text, r.ptr);
}

void append_json_number(std::string& s, double v) {
  if (!std::isfinite(v)) {
    s += "null";
  } else {
    append_number(s, v);
  }
}

}  // namespace

RunRecorder::RunRecorder(int flutes, const std::filesystem::path& revolutions_path,
                         bool keep_for_plots)
    : flutes_(flutes), keep_(keep_for_plots) {
  if (!revolutions_path.empty()) {
    jsonl_ = revolutions_path.extension() == ".jsonl";
    file_ = std::make_unique<OutputFile>(revolutions_path);
    write_header();
  }
}

void RunRecorder::write_header() {
  if (jsonl_) {
    return;
  }
  std::string h = "revolution,t_s,spindle_rpm,valid,cutting";
  for (int j = 1; j <= flutes_; ++j) {
    h += ",period_s_" + std::to_string(j);
  }
  h += ",alpha_deg";
  for (int j = 1; j <= flutes_; ++j) {
    const std::string f = std::to_string(j);
    h += ",peak_fx_N_" + f + ",peak_fy_N_" + f + ",peak_fz_N_" + f + ",peak_resultant_N_" + f;
  }
  h += ",delta_fy_N,residual_rms_fx_N,residual_rms_fy_N,residual_rms_fz_N,alerts,lock,labelling\n";
  file_->write(h);
}

std::string RunRecorder::active_alerts() const {
  std::string s;
  for (std::size_t k = 0; k < active_.size(); ++k) {
    if (active_[k]) {
      if (!s.empty()) {
        s += ';';
      }
      s += monitor::to_string(static_cast<monitor::AlertKind>(k));
    }
  }
  return s;
}

void RunRecorder::on_revolution(const monitor::RevolutionRecord& r) {
  const auto& m = r.measured;
  const int flutes = std::min(flutes_, monitor::kMaxFlutes);
  // Divided, not multiplied by 1e-6: 14694 µs is written 0.014694, not 0.014693999999999999.
  const double t_s = static_cast<double>(r.utime_us) / 1e6;
  const double nan = std::nan("");
  // As in the summary: periods, α and ΔFy need every tooth event (valid); each flute's peaks
  // only the revolution's bounds, both CE1 events (a flute that did not cut peaks near 0).
  auto valid_or_nan = [&](double v) { return m.valid ? v : nan; };
  // With one flute α is 360° and ΔFy 0 by definition: absent, as in the summary ("no alpha").
  const double alpha_deg = flutes > 1 ? valid_or_nan(m.alpha_deg) : nan;
  const double delta_fy_N = flutes > 1 ? valid_or_nan(m.delta_fy_N) : nan;
  auto bounded_or_nan = [&](double v) { return m.bounded ? v : nan; };
  const double rpm = r.spindle_rpm > 0.0 ? r.spindle_rpm : nan;  // 0: not measured
  if (file_) {
    std::string& s = line_;
    s.clear();
    const std::string alerts = active_alerts();
    if (jsonl_) {
      s += "{\"revolution\":" + std::to_string(r.revolution) + ",\"t_s\":";
      append_json_number(s, t_s);
      s += ",\"spindle_rpm\":";
      append_json_number(s, rpm);
      s += std::string(",\"valid\":") + (m.valid ? "true" : "false") +
           ",\"cutting\":" + (cutting_ ? "true" : "false") + ",\"period_s\":[";
      for (int j = 0; j < flutes; ++j) {
        s += j > 0 ? "," : "";
        append_json_number(s, valid_or_nan(m.flute_period_s[static_cast<std::size_t>(j)]));
      }
      s += "],\"alpha_deg\":";
      append_json_number(s, alpha_deg);
      const char* axes[] = {"fx", "fy", "fz"};
      s += ",\"peak_N\":{";
      for (std::size_t a = 0; a < 3; ++a) {
        s += std::string(a > 0 ? "," : "") + "\"" + axes[a] + "\":[";
        for (int j = 0; j < flutes; ++j) {
          s += j > 0 ? "," : "";
          append_json_number(s, bounded_or_nan(m.peak_N[static_cast<std::size_t>(j)][a]));
        }
        s += "]";
      }
      s += ",\"resultant\":[";
      for (int j = 0; j < flutes; ++j) {
        s += j > 0 ? "," : "";
        append_json_number(s, bounded_or_nan(m.peak_resultant_N[static_cast<std::size_t>(j)]));
      }
      s += "]},\"delta_fy_N\":";
      append_json_number(s, delta_fy_N);
      s += ",\"residual_rms_N\":";
      if (r.model_valid) {
        s += "{\"fx\":";
        append_json_number(s, r.residual_rms_N[0]);
        s += ",\"fy\":";
        append_json_number(s, r.residual_rms_N[1]);
        s += ",\"fz\":";
        append_json_number(s, r.residual_rms_N[2]);
        s += "}";
      } else {
        s += "null";
      }
      s += ",\"alerts\":[";
      std::size_t from = 0;
      while (from < alerts.size()) {
        const auto to = std::min(alerts.find(';', from), alerts.size());
        s += std::string(from > 0 ? "," : "") + "\"" + alerts.substr(from, to - from) + "\"";
        from = to + 1;
      }
      s += "],\"lock\":" + std::to_string(lock_) + ",\"labelling\":" + std::to_string(labelling_) +
           "}\n";
    } else {
      s += std::to_string(r.revolution) + ",";
      append_number(s, t_s);
      s += ",";
      append_number(s, rpm);
      s += std::string(",") + (m.valid ? "1" : "0") + "," + (cutting_ ? "1" : "0");
      for (int j = 0; j < flutes; ++j) {
        s += ",";
        append_number(s, valid_or_nan(m.flute_period_s[static_cast<std::size_t>(j)]));
      }
      s += ",";
      append_number(s, alpha_deg);
      for (int j = 0; j < flutes; ++j) {
        const auto uj = static_cast<std::size_t>(j);
        for (std::size_t a = 0; a < 3; ++a) {
          s += ",";
          append_number(s, bounded_or_nan(m.peak_N[uj][a]));
        }
        s += ",";
        append_number(s, bounded_or_nan(m.peak_resultant_N[uj]));
      }
      s += ",";
      append_number(s, delta_fy_N);
      for (std::size_t a = 0; a < 3; ++a) {
        s += ",";
        append_number(s, r.model_valid ? r.residual_rms_N[a] : nan);
      }
      s += "," + alerts + "," + std::to_string(lock_) + "," + std::to_string(labelling_) + "\n";
    }
    file_->write(s);
    ++written_;
  }
  if (keep_) {
    if (rows_.size() >= kMaxRowsKept) {  // thin out: every other row, half as many from now
      std::size_t k = 0;
      for (std::size_t i = 0; i < rows_.size(); i += 2) {
        rows_[k++] = rows_[i];
      }
      rows_.resize(k);
      stride_ *= 2;
    }
    if (r.revolution % static_cast<std::int64_t>(stride_) == 0) {
      Row row;
      row.revolution = r.revolution;
      row.t_s = t_s;
      row.spindle_rpm = rpm;
      row.valid = m.valid;
      row.bounded = m.bounded;
      row.alpha_deg = alpha_deg;
      row.delta_fy_N = delta_fy_N;
      for (int j = 0; j < flutes; ++j) {
        row.peak_resultant_N[static_cast<std::size_t>(j)] =
            m.peak_resultant_N[static_cast<std::size_t>(j)];
      }
      rows_.push_back(row);
    }
  }
}

void RunRecorder::on_spindle(const monitor::SpindleUpdate& u) {
  if (keep_ && u.estimate.valid && spindle_.size() < 4 * kMaxRowsKept) {
    spindle_.push_back({static_cast<double>(u.utime_us) / 1e6, u.estimate.spindle_rpm});
  }
}

void RunRecorder::on_sync_average(const monitor::SyncAverage& measured,
                                  const monitor::Lockstep* model, std::int64_t revolution,
                                  std::int64_t /*utime_us*/) {
  if (!keep_ || measured.revolutions() == 0) {
    return;
  }
  const int bins = measured.bins();
  sync_.revolution = revolution;
  sync_.window_revolutions = measured.revolutions();
  sync_.model_valid = model != nullptr;
  for (std::size_t a = 0; a < 3; ++a) {
    // The whole grid at once: a bin no sample reached takes its neighbours' mean (bin by bin it
    // would read 0, a spike to zero in the plot).
    measured.average(static_cast<int>(a), sync_.measured[a]);
    sync_.model[a].assign(static_cast<std::size_t>(bins), std::nan(""));
  }
  for (int b = 0; b < bins; ++b) {
    const auto ub = static_cast<std::size_t>(b);
    if (model != nullptr) {
      const auto m = model->force_at(2.0 * std::numbers::pi * b / bins);
      for (std::size_t a = 0; a < 3; ++a) {
        sync_.model[a][ub] = m[a];
      }
    }
  }
}

void RunRecorder::on_alert(const monitor::Alert& a) {
  const auto k = static_cast<std::size_t>(a.kind);
  if (k < active_.size()) {
    active_[k] = a.active;
  }
}

void RunRecorder::on_event(const monitor::PipelineEvent& e) {
  if (e.kind == monitor::PipelineEventKind::kFlutesRelabelled) {
    ++labelling_;  // the revolutions from the next lock on name their flutes from a new CE1
  } else if (e.kind == monitor::PipelineEventKind::kCuttingStopped) {
    cutting_ = false;
  } else if (e.kind == monitor::PipelineEventKind::kCuttingResumed ||
             e.kind == monitor::PipelineEventKind::kLockAcquired) {
    lock_ += e.kind == monitor::PipelineEventKind::kLockAcquired ? 1 : 0;
    cutting_ = true;  // a lock needs a cutting force: the pipeline is no longer idle after it
  }
}

void RunRecorder::add_samples(const monitor::SampleBlock& b) {
  if (!keep_ || raw_done_ || b.fx_N.empty()) {
    return;
  }
  if (raw_rate_hz_ == 0.0) {
    raw_rate_hz_ = b.sample_rate_hz;
  }
  if (b.sample_rate_hz != raw_rate_hz_ || raw_[0].size() >= kSpectrumSamples) {
    raw_done_ = true;
    return;
  }
  const std::size_t n = std::min(b.fx_N.size(), kSpectrumSamples - raw_[0].size());
  raw_[0].insert(raw_[0].end(), b.fx_N.begin(), b.fx_N.begin() + static_cast<std::ptrdiff_t>(n));
  raw_[1].insert(raw_[1].end(), b.fy_N.begin(), b.fy_N.begin() + static_cast<std::ptrdiff_t>(n));
  raw_[2].insert(raw_[2].end(), b.fz_N.begin(), b.fz_N.begin() + static_cast<std::ptrdiff_t>(n));
}

void RunRecorder::commit() {
  if (file_) {
    file_->commit();
  }
}

}  // namespace millwatch::shell
