#pragma once
// Pipeline stage: the body-model fit of paper 2 for every depth frame. Runs after the forearm
// stage, whose per-sample forearm orientations K_from_F (ForearmOrientations) it consumes for
// the imu term (eq. 9-11) and the forearm roll (II-B).
//
// Order of work:
//  1. Frames: a camera frame (frame_assembler.hpp) with a depth frame and the skeleton of the
//     person `fit.body_id` (the first body seen by default); its silhouette is that person's body
//     index.
//  2. The fit (fit::BodyTracker, fit/body_tracker.hpp): personalisation from the frames of the
//     first `fit.calibration_s` seconds (`fit.fine_shape`), the two starts of II-G
//     (`fit.skeleton_start_energy`, `fit.start_velocity_gain`), lost tracking above
//     `fit.lost_energy` (FIT_LOST), smoothing over `fit.smoothing_frames`, the forearm roll.
//  3. Frames wait (up to `fit.imu_wait_s`) until the forearm orientations covering them have
//     arrived, so that the imu term has them; then they are fitted without (FIT_NO_IMU).
//
// Hands on a FittedFrame per fitted frame (the frame merge chooses between its estimates and
// the forearm stages', frame_merge.hpp) and at every camera frame FramesDone. The fit's joint
// confidence follows the camera's tracking state (1 tracked, 0.5 otherwise).
//
// Problems that skip a frame are warnings (FIT_FRAME naming the field, e.g. "frame.body_index"
// for an empty silhouette, "skeleton" for a missing one); the session goes on.
#include <cstdint>
#include <deque>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "body/template_generator.hpp"
#include "fit/body_tracker.hpp"
#include "fit/packed_body_frame.hpp"
#include "fit/tracked_skeleton.hpp"
#include "session/pipeline_stage.hpp"
#include "session/stages/body_fit_options.hpp"

namespace posefuse::session {

using fit::BodyFitFrame;
using fit::BodyFitFrameStats;
using fit::needs_skeleton_start;

// A frame waiting for its forearm orientations: the silhouette and its depth only (the fit reads
// nothing else), ~40 kB instead of 651 kB, so that `fit.imu_wait_s` can cover IMU data that a
// stream delivers long after the camera frames (docs/fitting.md, "Body-fit stage").
struct QueuedBodyFitFrame {
  std::int64_t t_us = 0;
  fit::PackedBodyFrame frame;
  std::optional<fit::TrackedSkeleton> skeleton;
  double assemble_s = 0;
};

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
  std::size_t held_bytes() const override;

  // With `on`, every fitted frame from then on appends a BodyFitFrameStats (off by default: a
  // long session would grow the list without bound).
  void record_frame_stats(bool on);
  // One entry per fitted frame while recording, in fit order.
  const std::vector<BodyFitFrameStats>& frame_stats() const;

 private:
  void add_camera_frame(const CameraFrame& camera, StageOutput& out);
  // FramesDone: every frame before the oldest one not handed on yet (all when disabled).
  std::int64_t frames_done_up_to() const;
  // Frames the tracker admits (personalised) go to queue_, packed.
  void enqueue(fit::BodyTracker::Admitted&& admitted, StageOutput& out);
  // Fits the queued frames whose forearm orientations are known (all when `all`).
  void fit_ready(bool all, StageOutput& out);
  void hand_on(fit::BodyTracker::Output&& fitted, StageOutput& out);
  std::optional<fit::ForearmOrientationSample> K_from_F_at(fit::ArmSide side, std::int64_t t_us) const;
  void report_shape(StageOutput& out) const;

  bool enabled_ = false;
  std::unique_ptr<fit::BodyTracker> tracker_;
  body::Sex sex_ = body::Sex::kMale;  // the template's (BodyShape.body_model)
  BodyFitOptions options_;
  int depth_width_ = 0, depth_height_ = 0;
  std::optional<std::uint32_t> body_id_;
  int arm_imus_ = 0;  // arm IMUs in the header

  std::uint64_t frames_without_skeleton_ = 0;  // depth frames without the fitted person's skeleton
  std::uint64_t frames_without_imu_ = 0;       // fitted while an arm IMU's orientation was missing
  std::uint64_t frames_off_camera_ = 0;        // with a tracked camera joint far from the fit
  std::uint64_t frames_out_of_view_ = 0;       // with a fitted camera joint outside the depth image

  std::optional<std::int64_t> last_frame_t_us_;
  std::optional<std::int64_t> last_camera_t_us_;  // any camera frame
  std::deque<QueuedBodyFitFrame> queue_;          // personalised, waiting for forearm orientations
  std::size_t queued_pixel_bytes_ = 0;            // their packed pixels (PackedBodyFrame::bytes)

  // Forearm orientations by arm (v1::Arm), camera clock.
  // Per arm: each forearm sample's time and orientation, none where its confidence is below
  // forearm::kConfidentAt (it still tells that the forearm stage has reached that time).
  std::map<int, std::deque<std::pair<std::int64_t, std::optional<fit::ForearmOrientationSample>>>> K_from_F_;
  bool record_stats_ = false;
};

}  // namespace posefuse::session
