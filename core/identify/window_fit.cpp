#include "core/identify/window_fit.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <nlohmann/json.hpp>
#include <numbers>
#include <random>
#include <stdexcept>
#include <string>
#include <utility>

#include "core/model/dynamometer.hpp"
#include "core/model/flute_positions.hpp"
#include "core/model/parameter_map.hpp"
#include "core/model/steady_state.hpp"
#include "core/signal/real_spectrum.hpp"

namespace millwatch::identify {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kTwoPi = 2.0 * kPi;

/// e^{−2πi·m/n} for m = 0..n−1: the turns of a DFT of n points, for sums that take entry k·t mod
/// n instead of a sine and a cosine per term.
std::vector<std::complex<double>> unit_turns(std::size_t n) {
  std::vector<std::complex<double>> turn(n);
  for (std::size_t m = 0; m < n; ++m) {
    turn[m] = std::polar(1.0, -kTwoPi * static_cast<double>(m) / static_cast<double>(n));
  }
  return turn;
}

double wrap_pi(double a) {
  return a - kTwoPi * std::round(a / kTwoPi);
}

/// The flute that cuts least in a model: which, whether it cuts nothing (idle), and its largest
/// chip as a share of the largest flute's.
struct LeastCutting {
  int flute = -1;
  bool idle = false;
  double share = 1.0;
};

/// The model's settings a fit runs with: the variants of the systematic estimate change these.
struct Setting {
  int steps = 720;
  int fewer_harmonics = 0;  // harmonics left out at the top of each cut's K
  bool mean = false;        // the mean force (k = 0) compared too
  bool in_plane = false;    // fx and fy only, even where fz was measured
  int discs = 0;            // helix discs (0: as configured)
};

/// Step of the central differences, in units of each parameter's scale (0.01 µm of runout,
/// 1 mrad of alignment). Not smaller: on the angle grid the model's force moves with ρ in steps
/// too small to see in the fit but large enough to ruin a derivative taken over 1e-5 µm.
constexpr double kDifferenceStep = 1e-2;

/// The 95th percentile of χ² with one degree of freedom: a minimum whose cost exceeds the best's
/// by less than this many s² lies within the best's 95 % profile interval of some parameter —
/// the data do not reject it.
constexpr double kChiSquare1At95 = 3.841458820694124;

/// Levenberg–Marquardt on a few scaled parameters. The Jacobian by forward differences (one
/// model evaluation a parameter) while far from the optimum, by central differences (two) near
/// it, where the forward difference's O(h) error would bias where it stops; `near`: x is
/// already close (a seed, a refit), central from the first iteration. `linear`: parameters the
/// residual is nearly linear in (the coefficients under the deflection), whose forward
/// difference is as good as a central one. A column exactly zero at the first Jacobian (a
/// parameter no compared axis sees) stays zero without further evaluations.
template <typename Residual>
int levenberg_marquardt(Residual&& residual, Eigen::VectorXd& x, const Eigen::VectorXd& scale,
                        int max_iterations, double* cost_out, bool near = true,
                        const std::vector<bool>& linear = {}) {
  Eigen::VectorXd r = residual(x);
  double cost = r.squaredNorm();
  double lambda = 1e-3;
  const auto n = x.size();
  Eigen::MatrixXd j(r.size(), n);
  std::vector<bool> blind(static_cast<std::size_t>(n), false);
  bool central = near;
  int it = 0;
  for (; it < max_iterations; ++it) {
    for (Eigen::Index i = 0; i < n; ++i) {
      const auto ui = static_cast<std::size_t>(i);
      if (blind[ui]) {
        continue;
      }
      Eigen::VectorXd xp = x;
      const double h = kDifferenceStep * scale[i];
      xp[i] += h;
      if (central && !(ui < linear.size() && linear[ui])) {
        Eigen::VectorXd xm = x;
        xm[i] -= h;
        j.col(i) = (residual(xp) - residual(xm)) / (2.0 * h);
      } else {
        j.col(i) = (residual(xp) - r) / h;
      }
      blind[ui] = it == 0 && (j.col(i).array() == 0.0).all();
    }
    const Eigen::MatrixXd js = j * scale.asDiagonal();  // scaled parameters
    const Eigen::MatrixXd jtj = js.transpose() * js;
    const Eigen::VectorXd g = js.transpose() * r;
    bool improved = false;
    for (int tries = 0; tries < 10 && !improved; ++tries) {
      Eigen::MatrixXd a = jtj;
      a.diagonal() += lambda * (jtj.diagonal().array() + 1e-12).matrix();
      const Eigen::VectorXd step = -a.ldlt().solve(g);
      // Converged at the model's resolution: the Jacobian comes from differences over
      // kDifferenceStep, and on the angle grid the force moves in small jumps below it (a
      // step of 1e-4 µm in runout can double the cost near the optimum): a step far below the
      // difference step is not worth a model evaluation, nor is a negligible promised decrease.
      const double promised = -(2.0 * g.dot(step) + step.dot(jtj * step));
      if (central && (step.norm() < 0.1 * kDifferenceStep || promised < 1e-6 * cost)) {
        *cost_out = cost;
        return it;
      }
      const Eigen::VectorXd trial = x + scale.cwiseProduct(step);
      const Eigen::VectorXd rt = residual(trial);
      const double ct = rt.squaredNorm();
      if (std::isfinite(ct) && ct < cost) {
        const double relative = (cost - ct) / std::max(cost, 1e-300);
        x = trial;
        r = rt;
        cost = ct;
        lambda = std::max(lambda / 3.0, 1e-9);
        improved = true;
        if (central && (relative < 1e-5 || step.norm() < 1e-4)) {
          *cost_out = cost;
          return it + 1;
        }
        central = central || relative < 1e-3 || step.norm() < 1e-2;
      } else {
        lambda *= 4.0;
      }
    }
    if (!improved) {
      if (central) {
        break;
      }
      central = true;  // the forward difference may have pointed nowhere useful
    }
  }
  *cost_out = cost;
  return it;
}

}  // namespace

std::vector<std::complex<double>> revolution_harmonics(const std::vector<double>& x, int count) {
  const std::size_t bins = x.size();
  const auto b = static_cast<double>(bins);
  // Term n of harmonic k turns by entry k·n mod B of the table (no sine or cosine per term, and
  // no argument reduction of a large angle).
  const std::vector<std::complex<double>> turn = unit_turns(bins);
  std::vector<std::complex<double>> out(static_cast<std::size_t>(count));
  for (int k = 1; k <= count; ++k) {
    const auto step = static_cast<std::size_t>(k) % std::max<std::size_t>(bins, 1);
    double re = 0.0, im = 0.0;
    std::size_t m = 0;  // k·n mod B
    for (std::size_t n = 0; n < bins; ++n) {
      re += x[n] * turn[m].real();
      im += x[n] * turn[m].imag();
      m += step;
      m -= m >= bins ? bins : 0;
    }
    out[static_cast<std::size_t>(k - 1)] = 2.0 / b * std::complex<double>(re, im);
  }
  return out;
}

namespace {

/// The first field (JSON path) where two configurations differ, or "" when they do not.
std::string first_difference(const nlohmann::json& a, const nlohmann::json& b,
                             const std::string& path) {
  if (a.is_object() && b.is_object()) {
    for (const auto& [key, value] : a.items()) {
      const std::string where = path.empty() ? key : path + "." + key;
      if (!b.contains(key)) {
        return where;
      }
      std::string d = first_difference(value, b[key], where);
      if (!d.empty()) {
        return d;
      }
    }
    for (const auto& [key, value] : b.items()) {
      if (!a.contains(key)) {
        return path.empty() ? key : path + "." + key;
      }
    }
    return "";
  }
  return a == b ? "" : path;
}

/// What several cuts of one joint fit must share: the tool, the force law (its coefficients are
/// the starting values, the exponents are the model) and the effects (the runout's values are
/// fitted).
nlohmann::json shared_part(const model::ModelConfig& c) {
  nlohmann::json j = model::to_json(c);
  nlohmann::json out = {
      {"tool", j["tool"]}, {"material", j["material"]}, {"effects", j["effects"]}};
  out["material"].erase("name");
  out["effects"]["runout"].erase("offset_um");
  out["effects"]["runout"].erase("angle_rad");
  return out;
}

}  // namespace

struct WindowFitter::Impl {
  std::vector<model::ModelConfig> models;  // per cut, as commanded
  std::vector<FilterResponse> filters;     // per cut
  std::vector<std::string> cut_names;      // per cut, for messages
  model::ModelConfig commanded;            // the first cut's: the shared tool, law and effects
  FitOptions options;
  // Where each start solve() refined last ended (θ relabelled, the cost with the prior then
  // set): the competing minima fit() compares with the best (FitOptions::competing_minima).
  std::vector<std::pair<double, Eigen::VectorXd>> minima;
  bool separable = true;
  std::vector<std::string> coefficient_names;  // in θ when not separable
  model::ParameterMap extra_map;
  bool extra_moves_resonance = false;  // a dynamometer parameter among the extra ones
  model::ParameterMap coefficient_map;

  [[nodiscard]] int cuts() const { return static_cast<int>(models.size()); }
  /// θ = (u, v, extra..., [coefficients...], δ_0 … δ_{cuts−1}): the parameters before the
  /// alignments, shared by every cut.
  [[nodiscard]] int shared_size() const {
    return 2 + extra_map.size() + (separable ? 0 : coefficient_map.size());
  }

