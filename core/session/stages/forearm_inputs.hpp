#pragma once
// What the forearm stage takes from a camera frame: one arm's SDK joints as a forearm::ArmFrame
// (the depth and strap measurements are added to it by forearm/arm_frame_measurement.hpp) and
// views of the frame's depth and grey images.
#include <cstdint>

#include <opencv2/core.hpp>

#include "forearm/forearm_orientation.hpp"
#include "forearm/forearm_track.hpp"
#include "geometry/image_view.hpp"
#include "session/session_inputs.hpp"

namespace posefuse::session {

// The shoulder, elbow and wrist of `side` with their tracking states and the SDK's wrist
// orientation; the SDK elbow is kept as sdk_elbow_K (a depth-measured elbow replaces elbow_K).
forearm::ArmFrame arm_frame_from_skeleton(const Skeleton& skeleton, forearm::Side side, std::int64_t t_us);

// Views of a CV_16UC1 depth (mm) and a CV_8UC1 grey image; an empty Mat gives an empty view.
geometry::DepthImageView depth_view(const cv::Mat& depth_mm);
geometry::GrayImageView gray_view(const cv::Mat& gray);

}  // namespace posefuse::session
