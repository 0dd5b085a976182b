// The IMU batch decoder (session/imu_batch.*) and the sample checks the validator applies
// (imu::validate_imu_stream) on an arbitrary serialised ImuBatch. A batch that decodes has
// one sample per timestamp, and converting it back gives the same arrays.
#include <cstddef>
#include <cstdint>

#include "common/error.hpp"
#include "imu/imu_sample.hpp"
#include "seeds.hpp"
#include "session/imu_batch.hpp"

using namespace posefuse;

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  fuzz::init_harness([] {
    fuzz::Seeds seeds;
    int n = 0;
    for (const v1::SessionChunk& chunk : fuzz::tiny_session()) {
      if (chunk.has_imu()) seeds.push_back({"batch-" + std::to_string(n++), chunk.imu().SerializeAsString()});
    }
    return seeds;
  });
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  v1::ImuBatch batch;
  if (!batch.ParseFromArray(data, static_cast<int>(size))) return 0;
  try {
    const std::vector<imu::ImuSample> samples = session::samples_from_batch(batch, "imu");
    if (samples.size() != static_cast<std::size_t>(batch.t_us_size())) fuzz::invariant_failed("sample count");
    const v1::ImuBatch back = session::batch_from_samples(batch.device_id(), samples);
    if (back.t_us_size() != batch.t_us_size() || back.gyr_rad_s_size() != batch.gyr_rad_s_size() ||
        back.acc_m_s2_size() != batch.acc_m_s2_size() || back.mag_ut_size() != batch.mag_ut_size()) {
      fuzz::invariant_failed("round trip changed the array sizes");
    }
    imu::validate_imu_stream(samples, "imu");
  } catch (const Error&) {
  }
  return 0;
}