  // One cut's part of a problem: its measured harmonics and the model's columns.
  struct Part {
    Impl* owner = nullptr;
    int cut = 0;
    Setting setting;
    int harmonics = 0;           // K of this cut
    std::array<bool, 3> axes{};  // compared
    double rpm = 0.0;
    model::ModelConfig config;  // at the actual speed, with the trial's values
    model::SteadyStateWorkspace workspace;
    std::array<std::vector<std::complex<double>>, 3> measured;  // per axis, per entry
    // Columns: harmonics of each basis column (and the offset, last) per axis, filtered.
    std::vector<std::array<std::vector<std::complex<double>>, 3>> columns;
    std::vector<std::string> column_names;
    signal::RealSpectrum spectrum;                           // of a waveform on the model grid
    std::array<std::vector<std::complex<double>>, 3> gains;  // filter (× resonance) at k·f
    bool resonance = false;  // the dynamometer's resonance is in the gains
    std::vector<int> order;  // the spindle harmonic k of each entry (0: the mean)
    // The last evaluations, a central-difference Jacobian's worth (up to 31 parameters):
    // Levenberg–Marquardt comes back to its base point after each difference, an alignment
    // alone reuses the columns, and the Jacobian at a solution is asked for again at the same
    // points — by the second run with the runout prior, which starts where the first ended, and
    // by the covariance. With 4 entries a fit from the previous window's result (2-flute slot)
    // took 18 evaluations, with 64 it takes 11; the demo cut's replay, 3.9 s against 3.0 s.
    struct Cached {
      Eigen::VectorXd key;
      std::vector<std::array<std::vector<std::complex<double>>, 3>> columns;
    };
    static constexpr std::size_t kCached = 64;
    std::array<Cached, kCached> cache;
    std::size_t cache_next = 0;
    std::size_t cache_current = kCached;  // the entry `columns` holds (kCached: none)
    long evaluations = 0;                 // model evaluations (for the cost figures)

    void prepare(const MeasuredRevolution& m) {
      const int bins = static_cast<int>(m.force_N[0].size());
      harmonics =
          std::max(1, owner->harmonics_for(cut, m.spindle_rpm, bins) - setting.fewer_harmonics);
      axes = m.use_axis;
      if (setting.in_plane) {
        axes[2] = false;
      }
      order.clear();
      if (setting.mean) {
        order.push_back(0);
      }
      for (int k = 1; k <= harmonics; ++k) {
        order.push_back(k);
      }
      rpm = m.spindle_rpm;
      config = model::at_actual_speed(owner->models[static_cast<std::size_t>(cut)], rpm);
      // The dynamometer's resonance is linear: it joins the filter's gains per axis instead of
      // filtering every basis column in time.
      resonance = config.effects.dynamometer.enabled;
      compute_gains();
      config.effects.dynamometer.enabled = false;
      for (std::size_t a = 0; a < 3; ++a) {
        auto& out = measured[a];
        out.clear();
        if (!axes[a]) {
          continue;
        }
        auto h = revolution_harmonics(m.force_N[a], harmonics);
        if (m.shared_bins) {
          const auto b = static_cast<double>(m.force_N[a].size());
          for (int k = 1; k <= harmonics; ++k) {
            const double x = kPi * k / b;
            const double sinc = std::sin(x) / x;
            h[static_cast<std::size_t>(k - 1)] /= sinc * sinc;
          }
        }
        if (setting.mean) {
          double sum = 0.0;
          for (const double x : m.force_N[a]) {
            sum += x;
          }
          out.emplace_back(sum / static_cast<double>(m.force_N[a].size()), 0.0);
        }
        out.insert(out.end(), h.begin(), h.end());
      }
      if (setting.discs > 0) {
        config.effects.helix_lag.discs = setting.discs;
      }
      config.effects.runout.enabled = true;
      workspace.reserve(config, setting.steps);
      for (auto& entry : cache) {
        entry.key.resize(0);
      }
      cache_current = kCached;
    }

    /// The filter's response (times the dynamometer's resonance when on) at each entry.
    void compute_gains() {
      const auto& dyn = config.effects.dynamometer;
      for (std::size_t a = 0; a < 3; ++a) {
        gains[a].resize(order.size());
        for (std::size_t e = 0; e < order.size(); ++e) {
          const double hz = order[e] * rpm / 60.0;
          std::complex<double> g = owner->filters[static_cast<std::size_t>(cut)](hz);
          if (resonance) {
            g *= model::resonance_response(dyn.natural_hz[a], dyn.damping_ratio[a], hz);
          }
          gains[a][e] = g;
        }
      }
    }

    /// The entries (harmonics k = 1..K, and the mean) of a waveform on the model grid, times
    /// the filter's response.
    void harmonics_of(const std::vector<double>& w, std::size_t axis,
                      std::vector<std::complex<double>>& out) {
      const int s = setting.steps;
      if (spectrum.samples() != s) {
        spectrum = signal::RealSpectrum(s);  // planned once per grid
      }
      spectrum.transform(w);
      out.resize(order.size());
      for (std::size_t e = 0; e < order.size(); ++e) {
        const int k = order[e];
        out[e] = (k == 0 ? 1.0 : 2.0) / s * spectrum.bin(k) * gains[axis][e];
      }
    }

    /// `config` with the key's values: the runout, the extra parameters, and the coefficients
    /// when they are nonlinear parameters.
    void apply(const Eigen::VectorXd& key) {
      const double u = key[0], v = key[1];
      config.effects.runout.offset_um = std::hypot(u, v);
      config.effects.runout.angle_rad = std::atan2(v, u);
      const int n_extra = owner->extra_map.size();
      if (n_extra > 0) {
        model::set_parameters(owner->extra_map, key.segment(2, n_extra), config);
      }
      if (!owner->separable) {
        model::set_parameters(owner->coefficient_map,
                              key.segment(2 + n_extra, owner->coefficient_map.size()), config);
      }
    }

    /// The flute that cuts least at the key's values, and whether it cuts nothing: its largest
    /// chip at every slot of the bottom disc in every revolution of the cycle (the runout is
    /// the same on every disc) is below a ten-thousandth of the feed (sub-nanometre: the
    /// solver's rounding at an edge left 2·10⁻⁸ µm).
    [[nodiscard]] LeastCutting least_cutting_flute(const Eigen::VectorXd& key) {
      apply(key);
      const model::SteadyState& st = model::evaluate_steady_state(
          config, rpm, setting.steps, workspace, model::SteadyStateOutput::kMean);
      int least = 0;
      double least_um = std::numeric_limits<double>::infinity();
      double most_um = 0.0;
      for (int j = 0; j < config.tool.flutes; ++j) {
        double largest_um = 0.0;
        for (int m = 0; m < st.cycle_revolutions; ++m) {
          for (int b = 0; b < setting.steps; ++b) {
            largest_um = std::max(largest_um, workspace.chip_um(j, b, m));
          }
        }
        most_um = std::max(most_um, largest_um);
        if (largest_um < least_um) {
          least_um = largest_um;
          least = j;
        }
      }
      return {least, least_um <= 1e-4 * config.process.feed_per_tooth_um,
              most_um > 0.0 ? least_um / most_um : 0.0};
    }

    /// The model's columns for the shared nonlinear values (θ without the alignments).
    void evaluate(const Eigen::VectorXd& key) {
      // `config` follows the key asked for, cached or not: the fit reads its coefficients (their
      // scales, a start) and must not see whichever key was last evaluated.
      apply(key);
      for (std::size_t i = 0; i < kCached; ++i) {
        const Cached& entry = cache[i];
        if (entry.key.size() == key.size() && entry.key == key) {
          if (i != cache_current) {
            columns = entry.columns;
            cache_current = i;
          }
          return;
        }
      }
      if (owner->extra_map.size() > 0 && owner->extra_moves_resonance && resonance) {
        compute_gains();  // a fitted natural frequency or damping ratio
      }
      const int s = setting.steps;
      if (owner->separable) {
        const model::ForceBasis& basis =
            model::evaluate_force_basis(config, rpm, s, workspace, false);
        columns.resize(static_cast<std::size_t>(basis.columns + 1));
        column_names.assign(basis.names.begin(), basis.names.begin() + basis.columns);
        for (int c = 0; c <= basis.columns; ++c) {
          const model::ForceWaveform& w =
              c < basis.columns ? basis.unit[static_cast<std::size_t>(c)] : basis.offset;
          const std::array<const std::vector<double>*, 3> waves = {&w.fx_N, &w.fy_N, &w.fz_N};
          for (std::size_t a = 0; a < 3; ++a) {
            if (axes[a]) {
              harmonics_of(*waves[a], a, columns[static_cast<std::size_t>(c)][a]);
            }
          }
        }
      } else {
        const model::SteadyState& st = model::evaluate_steady_state(
            config, rpm, s, workspace, model::SteadyStateOutput::kMean);
        columns.resize(1);
        column_names.clear();
        const std::array<const std::vector<double>*, 3> waves = {&st.mean.fx_N, &st.mean.fy_N,
                                                                 &st.mean.fz_N};
        for (std::size_t a = 0; a < 3; ++a) {
          if (axes[a]) {
            harmonics_of(*waves[a], a, columns[0][a]);
          }
        }
      }
      Cached& entry = cache[cache_next];
      entry.key = key;
      entry.columns = columns;
      cache_current = cache_next;
      cache_next = (cache_next + 1) % kCached;
      ++evaluations;
    }

    /// Real values compared: 2 per entry and axis.
    [[nodiscard]] int rows() const {
      int n = 0;
      for (bool a : axes) {
        n += a ? 1 : 0;
      }
      return 2 * static_cast<int>(order.size()) * n;
    }

