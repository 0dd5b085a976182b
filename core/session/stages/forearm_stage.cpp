#include "session/stages/forearm_stage.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "body/smpl_model.hpp"
#include "common/error.hpp"
#include "common/held_bytes.hpp"
#include "common/number_text.hpp"
#include "forearm/arm_calibration.hpp"
#include "forearm/arm_frame_measurement.hpp"
#include "forearm/calibration_frames.hpp"
#include "forearm/forearm_orientation.hpp"
#include "forearm/orientation_uncertainty.hpp"
#include "geometry/rotation_mean.hpp"
#include "session/option_table.hpp"
#include "session/stages/forearm_inputs.hpp"
#include "session/stages/forearm_report.hpp"
#include "session/stages/proto_values.hpp"
#include "session/text_fields.hpp"

namespace posefuse::session {

namespace {

using forearm::Quat;
using forearm::Vec3;

// How long past the calibration window the frames waiting for it hold the frame merge.
constexpr double kCalibrationGraceS = 10.0;
// A mounting from motion is re-estimated once this many new frames (a second at 30 Hz) or a
// tenth more have been tracked.
constexpr std::size_t kMinNewMountingFrames = 30;
// The offline solution's samples per message: 51 s at 80 Hz, about 300 kB encoded.
constexpr std::size_t kOfflineBatchSamples = 4096;

double degrees(double rad) { return rad * 180.0 / std::numbers::pi; }

// One frame for the mounting from motion: the depth-fitted forearm and the IMU's K_from_A at its
// time; none for a frame whose forearm is the SDK's (its joints' bias would enter the axis).
std::optional<forearm::MountingFrame> mounting_frame(const forearm::ArmFrame& f, const Quat& K_from_A) {
  if (!f.axis_from_depth) return std::nullopt;
  return forearm::MountingFrame{f.t_us, K_from_A, f.wrist_K - f.elbow_K, f.upper_arm_direction_K};
}

std::int64_t seconds_to_us(double s) { return static_cast<std::int64_t>(std::llround(s * 1e6)); }

}  // namespace

ForearmStage::ForearmStage() = default;
ForearmStage::~ForearmStage() = default;

std::string_view ForearmStage::description() const {
  return "forearm orientation and pronation per arm IMU sample, the strap's IMU position per camera frame (RGB, "
         "eq. 10), clocks from buzzer and BLE";
}

const OptionTable& ForearmStage::options() const { return forearm_option_table(); }

void ForearmStage::start(const v1::SessionHeader& header, StageOutput& out) {
  for (const v1::ImuDevice& d : header.imu_devices()) {
    Device device;
    device.id = d.device_id();
    if (d.role() == v1::ImuDevice::ARM_LEFT) device.side = forearm::Side::kLeft;
    if (d.role() == v1::ImuDevice::ARM_RIGHT) device.side = forearm::Side::kRight;
    if (d.role() == v1::ImuDevice::BASE && base_id_.empty()) base_id_ = d.device_id();
    if (device.side || d.device_id() == base_id_) devices_.push_back(std::move(device));
  }
  const bool has_arm =
      std::any_of(devices_.begin(), devices_.end(), [](const Device& d) { return d.side.has_value(); });
  if (!has_arm) return;  // nothing to do: no arm IMU
  options_ = read_forearm_options(header);
  body_id_ = options_.body_id;

  if (base_id_.empty()) {
    out.warn(
        "FOREARM_NO_BASE_IMU", "header.imu_devices",
        "no BASE IMU: neither the clocks (buzzer) nor the camera alignment (eq. 7) can be found; no forearm results");
    return;
  }
  if (!options_.K_from_B) {
    out.warn("FOREARM_NO_CAMERA_ALIGNMENT", option_field(kForearmKFromBKey),
             "missing: the base IMU's orientation in the camera frame (eq. 8) is needed for K_from_W (eq. 7); "
             "no forearm results");
    return;
  }
  const SessionCameras session = session_cameras(header);
  forearm::StrapCameras cameras;
  cameras.depth = session.depth;
  if (session.color) {
    cameras.color = *session.color;
    cameras.color_from_depth = session.color_from_depth;
    cameras.color_from_depth_m = session.color_from_depth_m;
    cameras_ = cameras;
    depth_rays_.emplace(cameras.depth, "header.depth_intrinsics");
  } else {
    out.warn("FOREARM_NO_COLOR", "header.color_intrinsics",
             "no colour stream: the strap (paper 1, II-I) cannot be seen, so only forearm orientations are produced");
  }
  clocks_ = std::make_unique<StreamClocks>(base_id_, header.audio_sample_rate_hz(), header.audio_channels(),
                                           options_.buzzer_tone_hz);
  active_ = true;
}

void ForearmStage::on_value(const StageValue& value, StageOutput& out) {
  if (!active_) return;
  const auto* orientations = std::get_if<ImuOrientations>(&value);
  if (!orientations) return;
  for (Device& device : devices_) {
    if (device.id != orientations->device_id) continue;
    for (std::size_t i = 0; i < orientations->samples.size(); ++i) {
      const double uncertainty_rad = i < orientations->uncertainty_rad.size() ? orientations->uncertainty_rad[i] : 0.0;
      device.imu.push_back({orientations->samples[i].t_us, orientations->W_from_A[i], orientations->samples[i].acc_m_s2,
                            uncertainty_rad});
    }
  }
  advance(out);
}

void ForearmStage::on_camera_frame(const CameraFrame& frame, StageOutput& out) {
  last_camera_frame_us_ = frame.t_us;
  if (!active_) {
    hand_on_frames_done(true, out);
    return;
  }
  if (!body_id_ && !frame.skeletons.empty()) body_id_ = frame.skeletons.front().body_id;
  if (const Skeleton* skeleton = body_id_ ? frame.skeleton(*body_id_) : nullptr) {
    if (!first_frame_us_) first_frame_us_ = frame.t_us;
    last_frame_us_ = frame.t_us;
    detect_arms(frame, *skeleton, out);
  }
  advance(out);
  hand_on_frames_done(false, out);
}

void ForearmStage::hand_on_frames_done(bool all, StageOutput& out) {
  if (!last_camera_frame_us_) return;
  std::int64_t up_to = all ? INT64_MAX : *last_camera_frame_us_;
  // Frames held for a calibration that cannot be made (no clocks yet) would hold every later
  // stage's frames: past the window and kCalibrationGraceS they are no longer waited for (their
  // estimates, if the calibration comes, are late for the frame merge, which counts them).
  const bool waiting_for_calibration =
      first_frame_us_ &&
      *last_camera_frame_us_ <= *first_frame_us_ + seconds_to_us(options_.calibration_s + kCalibrationGraceS);
  for (const Device& device : devices_) {
    if (all || !device.side || device.calibration_failed) continue;
    if (!device.tracker) {
      if (!device.frames.empty() && waiting_for_calibration) up_to = std::min(up_to, device.frames.front().t_us - 1);
    } else if (const std::optional<std::int64_t> oldest = device.tracker->oldest_queued_us()) {
      up_to = std::min(up_to, *oldest - 1);
    }
  }
  out.hand_on(FramesDone{FrameSource::kForearm, up_to});
}

void ForearmStage::hand_on_track(Device& device, forearm::ForearmTrackOutput&& track, StageOutput& out) {
  const v1::Arm arm = to_proto_arm(*device.side);
  ForearmOrientations orientations = forearm_orientations_of(device.id, arm, track.samples);
  // Searched every kMinNewMountingFrames frames however many come at once (a track started late
  // tracks every frame buffered until then in one call).
  const std::int64_t keep_us = seconds_to_us(options_.calibration_s);
  for (const forearm::TrackedArmFrame& t : track.frames) {
    if (!device.from_motion || device.later_pose) break;
    device.recent_frames.emplace_back(t.frame, (K_from_W_->conjugate() * t.K_from_A).normalized());
    ++device.frames_since_pose_search;
    if (const auto frame = mounting_frame(t.frame, t.K_from_A)) device.mounting_frames.push_back(*frame);
    while (device.recent_frames.front().first.t_us < device.recent_frames.back().first.t_us - keep_us) {
      device.recent_frames.pop_front();
    }
    if (device.frames_since_pose_search >= kMinNewMountingFrames) {
      device.frames_since_pose_search = 0;
      search_later_pose(device, out);
    }
  }
  // The track first: the gaps' live estimate of these frames uses the fit's frames up to the
  // last call, as the fit's frames that these orientations complete come after it.
  if (!track.samples.empty() || !track.frames.empty()) {
    out.hand_on(ArmTrack{device.id, arm, std::move(track.samples), std::move(track.frames)});
  }
  if (!orientations.t_us.empty()) out.hand_on(std::move(orientations));
}

void ForearmStage::on_audio(const AudioBlock& audio, StageOutput& out) {
  if (!active_) return;
  clocks_->add(audio);
  advance(out);
}

void ForearmStage::on_clock_event(const ClockEvent& event, StageOutput& out) {
  if (!active_) return;
  clocks_->add(event);
  advance(out);
}

void ForearmStage::advance(StageOutput& out) {
  if (!calibrated_) try_calibrate(false, out);
  if (!calibrated_) return;
  estimate_motion_mountings(false, out);
  feed_trackers(false, out);
}

void ForearmStage::detect_arms(const CameraFrame& frame, const Skeleton& skeleton, StageOutput& out) {
  // The SDK's joints only say where to look; the axes and the strap are the images'.
  const geometry::DepthImageView depth = depth_view(frame.depth_mm);
  std::vector<Device*> arm_devices;
  std::vector<forearm::ArmFrame> arms;
  for (Device& device : devices_) {
    if (!device.side || device.calibration_failed) continue;
    forearm::ArmFrame arm = arm_frame_from_skeleton(skeleton, *device.side, frame.t_us);
    if (cameras_) {
      forearm::measure_arm_frame(
          arm, depth, *depth_rays_,
          {options_.axis_from_depth, options_.upper_arm_from_depth, !device.tracker || device.from_motion});
    }
    arm_devices.push_back(&device);
    arms.push_back(arm);
  }
  if (cameras_ && !frame.color.empty()) find_straps(frame, depth, arms, out);
  forearm::drop_straps_nearer_another_wrist(arms);
  for (std::size_t i = 0; i < arms.size(); ++i) {
    if (arm_devices[i]->tracker) {
      arm_devices[i]->tracker->add_frame(arms[i]);
    } else {
      arm_devices[i]->frames.push_back(arms[i]);
    }
  }
}

void ForearmStage::find_straps(const CameraFrame& frame, const geometry::DepthImageView& depth,
                               std::vector<forearm::ArmFrame>& arms, StageOutput& out) {
  // The colour frame is decoded only where the arms' strap searches read it, in one pass.
  std::vector<geometry::PixelRect> rects;
  for (const forearm::ArmFrame& arm : arms) {
    if (!arm.forearm_tracked) continue;
    const geometry::PixelRect rect = forearm::strap_profile_rect(*cameras_, arm.elbow_K, arm.wrist_K);
    if (!rect.empty()) rects.push_back(rect);
  }
  if (rects.empty()) return;
  try {
    frame.color.decode_gray(rects, color_gray_, "color");
  } catch (const Error& error) {
    // The frame's headers were checked when it arrived; its pixel data fails only now. The frame
    // is measured as one without a colour image: no strap.
    out.warn("FOREARM_COLOR_UNDECODABLE", error.field(),
             "the colour frame at t_us " + std::to_string(frame.color_t_us) + ": " + error.what() +
                 "; no strap search in it");
    return;
  }
  for (forearm::ArmFrame& arm : arms) forearm::find_arm_strap(arm, depth, gray_view(color_gray_), *cameras_);
}

void ForearmStage::try_calibrate(bool finishing, StageOutput& out) {
  const std::int64_t window_end_us = first_frame_us_ ? *first_frame_us_ + seconds_to_us(options_.calibration_s) : 0;
  if (!finishing && (!first_frame_us_ || last_frame_us_ < window_end_us)) return;
  const std::vector<std::string> arm_ids = arm_device_ids();
  if (!clock_map_) {
    clock_map_ = clocks_->try_build(arm_ids);
    sync_inputs_in_clock_map_ = clocks_->sync_input_count();
    clock_map_frame_us_ = last_frame_us_;
  }
  if (!clock_map_) {
    if (finishing) {
      const StreamClocks::Missing missing = clocks_->why_not(arm_ids);
      out.warn("FOREARM_NO_SYNC", missing.field, missing.message + "; no forearm results");
    }
    return;
  }
  const Device& base =
      *std::find_if(devices_.begin(), devices_.end(), [&](const Device& d) { return d.id == base_id_; });
  if (base.imu.empty()) {
    if (finishing) out.warn("FOREARM_NO_BASE_IMU", "imu", "the base IMU '" + base_id_ + "' sent no samples");
    return;
  }
  if (!finishing) {
    // Wait until every arm IMU's samples reach past the calibration window.
    for (const Device& d : devices_) {
      if (!d.side) continue;
      if (d.imu.empty() || clock_map_->to_camera_us(d.id, static_cast<double>(d.imu.back().t_device_us)) <
                               static_cast<double>(window_end_us)) {
        return;
      }
    }
  }
  if (!first_frame_us_) {
    out.warn("FOREARM_CALIBRATION", "skeleton", "no skeleton frames: no calibration pose (paper 1, II-H)");
    return;
  }
  std::vector<Quat> W_from_B;
  for (const ImuRecord& r : base.imu) W_from_B.push_back(r.W_from_A);
  K_from_W_ = (*options_.K_from_B * geometry::chordal_mean(W_from_B).conjugate()).normalized();  // eq. 7
  calibrated_ = true;
  check_arm_assignment();
  for (Device& device : devices_) {
    if (device.side) calibrate_arm(device, out);
  }
}

void ForearmStage::check_arm_assignment() {
  for (Device& device : devices_) {
    if (!device.side) continue;
    for (const Device& other : devices_) {
      if (!other.side || *other.side == *device.side) continue;
      if (const std::optional<std::string> why = forearm::imu_on_other_arm(mounting_frames_of(device, device.frames),
                                                                           mounting_frames_of(device, other.frames),
                                                                           forearm::MountingFromMotionOptions{})) {
        device.on_other_arm = *why;
      }
    }
  }
}

std::optional<Quat> ForearmStage::W_from_A_at(const Device& device, std::int64_t t_camera_us) const {
  const auto camera_us = [&](const ImuRecord& r) {
    return clock_map_->to_camera_us(device.id, static_cast<double>(r.t_device_us));
  };
  const double t = static_cast<double>(t_camera_us);
  // The samples are in device-clock order, and the clock map keeps that order.
  const auto after =
      std::partition_point(device.imu.begin(), device.imu.end(), [&](const ImuRecord& r) { return camera_us(r) < t; });
  if (after == device.imu.end() || after == device.imu.begin()) {
    if (after != device.imu.end() && camera_us(*after) == t) return after->W_from_A;
    return std::nullopt;
  }
  const auto before = std::prev(after);
  const double t0 = camera_us(*before), t1 = camera_us(*after);
  if (!(t1 > t0)) return std::nullopt;
  return before->W_from_A.slerp((t - t0) / (t1 - t0), after->W_from_A).normalized();
}

void ForearmStage::calibrate_arm(Device& device, StageOutput& out) {
  const std::string field = "forearm[" + device.id + "]";
  if (!device.on_other_arm.empty()) {
    device.from_motion = true;
    device.mounting_why_not = device.on_other_arm;
    out.warn("FOREARM_IMU_ON_OTHER_ARM", field + ".arm",
             std::string("the IMU named for the ") + (*device.side == forearm::Side::kLeft ? "left" : "right") +
                 " arm: " + device.on_other_arm +
                 ": the IMUs are on the wrong arms, or the header names them the wrong way round; no calibration "
                 "and no mounting from motion for this arm");
    return;
  }
  const std::int64_t window_end_us = *first_frame_us_ + seconds_to_us(options_.calibration_s);
  const forearm::CalibrationFrames selected = forearm::select_calibration_frames(
      device.frames, window_end_us, *K_from_W_ * Vec3::UnitZ(),
      [&](std::int64_t t_us) { return W_from_A_at(device, t_us); }, calibration_frame_options());
  if (options_.pose_orientation && options_.upper_arm_from_depth && !selected.depth_upper_arm) {
    out.warn("FOREARM_UPPER_ARM_NOT_SEEN", field + ".upper_arm",
             "the upper arm was measured in the depth image at " + std::to_string(selected.upper_arm_frames) +
                 " calibration frames (need " + std::to_string(calibration_options_.min_still_frames) +
                 "): the calibration pose's roll comes from the SDK shoulder");
  }
  device.strap_frames = static_cast<std::uint32_t>(selected.with_strap.size());
  forearm::ArmCalibration calibrated;
  try {
    calibrated = forearm::calibrate_arm(selected, *K_from_W_, calibration_options_);
  } catch (const Error& error) {
    device.from_motion = true;
    out.warn("FOREARM_CALIBRATION", field + ".calibration",
             std::string("no usable calibration pose (paper 1, II-H) in the first ") +
                 format_double(options_.calibration_s) + " s: " + error.what() + " (" +
                 std::to_string(selected.not_raised) + " tracked frames skipped: forearm not raised; " +
                 std::to_string(selected.overhead) + ": upper arm raised overhead; " +
                 std::to_string(selected.straight) +
                 ": elbow not flexed; paper 1 Fig. 3b); the IMU's mounting is estimated "
                 "from the session's motion instead, with no pronation relative to the calibration pose");
    return;
  }
  if (!calibrated.has_model) {
    out.warn("FOREARM_STRAP_NOT_SEEN", field + ".strap",
             calibrated.strap_not_seen + ": forearm orientation only, no IMU positions");
  }
  device.calibration = calibrated.calibration;
  const bool has_model = device.has_model = calibrated.has_model;
  device.tracker = std::make_unique<forearm::ForearmTrack>(
      *device.side, device.calibration->model, has_model, *K_from_W_, calibrated.K_from_F_held,
      forearm::pose_calibration_rms_rad(calibrated.calibration.F_from_A_spread_rad));
  if (options_.axis_correction_on && options_.axis_from_depth && has_model) {
    device.tracker->use_axis_correction(options_.axis_correction);
  }
  for (const forearm::ArmFrame& f : device.frames) device.tracker->add_frame(f);
  device.frames.clear();
  ArmTrackStart start;
  start.device_id = device.id;
  start.arm = to_proto_arm(*device.side);
  start.tracked = true;
  start.model = device.calibration->model;
  start.has_model = has_model;
  start.K_from_W = *K_from_W_;
  start.smoother = options_.smoother;
  if (options_.fit_anchor) start.fit_anchor = forearm::FitAnchorOptions{};
  out.hand_on(std::move(start));
}

forearm::CalibrationFrameOptions ForearmStage::calibration_frame_options() const {
  forearm::CalibrationFrameOptions frame_options;
  frame_options.pose_orientation = options_.pose_orientation;
  frame_options.upper_arm_from_depth = options_.upper_arm_from_depth;
  frame_options.min_upper_arm_frames = static_cast<std::size_t>(calibration_options_.min_still_frames);
  return frame_options;
}

void ForearmStage::search_later_pose(Device& device, StageOutput& out) {
  std::vector<forearm::ArmFrame> frames;
  for (const auto& [frame, W_from_A] : device.recent_frames) frames.push_back(frame);
  const auto W_from_A_at = [&](std::int64_t t_us) -> std::optional<Quat> {
    const auto at = std::lower_bound(device.recent_frames.begin(), device.recent_frames.end(), t_us,
                                     [](const auto& f, std::int64_t t) { return f.first.t_us < t; });
    if (at == device.recent_frames.end() || at->first.t_us != t_us) return std::nullopt;
    return at->second;
  };
  const forearm::CalibrationFrames selected = forearm::select_calibration_frames(
      frames, frames.back().t_us, *K_from_W_ * Vec3::UnitZ(), W_from_A_at, calibration_frame_options());
  forearm::ArmCalibration calibrated;
  try {
    calibrated = forearm::calibrate_arm(selected, *K_from_W_, calibration_options_);
  } catch (const Error&) {
    return;  // no pose here (yet)
  }
  // A hold still going on at the window's end is taken once it is over (from all its frames), not
  // from its first frames: those gave mountings 1-3 degrees worse on clips with the pose at the end.
  // One still going on when the session ends is not taken: arm_raising cut at 20 s with the arm
  // raised and still passed every bound and the axis check, 26 degrees off.
  if (calibrated.hold_end_us >= frames.back().t_us) return;
  // A pose whose forearm axis in A disagrees with the motion's beyond both their 99 % bounds is
  // not the pose it seems (a passing arm that happened to hold still).
  const Quat& pose_F_from_A = calibrated.calibration.model.F_from_A;
  const double pose_rms_rad = forearm::pose_calibration_rms_rad(calibrated.calibration.F_from_A_spread_rad);
  if (device.mounting) {
    const Vec3 pose_axis = pose_F_from_A.conjugate() * Vec3::UnitY();
    const Vec3 motion_axis = device.mounting->F_from_A.conjugate() * Vec3::UnitY();
    const double disagreement = std::acos(std::clamp(pose_axis.dot(motion_axis), -1.0, 1.0));
    const double bound =
        forearm::kDirectionBound99OverRms * device.mounting->axis_rms_rad + forearm::kBound99OverRms * pose_rms_rad;
    if (disagreement > bound) return;
  }
  device.later_pose = true;
  device.recent_frames.clear();
  device.calibration = calibrated.calibration;
  device.has_model = false;  // the gap recovery started without a strap model
  device.tracker->set_mounting(pose_F_from_A, pose_rms_rad);
  device.tracker->set_pronation_reference(calibrated.K_from_F_held);
  out.warn("FOREARM_CALIBRATION_LATER", "forearm[" + device.id + "].calibration",
           "the calibration pose at " +
               fixed_text(1e-6 * static_cast<double>(frames.back().t_us - *first_frame_us_), 1) + " s (" +
               std::to_string(calibrated.calibration.frame_count) + " frames, eq. 9 spread " +
               fixed_text(degrees(calibrated.calibration.F_from_A_spread_rad), 1) +
               " deg): its mounting replaces the one from motion, and pronation relative to it is given, from then "
               "on; IMU positions still need the pose within forearm.calibration_s of the start");
}

std::vector<forearm::MountingFrame> ForearmStage::mounting_frames_of(
    const Device& device, const std::vector<forearm::ArmFrame>& arm_frames) const {
  std::vector<forearm::MountingFrame> frames;
  for (const forearm::ArmFrame& f : arm_frames) {
    const std::optional<Quat> W_from_A = W_from_A_at(device, f.t_us);
    if (!W_from_A) continue;
    if (const auto frame = mounting_frame(f, (*K_from_W_ * *W_from_A).normalized())) frames.push_back(*frame);
  }
  return frames;
}

void ForearmStage::estimate_motion_mountings(bool finishing, StageOutput& out) {
  for (Device& device : devices_) {
    if (!device.from_motion || device.later_pose || !device.on_other_arm.empty()) continue;
    // Each estimate uses every frame so far; re-estimating once the frames have grown by a tenth
    // keeps the work linear in the session's length.
    const std::size_t seen = device.tracker ? device.mounting_frames.size() : device.frames.size();
    const std::size_t due =
        device.frames_at_last_estimate + std::max(kMinNewMountingFrames, device.frames_at_last_estimate / 10);
    if (seen == device.frames_at_last_estimate || (!finishing && seen < due)) continue;
    device.frames_at_last_estimate = seen;
    std::string why_not;
    const std::optional<forearm::MountingEstimate> estimate =
        forearm::estimate_mounting(device.tracker ? device.mounting_frames : mounting_frames_of(device, device.frames),
                                   *device.side, forearm::MountingFromMotionOptions{}, why_not);
    if (!estimate) {
      device.mounting_why_not = why_not;
      continue;
    }
    const double rms_rad = forearm::orientation_rms_rad(estimate->axis_rms_rad, estimate->roll_rms_rad);
    device.mounting = estimate;
    if (device.tracker) {
      device.tracker->set_mounting(device.mounting->F_from_A, rms_rad,
                                   forearm::forearm_axis_rms_rad(estimate->axis_rms_rad));
    } else {
      start_motion_track(device, *device.mounting, out);
    }
  }
  if (!finishing) return;
  for (Device& device : devices_) {
    if (!device.from_motion || device.tracker) continue;
    device.frames.clear();
    ArmTrackStart refused;
    refused.device_id = device.id;
    refused.arm = to_proto_arm(*device.side);
    out.hand_on(std::move(refused));
    out.warn("FOREARM_MOUNTING_NOT_OBSERVABLE", "forearm[" + device.id + "].mounting",
             "no calibration pose and the session's motion does not show the IMU's mounting: " +
                 (device.mounting_why_not.empty() ? std::string("no frame with the forearm measured in depth")
                                                  : device.mounting_why_not) +
                 "; no results for this arm");
  }
}

void ForearmStage::start_motion_track(Device& device, const forearm::MountingEstimate& estimate, StageOutput& out) {
  const double rms_rad = forearm::orientation_rms_rad(estimate.axis_rms_rad, estimate.roll_rms_rad);
  forearm::ForearmModel model;
  model.F_from_A = estimate.F_from_A;
  device.tracker =
      std::make_unique<forearm::ForearmTrack>(*device.side, model, false, *K_from_W_, std::nullopt, rms_rad,
                                              forearm::forearm_axis_rms_rad(estimate.axis_rms_rad));
  for (const forearm::ArmFrame& f : device.frames) device.tracker->add_frame(f);
  device.frames.clear();
  device.frames_at_last_estimate = 0;  // from now on counted in tracked frames (mounting_frames)
  ArmTrackStart start;
  start.device_id = device.id;
  start.arm = to_proto_arm(*device.side);
  start.tracked = true;
  start.model = model;
  start.has_model = false;
  start.K_from_W = *K_from_W_;
  start.smoother = options_.smoother;
  out.hand_on(std::move(start));
  out.warn("FOREARM_MOUNTING_FROM_MOTION", "forearm[" + device.id + "].mounting",
           "first estimate from " + std::to_string(estimate.frames) + " frames over " +
               fixed_text(estimate.seconds, 1) + " s" +
               (estimate.outlier_frames
                    ? " (" + std::to_string(estimate.outlier_frames) + " more left out: their forearm axis disagreed)"
                    : std::string()) +
               ": forearm axis +-" + fixed_text(degrees(estimate.axis_rms_rad), 1) + " deg RMS, roll +-" +
               fixed_text(degrees(estimate.roll_rms_rad), 1) + " deg RMS (" + estimate.roll_limit +
               "); refined as the session goes on, each orientation with its predicted error and confidence; no IMU "
               "positions (no strap model)");
}

std::vector<std::string> ForearmStage::arm_device_ids() const {
  std::vector<std::string> ids;
  for (const Device& d : devices_) {
    if (d.side) ids.push_back(d.id);
  }
  return ids;
}

void ForearmStage::refit_clocks(bool finishing) {
  // BLE receipts after the calibration (repeated bursts) make the drift between the IMUs
  // observable, later buzzer stops the base's against the camera; refit at most once per second
  // of camera time, and once more at the end so the reported offsets and drifts use the whole
  // session.
  constexpr std::int64_t kRefitEveryUs = 1'000'000;
  if (!clock_map_ || clocks_->sync_input_count() == sync_inputs_in_clock_map_) return;
  if (!finishing && last_frame_us_ < clock_map_frame_us_ + kRefitEveryUs) return;
  const std::vector<std::string> arm_ids = arm_device_ids();
  if (std::optional<sync::ClockMap> refit = clocks_->try_build(arm_ids)) clock_map_ = std::move(refit);
  sync_inputs_in_clock_map_ = clocks_->sync_input_count();
  clock_map_frame_us_ = last_frame_us_;
}

void ForearmStage::feed_trackers(bool all, StageOutput& out) {
  refit_clocks(all);
  for (Device& device : devices_) {
    if (!device.tracker) continue;
    std::vector<std::int64_t> t_us;
    std::vector<Quat> W_from_A;
    std::vector<Vec3> force;
    std::vector<double> filter_uncertainty_rad;
    for (const ImuRecord& r : device.imu) {
      std::int64_t t = std::llround(clock_map_->to_camera_us(device.id, static_cast<double>(r.t_device_us)));
      // A refitted clock may map a sample a little before the last one handed over (a fraction
      // of a millisecond): keep the order rather than drop the sample.
      if (device.last_camera_us && t <= *device.last_camera_us) t = *device.last_camera_us + 1;
      device.last_camera_us = t;
      t_us.push_back(t);
      W_from_A.push_back(r.W_from_A);
      force.push_back(r.specific_force_A);
      filter_uncertainty_rad.push_back(r.filter_uncertainty_rad);
    }
    if (!device.imu.empty()) {
      if (!device.first_device_us) device.first_device_us = device.imu.front().t_device_us;
      device.imu.clear();
    }
    device.tracker->add_imu(t_us, W_from_A, force, filter_uncertainty_rad);
    hand_on_track(device, device.tracker->process(all), out);
  }
}

void ForearmStage::hand_on_offline_solutions(StageOutput& out) {
  for (const Device& device : devices_) {
    if (!device.tracker) continue;
    const v1::Arm arm = to_proto_arm(*device.side);
    const std::vector<forearm::SettledArmSample> samples = device.tracker->offline_samples();
    // In batches, so that no message grows with the session's length.
    for (std::size_t begin = 0; begin < samples.size(); begin += kOfflineBatchSamples) {
      const std::size_t end = std::min(samples.size(), begin + kOfflineBatchSamples);
      ForearmOrientations batch = forearm_orientations_of(
          device.id, arm,
          std::vector<forearm::SettledArmSample>(samples.begin() + static_cast<std::ptrdiff_t>(begin),
                                                 samples.begin() + static_cast<std::ptrdiff_t>(end)));
      batch.offline = true;
      out.hand_on(std::move(batch));
    }
  }
}

std::size_t ForearmStage::held_bytes() const {
  std::size_t held = 0;
  for (const Device& device : devices_) {
    held += posefuse::held_bytes(device.imu) + posefuse::held_bytes(device.frames) +
            posefuse::held_bytes(device.mounting_frames) + posefuse::held_bytes(device.recent_frames);
    if (device.tracker) held += device.tracker->held_bytes();
  }
  return held;
}

void ForearmStage::finish(StageOutput& out) {
  if (!active_) {
    hand_on_frames_done(true, out);
    return;
  }
  if (!calibrated_) try_calibrate(true, out);
  if (calibrated_) {
    estimate_motion_mountings(false, out);
    feed_trackers(true, out);
    estimate_motion_mountings(true, out);  // an arm still without a mounting: the last chance, or named
    feed_trackers(true, out);
  }
  hand_on_frames_done(true, out);
  hand_on_offline_solutions(out);
  for (const Device& device : devices_) {
    if (!device.tracker || device.tracker->orientation_steps() == 0) continue;
    out.warn("FOREARM_ORIENTATION_STEP", "forearm[" + device.id + "].orientation",
             std::to_string(device.tracker->orientation_steps()) +
                 " frames changed the mounting their orientation implies by more than their uncertainty allows "
                 "(largest " +
                 fixed_text(degrees(device.tracker->largest_orientation_step_rad()), 1) + " deg at " +
                 fixed_text(1e-6 * static_cast<double>(device.tracker->largest_orientation_step_us()), 2) +
                 " s camera time); their uncertainty is raised to the step, so they are not confident");
  }
  v1::CalibrationReport& report = out.calibration();
  if (const std::optional<double> tone_hz = clocks_->buzzer_tone_hz()) report.set_buzzer_tone_hz(*tone_hz);
  for (const Device& device : devices_) {
    if (clock_map_ && clock_map_->has(device.id)) {
      const double first_us =
          static_cast<double>(device.first_device_us.value_or(device.imu.empty() ? 0 : device.imu.front().t_device_us));
      report_clock(device.id, clock_map_->camera_from(device.id), first_us, report);
    }
    if (device.side && device.calibration) {
      report_forearm_model(device.id, *device.side, *device.calibration, device.has_model, device.strap_frames, report);
    } else if (device.side && device.tracker && device.mounting) {
      report_motion_mounting(device.id, *device.side, *device.mounting, report);
    }
  }
  if (K_from_W_) *report.mutable_k_from_w() = to_proto(*K_from_W_);
}

}  // namespace posefuse::session
