#pragma once
// Paper 2's body fit over a sequence of depth frames (docs/fitting.md, "Body-fit stage"):
//  1. Personalisation (III): the frames of the first calibration_s seconds are kept; fit::personalise
//     on their skeletons gives the rough shape (III-A), then the fine tuning of shape and pose on the
//     middle frame's depth (III-B, fit::make_depth_shape_refiner; fine_shape). When the fine tuning
//     refuses (FIT_FINE_SHAPE) or the subject is not in the controlled pose (FIT_PERSONALISATION),
//     the shape of the subject's measured height (subject_height_m, fit/height_shape.hpp), else the
//     template shape (beta = 0); with fine_shape off, the rough shape.
//  2. Per frame, the start policy of II-G (docs/fitting.md, "Start policy"): an LM fit from the
//     previous frame's pose (moved on by constant velocity, fit/start_extrapolation.hpp) and one
//     from the pose built from the camera skeleton, the lower energy wins. A winner above
//     lost_energy is counted as lost; the next frame still starts from it.
//  3. Moving-average smoothing (PoseSmoother) and the output per frame (fit/fitted_body_frame.hpp).
// Takes and returns domain values; reading options and the values between stages is the caller's.
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <deque>
#include <functional>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "body/smpl_model.hpp"
#include "fit/arm_roll.hpp"
#include "fit/body_fit_frame_stats.hpp"
#include "fit/depth_frame.hpp"
#include "fit/fit_options.hpp"
#include "fit/fitted_body_frame.hpp"
#include "fit/pose_smoothing.hpp"
#include "fit/start_extrapolation.hpp"
#include "fit/tracked_skeleton.hpp"
#include "raycast/depth_camera.hpp"

namespace posefuse::fit {

struct BodyTrackerOptions {
  double calibration_s = 0;  // personalisation frames: the first this many seconds
  bool fine_shape = true;    // III-B after III-A
  // The subject's measured standing height (session header height_m): without a personalised
  // shape, the shape it implies (fit/height_shape.hpp) instead of the template's. The tracker's
  // constructor throws posefuse::Error "height_m" outside 0.5 .. 2.5 m.
  std::optional<double> subject_height_m;
  FitOptions fit;
  PoseSmoothingOptions smoothing;
  StartExtrapolationOptions extrapolation;
  double skeleton_start_energy = 0;  // needs_skeleton_start; 0: both starts always, on two threads
  double lost_energy = 0;            // above it a frame's tracking is lost
  // A released frame's pose averages the fits of its smoothing window, so where any of them lies
  // above it (or at a NaN energy) the frame's confidences are capped at untrusted_fit_confidence().
  double trusted_energy = std::numeric_limits<double>::infinity();
};

// One frame as the fit consumes it.
struct BodyFitFrame {
  std::int64_t t_us = 0;
  DepthFrame frame;
  std::optional<TrackedSkeleton> skeleton;
  double assemble_s = 0;  // thread CPU seconds the caller spent assembling it (BodyFitFrameStats)
};

// Something the tracker could not do; the session goes on.
struct FitWarning {
  std::string code, field, message;
};

// The start policy of II-G (docs/fitting.md, "Start policy"): the skeleton-built start is fitted
// when there is no previous-frame fit (`previous_energy` empty), when the policy is off
// (`skeleton_start_energy` <= 0: both starts always) or when the previous-frame fit ended at
// `skeleton_start_energy` or above (or at a NaN energy).
bool needs_skeleton_start(std::optional<double> previous_energy, double skeleton_start_energy);

// A forearm's orientation K_from_F at a camera time, where known (the caller's IMU data), with the
// imu term's weight for its forearm axis (forearm_direction_weight: 1 where the axis is confident).
struct ForearmOrientationSample {
  Eigen::Quaterniond K_from_F;
  double axis_weight = 1.0;
};
using ForearmOrientationAt = std::function<std::optional<ForearmOrientationSample>(ArmSide side, std::int64_t t_us)>;

// The fitted shape, for the calibration report.
struct FittedShape {
  Eigen::VectorXd beta;
  Eigen::Matrix3Xd rest_joints_K;  // the 24 joints at the zero pose of the fitted layout
  bool estimated = false;          // personalised (not the template shape after a refusal)
};

class BodyTracker {
 public:
  struct Output {
    std::vector<FittedBodyFrame> frames;  // in fit order, as smoothing releases them
    std::vector<FitWarning> warnings;
    bool fitted = false;  // fit(): the frame was fitted (no FIT_FRAME warning)
  };
  // What admit() gives back: the frames ready to be fitted, in time order.
  struct Admitted {
    std::vector<BodyFitFrame> frames;
    std::vector<FitWarning> warnings;
  };