    /// This cut's rows from `row` on: the measured harmonics y, the offset column b0 and the
    /// linear columns A at the shared values `key`, the model shifted by the alignment δ.
    void assemble(const Eigen::VectorXd& key, double delta, Eigen::VectorXd& y, Eigen::VectorXd& b0,
                  Eigen::MatrixXd& a, int row) {
      evaluate(key);
      const auto ncol = static_cast<Eigen::Index>(columns.size()) - 1;
      for (std::size_t ax = 0; ax < 3; ++ax) {
        if (!axes[ax]) {
          continue;
        }
        for (std::size_t uk = 0; uk < order.size(); ++uk) {
          const std::complex<double> shift = std::polar(1.0, order[uk] * delta);
          const std::complex<double> meas = measured[ax][uk];
          const std::complex<double> off = columns.back()[ax][uk] * shift;
          y[row] = meas.real();
          y[row + 1] = meas.imag();
          b0[row] = off.real();
          b0[row + 1] = off.imag();
          for (Eigen::Index c = 0; c < ncol; ++c) {
            const std::complex<double> v = columns[static_cast<std::size_t>(c)][ax][uk] * shift;
            a(row, c) = v.real();
            a(row + 1, c) = v.imag();
          }
          row += 2;
        }
      }
    }

    /// The best alignment of this cut alone (its own coefficients) on a grid of `steps` values
    /// for the shared values `key`: a rotation of the model by δ is a rotation of the
    /// measurement by −δ, so the model's columns are factored once and each δ costs one
    /// projection.
    std::pair<double, double> scan_alignment(const Eigen::VectorXd& key, int steps) {
      evaluate(key);
      const int m = rows();
      const auto ncol = static_cast<Eigen::Index>(columns.size()) - 1;
      Eigen::VectorXd y0(m), b0(m);
      Eigen::MatrixXd a(m, ncol);
      assemble(key, 0.0, y0, b0, a, 0);
      std::vector<Eigen::Index> used;
      const double biggest = a.cols() > 0 ? a.colwise().norm().maxCoeff() : 0.0;
      for (Eigen::Index c = 0; c < a.cols(); ++c) {
        if (a.col(c).norm() > 1e-9 * biggest) {
          used.push_back(c);
        }
      }
      Eigen::MatrixXd q(m, static_cast<Eigen::Index>(used.size()));
      if (!used.empty()) {
        Eigen::MatrixXd au(m, static_cast<Eigen::Index>(used.size()));
        for (std::size_t i = 0; i < used.size(); ++i) {
          au.col(static_cast<Eigen::Index>(i)) = a.col(used[i]);
        }
        const Eigen::HouseholderQR<Eigen::MatrixXd> qr(au);
        q = qr.householderQ() * Eigen::MatrixXd::Identity(m, au.cols());
      }
      double best = 1e300, best_delta = 0.0;
      Eigen::VectorXd z(m);
      // Harmonic k at trial i turns by entry k·i mod steps of the table.
      const std::vector<std::complex<double>> turn = unit_turns(static_cast<std::size_t>(steps));
      for (int i = 0; i < steps; ++i) {
        const double delta = kTwoPi * i / steps;
        int row = 0;
        for (std::size_t ax = 0; ax < 3; ++ax) {
          if (!axes[ax]) {
            continue;
          }
          for (std::size_t e = 0; e < order.size(); ++e) {
            const auto j = static_cast<std::size_t>((static_cast<long>(order[e]) * i) % steps);
            const std::complex<double> v = std::complex<double>(y0[row], y0[row + 1]) * turn[j];
            z[row] = v.real() - b0[row];
            z[row + 1] = v.imag() - b0[row + 1];
            row += 2;
          }
        }
        double cost = z.squaredNorm();
        if (q.cols() > 0) {
          cost -= (q.transpose() * z).squaredNorm();
        }
        if (cost < best) {
          best = cost;
          best_delta = delta;
        }
      }
      return {best_delta, best};
    }
  };

  // One problem: a setting and every cut's part.
  struct Problem {
    Impl* owner = nullptr;
    Setting setting;
    std::vector<std::unique_ptr<Part>> parts;
    double prior_weight = 0.0;          // rows (u, v)·prior_weight appended when > 0
    Eigen::VectorXd last_coefficients;  // the linear solve's result at the last residual

    void prepare(const std::vector<const MeasuredRevolution*>& m) {
      parts.clear();
      for (int i = 0; i < owner->cuts(); ++i) {
        auto part = std::make_unique<Part>();
        part->owner = owner;
        part->cut = i;
        part->setting = setting;
        part->prepare(*m[static_cast<std::size_t>(i)]);
        parts.push_back(std::move(part));
      }
    }

    /// The first cut's configuration (the tool every cut shares).
    [[nodiscard]] const model::ModelConfig& config() const { return parts.front()->config; }

    [[nodiscard]] long evaluations() const {
      long n = 0;
      for (const auto& part : parts) {
        n += part->evaluations;
      }
      return n;
    }

    [[nodiscard]] int data_size() const {
      int n = 0;
      for (const auto& part : parts) {
        n += part->rows();
      }
      return n;
    }

    /// The residual's rows after the data: the runout prior, (u, v)·weight.
    void append_prior(const Eigen::VectorXd& theta, Eigen::VectorXd& r) const {
      if (prior_weight > 0.0) {
        r.conservativeResize(r.size() + 2);
        r[r.size() - 2] = prior_weight * theta[0];
        r[r.size() - 1] = prior_weight * theta[1];
      }
    }

    [[nodiscard]] int residual_size() const { return data_size() + (prior_weight > 0.0 ? 2 : 0); }

    /// Whether θ is inside the configuration's bounds (the runout below a fifth of the tool
    /// radius, every extra parameter and coefficient within its limits).
    [[nodiscard]] bool admissible(const Eigen::VectorXd& theta) const {
      if (std::hypot(theta[0], theta[1]) >= 0.19 * model::tool_radius_um(config())) {
        return false;
      }
      const int ne = owner->extra_map.size();
      if (ne > 0 && !model::within_bounds(owner->extra_map, theta.segment(2, ne))) {
        return false;
      }
      const int nc = owner->separable ? 0 : owner->coefficient_map.size();
      return nc == 0 || model::within_bounds(owner->coefficient_map, theta.segment(2 + ne, nc));
    }

    /// The measured harmonics y, the offset column b0 and the linear columns A at θ, every
    /// cut's rows stacked (the coefficients are shared: one set of columns).
    void assemble(const Eigen::VectorXd& theta, Eigen::VectorXd& y, Eigen::VectorXd& b0,
                  Eigen::MatrixXd& a) {
      const int ns = owner->shared_size();
      const Eigen::VectorXd key = theta.head(ns);
      for (const auto& part : parts) {
        part->evaluate(key);
      }
      const int m = data_size();
      const auto ncol = static_cast<Eigen::Index>(parts.front()->columns.size()) - 1;
      y.resize(m);
      b0.resize(m);
      a.resize(m, ncol);
      int row = 0;
      for (std::size_t i = 0; i < parts.size(); ++i) {
        Part& part = *parts[i];
        if (static_cast<Eigen::Index>(part.columns.size()) - 1 != ncol) {
          throw std::logic_error("the cuts' force bases differ");  // fit_cuts checks the law
        }
        part.assemble(key, theta[ns + static_cast<Eigen::Index>(i)], y, b0, a, row);
        row += part.rows();
      }
    }

    /// θ: the residual, the force-law coefficients solved by linear least squares
    /// (last_coefficients).
    Eigen::VectorXd residual(const Eigen::VectorXd& theta) {
      if (!admissible(theta)) {
        return Eigen::VectorXd::Constant(residual_size(), 1e6);  // a step the fit must refuse
      }
      Eigen::VectorXd y, b0;
      Eigen::MatrixXd a;
      assemble(theta, y, b0, a);
      const Eigen::Index m = y.size();
      const Eigen::Index ncol = a.cols();
      Eigen::VectorXd r = y - b0;
      last_coefficients = Eigen::VectorXd::Zero(ncol);
      if (!r.allFinite() || !a.allFinite()) {
        return Eigen::VectorXd::Constant(residual_size(), 1e6);  // the model failed there
      }
      if (ncol > 0 && a.colwise().norm().maxCoeff() > 0.0) {
        // Columns no axis compared sees (e.g. the axial coefficients without fz) stay at 0.
        std::vector<Eigen::Index> used;
        const double biggest = a.colwise().norm().maxCoeff();
        for (Eigen::Index c = 0; c < ncol; ++c) {
          if (a.col(c).norm() > 1e-9 * biggest) {
            used.push_back(c);
          }
        }
        Eigen::MatrixXd au(m, static_cast<Eigen::Index>(used.size()));
        for (std::size_t i = 0; i < used.size(); ++i) {
          au.col(static_cast<Eigen::Index>(i)) = a.col(used[i]);
        }
        const Eigen::VectorXd c = au.colPivHouseholderQr().solve(r);
        for (std::size_t i = 0; i < used.size(); ++i) {
          last_coefficients[used[i]] = c[static_cast<Eigen::Index>(i)];
        }
        r -= au * c;
      }
      append_prior(theta, r);
      return r;
    }

    /// The residual at θ with the coefficients held at c: y − b0(θ) − A(θ)·c.
    Eigen::VectorXd residual_at(const Eigen::VectorXd& theta, const Eigen::VectorXd& c) {
      Eigen::VectorXd y, b0;
      Eigen::MatrixXd a;
      assemble(theta, y, b0, a);
      Eigen::VectorXd r = c.size() > 0 ? Eigen::VectorXd(y - b0 - a * c) : Eigen::VectorXd(y - b0);
      append_prior(theta, r);
      return r;
    }

    /// ∂r/∂c = −A(θ).
    Eigen::MatrixXd coefficient_jacobian(const Eigen::VectorXd& theta) {
      Eigen::VectorXd y, b0;
      Eigen::MatrixXd a;
      assemble(theta, y, b0, a);
      Eigen::MatrixXd j = Eigen::MatrixXd::Zero(residual_size(), a.cols());
      j.topRows(a.rows()) = -a;
      return j;
    }
  };

