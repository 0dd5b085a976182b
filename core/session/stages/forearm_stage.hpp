#pragma once
// Pipeline stage: forearm fusion of paper 1 (II-F to II-L) for every arm IMU of the session.
// Runs after the IMU orientation stage, whose W_from_A (ImuOrientations) it consumes.
//
// Inputs: header (IMU roles, depth and colour cameras, options), skeleton frames (shoulder,
// elbow, wrist of the person `forearm.body_id`), depth and colour frames (strap detection,
// II-I), IMU batches (specific force), audio and sync events (clocks, II-G).
//
// Order of work:
//  1. Until calibrated everything is buffered. Clocks: the base IMU's buzzer stop heard in the
//     audio, BLE receipts for the arm IMUs (stream_clocks.hpp). Camera alignment: eq. 7,
//     K_from_W = K_from_B * (mean W_from_B of the base IMU)^-1, K_from_B from the option
//     forearm.K_from_B (the rig's eq. 8 calibration, core/calib).
//  2. When the camera clock passes forearm.calibration_s after the first skeleton frame, each
//     arm is calibrated (II-H, forearm/arm_calibration.hpp): r, d_se, d_sw, d_ul and
//     eq. 9 over the longest still run. The forearm orientation in the pose comes from the
//     skeleton: the shoulder-elbow-wrist plane with the palm towards the camera
//     (forearm.calibration_orientation = pose, forearm_orientation.hpp), or from the SDK's
//     wrist orientation (= sdk, the paper's K_from_F', whose axes must then be F's).
//     With forearm.axis = depth (default) every frame's elbow and wrist are first replaced by
//     the ends of the forearm axis fitted to the depth image (forearm_axis_depth.hpp), so the
//     calibration, the strap search, the II-J tests and eq. 10 do not inherit the SDK's joint
//     bias; = sdk keeps paper 1's SDK joints. With forearm.upper_arm = depth (default) the arm
//     plane's upper arm (and so the calibration frame's roll about the forearm) is measured in
//     the depth image too (upper_arm_depth.hpp); = sdk takes it from the SDK shoulder.
//  3. Then in time order (forearm/forearm_track.hpp): forearm orientation + pronation per IMU
//     sample (ForearmOrientations; with forearm.axis_correction = auto and the depth axis,
//     turned slowly onto the forearm axes of the visible frames before it,
//     visual_axis_correction.hpp, so it waits for the frames up to its time), and per camera
//     frame the strap's IMU position when the II-J tests accept it (ArmTrack). The occlusion
//     gaps are the forearm_gaps stage's, after the body fit (forearm_gaps_stage.hpp).
// Hands on per arm an ArmTrackStart once its calibration is over (tracked or not) and, at every
// camera frame, FramesDone: every ArmTrack frame up to then has been handed on.
//  4. An arm whose calibration pose is missing or refused is not given up: its mounting F_from_A
//     is estimated from the session's natural motion (forearm/mounting_from_motion.hpp, warning
//     FOREARM_MOUNTING_FROM_MOTION with the estimate and what limits it), until a calibration pose
//     later in the session replaces it (FOREARM_CALIBRATION_LATER; pronation from then on). Its orientations carry
//     the estimate's predicted error and confidence, grow more certain as the estimate is
//     refined, and have no pronation relative to a calibration pose (NaN); no strap model, so no
//     IMU positions. FOREARM_MOUNTING_NOT_OBSERVABLE names an arm for which motion gave none.
//  5. At the end, every tracked arm's offline solution (ForearmOrientations with offline set): the
//     whole session again with the final mounting (forearm_track.hpp offline_samples).
// Problems that stop an arm are warnings naming them (the rest of the session goes on):
// FOREARM_NO_BASE_IMU, FOREARM_NO_CAMERA_ALIGNMENT, FOREARM_NO_SYNC (no buzzer event, the stop
// not heard, no shared BLE broadcast), FOREARM_CALIBRATION (too short or no calibration hold, or
// one no arm in the pose gives: forearm_model.hpp CalibrationOptions),
// FOREARM_STRAP_NOT_SEEN (no positions: orientation only).
#include <deque>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "forearm/calibration_frames.hpp"
#include "forearm/forearm_model.hpp"
#include "forearm/forearm_track.hpp"
#include "forearm/mounting_from_motion.hpp"
#include "forearm/strap_detection.hpp"
#include "geometry/image_view.hpp"
#include "geometry/pixel_rays.hpp"
#include "session/pipeline_stage.hpp"
#include "session/stages/forearm_options.hpp"
#include "session/stages/stream_clocks.hpp"

namespace posefuse::session {

class ForearmStage : public Stage {
 public:
  ForearmStage();
  ~ForearmStage() override;
  std::string_view name() const override { return "forearm"; }
  std::string_view description() const override;
  const OptionTable& options() const override;

  void start(const v1::SessionHeader& header, StageOutput& out) override;
  std::vector<ValueKind> consumes() const override { return {ValueKind::kImuOrientations}; }
  std::vector<ValueKind> produces() const override {
    return {ValueKind::kForearmOrientations, ValueKind::kArmTrackStart, ValueKind::kArmTrack, ValueKind::kFramesDone};
  }
  void on_value(const StageValue& value, StageOutput& out) override;
  void on_camera_frame(const CameraFrame& frame, StageOutput& out) override;
  void on_audio(const AudioBlock& audio, StageOutput& out) override;
  void on_clock_event(const ClockEvent& event, StageOutput& out) override;
  void finish(StageOutput& out) override;
  std::size_t held_bytes() const override;