  BodyTracker(std::shared_ptr<const body::SmplModel> model, const raycast::DepthIntrinsics& intrinsics,
              const BodyTrackerOptions& options);
  ~BodyTracker();
  BodyTracker(const BodyTracker&) = delete;
  BodyTracker& operator=(const BodyTracker&) = delete;

  // A new frame (in time order): kept while it is a calibration frame (nothing back); the first
  // frame after calibration_s personalises, and the calibration frames come back with it.
  // Afterwards each frame comes back at once.
  Admitted admit(BodyFitFrame&& frame);
  // End of session before calibration_s: personalises with the calibration frames kept (none:
  // nothing, and no shape).
  Admitted personalise_now();
  bool personalised() const { return personalised_; }

  // Fits one admitted frame (in time order); `K_from_F_at` gives the forearm orientations, for
  // the imu term at this frame and for the output of each frame smoothing releases. A frame that
  // cannot be fitted is a FIT_FRAME warning.
  Output fit(BodyFitFrame& frame, const ForearmOrientationAt& K_from_F_at);
  // End of session: the frames smoothing still holds.
  Output flush(const ForearmOrientationAt& K_from_F_at);

  // The oldest frame held (calibration frames, fitted frames smoothing has not released).
  std::optional<std::int64_t> oldest_held_t_us() const;
  // The memory those frames and the frame statistics take (session::Stage::held_bytes).
  std::size_t held_bytes() const;
  // After personalisation (or its refusal); none before.
  std::optional<FittedShape> shape() const;

  std::uint64_t frames_fitted() const { return frames_fitted_; }
  std::uint64_t frames_lost() const { return frames_lost_; }
  // Released frames not lost whose smoothing window holds a fit above trusted_energy (or at a
  // NaN energy): their confidences were capped.
  std::uint64_t frames_untrusted() const { return frames_untrusted_; }

  // With `on`, every fitted frame from then on appends a BodyFitFrameStats.
  void record_frame_stats(bool on) { record_stats_ = on; }
  const std::vector<BodyFitFrameStats>& frame_stats() const { return stats_; }

 private:
  struct Work;  // models, fitters, smoother
  // Per fitted frame, what its output needs beside the (smoothed) pose, in fit order.
  struct Fitted {
    std::int64_t t_us = 0;
    TrackedSkeleton skeleton;
    double energy = 0;
    bool imu_used = false;
  };

  std::vector<FitWarning> personalise();
  FittedBodyFrame release(const Eigen::VectorXd& theta, const ForearmOrientationAt& K_from_F_at);

  BodyTrackerOptions options_;
  std::unique_ptr<Work> work_;
  std::optional<std::int64_t> first_t_us_;
  std::vector<BodyFitFrame> calibration_frames_;
  std::size_t calibration_pixel_bytes_ = 0;  // their images' buffers
  bool personalised_ = false;
  std::deque<Fitted> fitted_;
  // The energies of the last released frames, as many as the smoothing window reaches back.
  std::deque<double> released_energies_;
  std::optional<Eigen::VectorXd> previous_theta_;
  std::int64_t previous_t_us_ = 0;
  // The fit before previous_theta_, while both belong to one track (the constant-velocity start).
  std::optional<FittedPose> before_last_fit_;
  bool record_stats_ = false;
  std::vector<BodyFitFrameStats> stats_;
  std::uint64_t frames_fitted_ = 0, frames_lost_ = 0, frames_untrusted_ = 0;
};

}  // namespace posefuse::fit
