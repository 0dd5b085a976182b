#include "session/stages/body_fit_stage.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <utility>

#include "body/template_generator.hpp"
#include "common/held_bytes.hpp"
#include "common/number_text.hpp"
#include "common/thread_cpu_time.hpp"
#include "forearm/orientation_uncertainty.hpp"
#include "session/stages/proto_values.hpp"
#include "session/text_fields.hpp"

namespace posefuse::session {

namespace {

// A forearm orientation further than this from the frame is not used.
constexpr std::int64_t kForearmToleranceUs = 20'000;
// The imu term uses a forearm orientation only where it is predicted within 15 degrees
// (forearm::kConfidentAt): a mounting not yet known must not pull the fit.
// Forearm orientations kept behind the oldest queued frame.
constexpr std::int64_t kForearmHistoryUs = 1'000'000;

fit::JointTracking tracking_from(JointState state) {
  switch (state) {
    case JointState::kTracked: return fit::JointTracking::kTracked;
    case JointState::kInferred: return fit::JointTracking::kInferred;
    case JointState::kNotTracked: break;
  }
  return fit::JointTracking::kNotTracked;
}

v1::Arm arm_of(fit::ArmSide side) { return side == fit::ArmSide::kLeft ? v1::LEFT : v1::RIGHT; }

fit::BodyTrackerOptions tracker_options(const BodyFitOptions& options) {
  fit::BodyTrackerOptions out;
  out.calibration_s = options.calibration_s;
  out.fine_shape = options.fine_shape;
  out.fit = options.fit;
  out.smoothing = options.smoothing;
  out.extrapolation = options.extrapolation;
  out.skeleton_start_energy = options.skeleton_start_energy;
  out.lost_energy = options.lost_energy;
  out.trusted_energy = options.trusted_energy;
  return out;
}

// The fit's joints and forearms as the frame merge takes them: FUSED where an IMU direction
// entered the fit, else VISUAL; the forearm orientations are the IMU's (FUSED).
FittedFrame fitted_frame_from(const fit::FittedBodyFrame& fitted) {
  FittedFrame out;
  out.lost = fitted.lost;
  FrameEstimate& frame = out.estimate;
  frame.t_us = fitted.t_us;
  frame.fit_energy = fitted.energy;
  const v1::Source source = fitted.imu_used ? v1::FUSED : v1::VISUAL;
  for (const fit::FittedJoint& j : fitted.smpl_joints) frame.smpl_joints.push_back({j.p_K, source, j.confidence});
  for (const fit::FittedJoint& j : fitted.camera_joints) frame.camera_joints.push_back({j.p_K, source, j.confidence});
  frame.smpl_rotations = fitted.K_from_joint;
  for (const fit::FittedForearm& f : fitted.forearms) {
    frame.forearms.push_back({arm_of(f.side), f.K_from_F, f.pronation_rad, v1::FUSED, f.confidence});
  }
  return out;
}

}  // namespace

fit::TrackedSkeleton tracked_skeleton_from(const Skeleton& skeleton) {
  fit::TrackedSkeleton out;
  for (std::size_t j = 0; j < skeleton.joints.size(); ++j) {
    out.positions_K[j] = skeleton.joints[j].p_K;
    out.tracking[j] = tracking_from(skeleton.joints[j].state);
  }
  return out;
}

BodyFitStage::BodyFitStage() = default;
BodyFitStage::~BodyFitStage() = default;

std::string_view BodyFitStage::description() const {
  return "body-model fit to every depth frame (paper 2): personalised shape, 24 SMPL joints, 25 camera joints, "
         "forearm roll from the wrist IMUs";
}

const OptionTable& BodyFitStage::options() const { return body_fit_option_table(); }

void BodyFitStage::record_frame_stats(bool on) {
  record_stats_ = on;
  if (tracker_) tracker_->record_frame_stats(on);
}

std::size_t BodyFitStage::held_bytes() const {
  std::size_t held = posefuse::held_bytes(queue_) + queued_pixel_bytes_;
  for (const auto& [arm, samples] : K_from_F_) held += posefuse::held_bytes(samples);
  return tracker_ ? held + tracker_->held_bytes() : held;
}

const std::vector<BodyFitFrameStats>& BodyFitStage::frame_stats() const {
  static const std::vector<BodyFitFrameStats> kNone;
  return tracker_ ? tracker_->frame_stats() : kNone;
}

void BodyFitStage::start(const v1::SessionHeader& header, StageOutput& /*out*/) {
  enabled_ = body_fit_enabled(header);
  if (!enabled_) return;
  options_ = read_body_fit_options(header);
  body_id_ = options_.body_id;
  arm_imus_ =
      static_cast<int>(std::count_if(header.imu_devices().begin(), header.imu_devices().end(), [](const auto& d) {
        return d.role() == v1::ImuDevice::ARM_LEFT || d.role() == v1::ImuDevice::ARM_RIGHT;
      }));
  sex_ = header.sex() == v1::SessionHeader::FEMALE ? body::Sex::kFemale : body::Sex::kMale;
  const raycast::DepthIntrinsics depth = session_cameras(header).depth;
  depth_width_ = depth.width;
  depth_height_ = depth.height;
  fit::BodyTrackerOptions tracker = tracker_options(options_);
  if (header.has_height_m()) tracker.subject_height_m = header.height_m();
  tracker_ = std::make_unique<fit::BodyTracker>(body::shared_template(sex_), depth, tracker);
  tracker_->record_frame_stats(record_stats_);
}

void BodyFitStage::on_camera_frame(const CameraFrame& camera, StageOutput& out) {
  last_camera_t_us_ = camera.t_us;
  add_camera_frame(camera, out);
  out.hand_on(FramesDone{FrameSource::kBodyFit, frames_done_up_to()});
}

std::int64_t BodyFitStage::frames_done_up_to() const {
  if (!enabled_) return INT64_MAX;
  std::int64_t up_to = last_camera_t_us_.value_or(INT64_MIN);
  if (const auto held = tracker_->oldest_held_t_us()) up_to = std::min(up_to, *held - 1);
  if (!queue_.empty()) up_to = std::min(up_to, queue_.front().t_us - 1);
  return up_to;
}

void BodyFitStage::add_camera_frame(const CameraFrame& camera, StageOutput& out) {
  if (!enabled_) return;
  if (!body_id_ && !camera.skeletons.empty()) body_id_ = camera.skeletons.front().body_id;
  if (camera.depth_mm.empty()) return;
  const Skeleton* skeleton = body_id_ ? camera.skeleton(*body_id_) : nullptr;
  if (!skeleton) {
    ++frames_without_skeleton_;
    return;
  }
  const double assemble_start = thread_cpu_seconds();
  BodyFitFrame frame;
  frame.t_us = camera.t_us;
  frame.frame.width = depth_width_;
  frame.frame.height = depth_height_;
  // Whole rows at a time: a cv::MatConstIterator checks for the row's end at every pixel, about
  // 0.25 ms per 512x424 frame, as much as building the point cloud (bench_fig4's phases).
  std::vector<std::uint16_t>& depth = frame.frame.depth_mm;
  depth.reserve(camera.depth_mm.total());
  for (int row = 0; row < camera.depth_mm.rows; ++row) {
    const std::uint16_t* values = camera.depth_mm.ptr<std::uint16_t>(row);
    depth.insert(depth.end(), values, values + camera.depth_mm.cols);
  }
  frame.frame.body_index.resize(depth.size());
  std::uint8_t* body = frame.frame.body_index.data();
  // Body ids are 8-bit in the image: a larger fit.body_id matches no pixel.
  if (camera.body_index.total() == depth.size() && *body_id_ <= 0xFF) {
    // A select rather than a conditional store, so that the loop vectorises.
    const std::uint8_t* ids = camera.body_index.ptr<std::uint8_t>();
    const std::uint8_t fitted = static_cast<std::uint8_t>(*body_id_);
    for (std::size_t i = 0; i < depth.size(); ++i) body[i] = ids[i] == fitted ? 0 : fit::kNoBody;
  } else {
    std::fill(body, body + depth.size(), fit::kNoBody);
  }
  frame.skeleton = tracked_skeleton_from(*skeleton);
  frame.assemble_s = thread_cpu_seconds() - assemble_start;
  last_frame_t_us_ = frame.t_us;
  enqueue(tracker_->admit(std::move(frame)), out);
  fit_ready(false, out);
}

void BodyFitStage::on_value(const StageValue& value, StageOutput& out) {
  const auto* batch = std::get_if<ForearmOrientations>(&value);
  // The offline solution comes after the last frame, too late for any fit.
  if (!enabled_ || !batch || batch->offline) return;
  auto& samples = K_from_F_[batch->arm];
  for (std::size_t i = 0; i < batch->t_us.size(); ++i) {
    const Eigen::Quaterniond& q = batch->K_from_F[i];
    if (!q.coeffs().allFinite() || std::abs(q.norm() - 1.0) > 1e-3) continue;
    if (!samples.empty() && batch->t_us[i] <= samples.back().first) continue;
    // The imu term uses the forearm axis y_F alone, so it is weighted by y_F's predicted error (the
    // mounting's axis and the filter's steady error), not the whole orientation's: a mounting
    // from motion knows its roll to +-30 deg only, and its axis better. Not the camera-checked
    // error either: the fit weighs the depth itself, and a camera check of the depth axis would
    // count its noise twice. A sample without one does not enter.
    const double axis_rms_rad =
        i < batch->axis_rms_rad.size() ? batch->axis_rms_rad[i] : std::numeric_limits<double>::quiet_NaN();
    const double weight = fit::forearm_direction_weight(axis_rms_rad);
    samples.emplace_back(batch->t_us[i], weight > 0 ? std::optional<fit::ForearmOrientationSample>(
                                                          fit::ForearmOrientationSample{q.normalized(), weight})
                                                    : std::nullopt);
  }
  if (tracker_->personalised()) fit_ready(false, out);
}

void BodyFitStage::enqueue(fit::BodyTracker::Admitted&& admitted, StageOutput& out) {
  for (const fit::FitWarning& w : admitted.warnings) out.warn(w.code, w.field, w.message);
  for (BodyFitFrame& frame : admitted.frames) {
    queue_.push_back({frame.t_us, fit::pack_body_pixels(frame.frame), std::move(frame.skeleton), frame.assemble_s});
    queued_pixel_bytes_ += queue_.back().frame.bytes();
  }
}

std::optional<fit::ForearmOrientationSample> BodyFitStage::K_from_F_at(fit::ArmSide side, std::int64_t t_us) const {
  const auto it = K_from_F_.find(arm_of(side));
  if (it == K_from_F_.end() || it->second.empty()) return std::nullopt;
  const auto& samples = it->second;
  const auto after =
      std::lower_bound(samples.begin(), samples.end(), t_us, [](const auto& s, std::int64_t t) { return s.first < t; });
  const std::pair<std::int64_t, std::optional<fit::ForearmOrientationSample>>* best = nullptr;
  if (after != samples.end()) best = &*after;
  if (after != samples.begin() && (!best || t_us - std::prev(after)->first < best->first - t_us))
    best = &*std::prev(after);
  if (!best || std::llabs(best->first - t_us) > kForearmToleranceUs) return std::nullopt;
  return best->second;
}

void BodyFitStage::fit_ready(bool all, StageOutput& out) {
  const fit::ForearmOrientationAt K_from_F = [this](fit::ArmSide side, std::int64_t t_us) {
    return K_from_F_at(side, t_us);
  };
  while (!queue_.empty()) {
    const std::int64_t t = queue_.front().t_us;
    int covered = 0;
    for (const auto& [arm, samples] : K_from_F_) covered += !samples.empty() && samples.back().first >= t;
    const bool waited = static_cast<double>(queue_.back().t_us - t) * 1e-6 >= options_.imu_wait_s;
    if (!all && covered < arm_imus_ && !waited) return;
    QueuedBodyFitFrame& queued = queue_.front();
    BodyFitFrame frame{queued.t_us, fit::unpack_body_pixels(queued.frame), std::move(queued.skeleton),
                       queued.assemble_s};
    queued_pixel_bytes_ -= queued.frame.bytes();
    queue_.pop_front();
    fit::BodyTracker::Output fitted = tracker_->fit(frame, K_from_F);
    const int orientations = (K_from_F(fit::ArmSide::kLeft, t) ? 1 : 0) + (K_from_F(fit::ArmSide::kRight, t) ? 1 : 0);
    if (fitted.fitted && orientations < arm_imus_) ++frames_without_imu_;
    hand_on(std::move(fitted), out);
  }
  // Forearm orientations are looked up for queued frames and for fitted frames the smoother has
  // not released yet; older ones are dropped.
  for (auto& [arm, samples] : K_from_F_) {
    if (samples.empty() || !last_frame_t_us_) continue;
    std::int64_t oldest = *last_frame_t_us_;  // later frames may still come for later samples
    if (const auto held = tracker_->oldest_held_t_us()) oldest = std::min(oldest, *held);
    if (!queue_.empty()) oldest = std::min(oldest, queue_.front().t_us);
    while (samples.size() > 1 && samples.front().first < oldest - kForearmHistoryUs) samples.pop_front();
  }
}

void BodyFitStage::hand_on(fit::BodyTracker::Output&& fitted, StageOutput& out) {
  for (const fit::FittedBodyFrame& f : fitted.frames) {
    if (f.joints_off_camera > 0) ++frames_off_camera_;
    if (f.joints_out_of_view > 0) ++frames_out_of_view_;
    out.hand_on(fitted_frame_from(f));
  }
  for (const fit::FitWarning& w : fitted.warnings) out.warn(w.code, w.field, w.message);
}

void BodyFitStage::finish(StageOutput& out) {
  if (!enabled_) {
    out.hand_on(FramesDone{FrameSource::kBodyFit, INT64_MAX});
    return;
  }
  enqueue(tracker_->personalise_now(), out);
  fit_ready(true, out);
  hand_on(tracker_->flush([this](fit::ArmSide side, std::int64_t t_us) { return K_from_F_at(side, t_us); }), out);
  const std::uint64_t fitted = tracker_->frames_fitted();
  if (frames_without_skeleton_ > 0) {
    out.warn(
        "FIT_NO_SKELETON", "skeleton",
        std::to_string(frames_without_skeleton_) + " depth frames had no skeleton of the fitted person: not fitted");
  }
  if (frames_without_imu_ > 0) {
    out.warn("FIT_NO_IMU", "fit",
             std::to_string(frames_without_imu_) + " of " + std::to_string(fitted) +
                 " frames fitted without the forearm orientation of every arm IMU (none within " +
                 format_double(options_.imu_wait_s) + " s of camera time, fit.imu_wait_s)");
  }
  if (frames_off_camera_ > 0) {
    out.warn("FIT_OFF_CAMERA", "skeleton",
             std::to_string(frames_off_camera_) + " of " + std::to_string(fitted) +
                 " frames have a fitted joint more than " + format_double(fit::kCameraDisagreementM) +
                 " m from the camera's tracked joint, farther than the camera's error explains: those joints "
                 "have no confidence, since either the fit or the camera is that far off");
  }
  if (frames_out_of_view_ > 0) {
    out.warn("FIT_OUT_OF_VIEW", "fit",
             std::to_string(frames_out_of_view_) + " of " + std::to_string(fitted) +
                 " frames have a fitted joint outside the depth image: nothing the camera gives sees those joints, "
                 "which have no confidence (the subject partly out of view)");
  }
  if (tracker_->frames_untrusted() > 0) {
    out.warn("FIT_UNTRUSTED", "fit",
             std::to_string(tracker_->frames_untrusted()) + " of " + std::to_string(fitted) +
                 " frames fitted, or smoothed with a neighbour fitted, at an energy above " +
                 format_double(options_.trusted_energy) +
                 " (fit.trusted_energy) but not lost: the fit matches their depth less well than fits measured to "
                 "be within 15 deg; their joints and forearms have confidence at most " +
                 fixed_text(fit::untrusted_fit_confidence(), 4));
  }
  if (tracker_->frames_lost() > 0) {
    out.warn("FIT_LOST", "fit",
             "tracking lost (energy above " + format_double(options_.lost_energy) + ") in " +
                 std::to_string(tracker_->frames_lost()) + " of " + std::to_string(fitted) + " frames");
  }
  report_shape(out);
  out.hand_on(FramesDone{FrameSource::kBodyFit, INT64_MAX});
}

void BodyFitStage::report_shape(StageOutput& out) const {
  const std::optional<fit::FittedShape> fitted = tracker_->shape();
  if (!fitted) return;
  v1::BodyShape& shape = *out.calibration().mutable_body_shape();
  shape.clear_betas();
  for (int i = 0; i < fitted->beta.size(); ++i) shape.add_betas(fitted->beta[i]);
  const auto length = [&](int a, int b) {
    return (fitted->rest_joints_K.col(a) - fitted->rest_joints_K.col(b)).norm();
  };
  shape.set_upper_arm_length_left_m(length(body::kLeftShoulder, body::kLeftElbow));
  shape.set_upper_arm_length_right_m(length(body::kRightShoulder, body::kRightElbow));
  shape.set_forearm_length_left_m(length(body::kLeftElbow, body::kLeftWrist));
  shape.set_forearm_length_right_m(length(body::kRightElbow, body::kRightWrist));
  shape.set_shoulder_width_m(length(body::kLeftShoulder, body::kRightShoulder));
  shape.set_torso_length_m(length(body::kPelvis, body::kNeck));
  shape.set_estimated(fitted->estimated);
  shape.set_body_model(sex_ == body::Sex::kFemale ? v1::BodyShape::TEMPLATE_FEMALE : v1::BodyShape::TEMPLATE_MALE);
}

}  // namespace posefuse::session