 private:
  struct ImuRecord {
    std::int64_t t_device_us = 0;
    forearm::Quat W_from_A;
    forearm::Vec3 specific_force_A;
    double filter_uncertainty_rad = 0.0;  // ImuOrientations::uncertainty_rad
  };
  struct Device {
    std::string id;
    std::optional<forearm::Side> side;            // none: the base IMU
    std::vector<ImuRecord> imu;                   // device clock, as received
    std::optional<std::int64_t> first_device_us;  // first sample handed to the tracker
    std::optional<std::int64_t> last_camera_us;   // last sample handed to the tracker, camera clock
    std::vector<forearm::ArmFrame> frames;        // camera frames until calibration
    std::optional<forearm::ForearmCalibration> calibration;
    bool calibration_failed = false;
    std::uint32_t strap_frames = 0;
    bool has_model = false;
    std::unique_ptr<forearm::ForearmTrack> tracker;
    // No usable calibration pose: the mounting is estimated from the session's motion
    // (forearm/mounting_from_motion.hpp), first from the frames buffered so far, then refined
    // from every tracked frame (mounting_frames) as they grow.
    bool from_motion = false;
    std::vector<forearm::MountingFrame> mounting_frames;
    std::size_t frames_at_last_estimate = 0;
    std::optional<forearm::MountingEstimate> mounting;
    std::string mounting_why_not;
    // The calibration pose searched for in the last forearm.calibration_s of tracked frames (with
    // the IMU's W_from_A at each); once found, its mounting replaces the one from motion.
    std::deque<std::pair<forearm::ArmFrame, forearm::Quat>> recent_frames;
    std::size_t frames_since_pose_search = 0;
    bool later_pose = false;
    // The IMU turns with the other arm's forearm (forearm::imu_on_other_arm), in words: no
    // results for this arm.
    std::string on_other_arm;
  };

  // Calibrates once the calibration window has passed, then feeds the trackers.
  void advance(StageOutput& out);
  void detect_arms(const CameraFrame& frame, const Skeleton& skeleton, StageOutput& out);
  // The arms' straps in the frame's colour image (cameras_ set, the frame has colour).
  void find_straps(const CameraFrame& frame, const geometry::DepthImageView& depth,
                   std::vector<forearm::ArmFrame>& arms, StageOutput& out);
  void try_calibrate(bool finishing, StageOutput& out);
  // Before the calibration: each arm IMU checked against both forearms' frames so far.
  void check_arm_assignment();
  void calibrate_arm(Device& device, StageOutput& out);
  std::vector<std::string> arm_device_ids() const;  // the arm IMUs, header order
  void refit_clocks(bool finishing);
  void feed_trackers(bool all, StageOutput& out);
  // The arm's new settled samples and tracked frames, handed on.
  void hand_on_track(Device& device, forearm::ForearmTrackOutput&& track, StageOutput& out);
  // Every tracked arm's offline solution (ForearmTrack::offline_samples), after its last live batch.
  void hand_on_offline_solutions(StageOutput& out);
  // FramesDone: every frame up to the oldest one still held (all at the end or when inactive).
  void hand_on_frames_done(bool all, StageOutput& out);
  std::optional<forearm::Quat> W_from_A_at(const Device& device, std::int64_t t_camera_us) const;
  // Mountings from motion: the first estimate starts the arm's tracker (orientation only, no
  // pronation reference), later ones refine it; at the end, an arm with none is named.
  void estimate_motion_mountings(bool finishing, StageOutput& out);
  void start_motion_track(Device& device, const forearm::MountingEstimate& estimate, StageOutput& out);
  // Buffered arm frames (this device's arm or the other's) with this device's K_from_A at each.
  std::vector<forearm::MountingFrame> mounting_frames_of(const Device& device,
                                                         const std::vector<forearm::ArmFrame>& arm_frames) const;
  // A calibration pose among the recent tracked frames of an arm whose mounting came from motion:
  // taken when calibrate_arm accepts it, its hold is over and its forearm axis agrees with the
  // motion's estimate.
  void search_later_pose(Device& device, StageOutput& out);
  forearm::CalibrationFrameOptions calibration_frame_options() const;

  bool active_ = false;
  std::vector<Device> devices_;  // header order
  std::string base_id_;
  ForearmOptions options_;
  std::optional<std::uint32_t> body_id_;
  std::optional<forearm::StrapCameras> cameras_;
  std::optional<geometry::PixelRays> depth_rays_;  // cameras_->depth's, with cameras_
  cv::Mat color_gray_;                             // the colour pixels the strap searches read, decoded frame by frame
  forearm::CalibrationOptions calibration_options_;
  std::unique_ptr<StreamClocks> clocks_;
  std::optional<sync::ClockMap> clock_map_;
  std::size_t sync_inputs_in_clock_map_ = 0;
  std::int64_t clock_map_frame_us_ = 0;  // camera time of the last frame when the map was fitted
  std::optional<forearm::Quat> K_from_W_;
  std::optional<std::int64_t> first_frame_us_;
  std::int64_t last_frame_us_ = 0;
  std::optional<std::int64_t> last_camera_frame_us_;  // any camera frame, with or without the body
  bool calibrated_ = false;
};

}  // namespace posefuse::session
