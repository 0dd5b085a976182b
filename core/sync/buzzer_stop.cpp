#include "sync/buzzer_stop.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>

#include "common/error.hpp"

namespace posefuse::sync {

namespace {

double median_of(std::vector<double> v) {
  const auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
  std::nth_element(v.begin(), mid, v.end());
  return *mid;
}

void check_options(const AudioPcm& audio, const BuzzerStopOptions& o) {
  if (!std::isfinite(audio.t0_camera_us)) throw_invalid("audio.t0_camera_us", "not finite");
  if (!std::isfinite(audio.sample_rate_hz) || audio.sample_rate_hz <= 0.0) {
    throw_invalid("audio.sample_rate_hz", "must be a positive rate, got " + std::to_string(audio.sample_rate_hz));
  }
  if (audio.samples.empty()) throw_invalid("audio.samples", "no samples");
  if (!std::isfinite(o.tone_hz) || o.tone_hz <= 0.0 || o.tone_hz >= audio.sample_rate_hz / 2.0) {
    throw_invalid("options.tone_hz", "must lie in (0, sample_rate/2), got " + std::to_string(o.tone_hz));
  }
  if (!(o.window_s > 0.0) || !(o.min_on_s > 0.0) || !(o.min_off_s > 0.0) || !(o.min_on_to_off_ratio > 1.0)) {
    throw_invalid("options", "window_s, min_on_s, min_off_s must be > 0 and ratio > 1");
  }
}

}  // namespace

BuzzerStop detect_buzzer_stop(const AudioPcm& audio, const BuzzerStopOptions& o) {
  check_options(audio, o);
  const double fs = audio.sample_rate_hz;
  const auto n = static_cast<std::ptrdiff_t>(audio.samples.size());

  // A whole number of tone periods per window, so the demodulated 2f ripple averages out.
  const double periods = std::max(1.0, std::round(o.window_s * o.tone_hz));
  const auto window = std::max<std::ptrdiff_t>(2, std::lround(periods * fs / o.tone_hz));
  const auto min_on = static_cast<std::ptrdiff_t>(std::ceil(o.min_on_s * fs));
  const auto min_off = static_cast<std::ptrdiff_t>(std::ceil(o.min_off_s * fs));
  if (n < window + min_on + min_off + std::lround(fs / o.tone_hz)) {
    throw_precondition("audio.samples", std::to_string(n) +
                                            " samples are too few for the tone-on, tone-off and "
                                            "envelope windows");
  }

  // Quadrature demodulation with prefix sums.
  const double omega = 2.0 * std::numbers::pi * o.tone_hz / fs;
  std::vector<double> cum_i(static_cast<std::size_t>(n) + 1, 0.0);
  std::vector<double> cum_q(static_cast<std::size_t>(n) + 1, 0.0);
  for (std::ptrdiff_t k = 0; k < n; ++k) {
    const double x = audio.samples[static_cast<std::size_t>(k)];
    const double phase = omega * static_cast<double>(k);
    cum_i[static_cast<std::size_t>(k) + 1] = cum_i[static_cast<std::size_t>(k)] + x * std::cos(phase);
    cum_q[static_cast<std::size_t>(k) + 1] = cum_q[static_cast<std::size_t>(k)] + x * std::sin(phase);
  }
  // Window sums over whole tone periods, then a second box over half a tone period: inside the
  // edge ramp a window holds a partial tone, whose demodulated 2f term would otherwise ripple
  // the ramp by up to 1/sin(omega) samples; the half-period box cancels it. Both boxes are
  // symmetric, so the step still crosses half level at its true time.
  const auto half_period = std::max<std::ptrdiff_t>(1, std::lround(0.5 * fs / o.tone_hz));
  const std::ptrdiff_t sum_count = n - window + 1;
  const std::ptrdiff_t m_count = sum_count - half_period + 1;
  std::vector<double> cum_wi(static_cast<std::size_t>(sum_count) + 1, 0.0);
  std::vector<double> cum_wq(static_cast<std::size_t>(sum_count) + 1, 0.0);
  for (std::ptrdiff_t m = 0; m < sum_count; ++m) {
    const auto a = static_cast<std::size_t>(m);
    const auto b = static_cast<std::size_t>(m + window);
    cum_wi[a + 1] = cum_wi[a] + (cum_i[b] - cum_i[a]);
    cum_wq[a + 1] = cum_wq[a] + (cum_q[b] - cum_q[a]);
  }
  std::vector<double> env(static_cast<std::size_t>(m_count));
  const double scale = 2.0 / static_cast<double>(window * half_period);
  for (std::ptrdiff_t m = 0; m < m_count; ++m) {
    const auto a = static_cast<std::size_t>(m);
    const auto b = static_cast<std::size_t>(m + half_period);
    env[a] = scale * std::hypot(cum_wi[b] - cum_wi[a], cum_wq[b] - cum_wq[a]);
  }

  const double peak = *std::max_element(env.begin(), env.end());
  std::ptrdiff_t last_high = -1;
  for (std::ptrdiff_t m = m_count - 1; m >= 0; --m) {
    if (env[static_cast<std::size_t>(m)] >= 0.5 * peak) {
      last_high = m;
      break;
    }
  }
  const std::ptrdiff_t on_end = last_high - window;
  const std::ptrdiff_t off_begin = last_high + window;
  if (peak <= 0.0 || on_end - min_on < 0 || off_begin + min_off > m_count) {
    throw_precondition("audio.buzzer", "no tone stop with " + std::to_string(o.min_on_s) + " s of tone before and " +
                                           std::to_string(o.min_off_s) + " s of silence after it");
  }
  auto level_over = [&](std::ptrdiff_t begin, std::ptrdiff_t end) {
    return std::vector<double>(env.begin() + begin, env.begin() + end);
  };
  const std::vector<double> on_values = level_over(on_end - min_on, on_end);
  const double on_level = median_of(on_values);
  const double off_level = median_of(level_over(off_begin, off_begin + min_off));
  if (on_level < 0.5 * peak || on_level < o.min_on_to_off_ratio * off_level) {
    throw_precondition("audio.buzzer", "tone level " + std::to_string(on_level) +
                                           " is not clearly above the silence level " + std::to_string(off_level));
  }

  // Least-squares line through the ramp between 30% and 70% of the tone level; the true
  // amplitude passes half the tone level exactly at the step (symmetric window). Using
  // on_level/2 rather than (on+off)/2 avoids the noise floor biasing the edge early.
  double s_t = 0, s_e = 0, s_tt = 0, s_te = 0;
  int count = 0;
  for (std::ptrdiff_t m = std::max<std::ptrdiff_t>(0, last_high - window);
       m <= std::min(m_count - 1, last_high + window); ++m) {
    const double e = env[static_cast<std::size_t>(m)];
    if (e < 0.3 * on_level || e > 0.7 * on_level) continue;
    const double t = static_cast<double>(m - last_high);
    s_t += t;
    s_e += e;
    s_tt += t * t;
    s_te += t * e;
    ++count;
  }
  double crossing = 0.0;  // in samples relative to last_high
  double slope = 0.0;     // envelope units per sample
  const double det = count * s_tt - s_t * s_t;
  if (count >= 2 && det > 0.0) {
    slope = (count * s_te - s_t * s_e) / det;
    const double intercept = (s_e - slope * s_t) / count;
    crossing = (0.5 * on_level - intercept) / slope;
  }
  if (!(slope < 0.0) || std::abs(crossing) > static_cast<double>(window)) {
    // Too few ramp samples (very short window): interpolate between the two samples around
    // the half level.
    const double e0 = env[static_cast<std::size_t>(last_high)];
    const double e1 = env[static_cast<std::size_t>(last_high + 1)];
    slope = e1 - e0;
    crossing = slope < 0.0 ? (0.5 * on_level - e0) / slope : 0.0;
  }

  // Envelope noise: robust spread on the tone plateau. Samples inside one ramp share most of
  // their window, so the fit averages almost nothing away: sigma_t = sigma_env / |slope|.
  std::vector<double> deviations;
  deviations.reserve(on_values.size());
  for (double v : on_values) deviations.push_back(std::abs(v - on_level));
  const double sigma_env = 1.4826 * median_of(deviations);
  const double noise_samples = slope < 0.0 ? sigma_env / -slope : static_cast<double>(window);
  // Two limits no envelope can beat: the stop lies anywhere between two samples (uniform, half
  // a sample either way), and inside the ramp the truncated tone's mirror frequency leaves a
  // constant complex term that shifts the half-level crossing by up to 1 / (2 sin omega)
  // samples depending on the tone's phase at the stop (uniform too: divide by sqrt(3)).
  const double mirror_bias = 0.5 / std::abs(std::sin(omega));
  const double sigma_samples = std::sqrt(noise_samples * noise_samples + 1.0 / 12.0 + mirror_bias * mirror_bias / 3.0);

  BuzzerStop stop;
  const double centre = static_cast<double>(last_high) + crossing + 0.5 * static_cast<double>(window - 1) +
                        0.5 * static_cast<double>(half_period - 1);
  stop.t_camera_us = audio.t0_camera_us + centre * 1e6 / fs;
  stop.sigma_us = sigma_samples * 1e6 / fs;
  stop.on_level = on_level;
  stop.off_level = off_level;
  return stop;
}

ClockObservation buzzer_observation(const BuzzerStop& stop, double base_stop_device_us, double base_stop_sigma_us) {
  if (!std::isfinite(base_stop_device_us)) throw_invalid("base_stop_device_us", "not finite");
  if (!std::isfinite(base_stop_sigma_us) || base_stop_sigma_us < 0.0) {
    throw_invalid("base_stop_sigma_us", "must be finite and >= 0");
  }
  ClockObservation obs;
  obs.device_us = base_stop_device_us;
  obs.reference_us = stop.t_camera_us;
  obs.sigma_us = std::hypot(stop.sigma_us, base_stop_sigma_us);
  return obs;
}

}  // namespace posefuse::sync
