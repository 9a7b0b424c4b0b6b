#include "replay/simulate_command.hpp"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <string>
#include <vector>

#include "core/config/json_reader.hpp"
#include "core/model/flute_positions.hpp"
#include "core/model/steady_state.hpp"
#include "core/monitor/monitor_config.hpp"
#include "core/sim/channel_stats.hpp"
#include "core/sim/cut_simulator.hpp"
#include "replay/stop_signal.hpp"
#include "shell/json_file.hpp"
#include "shell/output_file.hpp"

namespace millwatch::shell {
namespace {

/// What the played steady states were like, in words: what of the record is not the model's
/// steady state revolution by revolution (empty: all of it is).
std::vector<std::string> steady_state_notes(const sim::PlayedSteadyStates& p,
                                            long revolutions_round_again) {
  std::vector<std::string> notes;
  if (revolutions_round_again > 0) {
    notes.push_back(fmt::format(
        "the model's cycle (the least common multiple of its slots' periods) outgrew {} "
        "revolutions: {} revolutions of the record play the first {} round again, each exact "
        "away from the seams between rounds",
        model::kMaxCycleRevolutions, revolutions_round_again, model::kMaxCycleRevolutions));
  }
  if (p.unsettled_slots > 0) {
    notes.push_back(fmt::format(
        "{} of {} slots (disc, immersion) did not repeat within {} revolutions (accumulation "
        "without a period): their state at the last of them is played",
        p.unsettled_slots, p.slots, model::kMaxSlotRevolutions));
  }
  return notes;
}

nlohmann::json truth_json(const sim::Scenario& s, const sim::CutSimulator& simulator) {
  nlohmann::json rev;
  std::vector<double> start, rpm, ft, offset, angle;
  std::vector<std::vector<double>> wear;
  std::vector<bool> cutting;
  double rpm_sum = 0.0;
  int cutting_revs = 0;
  long round_again = 0;
  for (const auto& t : simulator.truth()) {
    if (t.start_s > s.duration_s) {
      break;  // prepared ahead, never reached
    }
    start.push_back(t.start_s);
    rpm.push_back(t.spindle_rpm);
    ft.push_back(t.feed_per_tooth_um);
    offset.push_back(t.runout_offset_um);
    angle.push_back(t.runout_angle_rad);
    wear.push_back(t.wear_um);
    cutting.push_back(t.cutting);
    round_again += t.round_again ? 1 : 0;
    if (t.cutting) {
      rpm_sum += t.spindle_rpm;
      ++cutting_revs;
    }
  }
  const auto& r = s.model.effects.runout;
  const sim::PlayedSteadyStates& played = simulator.played_steady_states();
  return {
      {"spindle_rpm_actual", sim::actual_rpm(s)},
      {"model_steady_state",
       {{"evaluations", played.evaluations},
        {"cycles_cut", played.cycles_cut},
        {"revolutions_round_again", round_again},
        {"longest_cycle_revolutions", played.longest_cycle_revolutions},
        {"unsettled_slots", played.unsettled_slots},
        {"slots", played.slots},
        {"notes", steady_state_notes(played, round_again)}}},
      {"spindle_rpm_mean_while_cutting", cutting_revs > 0 ? rpm_sum / cutting_revs : 0.0},
      {"runout", {{"enabled", r.enabled}, {"offset_um", r.offset_um}, {"angle_rad", r.angle_rad}}},
      {"revolutions",
       {{"start_s", start},
        {"spindle_rpm", rpm},
        {"feed_per_tooth_um", ft},
        {"runout_offset_um", offset},
        {"runout_angle_rad", angle},
        {"wear_um", wear},
        {"cutting", cutting}}}};
}

/// The sidecar's truth: the truth without its per-revolution arrays (most of it: ~60 kB a
/// second of cut, which every replay of the cut would read for nothing), and where they are.
nlohmann::json truth_summary_json(nlohmann::json truth, const std::string& truth_file_name) {
  truth.erase("revolutions");
  truth["revolutions_file"] = truth_file_name;
  return truth;
}

nlohmann::json sidecar_json(const sim::Scenario& s, const sim::CutSimulator& simulator,
                            const nlohmann::json& truth_summary, const std::string& csv_name) {
  const nlohmann::json model = model::to_json(s.model);
  return {{"format", "millwatch-cut/1"},
          {"csv", csv_name},
          {"columns", {"t_s", "fx_N", "fy_N", "fz_N"}},
          {"samples", simulator.samples_done()},
          {"sample_rate_hz", s.sample_rate_hz},
          {"duration_s", static_cast<double>(simulator.samples_done()) / s.sample_rate_hz},
          {"tool", model["tool"]},
          {"process", model["process"]},
          {"material", model["material"]},
          {"force_sign_convention",
           {{"columns",
             "what a dynamometer under the workpiece reads: the force on the workpiece, i.e. minus "
             "the force on the tool, in its own channel order"},
            {"model_frame",
             "force on the tool; x feed, y cross-feed, z from the workpiece towards the spindle"},
            {"axis_map", signal::to_json(s.axis_map)},
            {"axis_map_meaning", "model[axis] = sign * column[channel]"}}},
          {"model", model},
          {"truth", truth_summary},
          {"scenario", sim::to_json(s)}};
}

/// Says so when `millwatch replay` would refuse the recording as its sidecar describes it
/// (a sample rate too low for the monitor's default low-pass, a spindle window the speed does
/// not suit): the recording is written all the same, a --config can replay it.
void warn_if_replay_refuses(const nlohmann::json& sidecar, const std::filesystem::path& path) {
  try {
    (void)monitor::monitor_config_from_json(monitor::monitor_json_from_sidecar(sidecar));
  } catch (const std::exception& e) {  // a ConfigError naming the value, or a sidecar fault
    spdlog::warn(
        "{}: replay will refuse this recording as its sidecar describes it ({}); set "
        "the value in replay's --config",
        path.string(), e.what());
  }
}

/// `steady_state`: the truth's model_steady_state.
void print_summary(const sim::Scenario& s, const sim::CutSimulator& simulator,
                   const sim::ChannelStats& clean, const nlohmann::json& steady_state,
                   const std::string& csv_path, const std::string& sidecar_path,
                   const std::string& truth_path) {
  const auto& m = s.model;
  const auto pitch = model::flute_pitch_angles_rad(m.tool);
  const auto& r = m.effects.runout;
  const auto flutes =
      model::flute_positions(m.tool.diameter_mm * 500.0, pitch, r.enabled ? r.offset_um : 0.0,
                             r.enabled ? r.angle_rad : 0.0);
  std::printf("simulated cut \"%s\"\n", s.name.c_str());
  std::printf("  tool            %.3f mm, %d flutes, helix %.0f deg; %s, a_p %.3f mm\n",
              m.tool.diameter_mm, m.tool.flutes, m.tool.helix_deg,
              model::to_string(m.process.operation).c_str(), m.process.axial_depth_mm);
  std::printf(
      "  spindle         %.0f rpm commanded, %.0f rpm actual; feed %.2f um/tooth commanded\n",
      m.process.spindle_rpm, sim::actual_rpm(s), m.process.feed_per_tooth_um);
  std::printf("  runout          %.2f um at %.2f rad: flute radii", r.enabled ? r.offset_um : 0.0,
              r.enabled ? r.angle_rad : 0.0);
  for (const auto& f : flutes) {
    std::printf(" %.3f", f.radius_um);
  }
  std::printf(" um\n");
  // The turns the record holds, each revolution the truth describes counted by the part of it
  // inside the record (a 1 ms record at 25,252 rpm: 0.42, where "1 revolutions" had been said);
  // a ramp's or a stop's revolutions by their own lengths.
  const double duration_s = static_cast<double>(simulator.samples_done()) / s.sample_rate_hz;
  const auto& truth = simulator.truth();
  double turns = 0.0;
  for (std::size_t i = 0; i < truth.size() && truth[i].start_s < duration_s; ++i) {
    const double end_s = i + 1 < truth.size() ? truth[i + 1].start_s
                         : truth[i].spindle_rpm > 0.0
                             ? truth[i].start_s + 60.0 / truth[i].spindle_rpm
                             : truth[i].start_s;
    const double length_s = end_s - truth[i].start_s;
    turns += length_s > 0.0 ? std::min(1.0, (duration_s - truth[i].start_s) / length_s) : 0.0;
  }
  std::printf("  recording       %lld samples at %.0f Hz = %.3f s, %.*f revolution%s\n",
              static_cast<long long>(simulator.samples_done()), s.sample_rate_hz, duration_s,
              turns < 10.0 ? 2 : 0, turns, turns == 1.0 ? "" : "s");
  std::printf(
      "  force on tool   peak |Fxy| %.3f N; Fx [%.3f, %.3f] Fy [%.3f, %.3f] Fz [%.3f, %.3f] N\n",
      clean.peak_resultant_xy(), clean.min(0), clean.max(0), clean.min(1), clean.max(1),
      clean.min(2), clean.max(2));
  const int longest = steady_state["longest_cycle_revolutions"].get<int>();
  std::printf("  model cycle     %d revolution%s, the longest played\n", longest,
              longest == 1 ? "" : "s");
  for (const auto& note : steady_state["notes"]) {
    std::printf("  note            %s\n", note.get<std::string>().c_str());
  }
  std::printf("  wrote           %s\n                  %s\n                  %s\n",
              csv_path.c_str(), sidecar_path.c_str(), truth_path.c_str());
}

}  // namespace

int run_simulate(const SimulateOptions& o) {
  sim::Scenario scenario;
  // The overrides go into the scenario before it is read, so that they are checked as the
  // file's own values are (a duration beyond the limit, a ramp past the record's end).
  std::string overridden;
  try {
    nlohmann::json j = read_json_file(o.scenario_path);
    if (j.is_object() && o.duration_s > 0.0) {
      j["recording"]["duration_s"] = o.duration_s;
      overridden += fmt::format(" --duration {}", o.duration_s);
    }
    if (j.is_object() && o.seed >= 0) {
      j["recording"]["seed"] = o.seed;
      overridden += fmt::format(" --seed {}", o.seed);
    }
    scenario = sim::scenario_from_json(j);
  } catch (const config::ConfigError& e) {
    spdlog::error("{}{}: {}", o.scenario_path, overridden.empty() ? "" : " with" + overridden,
                  e.what());
    return 2;
  } catch (const std::exception& e) {
    spdlog::error("{}", e.what());
    return 2;
  }
  const std::filesystem::path csv_path = o.output_csv;
  std::filesystem::path sidecar_path = csv_path;
  sidecar_path.replace_extension(".json");
  if (sidecar_path == csv_path) {
    sidecar_path += ".json";
  }
  std::filesystem::path truth_path = o.truth_json;
  if (truth_path.empty()) {
    truth_path = csv_path;
    truth_path.replace_extension(".truth.json");
  }
  // One file by two names (./cut.csv and cut.csv, a hard link): the same file.
  const auto same_file = [](const std::filesystem::path& a, const std::filesystem::path& b) {
    std::error_code ec_a, ec_b;
    if (std::filesystem::equivalent(a, b, ec_a)) {
      return true;
    }
    const auto canonical_a = std::filesystem::weakly_canonical(a, ec_a);
    const auto canonical_b = std::filesystem::weakly_canonical(b, ec_b);
    return !ec_a && !ec_b ? canonical_a == canonical_b : a == b;
  };
  if (same_file(truth_path, csv_path) || same_file(truth_path, sidecar_path)) {
    spdlog::error("--truth-json {}: the CSV and its sidecar go there", truth_path.string());
    return 2;
  }
  // `simulate cut.json -o cut.csv` would write the sidecar over the scenario it reads.
  for (const auto& [output, what] :
       {std::pair{csv_path, "the CSV"}, std::pair{sidecar_path, "its sidecar"},
        std::pair{truth_path, "the truth"}}) {
    if (same_file(output, o.scenario_path)) {
      if (output == truth_path && !o.truth_json.empty()) {
        spdlog::error("--truth-json {}: the scenario being read; name the truth file otherwise",
                      truth_path.string());
        return 2;
      }
      spdlog::error(
          "-o {}: {} would go to {}, the scenario being read: name the output "
          "otherwise (e.g. -o {})",
          csv_path.string(), what, output.string(),
          (csv_path.parent_path() / (csv_path.stem().string() + "_cut.csv")).string());
      return 2;
    }
  }

  install_stop_signals();
  try {
    sim::CutSimulator simulator(scenario);
    OutputFile csv(csv_path);
    OutputFile sidecar(sidecar_path);
    OutputFile truth_file(truth_path);
    std::fputs("t_s,fx_N,fy_N,fz_N\n", csv.stream());
    constexpr std::size_t kBlock = 4096;
    std::vector<double> t(kBlock), fx(kBlock), fy(kBlock), fz(kBlock);
    while (!stop_requested()) {
      const std::size_t n = simulator.next_block(t, fx, fy, fz);
      if (n == 0) {
        break;
      }
      for (std::size_t i = 0; i < n; ++i) {
        std::fprintf(csv.stream(), "%.9f,%.6g,%.6g,%.6g\n", t[i], fx[i], fy[i], fz[i]);
      }
    }
    if (stop_requested()) {
      spdlog::error("interrupted: no output written");
      return 130;
    }
    const nlohmann::json truth = truth_json(scenario, simulator);
    truth_file.write(truth.dump(2) + "\n");
    // The sidecar names the truth file relative to itself when they share a folder.
    const std::string truth_name = truth_path.parent_path() == sidecar_path.parent_path()
                                       ? truth_path.filename().string()
                                       : std::filesystem::absolute(truth_path).string();
    const nlohmann::json side = sidecar_json(
        scenario, simulator, truth_summary_json(truth, truth_name), csv_path.filename().string());
    sidecar.write(side.dump(2) + "\n");
    csv.commit();
    sidecar.commit();
    truth_file.commit();
    warn_if_replay_refuses(side, sidecar_path);
    print_summary(scenario, simulator, simulator.clean_stats(), truth["model_steady_state"],
                  csv_path.string(), sidecar_path.string(), truth_path.string());
  } catch (const config::ConfigError& e) {
    spdlog::error("{}: {}", o.scenario_path, e.what());
    return 2;
  } catch (const std::exception& e) {
    spdlog::error("{}", e.what());
    return 1;
  }
  return 0;
}

}  // namespace millwatch::shell
