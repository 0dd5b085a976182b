#pragma once
// Pipeline stage, after the frame merge: the clinical measures of the fitted body
// (docs/measures.md). A thin adapter over measures/joint_angles.hpp and measures/repetitions.hpp.
//
// Consumes every FrameEstimate with 24 SMPL joints (a body fit) and hands on its ISB joint angles
// (FrameAngles); pronation comes from the frame's forearm orientation K_from_F (the wrist IMU)
// turned into the fitted arm. The vertical (measures/session_vertical.hpp) is the floor that the
// camera frames' depth shows, or the world's z mapped by the forearm stage's K_from_W
// (ArmTrackStart), whichever is known first; until one is, K's y (a level camera), at half
// confidence for the thorax angles, with warning MEASURES_VERTICAL_ASSUMED. The calibration
// report's `vertical` says which it was. After the last frame it segments
// repetitions on measures.repetition_angle (auto: the arm or trunk angle that moves most) and
// hands on a Repetitions value. Warnings: MEASURES_NO_BODY_FIT, fit.enabled but no frame had a
// fitted body (with the fit off there are no angles, by design, and no warning);
// MEASURES_FRAME_SKIPPED, fitted frames whose joints span no segment frame (counted, the first
// named), which get no angles while the session goes on; MEASURES_REPETITIONS_UNCERTAIN, fewer
// than half of the segmented angle's frames at confidence >= measures::kConfidentAt, else
// MEASURES_REPETITION_RANGE_UNCERTAIN, counted repetitions whose range is below it;
// MEASURES_START_AMBIGUOUS, a start out of rest that may hold one repetition more than counted;
// MEASURES_REST_AMBIGUOUS, turns within the hysteresis of the resting-half bound.
// Holds: the candidate angles' series and confidences, 12 bytes per angle per frame (9 angles
// with auto: about 12 MB per session-hour at 30 Hz), and the last frame's angles.
#include <array>
#include <optional>
#include <vector>

#include "geometry/pinhole_camera.hpp"
#include "measures/session_vertical.hpp"
#include "session/pipeline_stage.hpp"
#include "session/stages/measures_options.hpp"

namespace posefuse::session {

class MeasuresStage : public Stage {
 public:
  std::string_view name() const override { return "measures"; }
  std::string_view description() const override;
  const OptionTable& options() const override;
  std::vector<ValueKind> consumes() const override { return {ValueKind::kArmTrackStart, ValueKind::kFrameEstimate}; }
  std::vector<ValueKind> produces() const override { return {ValueKind::kFrameAngles, ValueKind::kRepetitions}; }
  void start(const v1::SessionHeader& header, StageOutput& out) override;
  void on_camera_frame(const CameraFrame& frame, StageOutput& out) override;
  void on_value(const StageValue& value, StageOutput& out) override;
  void finish(StageOutput& out) override;
  std::size_t held_bytes() const override { return series_.held_bytes(); }

 private:
  void count_length_limited_elbows(const measures::PosedUpperBody& body, const measures::JointAngles& angles);
  void count_thorax_limited_elevations(const measures::PosedUpperBody& body, const measures::JointAngles& angles);
  void count_tilt_limited_thorax(const measures::PosedUpperBody& body, const measures::JointAngles& angles);
  void add_frame(const FrameEstimate& frame, StageOutput& out);
  void warn_uncertain_repetitions(const measures::SessionRepetitions& repetitions, StageOutput& out);
  void report_vertical(StageOutput& out) const;

  MeasuresOptions options_;
  measures::SessionVertical vertical_;
  std::optional<geometry::PinholeCamera> depth_camera_;  // for the floor search
  bool warned_vertical_ = false;
  bool fit_enabled_ = false;
  std::size_t skipped_frames_ = 0;  // fitted frames whose joints gave no segment frames
  std::string first_skip_;
  // Elbow flexion values (two per frame) whose joints are confident but whose arm lengths are
  // not (measures.arm_length_uncertainty), and the values of each arm angle (two per frame).
  std::size_t length_limited_elbows_ = 0, arm_values_ = 0;
  // Elevations (two per frame) below confidence 0.5 although every joint they are read from is
  // at least 0.5: the thorax's error and the humerus' own add up (docs/measures.md).
  std::size_t thorax_limited_elevations_ = 0;
  // Frames whose thorax flexion is below confidence 0.5 although its joints and the vertical are
  // at least 0.5: the trunk tilted sideways towards Z-X-Y's gimbal lock (docs/measures.md).
  std::size_t tilt_limited_thorax_ = 0, thorax_values_ = 0;
  std::optional<measures::JointAngles> previous_;
  measures::AngleSeries series_;
};

}  // namespace posefuse::session
