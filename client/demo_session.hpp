#pragma once
// A small deterministic session made in code. It is not realistic data (no body in its depth
// frames, so the body fit skips them; realistic sessions come from the simulator, core/sim and
// posefuse-sim); it exercises every part of the stream so that the client and server tests have
// something small to send.
//
// Content (defaults): the header; 10 s of two 9-axis IMUs at 80 Hz, "arm_left" turning through
// a smooth synthetic motion (yaw, pitch, roll sinusoids after 1.5 s of rest) and "base" at rest,
// both with gravity, an earth-like magnetic field (49 uT, 60 deg dip), a constant gyro bias and
// seeded Gaussian noise; small 64x53 depth and body-index frames (a wall and an ellipse "person"
// that sways) and a 25-joint skeleton at 30 Hz; the end marker with the stream's counts.
// Each device has its own clock (different start times), as in a real recording.
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "geometry/quaternion.hpp"
#include "posefuse/v1/session.pb.h"

namespace posefuse::demo {

inline const char* const kArmDevice = "arm_left";
inline const char* const kBaseDevice = "base";
// Device clock values of each stream's first sample, microseconds.
inline constexpr std::int64_t kArmClockStartUs = 500'000;
inline constexpr std::int64_t kBaseClockStartUs = 1'300'000;
inline constexpr std::int64_t kCameraClockStartUs = 10'000'000;

struct DemoSessionOptions {
  double duration_s = 10.0;
  double imu_rate_hz = 80.0;
  double camera_rate_hz = 30.0;
  std::uint32_t depth_width = 64;  // pixels (Kinect v2's 512x424, scaled by 1/8)
  std::uint32_t depth_height = 53;
  int imu_samples_per_batch = 32;
  std::uint32_t seed = 1;  // noise seed; same seed, same session
};

// The ground truth the arm IMU's signals were made from: W_from_A at `t_s` seconds after the
// arm's first sample (W: x magnetic north, y west, z up).
geometry::Quat demo_arm_W_from_A(double t_s);
// The base IMU's fixed orientation W_from_B.
geometry::Quat demo_base_W_from_B();

// The whole session: header, data chunks in stream order, end marker.
std::vector<v1::SessionChunk> make_demo_session(const DemoSessionOptions& options = {});

// Writes the demo session as a chunk file when `out` ends in ".pfchunks", else as a new
// recording directory. Returns the number of chunks written.
std::uint64_t write_demo_session(const std::filesystem::path& out, const DemoSessionOptions& options = {});

}  // namespace posefuse::demo