  Impl(std::vector<model::ModelConfig> cut_models, std::vector<FilterResponse> responses,
       std::vector<std::string> names, FitOptions o)
      : models(std::move(cut_models)),
        filters(std::move(responses)),
        cut_names(std::move(names)),
        options(std::move(o)) {
    if (models.empty()) {
      throw std::invalid_argument("a fit needs at least one cut");
    }
    for (const auto& m : models) {
      model::validate(m);
    }
    commanded = models.front();
    const nlohmann::json shared = shared_part(commanded);
    for (std::size_t i = 1; i < models.size(); ++i) {
      const std::string d = first_difference(shared, shared_part(models[i]), "");
      if (!d.empty()) {
        throw std::invalid_argument(
            "cut " + cut_names[i] + ": " + d + " differs from cut " + cut_names[0] +
            "'s: a joint fit needs one tool, one clamping and one force law (only the process, " +
            "i.e. feed, speed and engagement, may differ)");
      }
    }
    separable = !commanded.effects.deflection.enabled;
    if (!options.extra_parameters.empty()) {
      extra_map = model::make_parameter_map(commanded, options.extra_parameters);
      for (const auto& info : extra_map.parameters) {
        extra_moves_resonance = extra_moves_resonance || info.effect == "dynamometer";
      }
    }
    if (!separable) {
      // The coefficients the separable fit would solve for (the ploughing regime's too, with
      // the minimum chip thickness), unless named among the extra parameters.
      for (const char* p : model::linear_coefficient_names(commanded)) {
        if (std::find(options.extra_parameters.begin(), options.extra_parameters.end(), p) ==
            options.extra_parameters.end()) {
          coefficient_names.emplace_back(p);
        }
      }
      coefficient_map = model::make_parameter_map(commanded, coefficient_names);
    }
  }

  /// Harmonics the cut's filter passes at its speed.
  [[nodiscard]] int harmonics_for(int cut, double rpm, int bins) const {
    const double f = rpm / 60.0;
    const FilterResponse& filter = filters[static_cast<std::size_t>(cut)];
    int k = 1;
    while (k < bins / 2 - 1 && std::abs(filter((k + 1) * f)) >= options.passband_gain) {
      ++k;
    }
    return k;
  }

  /// Which entries of θ the residual is nearly linear in: the coefficients, when the deflection
  /// puts them in θ (it bends the force's dependence on them only slightly).
  [[nodiscard]] std::vector<bool> linear_mask() const {
    std::vector<bool> m(static_cast<std::size_t>(shared_size() + cuts()), false);
    if (!separable) {
      const int ne = extra_map.size();
      for (int i = 0; i < coefficient_map.size(); ++i) {
        m[static_cast<std::size_t>(2 + ne + i)] = true;
      }
    }
    return m;
  }

  /// The nonlinear vector θ's scales for a problem.
  [[nodiscard]] Eigen::VectorXd scales(const model::ModelConfig& c) const {
    const int ne = extra_map.size();
    const int nc = separable ? 0 : coefficient_map.size();
    const int ns = shared_size();
    Eigen::VectorXd s(ns + cuts());
    s[0] = s[1] = 1.0;  // µm
    if (ne > 0) {
      s.segment(2, ne) = model::parameter_scales(extra_map);
    }
    if (nc > 0) {
      Eigen::VectorXd values(nc);
      model::get_parameters(coefficient_map, c, values);
      s.segment(2 + ne, nc) = values.cwiseAbs().cwiseMax(model::parameter_scales(coefficient_map));
    }
    s.tail(cuts()).setConstant(0.1);  // rad
    return s;
  }

  [[nodiscard]] Eigen::VectorXd initial_theta(const model::ModelConfig& c, double u, double v,
                                              double delta) const {
    const int ne = extra_map.size();
    const int nc = separable ? 0 : coefficient_map.size();
    Eigen::VectorXd t(shared_size() + cuts());
    t[0] = u;
    t[1] = v;
    if (ne > 0) {
      Eigen::VectorXd e(ne);
      model::get_parameters(extra_map, c, e);
      t.segment(2, ne) = e;
    }
    if (nc > 0) {
      Eigen::VectorXd e(nc);
      model::get_parameters(coefficient_map, c, e);
      t.segment(2 + ne, nc) = e;
    }
    t.tail(cuts()).setConstant(delta);
    return t;
  }

  /// Relabels the flutes so that flute 0 has the largest cut (uniform pitch): γ' = γ + ψ_j*,
  /// every δ' = δ − ψ_j*. The force is unchanged.
  void relabel(Eigen::VectorXd& theta) const {
    if (!commanded.tool.pitch_deg.empty()) {
      return;  // a non-uniform pitch has labelled flutes
    }
    const int flutes = commanded.tool.flutes;
    const double u = theta[0], v = theta[1];
    const double rho = std::hypot(u, v);
    const double gamma = std::atan2(v, u);
    const double radius = model::tool_radius_um(commanded);
    const std::vector<double> pitch = model::flute_pitch_angles_rad(commanded.tool);
    const auto pos = model::flute_positions(radius, pitch, rho, gamma);
    int best = 0;
    double best_cut = -1e300;
    for (int j = 0; j < flutes; ++j) {
      const int prev = (j - 1 + flutes) % flutes;
      const double cut = pos[static_cast<std::size_t>(j)].radius_um -
                         pos[static_cast<std::size_t>(prev)].radius_um;
      if (cut > best_cut + 1e-12) {
        best_cut = cut;
        best = j;
      }
    }
    const double psi = pitch[static_cast<std::size_t>(best)];
    const double g = wrap_pi(gamma + psi);
    theta[0] = rho * std::cos(g);
    theta[1] = rho * std::sin(g);
    for (Eigen::Index i = shared_size(); i < theta.size(); ++i) {
      theta[i] = wrap_pi(theta[i] - psi);
    }
  }

  /// p's residual as Levenberg–Marquardt calls it: with the runout held at `held`'s when the
  /// options do not fit it.
  auto residual_of(Problem& p, const Eigen::VectorXd& held) const {
    return [this, &p, &held](const Eigen::VectorXd& x) -> Eigen::VectorXd {
      if (options.fit_runout) {
        return p.residual(x);
      }
      Eigen::VectorXd y = x;
      y.head(2) = held.head(2);
      return p.residual(y);
    };
  }

  /// Best start: runout on a grid, each cut's alignment on a fine grid; then the best few
  /// refined. `grid`: the problem the starts are ranked on (a coarser angle grid: only their
  /// order matters), or null to refine the seed alone.
  Eigen::VectorXd solve(Problem& p, Problem* grid, const Eigen::VectorXd* seed, double* cost,
                        int* iterations) {
    const Eigen::VectorXd scale = scales(p.config());
    const int ns = shared_size();
    std::vector<std::pair<double, Eigen::VectorXd>> starts;
    auto consider = [&](double u, double v) {
      Eigen::VectorXd t = initial_theta(p.config(), u, v, 0.0);
      if (!p.admissible(t)) {
        return;
      }
      // Each cut's alignment on a grid of 2.5° (Levenberg–Marquardt refines them).
      const Eigen::VectorXd key = t.head(ns);
      double c = 0.0;
      for (std::size_t i = 0; i < grid->parts.size(); ++i) {
        const auto [delta, ci] = grid->parts[i]->scan_alignment(key, 144);
        t[ns + static_cast<Eigen::Index>(i)] = delta;
        c += ci;
      }
      if (grid->parts.size() > 1) {
        c = grid->residual(t).squaredNorm();  // with the coefficients shared
      }
      starts.emplace_back(c, t);
    };
    const double ft = p.config().process.feed_per_tooth_um;
    if (grid == nullptr) {
      // Seed only.
    } else if (options.fit_runout) {
      consider(0.0, 0.0);
      // Relabelling the flutes turns (u, v) by a pitch and leaves the force: directions over
      // one pitch cover every runout. The basin is narrow (about half a micrometre at a few
      // micrometres of feed), hence rings a fifth of the feed apart.
      const double sector = kTwoPi / std::max(1, p.config().tool.flutes);
      const auto ring_of = [&](int ring, double rho) {
        for (int g = 0; g < 8; ++g) {
          const double gamma = sector * (g + 0.5 * (ring % 2)) / 8.0;
          consider(rho * std::cos(gamma), rho * std::sin(gamma));
        }
      };
      for (int ring = 1; ring <= 5; ++ring) {
        ring_of(ring, 0.2 * ring * ft);
      }
      // Below the minimum chip, material piles up to h_min before a pass removes it (chip
      // accumulation, [002] eqs 11-12): a flute lying several feeds inside the one before it
      // still meets the piled-up material now and then. Rings out to the feed alone never start
      // there (the copper preset's cut: f_t 0.125 µm, h_min 0.9 µm, its radii 1.755 µm apart,
      // had ended at 0.11 µm with negative edge coefficients standing in for the runout). These
      // rings, a fifth of h_min apart, are coarser than the feed's: enough on that cut. In a
      // calibration, the first cut's f_t and h_min decide.
      const double h_min = p.config().effects.min_chip.h_min_um;
      if (p.config().effects.min_chip.enabled && p.config().effects.accumulation.enabled &&
          h_min > ft) {
        for (int ring = 1; ring <= 5; ++ring) {
          ring_of(ring + 5, ft + 0.2 * ring * h_min);
        }
      }
    } else {
      const double rho =
          commanded.effects.runout.enabled ? commanded.effects.runout.offset_um : 0.0;
      consider(rho * std::cos(commanded.effects.runout.angle_rad),
               rho * std::sin(commanded.effects.runout.angle_rad));
    }
    std::sort(starts.begin(), starts.end(),
              [](const auto& a, const auto& b) { return a.first < b.first; });
    if (seed != nullptr) {
      // A seed (the coarse fit, the previous window) is refined whatever its cost: it is near
      // the optimum but, in a narrow basin, not necessarily below a start of the grid.
      starts.insert(starts.begin(), {p.residual(*seed).squaredNorm(), *seed});
    }
    // A weak runout prior from the start, at a tenth of the best start's noise level, keeps
    // Levenberg–Marquardt from wandering along a direction the data hardly pin; fit() sets it
    // to the converged noise level afterwards.
    if (options.runout_prior_um > 0.0 && options.fit_runout && !starts.empty()) {
      const double dof = std::max(1.0, static_cast<double>(p.data_size() - scale.size()));
      p.prior_weight = 0.1 * std::sqrt(starts.front().first / dof) / options.runout_prior_um;
    }
    const auto refined =
        std::min<std::size_t>(starts.size(), static_cast<std::size_t>(options.refined_starts) +
                                                 (seed != nullptr ? 1 : 0));
    Eigen::VectorXd best;
    double best_cost = 1e300;
    *iterations = 0;
    minima.clear();
    for (std::size_t i = 0; i < refined; ++i) {
      if (i > (seed != nullptr ? 1U : 0U) &&
          starts[i].first > 4.0 * starts[seed != nullptr ? 1 : 0].first) {
        break;  // a start far worse than the best is another, worse basin
      }
      Eigen::VectorXd t = starts[i].second;
      double c = 0.0;
      *iterations +=
          levenberg_marquardt(residual_of(p, starts[i].second), t, scale, options.max_iterations,
                              &c, seed != nullptr && i == 0, linear_mask());
      if (c < best_cost) {
        best_cost = c;
        best = t;
      }
      if (std::isfinite(c)) {
        minima.emplace_back(c, t);
        relabel(minima.back().second);  // as the solution will be: the same labelling
      }
    }
    if (best.size() == 0) {  // no start refined: none admissible, or no finite residual
      *cost = std::numeric_limits<double>::infinity();
      return starts.empty() ? initial_theta(p.config(), 0.0, 0.0, 0.0) : starts.front().second;
    }
    relabel(best);
    const double prior = p.prior_weight;
    p.prior_weight = 0.0;
    *cost = p.residual(best).squaredNorm();  // the data's part
    p.prior_weight = prior;
    return best;
  }

