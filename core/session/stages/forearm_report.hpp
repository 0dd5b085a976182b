#pragma once
// The forearm stage's part of the CalibrationReport (docs/server.md, calibration.json): each
// IMU's clock against the camera's and each calibrated arm's forearm model (paper 1, II-H).
#include <cstdint>
#include <string>

#include "forearm/forearm_model.hpp"
#include "forearm/forearm_orientation.hpp"
#include "forearm/mounting_from_motion.hpp"
#include "posefuse/v1/results.pb.h"
#include "sync/linear_clock.hpp"

namespace posefuse::session {

// The result schema's arm of a forearm side.
inline v1::Arm to_proto_arm(forearm::Side side) { return side == forearm::Side::kLeft ? v1::LEFT : v1::RIGHT; }

// The clock's offset at the device's first sample (camera minus device time), its sigma there
// and its drift.
void report_clock(const std::string& device_id, const sync::LinearClock& camera_from_device, double first_device_us,
                  v1::CalibrationReport& report);

// has_model: the strap was seen (r, d_se, d_sw known); without it those are reported as 0.
void report_forearm_model(const std::string& device_id, forearm::Side side, const forearm::ForearmCalibration& c,
                          bool has_model, std::uint32_t strap_frames, v1::CalibrationReport& report);

// An arm whose mounting came from motion (no strap model: r, d_se, d_sw reported as 0).
void report_motion_mounting(const std::string& device_id, forearm::Side side, const forearm::MountingEstimate& m,
                            v1::CalibrationReport& report);

}  // namespace posefuse::session
