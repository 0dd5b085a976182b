#include "session/imu_batch.hpp"

#include "common/error.hpp"

namespace posefuse::session {

namespace {

void check_size(int actual, int expected, const std::string& field) {
  if (actual != expected) {
    throw_invalid(field, "has " + std::to_string(actual) + " values, expected " + std::to_string(expected) +
                             " (x y z per sample)");
  }
}

imu::Vec3 vec_at(const google::protobuf::RepeatedField<float>& values, int sample) {
  return {values[3 * sample], values[3 * sample + 1], values[3 * sample + 2]};
}

void append(google::protobuf::RepeatedField<float>* values, const imu::Vec3& v) {
  for (int k = 0; k < 3; ++k) values->Add(static_cast<float>(v[k]));
}

}  // namespace

std::vector<imu::ImuSample> samples_from_batch(const v1::ImuBatch& batch, const std::string& field) {
  const int n = batch.t_us_size();
  if (n == 0) throw_invalid(field + ".t_us", "batch has no samples");
  check_size(batch.gyr_rad_s_size(), 3 * n, field + ".gyr_rad_s");
  check_size(batch.acc_m_s2_size(), 3 * n, field + ".acc_m_s2");
  check_size(batch.mag_ut_size(), 3 * n, field + ".mag_uT");
  std::vector<imu::ImuSample> samples(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) {
    imu::ImuSample& s = samples[static_cast<std::size_t>(i)];
    s.t_us = batch.t_us(i);
    s.gyr_rad_s = vec_at(batch.gyr_rad_s(), i);
    s.acc_m_s2 = vec_at(batch.acc_m_s2(), i);
    s.mag_uT = vec_at(batch.mag_ut(), i);
  }
  return samples;
}

v1::ImuBatch batch_from_samples(const std::string& device_id, const std::vector<imu::ImuSample>& samples) {
  v1::ImuBatch batch;
  batch.set_device_id(device_id);
  const int n = static_cast<int>(samples.size());
  batch.mutable_t_us()->Reserve(n);
  batch.mutable_gyr_rad_s()->Reserve(3 * n);
  batch.mutable_acc_m_s2()->Reserve(3 * n);
  batch.mutable_mag_ut()->Reserve(3 * n);
  for (const imu::ImuSample& s : samples) {
    batch.add_t_us(s.t_us);
    append(batch.mutable_gyr_rad_s(), s.gyr_rad_s);
    append(batch.mutable_acc_m_s2(), s.acc_m_s2);
    append(batch.mutable_mag_ut(), s.mag_uT);
  }
  return batch;
}

}  // namespace posefuse::session