  /// Whether the residual `r` at `theta` sits on a flute's contact edge along one parameter,
  /// from its changes to `rp` and `rm` (a step either way), the fit's degrees of freedom and
  /// the model's least-cutting flute there (`idle()`: LeastCutting, asked only past the ratio
  /// test; kContactEdgeRatio and below). At an ordinary minimum the two changes are ±J·h to first
  /// order.
  template <typename Idle>
  [[nodiscard]] static bool at_contact_edge(Problem& p, const Eigen::VectorXd& theta,
                                            const Eigen::VectorXd& r, const Eigen::VectorXd& rp,
                                            const Eigen::VectorXd& rm, double dof, Idle&& idle) {
    const double up = (rp - r).norm();
    const double down = (r - rm).norm();
    if (!(std::max(up, down) > kContactEdgeRatio * std::min(up, down))) {
      return false;
    }
    // The step onto the steep side raises the cost by more than one value's variance RSS/dof;
    // or, with a kink, the model leaves a flute idle: the step across starts it cutting, and the
    // change need only stand above the model's rounding by less (kContactEdgeIdleSignificance).
    const double rss = r.squaredNorm();
    const double steep_cost = (up > down ? rp : rm).squaredNorm() - rss;
    const bool steep = steep_cost > rss / dof;
    if (!steep && !idle().idle) {
      return false;
    }
    // An edge is where a flute stops cutting: one whose largest chip is at least half the
    // largest flute's is nowhere near it, whatever the cost's asymmetry says (a model that
    // leaves most of the force unexplained has kinks of its own: PHM c1_cut315's ball-nose, its
    // radii 0.4 µm apart against chips of up to 14 µm, had read "ρ ≥ 0.25 µm").
    if (steep && !idle().idle && idle().share > kContactEdgeMaxChipShare) {
      return false;
    }
    Eigen::VectorXd y, b0;
    Eigen::MatrixXd a;
    p.assemble(theta, y, b0, a);
    return std::max(up, down) >
           (steep ? kContactEdgeSignificance : kContactEdgeIdleSignificance) * y.norm();
  }

  /// Refits from `theta` with another setting (a variant of the model's approximations).
  Eigen::VectorXd refit(const std::vector<const MeasuredRevolution*>& m, const Setting& s,
                        const Eigen::VectorXd& theta, double prior_weight) {
    Problem p;
    p.owner = this;
    p.setting = s;
    p.prepare(m);
    p.prior_weight = prior_weight;
    Eigen::VectorXd t = theta;
    double c = 0.0;
    // The optimum's shift: a step or two.
    levenberg_marquardt(residual_of(p, theta), t, scales(p.config()), 2, &c, true, linear_mask());
    relabel(t);
    p.residual(t);
    Eigen::VectorXd out(t.size() + p.last_coefficients.size());
    out << t, p.last_coefficients;
    return out;
  }

  JointFitResult fit(const std::vector<const MeasuredRevolution*>& m, const FitResult* previous,
                     bool with_variants = true);
};

