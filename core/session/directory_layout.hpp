#pragma once
// Names and columns of the directory form of a recording (docs/recording-format.md), shared by
// DirectoryReader and DirectoryWriter.
#include <array>
#include <string>
#include <vector>

#include "geometry/kinect_joints.hpp"

namespace posefuse::session::layout {

inline const char* const kHeaderJson = "header.json";
inline const char* const kEndJson = "end.json";
inline const char* const kDepthDir = "depth";           // depth/<t_us>.png (16-bit PNG)
inline const char* const kBodyIndexDir = "body_index";  // body_index/<t_us>.png (8-bit PNG)
inline const char* const kColorDir = "color";           // color/<t_us>.jpg | .png
inline const char* const kImuDir = "imu";               // imu/<device_id>.csv
inline const char* const kSkeletonCsv = "skeleton.csv";
inline const char* const kSyncEventsCsv = "sync_events.csv";
inline const char* const kAudioWav = "audio.wav";
inline const char* const kAudioChunksCsv = "audio_chunks.csv";

// The directory keeps IMU samples, not batches: reading it back groups each device's rows into
// batches of this many consecutive samples (the last batch may be shorter).
inline constexpr int kImuSamplesPerBatch = 32;

inline const std::vector<std::string> kSkeletonColumns = {"t_us", "body_id", "joint", "joint_name", "state", "x_m",
                                                          "y_m",  "z_m",     "qw",    "qx",         "qy",    "qz"};
inline const std::vector<std::string> kImuColumns = {"t_us", "gx", "gy", "gz", "ax", "ay", "az", "mx", "my", "mz"};
inline const std::vector<std::string> kAudioChunkColumns = {"t_us", "frames"};
inline const std::vector<std::string> kSyncEventColumns = {"t_us", "device_id", "kind", "payload_hex"};

// Kinect v2 JointType names, in JointType order (the skeleton.csv joint_name column).
using geometry::kKinectJointNames;

}  // namespace posefuse::session::layout
