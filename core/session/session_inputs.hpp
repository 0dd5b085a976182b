#pragma once
// What the stages read of a session: the chunk stream decoded once by the FrameAssembler
// (frame_assembler.hpp) into typed values. No stage decodes an image or reads a data chunk's
// proto; the header (options, devices) is the stages' only proto input.
#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "geometry/kinect_joints.hpp"
#include "geometry/pinhole_camera.hpp"
#include "imu/imu_sample.hpp"
#include "posefuse/v1/session.pb.h"
#include "session/color_image.hpp"

namespace posefuse::session {

enum class JointState { kNotTracked, kInferred, kTracked };

struct SkeletonJoint {
  geometry::Vec3 p_K = geometry::Vec3::Zero();  // camera frame K, metres
  JointState state = JointState::kNotTracked;
  // The SDK's joint orientation; all zero where the SDK gives none (end joints).
  geometry::Quat orientation = geometry::Quat(0, 0, 0, 0);
};

// One body of the camera's 25-joint skeleton (geometry::KinectJoint order).
struct Skeleton {
  std::uint32_t body_id = 0;
  std::array<SkeletonJoint, geometry::kKinectJointCount> joints{};
};

// Every camera stream of one instant. The frame's time is its depth frame's, or its skeleton's
// where no depth frame came within kSameFrameToleranceUs. Images are empty where the stream sent
// nothing for this instant; cv::Mat shares the pixels, so a stage may keep a frame cheaply.
struct CameraFrame {
  std::int64_t t_us = 0;
  cv::Mat depth_mm;                 // CV_16UC1, millimetres, 0 = no reading
  cv::Mat body_index;               // CV_8UC1, the body id of each pixel, 255 = background
  std::vector<Skeleton> skeletons;  // one per body seen, by body id
  ColorImage color;                 // the colour frame nearest in time (decoded where a stage looks)
  std::int64_t color_t_us = 0;

  // The skeleton of `body_id`, or nullptr.
  const Skeleton* skeleton(std::uint32_t body_id) const;
};

// One IMU batch, on its device's clock.
struct ImuBlock {
  std::string device_id;
  std::vector<imu::ImuSample> samples;
};

// The camera microphone's first channel (the buzzer's tone, paper 1 II-G).
struct AudioBlock {
  std::int64_t t_us = 0;  // camera clock, first sample
  std::vector<std::int16_t> mono;
};

// A clock event (core/sync): a BUZZER_STOP or a BLE receipt with its broadcast's sequence number.
struct ClockEvent {
  enum class Kind { kBuzzerStop, kBleReceipt };
  Kind kind = Kind::kBuzzerStop;
  std::string device_id;
  std::int64_t t_us = 0;           // device clock
  std::uint32_t ble_sequence = 0;  // kBleReceipt only
};

// The session's cameras from the header, with full Brown-Conrady distortion (one model for
// every stage).
struct SessionCameras {
  geometry::PinholeCamera depth;
  std::optional<geometry::PinholeCamera> color;
  geometry::Quat color_from_depth = geometry::Quat::Identity();
  geometry::Vec3 color_from_depth_m = geometry::Vec3::Zero();
  double color_rate_hz = 0.0;  // 0: not given
};
geometry::PinholeCamera pinhole_camera(const v1::CameraIntrinsics& intrinsics);
// The inverse: a header's intrinsics for a camera.
v1::CameraIntrinsics camera_intrinsics(const geometry::PinholeCamera& camera);
SessionCameras session_cameras(const v1::SessionHeader& header);

}  // namespace posefuse::session