JointFitResult WindowFitter::Impl::fit(const std::vector<const MeasuredRevolution*>& ms,
                                       const FitResult* previous, bool with_variants) {
  JointFitResult joint;
  FitResult& out = joint.fit;
  out.config = commanded;
  if (ms.size() != models.size()) {
    throw std::invalid_argument("a joint fit needs one measurement per cut");
  }
  for (std::size_t i = 0; i < ms.size(); ++i) {
    const int bins = static_cast<int>(ms[i]->force_N[0].size());
    if (bins < 16 || !(ms[i]->spindle_rpm > 0.0)) {
      out.message = ms.size() == 1 ? "no revolution average to fit"
                                   : "cut " + cut_names[i] + ": no revolution average to fit";
      return joint;
    }
  }
  const int ns = shared_size();
  const int ncut = cuts();
  Setting base;
  base.steps = options.steps_per_rev;
  base.mean = options.use_mean;
  Problem p;
  p.owner = this;
  p.setting = base;
  p.prepare(ms);

  Eigen::VectorXd seed;
  const Eigen::VectorXd* seed_ptr = nullptr;
  if (previous != nullptr && previous->ok) {
    // The previous model's runout (on a contact edge the stated ρ is only the least allowed).
    const auto& runout = previous->config.effects.runout;
    const double rho = runout.enabled ? runout.offset_um : previous->rho_um.value;
    const double gamma = runout.enabled ? runout.angle_rad : previous->gamma_rad.value;
    seed = initial_theta(previous->config, rho * std::cos(gamma), rho * std::sin(gamma),
                         previous->alignment_rad.value);
    seed_ptr = &seed;
  }
  double cost = 0.0;
  int full_iterations = 0;
  Eigen::VectorXd theta;
  // The seeded solution, kept when it also moved far (below) and fits better than the search.
  Eigen::VectorXd seeded;
  double seeded_cost = std::numeric_limits<double>::infinity();
  int seeded_iterations = 0;
  if (seed_ptr != nullptr) {
    // From the previous window: refine it alone, and search afresh only when the result fits
    // much worse than the previous one did (the runout or the cut changed), or when the runout
    // went far from the previous one's, beyond 3·√2 of its σ: a step of the runout may have
    // left the seed in another valley of the cost, which a window cleaner than the last can
    // fit within twice its residual (an exact window after noisy ones: 2.64 µm found for 2.0).
    theta = solve(p, nullptr, seed_ptr, &cost, &full_iterations);
    const double rms = std::sqrt(cost / std::max(1, p.data_size()));
    const double before = std::hypot(previous->residual_rms_N[0], previous->residual_rms_N[1],
                                     previous->residual_rms_N[2]);
    const double moved_um = std::hypot(theta[0] - seed[0], theta[1] - seed[1]);
    if (!(rms <= 2.0 * before + 1e-9)) {
      seed_ptr = nullptr;
    } else if (moved_um > 3.0 * std::sqrt(2.0) * previous->rho_um.sigma) {
      seeded = theta;
      seeded_cost = cost;
      seeded_iterations = full_iterations;
      seed_ptr = nullptr;
    }
  }
  if (seed_ptr == nullptr) {
    Setting coarse = base;
    coarse.steps = std::max(90, base.steps / 4);
    Problem grid;
    grid.owner = this;
    grid.setting = coarse;
    grid.prepare(ms);
    theta = solve(p, &grid, nullptr, &cost, &full_iterations);
    out.evaluations += grid.evaluations();
    full_iterations += seeded_iterations;
    if (seeded_cost < cost) {
      theta = seeded;
      cost = seeded_cost;
    }
  }
  out.iterations += full_iterations;
  if (!std::isfinite(cost)) {
    out.message = "the fit did not converge (no start gave a finite residual)";
    return joint;
  }
  // The weak runout prior, at the noise level the data-only fit leaves.
  if (options.runout_prior_um > 0.0 && options.fit_runout) {
    const double dof0 = std::max(1.0, static_cast<double>(p.data_size() - theta.size()));
    p.prior_weight = std::sqrt(cost / dof0) / options.runout_prior_um;
    double c = 0.0;
    out.iterations += levenberg_marquardt(residual_of(p, theta), theta, scales(p.config()),
                                          options.max_iterations, &c, true, linear_mask());
    relabel(theta);
    cost = c;
  }
  const Eigen::VectorXd r = p.residual(theta);
  const Eigen::VectorXd coefficients = p.last_coefficients;
  // The flute that cuts least at the solution (the first cut's), and whether the model leaves
  // one idle in any cut (the contact-edge test below): a model evaluation, made only for a fit
  // the one-sided differences put near an edge.
  LeastCutting least_cutting{-1, false, 1.0};
  const auto least_cutting_flute = [&]() -> const LeastCutting& {
    if (least_cutting.flute < 0) {
      double share = 1.0;
      const Eigen::VectorXd key = theta.head(ns);
      for (auto& part : p.parts) {
        const LeastCutting l = part->least_cutting_flute(key);
        if (least_cutting.flute < 0 || (l.idle && !least_cutting.idle)) {
          least_cutting = l;
        }
        share = std::min(share, l.share);
      }
      least_cutting.share = share;
    }
    return least_cutting;
  };
  const Eigen::Index nt = theta.size();
  const Eigen::Index nc = coefficients.size();
  const int mres = p.residual_size();

  // Statistical covariance of all parameters from the full Jacobian at the solution.
  Eigen::MatrixXd j(mres, nt + nc);
  {
    const Eigen::VectorXd scale = scales(p.config());
    for (Eigen::Index i = 0; i < nt; ++i) {
      Eigen::VectorXd tp = theta;
      const double h = kDifferenceStep * scale[i];
      tp[i] += h;
      Eigen::VectorXd tm = theta;
      tm[i] -= h;
      const Eigen::VectorXd rp = p.residual_at(tp, coefficients);
      const Eigen::VectorXd rm = p.residual_at(tm, coefficients);
      j.col(i) = (rp - rm) / (2.0 * h);
      if (i < 2 && options.fit_runout) {
        out.runout_at_contact_edge =
            out.runout_at_contact_edge ||
            at_contact_edge(p, theta, r, rp, rm, std::max(1.0, static_cast<double>(mres - nt - nc)),
                            [&] { return least_cutting_flute(); });
      }
    }
    // The flute there, where the model leaves it idle (an edge found by the cost alone has its
    // flute still cutting a little).
    out.edge_flute =
        out.runout_at_contact_edge && least_cutting_flute().idle ? least_cutting_flute().flute : -1;
    if (nc > 0) {
      j.rightCols(nc) = p.coefficient_jacobian(theta);
      // Coefficients the linear solve left at 0 (no axis sees them) are not parameters.
      for (Eigen::Index c = 0; c < nc; ++c) {
        if (j.col(nt + c).norm() <= 1e-9 * j.rightCols(nc).colwise().norm().maxCoeff()) {
          j.col(nt + c).setZero();
        }
      }
    }
  }
  // Coefficients no axis sees were not fitted: leave them out of the covariance.
  std::vector<Eigen::Index> free;
  for (Eigen::Index i = 0; i < nt + nc; ++i) {
    if (j.col(i).norm() > 0.0) {
      free.push_back(i);
    }
  }
  const auto nf = static_cast<Eigen::Index>(free.size());
  if (nf == 0 || !j.allFinite() || !r.allFinite()) {
    out.message = nf == 0 ? "the fit did not converge (the force depends on no parameter there)"
                          : "the fit did not converge (the residual is not finite)";
    return joint;
  }
  Eigen::MatrixXd jf(mres, nf);
  for (Eigen::Index i = 0; i < nf; ++i) {
    jf.col(i) = j.col(free[static_cast<std::size_t>(i)]);
  }
  const double dof = std::max(1.0, static_cast<double>(mres - nf));
  const double s2 = r.squaredNorm() / dof;
  // (JᵀJ)⁻¹ through the SVD of the column-scaled J. A direction the data do not pin (a singular
  // value below 1e-10 of the largest: e.g. ρ·sin γ in a model where only the radii see runout)
  // must come out with a huge variance, not the zero a pseudo-inverse would give it.
  Eigen::VectorXd col_scale(nf);
  for (Eigen::Index i = 0; i < nf; ++i) {
    col_scale[i] = std::max(jf.col(i).norm(), 1e-300);
  }
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(jf * col_scale.cwiseInverse().asDiagonal(),
                                              Eigen::ComputeThinV);
  const Eigen::VectorXd sv = svd.singularValues();
  const double floor = std::max(sv.size() > 0 ? sv[0] : 0.0, 1e-300) * 1e-10;
  Eigen::VectorXd inv2(sv.size());
  for (Eigen::Index i = 0; i < sv.size(); ++i) {
    const double x = std::max(sv[i], floor);
    inv2[i] = 1.0 / (x * x);
  }
  const Eigen::MatrixXd cov_free = s2 * col_scale.cwiseInverse().asDiagonal() * svd.matrixV() *
                                   inv2.asDiagonal() * svd.matrixV().transpose() *
                                   col_scale.cwiseInverse().asDiagonal();
  // Pinned: fitted, and its σ not beyond 10⁶ of what the data's sensitivity to it alone would
  // give (σ·‖J_i‖/s = √(V·S⁻²·Vᵀ)_ii in the scaled problem, 1 for a parameter no other one
  // mimics): a variance from the singular-value floor above is a direction the data do not see.
  std::vector<bool> pinned(static_cast<std::size_t>(nt + nc), false);
  for (Eigen::Index a = 0; a < nf; ++a) {
    const double scaled_var =
        (svd.matrixV().row(a).cwiseAbs2().transpose().cwiseProduct(inv2)).sum();
    pinned[static_cast<std::size_t>(free[static_cast<std::size_t>(a)])] = scaled_var <= 1e12;
  }
  Eigen::MatrixXd cov = Eigen::MatrixXd::Zero(nt + nc, nt + nc);
  for (Eigen::Index a = 0; a < nf; ++a) {
    for (Eigen::Index b = 0; b < nf; ++b) {
      cov(free[static_cast<std::size_t>(a)], free[static_cast<std::size_t>(b)]) = cov_free(a, b);
    }
  }

  // Systematic: the spread of the estimates over variants of the model's approximations.
  Eigen::VectorXd full(nt + nc);
  full << theta, coefficients;
  Eigen::VectorXd sys2 = Eigen::VectorXd::Zero(nt + nc);
  if (options.systematic && with_variants) {
    // Each variant changes one of the model's approximations by a factor of two (coarser, so
    // that the variants cost less than the fit), or what is compared.
    int fewest_harmonics = p.parts.front()->harmonics;
    bool axial = false;
    for (const auto& part : p.parts) {
      fewest_harmonics = std::min(fewest_harmonics, part->harmonics);
      axial = axial || part->axes[2];
    }
    std::vector<Setting> variants;
    Setting coarser = base;
    coarser.steps = base.steps / 2;
    variants.push_back(coarser);
    if (commanded.effects.helix_lag.enabled && commanded.effects.helix_lag.discs >= 2) {
      Setting discs = base;
      discs.discs = commanded.effects.helix_lag.discs / 2;
      variants.push_back(discs);
    }
    if (fewest_harmonics >= 5) {
      Setting fewer = base;
      fewer.fewer_harmonics = 2;
      variants.push_back(fewer);
    }
    if (axial) {
      Setting plane = base;
      plane.in_plane = true;
      variants.push_back(plane);
    }
    for (const Setting& v : variants) {
      const Eigen::VectorXd alt = refit(ms, v, theta, p.prior_weight);
      Eigen::VectorXd d = alt - full;
      for (Eigen::Index i = ns; i < nt; ++i) {
        d[i] = wrap_pi(d[i]);
      }
      for (Eigen::Index i = 0; i < nt + nc; ++i) {
        if (cov(i, i) == 0.0 && i >= nt) {
          d[i] = 0.0;  // not fitted in the base: nothing to compare
        }
      }
      sys2 = sys2.cwiseMax(d.cwiseAbs2());  // the largest shift: each variant is one cause
    }
  }
  // Other minima the data cannot tell from this one: their cost within the 95 % profile
  // threshold of one parameter (ΔRSS ≤ χ²₁(0.95)·s²: the data do not reject them). A fit whose
  // model leaves most of the force unexplained has several (PHM 2010's cut 158: eight starts ended
  // 203–213 against a noise s² of 1.7, k_nc anywhere from −5600 to −2300 N/mm²); which one the
  // search reaches first then turns on the last bits of the data, and a σ from one of them alone
  // would state a precision the record does not hold. Each one's distance from the solution (where
  // it ended: the final prior, ten times the search's, moves a minimum by a tenth of the runout's σ
  // at most) is weighed against the σ's once every other cause is in (below).
  std::vector<Eigen::VectorXd> competing;
  if (options.competing_minima) {
    const double allowed = s2 * kChiSquare1At95;
    const double here = p.residual(theta).squaredNorm();
    for (const auto& [start_cost, t] : minima) {
      if (!(std::abs(p.residual(t).squaredNorm() - here) <= allowed)) {
        continue;  // another, worse basin (or a better one found late: worse for this one)
      }
      Eigen::VectorXd alt(nt + nc);
      alt << t, p.last_coefficients;
      Eigen::VectorXd d = alt - full;
      for (Eigen::Index i = ns; i < nt; ++i) {
        d[i] = wrap_pi(d[i]);
      }
      for (Eigen::Index i = nt; i < nt + nc; ++i) {
        if (cov(i, i) == 0.0) {
          d[i] = 0.0;  // not fitted in the base: nothing to compare
        }
      }
      competing.push_back(d);
    }
    p.residual(theta);  // the solution's coefficients in p again
  }
  if (options.fit_runout) {
    // What no variant shows: the measurement's own systematic errors (the angle map's jitter
    // through the synchronous average, the filter's response as modelled). On simulated cuts
    // with known truth they move (u, v) by up to about 0.2 % of the feed per tooth; half a
    // percent (of the cuts' mean feed) is the floor of their σ.
    double feed_um = 0.0;
    for (const auto& m : models) {
      feed_um += m.process.feed_per_tooth_um / static_cast<double>(ncut);
    }
    const double floor_um = 0.005 * feed_um;
    sys2[0] += floor_um * floor_um;
    sys2[1] += floor_um * floor_um;
  }
  // The same floor for the other chip-thickness parameters (h_min, a wear land): the measured
  // chip's errors move them on the same scale (h_min by 0.35 % of f_t on a simulated cut).
  for (int i = 0; i < extra_map.size(); ++i) {
    const auto id = extra_map.parameters[static_cast<std::size_t>(i)].id;
    if (id == model::ParameterId::kHmin || id == model::ParameterId::kWear ||
        id == model::ParameterId::kWearFlute) {
      double feed_um = 0.0;
      for (const auto& m : models) {
        feed_um += m.process.feed_per_tooth_um / static_cast<double>(ncut);
      }
      const double floor_um = 0.005 * feed_um;
      sys2[2 + i] += floor_um * floor_um;
    }
  }
  if (options.coefficient_floor > 0.0) {
    const int ne = extra_map.size();
    for (int i = 0; i < (separable ? 0 : coefficient_map.size()); ++i) {
      const double f = options.coefficient_floor * theta[2 + ne + i];
      sys2[2 + ne + i] += f * f;
    }
    for (Eigen::Index c = 0; c < nc; ++c) {
      if (cov(nt + c, nt + c) > 0.0) {
        const double f = options.coefficient_floor * coefficients[c];
        sys2[nt + c] += f * f;
      }
    }
  }
  // A competing minimum apart from the solution by more than some parameter's σ (statistical and
  // systematic, every other cause in) is another answer the record allows: its distance joins
  // the systematic σ's. One within every σ is this minimum reached again; one within every σ of
  // a minimum counted already is that one again. The σ's they are weighed against are those
  // before any of them, so that neither the count nor the σ's depend on their order.
  const Eigen::ArrayXd var = cov.diagonal().array() + sys2.array();
  std::vector<const Eigen::VectorXd*> counted;
  Eigen::VectorXd spread2 = Eigen::VectorXd::Zero(sys2.size());
  for (const Eigen::VectorXd& d : competing) {
    const auto apart = [&](const Eigen::VectorXd& e) {
      return ((d - e).cwiseAbs2().array() > var).any();
    };
    if (!(d.cwiseAbs2().array() > var).any()) {
      continue;
    }
    spread2 = spread2.cwiseMax(d.cwiseAbs2());
    if (std::all_of(counted.begin(), counted.end(),
                    [&](const Eigen::VectorXd* e) { return apart(*e); })) {
      counted.push_back(&d);
    }
  }
  out.competing_minima = static_cast<int>(counted.size());
  sys2 = sys2.cwiseMax(spread2);

  // Reported parameters: ρ, γ from (u, v) by the delta method.
  const double u = theta[0], v = theta[1];
  const double rho = std::hypot(u, v);
  const double gamma = std::atan2(v, u);
  Eigen::MatrixXd t = Eigen::MatrixXd::Identity(nt + nc, nt + nc);
  if (rho > 0.0) {
    t(0, 0) = u / rho;
    t(0, 1) = v / rho;
    t(1, 0) = -v / (rho * rho);
    t(1, 1) = u / (rho * rho);
  }
  const Eigen::MatrixXd cov_rep = t * cov * t.transpose();
  // The systematic spread of (u, v) mapped the same way (its components' squares).
  const Eigen::VectorXd sys2_rep = (t.cwiseAbs2() * sys2);
  auto estimate = [&](const std::string& name, Eigen::Index i, double value) {
    Estimate e;
    e.name = name;
    e.value = value;
    e.sigma_stat = std::sqrt(std::max(0.0, cov_rep(i, i)));
    e.sigma_sys = std::sqrt(std::max(0.0, sys2_rep[i]));
    e.sigma = std::hypot(e.sigma_stat, e.sigma_sys);
    return e;
  };
  out.rho_um = estimate("rho_um", 0, rho);
  out.gamma_rad = estimate("gamma_rad", 1, gamma);
  // ρ and γ are not linear in (u, v): where one direction is pinned weakly (σ comparable with
  // ρ), the delta method says nothing useful (∂ρ/∂v = 0 at v = 0). Their spread is taken from
  // (u, v) drawn from its distribution (statistical and systematic parts), deterministic draws.
  {
    Eigen::Matrix2d su = cov.topLeftCorner(2, 2);
    Eigen::Matrix2d ss = Eigen::Matrix2d::Zero();
    ss.diagonal() = sys2.head(2);
    const Eigen::LLT<Eigen::Matrix2d> chol_stat(su + 1e-18 * Eigen::Matrix2d::Identity());
    const Eigen::LLT<Eigen::Matrix2d> chol_all(su + ss + 1e-18 * Eigen::Matrix2d::Identity());
    std::mt19937_64 rng(20231);
    std::normal_distribution<double> z(0.0, 1.0);
    double rs = 0.0, ra = 0.0, gs = 0.0, ga = 0.0;
    constexpr int kDraws = 4000;
    for (int i = 0; i < kDraws; ++i) {
      const Eigen::Vector2d e(z(rng), z(rng));
      const Eigen::Vector2d a = Eigen::Vector2d(u, v) + chol_stat.matrixL() * e;
      const Eigen::Vector2d b = Eigen::Vector2d(u, v) + chol_all.matrixL() * e;
      rs += std::pow(a.norm() - rho, 2);
      ra += std::pow(b.norm() - rho, 2);
      gs += std::pow(wrap_pi(std::atan2(a[1], a[0]) - gamma), 2);
      ga += std::pow(wrap_pi(std::atan2(b[1], b[0]) - gamma), 2);
    }
    out.rho_um.sigma_stat = std::sqrt(rs / kDraws);
    out.rho_um.sigma = std::sqrt(ra / kDraws);
    out.rho_um.sigma_sys = std::sqrt(std::max(
        0.0, out.rho_um.sigma * out.rho_um.sigma - out.rho_um.sigma_stat * out.rho_um.sigma_stat));
    out.gamma_rad.sigma_stat = std::min(kPi, std::sqrt(gs / kDraws));
    out.gamma_rad.sigma = std::min(kPi, std::sqrt(ga / kDraws));
    out.gamma_rad.sigma_sys =
        std::sqrt(std::max(0.0, out.gamma_rad.sigma * out.gamma_rad.sigma -
                                    out.gamma_rad.sigma_stat * out.gamma_rad.sigma_stat));
  }
  out.alignment_rad = estimate("alignment_rad", ns, theta[ns]);
  const int ne = extra_map.size();
  // A parameter the data do not pin is no estimate: its value stays the fit's (as the model uses
  // it), its σs 0.
  const auto undetermined = [](Estimate& e) {
    e.determined = false;
    e.sigma = e.sigma_stat = e.sigma_sys = 0.0;
  };
  for (int i = 0; i < ne; ++i) {
    out.extra.push_back(
        estimate(extra_map.parameters[static_cast<std::size_t>(i)].name, 2 + i, theta[2 + i]));
    // Or a σ beyond kUndeterminedSigmaRatio times the parameter's magnitude (its value, or its
    // typical magnitude where that is larger): a column the force hardly sees (the stiffness of
    // a cut without runout, whose flutes' chips it leaves equal: ±4e7 N/µm at 1 N/µm). Not
    // h_min for a vanished column: the chip regime switches on the angle grid, so its force is
    // piecewise constant and its column zero at the fitted point, which the fit's steps across
    // the grid still pin (its σ then the chip-thickness floor's).
    Estimate& e = out.extra.back();
    const model::ParameterInfo& info = extra_map.parameters[static_cast<std::size_t>(i)];
    const bool vanished = !pinned[static_cast<std::size_t>(2 + i)] && cov(2 + i, 2 + i) == 0.0;
    const double magnitude = std::max(std::fabs(e.value), info.scale);
    if ((!pinned[static_cast<std::size_t>(2 + i)] &&
         !(vanished && info.id == model::ParameterId::kHmin)) ||
        e.sigma_stat > kUndeterminedSigmaRatio * magnitude) {
      undetermined(e);
    }
  }
  // A coefficient in a direction of the floor's variance.
  const auto undetermined_if_unpinned = [&](Estimate& e, Eigen::Index i) {
    if (!pinned[static_cast<std::size_t>(i)]) {
      undetermined(e);
    }
  };
  std::vector<std::string> names(static_cast<std::size_t>(nt + nc));
  names[0] = "rho_um";
  names[1] = "gamma_rad";
  for (int i = 0; i < ncut; ++i) {
    names[static_cast<std::size_t>(ns + i)] =
        ncut == 1 ? "alignment_rad" : "alignment_rad[" + std::to_string(i) + "]";
  }
  for (int i = 0; i < ne; ++i) {
    names[static_cast<std::size_t>(2 + i)] = extra_map.parameters[static_cast<std::size_t>(i)].name;
  }
  if (!separable) {
    Eigen::VectorXd configured(coefficient_map.size());
    model::get_parameters(coefficient_map, commanded, configured);
    for (int i = 0; i < coefficient_map.size(); ++i) {
      const std::string& n = coefficient_map.parameters[static_cast<std::size_t>(i)].name;
      names[static_cast<std::size_t>(2 + ne + i)] = n;
      if (cov(2 + ne + i, 2 + ne + i) > 0.0) {
        out.coefficients.push_back(estimate(n, 2 + ne + i, theta[2 + ne + i]));
        undetermined_if_unpinned(out.coefficients.back(), 2 + ne + i);
      } else {
        // No axis compared sees it (K_ac without fz): not fitted, as configured. Levenberg–
        // Marquardt's damped solve may have moved it by rounding.
        theta[2 + ne + i] = configured[i];
      }
    }
  }
  for (Eigen::Index c = 0; c < nc; ++c) {
    const std::string& n = p.parts.front()->column_names[static_cast<std::size_t>(c)];
    names[static_cast<std::size_t>(nt + c)] = n;
    if (cov(nt + c, nt + c) > 0.0) {
      out.coefficients.push_back(estimate(n, nt + c, coefficients[c]));
      undetermined_if_unpinned(out.coefficients.back(), nt + c);
    }
  }
  for (Eigen::Index a = 0; a < nt + nc; ++a) {
    for (Eigen::Index b = a + 1; b < nt + nc; ++b) {
      const double d = std::sqrt(cov_rep(a, a) * cov_rep(b, b));
      if (d > 0.0 && std::fabs(cov_rep(a, b) / d) > 0.9) {
        out.correlated.emplace_back(names[static_cast<std::size_t>(a)],
                                    names[static_cast<std::size_t>(b)]);
      }
    }
  }

  // The fitted configuration (commanded speed, fitted values).
  out.config = commanded;
  out.config.effects.runout.enabled = true;
  out.config.effects.runout.offset_um = rho;
  out.config.effects.runout.angle_rad = gamma;
  if (ne > 0) {
    model::set_parameters(extra_map, theta.segment(2, ne), out.config);
  }
  if (!separable) {
    model::set_parameters(coefficient_map, theta.segment(2 + ne, coefficient_map.size()),
                          out.config);
  } else if (nc > 0) {
    std::vector<std::string> fitted;
    std::vector<double> values;
    for (Eigen::Index c = 0; c < nc; ++c) {
      if (cov(nt + c, nt + c) > 0.0) {
        fitted.push_back(p.parts.front()->column_names[static_cast<std::size_t>(c)]);
        values.push_back(coefficients[c]);
      }
    }
    const model::ParameterMap map = model::make_parameter_map(commanded, fitted);
    model::set_parameters(
        map,
        Eigen::Map<const Eigen::VectorXd>(values.data(), static_cast<Eigen::Index>(values.size())),
        out.config);
  }

  // Cutting radii per flute, with σ through (u, v).
  const int flutes = commanded.tool.flutes;
  const double radius = model::tool_radius_um(commanded);
  const std::vector<double> pitch = model::flute_pitch_angles_rad(commanded.tool);
  auto radii = [&](double uu, double vv) {
    const auto pos = model::flute_positions(radius, pitch, std::hypot(uu, vv), std::atan2(vv, uu));
    Eigen::VectorXd rr(flutes);
    for (int jf2 = 0; jf2 < flutes; ++jf2) {
      rr[jf2] = pos[static_cast<std::size_t>(jf2)].radius_um;
    }
    return rr;
  };
  const Eigen::VectorXd r0 = radii(u, v);
  const double h = 1e-4;
  Eigen::MatrixXd dr(flutes, 2);
  dr.col(0) = (radii(u + h, v) - r0) / h;
  dr.col(1) = (radii(u, v + h) - r0) / h;
  const Eigen::MatrixXd cov_r = dr * cov.topLeftCorner(2, 2) * dr.transpose();
  const Eigen::VectorXd sys_r = (dr.cwiseAbs2() * sys2.head(2));
  // A quantity of the runout alone, with σ through its gradient in (u, v).
  auto through_runout = [&](std::string name, double value, const Eigen::RowVectorXd& g) {
    Estimate e;
    e.name = std::move(name);
    e.value = value;
    e.sigma_stat = std::sqrt(std::max(0.0, (g * cov.topLeftCorner(2, 2) * g.transpose())(0, 0)));
    e.sigma_sys = std::sqrt(std::max(0.0, (g.cwiseAbs2() * sys2.head(2))(0, 0)));
    e.sigma = std::hypot(e.sigma_stat, e.sigma_sys);
    return e;
  };
  for (int jf2 = 0; jf2 < flutes; ++jf2) {
    Estimate e;
    e.name = "r_ce" + std::to_string(jf2 + 1) + "_um";
    e.value = r0[jf2];
    e.sigma_stat = std::sqrt(std::max(0.0, cov_r(jf2, jf2)));
    e.sigma_sys = std::sqrt(std::max(0.0, sys_r[jf2]));
    e.sigma = std::hypot(e.sigma_stat, e.sigma_sys);
    out.cutting_radius_um.push_back(e);
    out.radius_from_ce1_um.push_back(
        through_runout("r_ce" + std::to_string(jf2 + 1) + "_minus_r_ce1_um", r0[jf2] - r0[0],
                       dr.row(jf2) - dr.row(0)));
  }
  if (out.edge_flute >= 0 && flutes == 2 && r0[0] != r0[1]) {
    // Two flutes, one idle: the force pins u = (r_CE1 − r_CE2)/2 from below, not v = ρ·sin γ,
    // which deflection or the prior may leave anywhere (a 2-flute slot stated ρ 5.98 µm at 71°
    // for 3.0 at 5.7°). Stated instead: the least ρ those radii allow — max over γ of
    // |r_CE1 − r_CE2| is 2ρ exactly, so ρ ≥ |r_CE1 − r_CE2|/2 — at the γ that reaches it, 0 (or
    // π), with σ 90°: any γ within a quarter turn of it allows a larger ρ. The model keeps the
    // fit's runout (`config`): it is the force's.
    const double sign = r0[0] > r0[1] ? 1.0 : -1.0;
    out.rho_um = through_runout("rho_um", 0.5 * sign * (r0[0] - r0[1]),
                                0.5 * sign * (dr.row(0) - dr.row(1)));
    out.gamma_rad.value = sign > 0.0 ? 0.0 : kPi;
    out.gamma_rad.sigma = out.gamma_rad.sigma_stat = 0.5 * kPi;
    out.gamma_rad.sigma_sys = 0.0;
  }
  if (flutes >= 2) {
    // The geometric cutting-edge phase angle: how far the edge after CE2 follows CE2, in degrees
    // of rotation — what α = 360°·T₂/T measures of the cut ([001] eq 36), without the force.
    auto alpha = [&](double uu, double vv) {
      const auto pos =
          model::flute_positions(radius, pitch, std::hypot(uu, vv), std::atan2(vv, uu));
      return model::flute_spacing_rad(pitch, pos, 1, 2 % flutes) * 180.0 / kPi;
    };
    const double a0 = alpha(u, v);
    Eigen::RowVectorXd da(2);
    da << (alpha(u + h, v) - a0) / h, (alpha(u, v + h) - a0) / h;
    out.alpha_deg = through_runout("alpha_deg", a0, da);
  }

  // Residual and measured RMS per axis over the harmonics compared: √(Σ|X_k|²/2), per cut and
  // (the mean square over the cuts) for all of them.
  int row = 0;
  std::array<double, 3> rr_all{}, mm_all{};
  for (std::size_t i = 0; i < p.parts.size(); ++i) {
    const Part& part = *p.parts[i];
    CutFitQuality q;
    q.alignment_rad =
        estimate(names[static_cast<std::size_t>(ns) + i], ns + static_cast<Eigen::Index>(i),
                 theta[ns + static_cast<Eigen::Index>(i)]);
    for (std::size_t a = 0; a < 3; ++a) {
      if (!part.axes[a]) {
        continue;
      }
      double rr = 0.0, mm = 0.0;
      for (std::size_t e = 0; e < part.order.size(); ++e) {
        if (part.order[e] > 0) {  // about the mean: the harmonics' share of the RMS
          rr += r[row] * r[row] + r[row + 1] * r[row + 1];
          mm += std::norm(part.measured[a][e]);
        }
        row += 2;
      }
      q.residual_rms_N[a] = std::sqrt(rr / 2.0);
      q.measured_rms_N[a] = std::sqrt(mm / 2.0);
      q.compared[a] = true;
      out.compared[a] = true;
      rr_all[a] += rr / 2.0 / ncut;
      mm_all[a] += mm / 2.0 / ncut;
    }
    q.harmonics = part.harmonics;
    q.effective_samples = part.rows();
    joint.cuts.push_back(q);
  }
  for (std::size_t a = 0; a < 3; ++a) {
    out.residual_rms_N[a] = std::sqrt(rr_all[a]);
    out.measured_rms_N[a] = std::sqrt(mm_all[a]);
  }
  out.harmonics = p.parts.front()->harmonics;
  out.effective_samples = p.data_size();
  out.evaluations += p.evaluations();
  out.ok = std::isfinite(cost);
  out.message = out.ok ? "converged" : "the fit did not converge";
  return joint;
}

