#include "sync/tone_search.hpp"

#include <algorithm>
#include <cmath>
#include <complex>
#include <numbers>
#include <string>
#include <vector>

#include "common/error.hpp"

namespace posefuse::sync {

namespace {

using Complex = std::complex<double>;

// In-place iterative radix-2 FFT; x.size() is a power of two.
void fft(std::vector<Complex>& x) {
  const std::size_t n = x.size();
  for (std::size_t i = 1, j = 0; i < n; ++i) {  // bit-reversal permutation
    std::size_t bit = n >> 1;
    for (; j & bit; bit >>= 1) j ^= bit;
    j ^= bit;
    if (i < j) std::swap(x[i], x[j]);
  }
  for (std::size_t length = 2; length <= n; length <<= 1) {
    const Complex step = std::polar(1.0, -2.0 * std::numbers::pi / static_cast<double>(length));
    for (std::size_t start = 0; start < n; start += length) {
      Complex w = 1.0;
      for (std::size_t k = 0; k < length / 2; ++k, w *= step) {
        const Complex even = x[start + k], odd = w * x[start + k + length / 2];
        x[start + k] = even + odd;
        x[start + k + length / 2] = even - odd;
      }
    }
  }
}

// Where the parabola through (-1, a), (0, b), (1, c) peaks, in (-1, 1).
double parabola_peak(double a, double b, double c) {
  const double curvature = a - 2.0 * b + c;
  if (!(curvature < 0.0)) return 0.0;
  return std::clamp(0.5 * (a - c) / curvature, -0.5, 0.5);
}

constexpr std::size_t kBandNear = 4, kBandFar = 12;  // the neighbourhood, in bins (Hann main lobe: +-2)
constexpr std::size_t kLoudRank = 3;                 // the on-level is the third-loudest frame's

}  // namespace

void validate_tone_search(const ToneSearchOptions& o, double rate) {
  if (!std::isfinite(rate) || rate <= 0.0) throw_invalid("audio.sample_rate_hz", "must be > 0");
  if (!(o.min_hz > 0.0) || !(o.max_hz > o.min_hz) || !(o.min_hz < rate / 2.0)) {
    throw_invalid("options", "need 0 < min_hz < max_hz and min_hz below the Nyquist frequency " +
                                 std::to_string(rate / 2.0) + " Hz");
  }
  if (!(o.frame_s > 0.0) || !(o.min_on_to_off_ratio > 1.0) || !(o.min_peak_to_band_ratio > 1.0)) {
    throw_invalid("options", "need frame_s > 0 and both ratios > 1");
  }
}

std::optional<FoundTone> find_stopping_tone(const AudioPcm& audio, const ToneSearchOptions& options) {
  const double rate = audio.sample_rate_hz;
  validate_tone_search(options, rate);
  const ToneSearchOptions& o = options;
  std::size_t n = 64;
  while (static_cast<double>(n) < o.frame_s * rate) n <<= 1;
  const std::size_t frames = audio.samples.size() / n;
  if (frames < 4) return std::nullopt;
  const double bin_hz = rate / static_cast<double>(n);
  const std::size_t k_min = std::max<std::size_t>(kBandFar + 1, static_cast<std::size_t>(std::ceil(o.min_hz / bin_hz)));
  const std::size_t k_max =
      std::min(n / 2 - kBandFar - 1, static_cast<std::size_t>(std::floor(std::min(o.max_hz, rate / 2.0) / bin_hz)));
  if (k_min > k_max) return std::nullopt;

  // power[f][k]: frame f, bin k (all bins up to Nyquist, for the neighbourhoods).
  std::vector<std::vector<double>> power(frames, std::vector<double>(n / 2 + 1));
  std::vector<double> hann(n);
  for (std::size_t i = 0; i < n; ++i)
    hann[i] = 0.5 - 0.5 * std::cos(2.0 * std::numbers::pi * static_cast<double>(i) / static_cast<double>(n));
  std::vector<Complex> x(n);
  for (std::size_t f = 0; f < frames; ++f) {
    for (std::size_t i = 0; i < n; ++i) x[i] = hann[i] * static_cast<double>(audio.samples[f * n + i]);
    fft(x);
    for (std::size_t k = 0; k <= n / 2; ++k) power[f][k] = std::norm(x[k]) + 1e-9;  // no log of zero
  }

  std::optional<FoundTone> best;
  std::size_t best_k = 0, best_frame = 0;
  double best_on = 0.0;
  std::vector<std::pair<double, std::size_t>> level(frames);
  for (std::size_t k = k_min; k <= k_max; ++k) {
    for (std::size_t f = 0; f < frames; ++f) level[f] = {power[f][k], f};
    std::sort(level.begin(), level.end(), std::greater<>());
    const double on = level[kLoudRank - 1].first, off = level.back().first;
    const std::size_t loud_frame = level[kLoudRank - 1].second;
    const double on_to_off = std::sqrt(on / off);
    if (on_to_off < o.min_on_to_off_ratio || on <= best_on) continue;
    // A tone is a local peak standing above its neighbourhood in the loud frame.
    const std::vector<double>& p = power[loud_frame];
    if (p[k] < p[k - 1] || p[k] < p[k + 1]) continue;
    double band = 0.0;
    for (std::size_t d = kBandNear; d <= kBandFar; ++d) band += p[k - d] + p[k + d];
    band /= 2.0 * static_cast<double>(kBandFar - kBandNear + 1);
    const double peak_to_band = std::sqrt(p[k] / band);
    if (peak_to_band < o.min_peak_to_band_ratio) continue;
    best = FoundTone{0.0, on_to_off, peak_to_band};
    best_k = k;
    best_frame = loud_frame;
    best_on = on;
  }
  if (!best) return std::nullopt;
  // Refined per frame where the tone sounds (within 12 dB of its loud level), then averaged.
  double sum_hz = 0.0;
  int count = 0;
  for (std::size_t f = 0; f < frames; ++f) {
    const std::vector<double>& p = power[f];
    if (p[best_k] < best_on / 16.0 && f != best_frame) continue;
    std::size_t k = best_k;  // the local maximum next to it (the tone may sit on a bin edge)
    if (p[k - 1] > p[k]) --k;
    else if (p[k + 1] > p[k]) ++k;
    sum_hz += (static_cast<double>(k) + parabola_peak(std::log(p[k - 1]), std::log(p[k]), std::log(p[k + 1]))) * bin_hz;
    ++count;
  }
  best->hz = sum_hz / count;
  return best;
}

}  // namespace posefuse::sync
