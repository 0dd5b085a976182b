#pragma once
// Pipeline stage: orientation W_from_A of every IMU, sample by sample, with
// imu::RobustOrientationFilter (one filter per device in header.imu_devices).
//
// Each IMU block is answered at once with ImuOrientations (stage_values.hpp): the samples and one
// W_from_A per sample, device clock; the quaternion sign is kept continuous from sample to
// sample. The forearm stage reads them; the client gets them as an ImuOrientationBatch. At the end every device gets an
// ImuCalibration entry: the gyro bias the filter estimated and the magnetic field magnitude it
// learned. The paper's magnetometer calibration (ellipsoid fit, paper 1 II-E-1) is not run by
// this stage (mag_fit_residual is NaN, mag_coverage 0); a calibration made before the session
// can come in the header (mag_calibration_option.hpp, "imu.mag_calibration.<device_id>") and is
// then applied to every reading before the filter (eq. 3), and `calibrated` is true.
//
// Options (SessionHeader.options): imu_options.hpp.
#include <map>
#include <optional>
#include <string>

#include "imu/mag_calibration.hpp"
#include "imu/robust_orientation_filter.hpp"
#include "session/pipeline_stage.hpp"

namespace posefuse::session {

class ImuOrientationStage : public Stage {
 public:
  std::string_view name() const override { return "imu_orientation"; }
  std::string_view description() const override;
  const OptionTable& options() const override;

  void start(const v1::SessionHeader& header, StageOutput& out) override;
  std::vector<ValueKind> produces() const override { return {ValueKind::kImuOrientations}; }
  void on_imu(const ImuBlock& block, StageOutput& out) override;
  void finish(StageOutput& out) override;

 private:
  struct Device {
    imu::RobustOrientationFilter filter;
    std::uint64_t samples = 0;
    imu::Quat last_W_from_A = imu::Quat::Identity();
    std::optional<imu::MagCalibration> mag_calibration = std::nullopt;  // from the header, applied by eq. 3
  };
  // In header order, so the calibration report lists devices as the header does.
  std::vector<std::string> device_order_;
  std::map<std::string, Device> devices_;
};

}  // namespace posefuse::session
