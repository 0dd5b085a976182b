#pragma once
// Pipeline stage: the body-model fit of paper 2 for every depth frame. Runs after the forearm
// stage, whose per-sample forearm orientations K_from_F (ForearmOrientations) it consumes for
// the imu term (eq. 9-11) and the forearm roll (II-B).
//
// Order of work:
//  1. Frames: a camera frame (frame_assembler.hpp) with a depth frame and the skeleton of the
//     person `fit.body_id` (the first body seen by default); its silhouette is that person's body
//     index.
//  2. Personalisation (III): the frames of the first `fit.calibration_s` seconds are the
//     calibration frames; fit::personalise on their skeletons gives the shape: the rough shape
//     (III-A), then the fine tuning of shape and pose on the middle frame's depth (III-B,
//     fit::make_depth_shape_refiner; `fit.fine_shape`, default on). When the fine tuning refuses
//     (FIT_FINE_SHAPE) the rough shape is used; when the subject is not in the controlled pose the
//     stage warns FIT_PERSONALISATION and fits the template shape (beta = 0).
//  3. Per frame (II-G, II-H): prepare_observation, an LM fit from the previous frame's pose and
//     one from the starting pose built from the camera skeleton, the lower energy wins; the
//     skeleton start is fitted only when the previous-frame fit is missing or ends at
//     `fit.skeleton_start_energy` or above (0: both always, on two threads). Tracking is lost
//     when the winner's energy exceeds `fit.lost_energy`: counted (FIT_LOST); the next frame still
//     starts from it, and the start policy adds the skeleton start. Frames wait (up to
//     `fit.imu_wait_s`) until the forearm orientations covering them have arrived, so that the imu
//     term has them; then they are fitted without.
//  4. Post-processing: moving average over `fit.smoothing_frames` frames (PoseSmoother), forearm
//     roll from the IMU (fit::forearm_roll), and a FittedFrame per frame: 24 SMPL joints, the 25
//     camera-compatible joints, forearm orientations, per-joint source and confidence, energy.
//
// Hands on a FittedFrame per fitted frame (the frame merge chooses between its estimates and
// the forearm stages', frame_merge.hpp) and at every camera frame FramesDone. The fit's joint
// confidence follows the camera's tracking state (1 tracked, 0.5 otherwise).
//
// Problems that skip a frame are warnings (FIT_FRAME naming the field, e.g. "frame.body_index"
// for an empty silhouette, "skeleton" for a missing one); the session goes on.
#include <cstdint>
#include <deque>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "fit/depth_frame.hpp"
#include "fit/frame_observation.hpp"
#include "fit/packed_body_frame.hpp"
#include "fit/start_extrapolation.hpp"
#include "fit/tracked_skeleton.hpp"
#include "session/pipeline_stage.hpp"
#include "session/stages/body_fit_options.hpp"

namespace posefuse::session {

// One frame as the fit consumes it (the stage's input after decoding).
struct BodyFitFrame {
  std::int64_t t_us = 0;
  fit::DepthFrame frame;
  std::optional<fit::TrackedSkeleton> skeleton;
  double assemble_s = 0;  // thread CPU seconds spent assembling it (BodyFitFrameStats)
};

// A frame waiting for its forearm orientations: the silhouette and its depth only (the fit reads
// nothing else), ~40 kB instead of 651 kB, so that `fit.imu_wait_s` can cover IMU data that a
// stream delivers long after the camera frames (docs/fitting.md, "Body-fit stage").
struct QueuedBodyFitFrame {
  std::int64_t t_us = 0;
  fit::PackedBodyFrame frame;
  std::optional<fit::TrackedSkeleton> skeleton;
  double assemble_s = 0;
};

// Per fitted frame: where the stage's CPU time went and what the two starts of II-G did (for the
// per-phase benchmark tables and the tests of the start policy). Times are CPU seconds of the
// thread that did the work; a start that was not run has 0 iterations and a NaN energy.
struct BodyFitFrameStats {
  std::int64_t t_us = 0;
  double assemble_s = 0;  // depth, body index and skeleton into one frame (decoding not counted)
  double cleanup_s = 0;   // fit::remove_off_body_depth
  fit::ObservationTimes observation;  // fit::prepare_observation by part
  double start_pose_s = 0;     // the skeleton-built starting pose (SkeletonPoseInitializer)
  double fit_previous_s = 0;   // LM from the previous frame's pose
  double fit_skeleton_s = 0;   // LM from the skeleton-built pose
  double post_s = 0;           // smoothing, joints, forearm roll, the emitted result
  int iterations_previous = 0, iterations_skeleton = 0;
  double energy_previous = std::numeric_limits<double>::quiet_NaN();
  double energy_skeleton = std::numeric_limits<double>::quiet_NaN();
  bool previous_won = false;
  bool extrapolated = false;  // the previous-frame fit started from the constant-velocity pose
  double total_s() const {
    return assemble_s + cleanup_s + observation.total_s() + start_pose_s + fit_previous_s + fit_skeleton_s + post_s;
  }
};

// Paper 2 II-G start policy (docs/fitting.md, "Start policy"): the skeleton-built start is fitted
// when there is no previous-frame fit (`previous_energy` empty), when the policy is off
// (`skeleton_start_energy` <= 0: both starts always) or when the previous-frame fit ended at
// `skeleton_start_energy` or above (or at a NaN energy).
bool needs_skeleton_start(std::optional<double> previous_energy, double skeleton_start_energy);

// The camera skeleton as the fit reads it (positions and tracking states).
fit::TrackedSkeleton tracked_skeleton_from(const Skeleton& skeleton);

class BodyFitStage : public Stage {
 public:
  BodyFitStage();
  ~BodyFitStage() override;
  std::string_view name() const override { return "body_fit"; }
  std::string_view description() const override;
  const OptionTable& options() const override;