WindowFitter::WindowFitter(const model::ModelConfig& model, FilterResponse filter,
                           FitOptions options)
    : impl_(std::make_unique<Impl>(std::vector<model::ModelConfig>{model},
                                   std::vector<FilterResponse>{std::move(filter)},
                                   std::vector<std::string>{"0"}, std::move(options))) {}
WindowFitter::~WindowFitter() = default;
WindowFitter::WindowFitter(WindowFitter&&) noexcept = default;
WindowFitter& WindowFitter::operator=(WindowFitter&&) noexcept = default;

FitResult WindowFitter::fit(const MeasuredRevolution& measured, const FitResult* previous,
                            bool variants) {
  return impl_->fit({&measured}, previous, variants).fit;
}

const FitOptions& WindowFitter::options() const {
  return impl_->options;
}

JointFitResult fit_cuts(const std::vector<FitCut>& cuts, const FitOptions& options) {
  std::vector<model::ModelConfig> models;
  std::vector<FilterResponse> filters;
  std::vector<std::string> names;
  std::vector<const MeasuredRevolution*> measured;
  for (std::size_t i = 0; i < cuts.size(); ++i) {
    models.push_back(cuts[i].model);
    filters.push_back(cuts[i].filter);
    names.push_back(cuts[i].name.empty() ? std::to_string(i + 1) : cuts[i].name);
    measured.push_back(&cuts[i].measured);
  }
  WindowFitter::Impl impl(std::move(models), std::move(filters), std::move(names), options);
  return impl.fit(measured, nullptr);
}

double unexplained_variance(const std::array<double, 3>& residual_rms_N,
                            const std::array<double, 3>& measured_rms_N) {
  double residual2 = 0.0, measured2 = 0.0;
  for (std::size_t a = 0; a < 3; ++a) {
    residual2 += residual_rms_N[a] * residual_rms_N[a];
    measured2 += measured_rms_N[a] * measured_rms_N[a];
  }
  return measured2 > 0.0 ? residual2 / measured2 : 1.0;
}

}  // namespace millwatch::identify
