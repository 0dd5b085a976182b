#include "imu/imu_sample.hpp"

#include <cmath>
#include <string>

#include "common/error.hpp"

namespace posefuse::imu {

namespace {
std::string at(const char* stream, std::size_t i, const char* field) {
  return std::string(stream) + "[" + std::to_string(i) + "]." + field;
}
}  // namespace

void validate_imu_sample(const ImuSample& s, const char* stream, std::size_t i) {
  if (!s.gyr_rad_s.allFinite()) throw_invalid(at(stream, i, "gyr_rad_s"), "not finite");
  if (!s.acc_m_s2.allFinite()) throw_invalid(at(stream, i, "acc_m_s2"), "not finite");
  for (int k = 0; k < 3; ++k) {
    if (std::isinf(s.mag_uT[k])) throw_invalid(at(stream, i, "mag_uT"), "infinite");
  }
}

void validate_imu_stream(const std::vector<ImuSample>& samples, const char* stream) {
  if (samples.empty()) throw_invalid(stream, "no samples");
  for (std::size_t i = 0; i < samples.size(); ++i) {
    const ImuSample& s = samples[i];
    validate_imu_sample(s, stream, i);
    if (i > 0 && s.t_us <= samples[i - 1].t_us) {
      throw_invalid(at(stream, i, "t_us"), "timestamp " + std::to_string(s.t_us) + " is not after the previous one (" +
                                               std::to_string(samples[i - 1].t_us) + ")");
    }
  }
}

}  // namespace posefuse::imu
