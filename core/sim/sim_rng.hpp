#pragma once
// The simulator's random numbers: deterministic for a seed on every platform.
//
// std::normal_distribution and friends are implementation-defined (libstdc++ and libc++ give
// different sequences for the same engine), so we draw from the fully specified mt19937_64 and
// shape the numbers ourselves. Independent parts of a simulation (error draw, noise, packet
// loss, ...) take their own stream, derived from the session seed and a stream name, so that
// switching one part on or off does not change the numbers another part sees.
#include <cmath>
#include <cstdint>
#include <random>
#include <string_view>

namespace posefuse::sim {

class SimRng {
 public:
  // `stream` names the consumer ("imu_noise", "packet_loss", ...).
  SimRng(std::uint64_t seed, std::string_view stream) : engine_(mix(seed, stream)) {}

  // Uniform in [0, 1), 53 random bits.
  double uniform() { return static_cast<double>(engine_() >> 11) * 0x1.0p-53; }

  // 64 random bits (for samplers that split one draw, see ziggurat_normal.hpp).
  std::uint64_t bits() { return engine_(); }

  // Standard normal by Box-Muller (both values used).
  double normal() {
    if (has_spare_) {
      has_spare_ = false;
      return spare_;
    }
    double u1 = uniform();
    while (u1 <= 0.0) u1 = uniform();
    const double u2 = uniform();
    const double radius = std::sqrt(-2.0 * std::log(u1));
    const double angle = 2.0 * 3.14159265358979323846 * u2;
    spare_ = radius * std::sin(angle);
    has_spare_ = true;
    return radius * std::cos(angle);
  }

 private:
  // splitmix64 finaliser over the seed and an FNV-1a hash of the stream name.
  static std::uint64_t mix(std::uint64_t seed, std::string_view stream) {
    std::uint64_t h = 1469598103934665603ull;
    for (char c : stream) h = (h ^ static_cast<unsigned char>(c)) * 1099511628211ull;
    std::uint64_t z = seed ^ (h + 0x9e3779b97f4a7c15ull + (seed << 6) + (seed >> 2));
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
  }

  std::mt19937_64 engine_;
  double spare_ = 0.0;
  bool has_spare_ = false;
};

}  // namespace posefuse::sim
