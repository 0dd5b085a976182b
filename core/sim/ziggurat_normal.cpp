#include "sim/ziggurat_normal.hpp"

#include <array>
#include <cmath>

namespace posefuse::sim {
namespace {

constexpr int kLayers = 128;
// Marsaglia and Tsang's constants for 128 layers: the tail's start and each layer's area.
constexpr double kTailStart = 3.442619855899;
constexpr double kLayerArea = 9.91256303526217e-3;

double density(double x) { return std::exp(-0.5 * x * x); }

struct Layers {
  // x[i]: right edge of layer i (x[0] = v / f(r), the base layer's width as one rectangle);
  // f[i] = density(x[i]); x[128] = 0, f[128] = 1.
  std::array<double, kLayers + 1> x{}, f{};
  Layers() {
    x[0] = kLayerArea / density(kTailStart);
    x[1] = kTailStart;
    for (int i = 1; i < kLayers - 1; ++i) {
      // Layer i has area x_i (f(x_{i+1}) - f(x_i)) = v.
      const double next_density = density(x[i]) + kLayerArea / x[i];
      x[i + 1] = std::sqrt(-2.0 * std::log(next_density));
    }
    x[kLayers] = 0.0;
    for (int i = 0; i <= kLayers; ++i) f[i] = density(x[i]);
  }
};

const Layers& layers() {
  static const Layers table;
  return table;
}

}  // namespace

double ziggurat_normal(SimRng& rng) {
  const Layers& t = layers();
  for (;;) {
    // Low 7 bits: the layer; bit 7: the sign; the top 53 bits: the position in the layer.
    const std::uint64_t draw = rng.bits();
    const auto layer = static_cast<int>(draw & (kLayers - 1));
    const double sign = (draw & 0x80u) != 0 ? -1.0 : 1.0;
    const double u = static_cast<double>(draw >> 11) * 0x1.0p-53;
    const double x = u * t.x[static_cast<std::size_t>(layer)];
    if (x < t.x[static_cast<std::size_t>(layer) + 1]) return sign * x;
    if (layer == 0) {
      // The tail beyond r: x = r + e1 / r accepted when e2 * 2 >= (e1 / r)^2 (exponentials e1, e2).
      for (;;) {
        double u1 = rng.uniform(), u2 = rng.uniform();
        while (u1 <= 0.0) u1 = rng.uniform();
        while (u2 <= 0.0) u2 = rng.uniform();
        const double beyond = -std::log(u1) / kTailStart;
        if (-2.0 * std::log(u2) >= beyond * beyond) return sign * (kTailStart + beyond);
      }
    }
    // The wedge between x_{i+1} and x_i: accept under the curve.
    const auto i = static_cast<std::size_t>(layer);
    const double y = t.f[i] + rng.uniform() * (t.f[i + 1] - t.f[i]);
    if (y < density(x)) return sign * x;
  }
}

}  // namespace posefuse::sim
