#include "session/result_encoder.hpp"

namespace posefuse::session {

namespace {

void encode(const ImuOrientations& value, v1::FitResult& result) {
  v1::ImuOrientationBatch& batch = *result.mutable_imu_orientations();
  batch.set_device_id(value.device_id);
  batch.mutable_t_us()->Reserve(static_cast<int>(value.samples.size()));
  batch.mutable_w_from_a()->Reserve(4 * static_cast<int>(value.W_from_A.size()));
  for (std::size_t i = 0; i < value.samples.size() && i < value.W_from_A.size(); ++i) {
    batch.add_t_us(value.samples[i].t_us);
    for (const double v : geometry::to_wxyz(value.W_from_A[i])) batch.add_w_from_a(v);
  }
}

void encode(const ForearmOrientations& value, v1::FitResult& result) {
  v1::ForearmOrientationBatch& batch = *result.mutable_forearm_orientations();
  batch.set_device_id(value.device_id);
  batch.set_arm(value.arm);
  for (std::size_t i = 0; i < value.t_us.size(); ++i) {
    batch.add_t_us(value.t_us[i]);
    for (const double v : geometry::to_wxyz(value.K_from_F[i])) batch.add_k_from_f(v);
    batch.add_pronation_rad(value.pronation_rad[i]);
  }
}

}  // namespace

const char* value_kind_name(ValueKind kind) {
  switch (kind) {
    case ValueKind::kImuOrientations: return "imu_orientations";
    case ValueKind::kForearmOrientations: return "forearm_orientations";
  }
  return "(unknown value kind)";
}

v1::FitResult encode_value(const StageValue& value) {
  v1::FitResult result;
  std::visit([&](const auto& v) { encode(v, result); }, value);
  return result;
}

}  // namespace posefuse::session