  void start(const v1::SessionHeader& header, StageOutput& out) override;
  std::vector<ValueKind> consumes() const override { return {ValueKind::kForearmOrientations}; }
  std::vector<ValueKind> produces() const override { return {ValueKind::kFittedFrame, ValueKind::kFramesDone}; }
  void on_camera_frame(const CameraFrame& frame, StageOutput& out) override;
  void on_value(const StageValue& value, StageOutput& out) override;
  void finish(StageOutput& out) override;

  // With `on`, every fitted frame from then on appends a BodyFitFrameStats (off by default: a
  // long session would grow the list without bound).
  void record_frame_stats(bool on) { record_stats_ = on; }
  // One entry per fitted frame while recording, in fit order.
  const std::vector<BodyFitFrameStats>& frame_stats() const { return stats_; }

 private:
  struct Work;  // models, fitter, smoother: built in start()

  void add_camera_frame(const CameraFrame& camera, StageOutput& out);
  // FramesDone: every frame before the oldest one not handed on yet (all when disabled).
  std::int64_t frames_done_up_to() const;
  void add_frame(BodyFitFrame&& frame, StageOutput& out);
  void enqueue(BodyFitFrame&& frame);  // packed into queue_
  void personalise(StageOutput& out);
  // Fits the queued frames whose forearm orientations are known (all when `all`).
  void fit_ready(bool all, StageOutput& out);
  void fit_frame(BodyFitFrame& frame, StageOutput& out);
  void emit_smoothed(const Eigen::VectorXd& theta, StageOutput& out);
  std::optional<Eigen::Quaterniond> K_from_F_at(int arm, std::int64_t t_us) const;

  bool enabled_ = false;
  std::unique_ptr<Work> work_;
  BodyFitOptions options_;
  std::optional<std::uint32_t> body_id_;
  int arm_imus_ = 0;  // arm IMUs in the header

  std::uint64_t frames_without_skeleton_ = 0;  // depth frames without the fitted person's skeleton

  std::optional<std::int64_t> first_t_us_, last_frame_t_us_;
  std::optional<std::int64_t> last_camera_t_us_;  // any camera frame
  std::vector<BodyFitFrame> calibration_frames_;
  bool personalised_ = false;
  std::deque<QueuedBodyFitFrame> queue_;  // personalised, waiting for forearm orientations

  // Forearm orientations by arm (v1::Arm), camera clock.
  std::map<int, std::deque<std::pair<std::int64_t, Eigen::Quaterniond>>> K_from_F_;

  // Per fitted frame, what the emitted result needs beside the (smoothed) pose, in fit order.
  struct Fitted {
    std::int64_t t_us = 0;
    fit::TrackedSkeleton skeleton;
    double energy = 0;
    bool imu_used = false;
  };
  std::deque<Fitted> fitted_;
  std::optional<Eigen::VectorXd> previous_theta_;
  std::int64_t previous_t_us_ = 0;
  // The fit before previous_theta_, while both belong to one track (the constant-velocity start).
  std::optional<fit::FittedPose> before_last_fit_;
  bool record_stats_ = false;
  std::vector<BodyFitFrameStats> stats_;
  std::uint64_t frames_fitted_ = 0, frames_lost_ = 0;
  std::uint64_t frames_without_imu_ = 0;  // fitted while an arm IMU's orientation was missing
};

}  // namespace posefuse::session
