#include "session/stages/body_fit_stage.hpp"

#include <algorithm>
#include <cmath>
#include <future>
#include <string>
#include <utility>

#include "body/template_generator.hpp"
#include "common/error.hpp"
#include "common/thread_cpu_time.hpp"
#include "fit/arm_roll.hpp"
#include "fit/camera_joints.hpp"
#include "fit/frame_fitter.hpp"
#include "fit/joint_kinematics.hpp"
#include "fit/personalisation.hpp"
#include "fit/pose_smoothing.hpp"
#include "fit/shape_pose_refiner.hpp"
#include "fit/silhouette_cleanup.hpp"
#include "fit/skeleton_pose_init.hpp"
#include "fit/start_extrapolation.hpp"
#include "raycast/depth_camera.hpp"
#include "session/stages/proto_values.hpp"
#include "session/text_fields.hpp"

namespace posefuse::session {

namespace {

// A forearm orientation further than this from the frame is not used.
constexpr std::int64_t kForearmToleranceUs = 20'000;
// Forearm orientations kept behind the oldest queued frame.
constexpr std::int64_t kForearmHistoryUs = 1'000'000;
constexpr double kUntrackedConfidence = 0.5;

fit::JointTracking tracking_from(JointState state) {
  switch (state) {
    case JointState::kTracked: return fit::JointTracking::kTracked;
    case JointState::kInferred: return fit::JointTracking::kInferred;
    case JointState::kNotTracked: break;
  }
  return fit::JointTracking::kNotTracked;
}

double confidence_of(const fit::TrackedSkeleton& skeleton, int camera_joint) {
  return skeleton.tracking[static_cast<size_t>(camera_joint)] == fit::JointTracking::kTracked ? 1.0
                                                                                           : kUntrackedConfidence;
}


}  // namespace

bool needs_skeleton_start(std::optional<double> previous_energy, double skeleton_start_energy) {
  return !previous_energy || skeleton_start_energy <= 0.0 || !(*previous_energy < skeleton_start_energy);
}

fit::TrackedSkeleton tracked_skeleton_from(const Skeleton& skeleton) {
  fit::TrackedSkeleton out;
  for (std::size_t j = 0; j < skeleton.joints.size(); ++j) {
    out.positions_K[j] = skeleton.joints[j].p_K;
    out.tracking[j] = tracking_from(skeleton.joints[j].state);
  }
  return out;
}

struct BodyFitStage::Work {
  std::shared_ptr<const body::SmplModel> model;
  raycast::DepthCamera camera;
  body::PoseLayout layout = body::PoseLayout::upper_body();
  fit::FitOptions fit_options;
  fit::FrameFitter fitter;
  std::optional<fit::FrameFitter> second_fitter;  // the skeleton start's, when both run on two threads
  fit::PoseSmoother smoother;
  Eigen::VectorXd beta;
  std::optional<fit::Personalisation> personalisation;
  std::optional<fit::SkeletonPoseInitializer> init;
  Eigen::Matrix3Xd rest_joints;

  Work(std::shared_ptr<const body::SmplModel> m, const raycast::DepthIntrinsics& intrinsics, const fit::FitOptions& options,
       const fit::PoseSmoothingOptions& smoothing)
      : model(std::move(m)),
        camera(intrinsics),
        fit_options(options),
        fitter(model, layout, intrinsics, options),
        smoother(layout, smoothing),
        beta(Eigen::VectorXd::Zero(model->num_betas())) {}

  fit::FrameFitter& fitter_for_second_thread() {
    if (!second_fitter) second_fitter.emplace(model, layout, camera.intrinsics(), fit_options);
    return *second_fitter;
  }

  void set_shape(const Eigen::VectorXd& shape) {
    beta = shape;
    init.emplace(model, layout, beta);
    rest_joints = fit::rest_joints(*model, beta);
  }
};

BodyFitStage::BodyFitStage() = default;
BodyFitStage::~BodyFitStage() = default;

std::string_view BodyFitStage::description() const {
  return "body-model fit to every depth frame (paper 2): personalised shape, 24 SMPL joints, 25 camera joints, "
         "forearm roll from the wrist IMUs";
}

const OptionTable& BodyFitStage::options() const { return body_fit_option_table(); }

void BodyFitStage::start(const v1::SessionHeader& header, StageOutput& /*out*/) {
  enabled_ = body_fit_enabled(header);
  if (!enabled_) return;
  options_ = read_body_fit_options(header);
  body_id_ = options_.body_id;
  arm_imus_ = static_cast<int>(std::count_if(header.imu_devices().begin(), header.imu_devices().end(), [](const auto& d) {
    return d.role() == v1::ImuDevice::ARM_LEFT || d.role() == v1::ImuDevice::ARM_RIGHT;
  }));
  const body::Sex sex = header.sex() == v1::SessionHeader::FEMALE ? body::Sex::kFemale : body::Sex::kMale;
  work_ = std::make_unique<Work>(body::make_template(sex), session_cameras(header).depth, options_.fit,
                                 options_.smoothing);
}

void BodyFitStage::on_camera_frame(const CameraFrame& camera, StageOutput& out) {
  last_camera_t_us_ = camera.t_us;
  add_camera_frame(camera, out);
  out.hand_on(FramesDone{FrameSource::kBodyFit, frames_done_up_to()});
}

std::int64_t BodyFitStage::frames_done_up_to() const {
  if (!enabled_) return INT64_MAX;
  std::int64_t up_to = last_camera_t_us_.value_or(INT64_MIN);
  if (!calibration_frames_.empty()) up_to = std::min(up_to, calibration_frames_.front().t_us - 1);
  if (!queue_.empty()) up_to = std::min(up_to, queue_.front().t_us - 1);
  if (!fitted_.empty()) up_to = std::min(up_to, fitted_.front().t_us - 1);
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
  frame.frame.width = work_->camera.width();
  frame.frame.height = work_->camera.height();
  frame.frame.depth_mm.assign(camera.depth_mm.begin<std::uint16_t>(), camera.depth_mm.end<std::uint16_t>());
  frame.frame.body_index.assign(frame.frame.depth_mm.size(), fit::kNoBody);
  if (camera.body_index.total() == frame.frame.body_index.size()) {
    const std::uint8_t* ids = camera.body_index.ptr<std::uint8_t>();
    for (std::size_t i = 0; i < frame.frame.body_index.size(); ++i) {
      if (ids[i] == *body_id_) frame.frame.body_index[i] = 0;
    }
  }
  frame.skeleton = tracked_skeleton_from(*skeleton);
  frame.assemble_s = thread_cpu_seconds() - assemble_start;
  add_frame(std::move(frame), out);
}

void BodyFitStage::on_value(const StageValue& value, StageOutput& out) {
  const auto* batch = std::get_if<ForearmOrientations>(&value);
  if (!enabled_ || !batch) return;
  auto& samples = K_from_F_[batch->arm];
  for (std::size_t i = 0; i < batch->t_us.size(); ++i) {
    const Eigen::Quaterniond& q = batch->K_from_F[i];
    if (!q.coeffs().allFinite() || std::abs(q.norm() - 1.0) > 1e-3) continue;
    if (!samples.empty() && batch->t_us[i] <= samples.back().first) continue;
    samples.emplace_back(batch->t_us[i], q.normalized());
  }
  if (personalised_) fit_ready(false, out);
}

void BodyFitStage::add_frame(BodyFitFrame&& frame, StageOutput& out) {
  if (!first_t_us_) first_t_us_ = frame.t_us;
  last_frame_t_us_ = frame.t_us;
  if (!personalised_) {
    if (static_cast<double>(frame.t_us - *first_t_us_) * 1e-6 < options_.calibration_s) {
      calibration_frames_.push_back(std::move(frame));
      return;
    }
    personalise(out);
  }
  enqueue(std::move(frame));
  fit_ready(false, out);
}

void BodyFitStage::enqueue(BodyFitFrame&& frame) {
  queue_.push_back({frame.t_us, fit::pack_body_pixels(frame.frame), std::move(frame.skeleton), frame.assemble_s});
}

void BodyFitStage::personalise(StageOutput& out) {
  personalised_ = true;
  // Frames in which the camera skeleton's errors break the controlled pose (a straight arm looks
  // bent by up to ~50 deg with the simulator's biases) are left out; when none is left, all go in
  // and the pose check says why.
  std::vector<fit::TrackedSkeleton> all, in_pose;
  std::vector<const BodyFitFrame*> all_frames, in_pose_frames;
  for (const BodyFitFrame& f : calibration_frames_) {
    if (!f.skeleton) continue;
    all.push_back(*f.skeleton);
    all_frames.push_back(&f);
    try {
      fit::check_controlled_pose({*f.skeleton}, &work_->camera);
      in_pose.push_back(*f.skeleton);
      in_pose_frames.push_back(&f);
    } catch (const Error&) {
    }
  }
  const std::vector<fit::TrackedSkeleton>& skeletons = in_pose.empty() ? all : in_pose;
  Eigen::VectorXd beta = Eigen::VectorXd::Zero(work_->model->num_betas());
  // III-B on the same frames' depth (cleaned as every fitted frame). A refusal of the fine tuning
  // keeps the rough shape (III-A): the refiner's error is caught here, not in personalise().
  fit::ShapePoseRefiner refiner;
  std::optional<Error> fine_error;
  if (options_.fine_shape) {
    std::vector<fit::CalibrationFrame> depth_frames;
    for (const BodyFitFrame* f : in_pose.empty() ? all_frames : in_pose_frames) {
      depth_frames.push_back({f->frame, *f->skeleton});
      fit::remove_off_body_depth(depth_frames.back().frame, depth_frames.back().skeleton);
    }
    refiner = [&, depth = fit::make_depth_shape_refiner(work_->model, work_->camera, std::move(depth_frames))](
                  std::size_t frame_index, const Eigen::VectorXd& beta0, const Eigen::VectorXd& theta0) {
      try {
        return depth(frame_index, beta0, theta0);
      } catch (const Error& e) {
        fine_error = e;
        return fit::ShapePoseFit{beta0, theta0, 0.0};
      }
    };
  }
  try {
    work_->personalisation = fit::personalise(work_->model, skeletons, &work_->camera, refiner);
    if (fine_error) {
      work_->personalisation->fine_tuned = false;
      out.warn("FIT_FINE_SHAPE", fine_error->field(), std::string(fine_error->what()) + "; using the rough shape (III-A)");
    }
    beta = work_->personalisation->beta();
  } catch (const Error& e) {
    out.warn("FIT_PERSONALISATION", e.field(),
             std::string(e.what()) + "; fitting the template shape (beta = 0)");
  }
  work_->set_shape(beta);
  for (BodyFitFrame& f : calibration_frames_) enqueue(std::move(f));
  calibration_frames_.clear();
}

std::optional<Eigen::Quaterniond> BodyFitStage::K_from_F_at(int arm, std::int64_t t_us) const {
  const auto it = K_from_F_.find(arm);
  if (it == K_from_F_.end() || it->second.empty()) return std::nullopt;
  const auto& samples = it->second;
  const auto after = std::lower_bound(samples.begin(), samples.end(), t_us,
                                      [](const auto& s, std::int64_t t) { return s.first < t; });
  const std::pair<std::int64_t, Eigen::Quaterniond>* best = nullptr;
  if (after != samples.end()) best = &*after;
  if (after != samples.begin() && (!best || t_us - std::prev(after)->first < best->first - t_us)) best = &*std::prev(after);
  if (!best || std::llabs(best->first - t_us) > kForearmToleranceUs) return std::nullopt;
  return best->second;
}

void BodyFitStage::fit_ready(bool all, StageOutput& out) {
  while (!queue_.empty()) {
    const std::int64_t t = queue_.front().t_us;
    int covered = 0;
    for (const auto& [arm, samples] : K_from_F_) covered += !samples.empty() && samples.back().first >= t;
    const bool waited = static_cast<double>(queue_.back().t_us - t) * 1e-6 >= options_.imu_wait_s;
    if (!all && covered < arm_imus_ && !waited) return;
    QueuedBodyFitFrame& queued = queue_.front();
    BodyFitFrame frame{queued.t_us, fit::unpack_body_pixels(queued.frame), std::move(queued.skeleton), queued.assemble_s};
    queue_.pop_front();
    fit_frame(frame, out);
  }
  // Forearm orientations are looked up for queued frames and for fitted frames the smoother has
  // not emitted yet; older ones are dropped.
  for (auto& [arm, samples] : K_from_F_) {
    if (samples.empty() || !last_frame_t_us_) continue;
    std::int64_t oldest = *last_frame_t_us_;  // later frames may still come for later samples
    if (!calibration_frames_.empty()) oldest = std::min(oldest, calibration_frames_.front().t_us);
    if (!queue_.empty()) oldest = std::min(oldest, queue_.front().t_us);
    if (!fitted_.empty()) oldest = std::min(oldest, fitted_.front().t_us);
    while (samples.size() > 1 && samples.front().first < oldest - kForearmHistoryUs) samples.pop_front();
  }
}

void BodyFitStage::fit_frame(BodyFitFrame& frame, StageOutput& out) {
  Work& w = *work_;
  BodyFitFrameStats stats;
  stats.t_us = frame.t_us;
  stats.assemble_s = frame.assemble_s;
  double lap = thread_cpu_seconds();
  // Adds the CPU time since the last lap to `part`.
  const auto take = [&lap](double& part) {
    const double now = thread_cpu_seconds();
    part += now - lap;
    lap = now;
  };
  try {
    fit::ForearmDirections directions;
    const auto left = K_from_F_at(v1::LEFT, frame.t_us), right = K_from_F_at(v1::RIGHT, frame.t_us);
    if (left) directions.left_K = *left * Eigen::Vector3d::UnitY();  // F's y: elbow -> wrist
    if (right) directions.right_K = *right * Eigen::Vector3d::UnitY();
    std::optional<fit::KinectSkeleton> positions;
    if (frame.skeleton) {
      positions = frame.skeleton->positions_K;
      fit::remove_off_body_depth(frame.frame, *frame.skeleton);  // body index / depth misalignment
    }
    take(stats.cleanup_s);
    const fit::FrameObservation observation =
        fit::prepare_observation(frame.frame, w.camera, positions, w.fit_options, directions, &stats.observation);
    lap = thread_cpu_seconds();

    // II-G: from the previous frame's pose and from the skeleton-built pose; the lower energy
    // wins. The skeleton start is fitted only when the previous one is missing or ends at
    // fit.skeleton_start_energy or above (docs/fitting.md, "Start policy"); with the policy off
    // both always run, the skeleton start on a second thread.
    const Eigen::VectorXd previous = previous_theta_.value_or(Eigen::VectorXd());
    // The previous-frame start, moved on by the last frames' velocity where that is trusted.
    Eigen::VectorXd previous_start = previous;
    if (previous.size() > 0 && before_last_fit_ && options_.extrapolation.velocity_gain > 0) {
      if (auto moved = fit::extrapolate_start(w.layout, *before_last_fit_, {previous, previous_t_us_}, frame.t_us,
                                              options_.extrapolation)) {
        previous_start = std::move(*moved);
        stats.extrapolated = true;
      }
    }
    std::optional<fit::FitResult> best;
    const auto keep_lower = [&](fit::FitResult&& result, bool from_previous) {
      if (from_previous) {
        stats.iterations_previous = result.iterations;
        stats.energy_previous = result.energy.total();
      } else {
        stats.iterations_skeleton = result.iterations;
        stats.energy_skeleton = result.energy.total();
      }
      if (!best || result.energy.total() < best->energy.total()) {
        best = std::move(result);
        stats.previous_won = from_previous;
      }
    };
    // The skeleton-built start; without a previous pose its errors are the frame's.
    const auto skeleton_start = [&]() -> std::optional<Eigen::VectorXd> {
      try {
        Eigen::VectorXd theta = w.init->initialise(*frame.skeleton, previous).theta;
        take(stats.start_pose_s);
        return theta;
      } catch (const Error&) {
        if (previous.size() == 0) throw;
        take(stats.start_pose_s);
        return std::nullopt;
      }
    };
    if (previous.size() > 0 && options_.skeleton_start_energy == 0.0) {
      if (const auto start = skeleton_start()) {
        fit::FrameFitter& second = w.fitter_for_second_thread();
        auto job = std::async(std::launch::async, [&] {
          const double cpu_start = thread_cpu_seconds();
          fit::FitResult result = second.fit(observation, *start, w.beta);
          return std::make_pair(std::move(result), thread_cpu_seconds() - cpu_start);
        });
        lap = thread_cpu_seconds();
        fit::FitResult from_previous = w.fitter.fit(observation, previous_start, w.beta);
        take(stats.fit_previous_s);
        auto [from_skeleton, skeleton_cpu_s] = job.get();
        lap = thread_cpu_seconds();  // waiting is not work
        stats.fit_skeleton_s = skeleton_cpu_s;
        keep_lower(std::move(from_previous), true);
        keep_lower(std::move(from_skeleton), false);
      } else {
        keep_lower(w.fitter.fit(observation, previous_start, w.beta), true);
        take(stats.fit_previous_s);
      }
    } else {
      if (previous.size() > 0) {
        keep_lower(w.fitter.fit(observation, previous_start, w.beta), true);
        take(stats.fit_previous_s);
      }
      if (needs_skeleton_start(best ? std::optional<double>(best->energy.total()) : std::nullopt,
                               options_.skeleton_start_energy)) {
        if (const auto start = skeleton_start()) {
          keep_lower(w.fitter.fit(observation, *start, w.beta), false);
          take(stats.fit_skeleton_s);
        }
      }
    }
    const double energy = best->energy.total();
    // A velocity holds between two fits of the same track: the winner continued the previous pose.
    if (previous.size() > 0 && stats.previous_won)
      before_last_fit_ = fit::FittedPose{previous, previous_t_us_};
    else
      before_last_fit_.reset();
    // Lost tracking: reported, and no longer a restart from the skeleton alone (ours). The start
    // policy already fits the skeleton start after a fit at fit.skeleton_start_energy or above,
    // and the lower energy wins; dropping the previous pose threw away a good one whenever one
    // frame's energy jumped (single-frame depth or sampling outliers, and behind the back the
    // camera skeleton's wrists are 12-15 cm off). On paper 1's protocol (seeds 1 / 2) the arms' six
    // joints went from 21.2 / 22.8 to 18.8 / 18.2 mm; restarting from the last pose below the
    // threshold plus the skeleton start gave 20.2 / 18.3 mm (docs/fitting.md, "Paper 1's protocol").
    if (energy > options_.lost_energy) ++frames_lost_;
    previous_theta_ = best->theta;
    previous_t_us_ = frame.t_us;
    fitted_.push_back({frame.t_us, *frame.skeleton, energy, directions.left_K || directions.right_K});
    ++frames_fitted_;
    if ((left ? 1 : 0) + (right ? 1 : 0) < arm_imus_) ++frames_without_imu_;
    if (const auto smoothed = w.smoother.push(best->theta)) emit_smoothed(*smoothed, out);
    take(stats.post_s);
    if (record_stats_) stats_.push_back(stats);
  } catch (const Error& e) {
    out.warn("FIT_FRAME", e.field(), "frame t_us=" + std::to_string(frame.t_us) + " not fitted: " + e.what());
  }
}

void BodyFitStage::emit_smoothed(const Eigen::VectorXd& theta, StageOutput& out) {
  Work& w = *work_;
  const Fitted f = std::move(fitted_.front());
  fitted_.pop_front();
  const fit::JointPose pose = fit::pose_joints(w.rest_joints, w.layout, theta);
  const Eigen::Matrix3Xd camera_joints = fit::camera_joints_from_pose(pose);
  const v1::Source source = f.imu_used ? v1::FUSED : v1::VISUAL;

  FittedFrame fitted;
  fitted.lost = f.energy > options_.lost_energy;
  FrameEstimate& frame = fitted.estimate;
  frame.t_us = f.t_us;
  frame.fit_energy = f.energy;
  std::array<double, body::kNumJoints> smpl_confidence;
  smpl_confidence.fill(1.0);
  for (int j = 0; j < fit::kKinectJointCount; ++j) {
    const int smpl = fit::smpl_joint_at_camera_joint(j);
    if (smpl >= 0) smpl_confidence[static_cast<size_t>(smpl)] = confidence_of(f.skeleton, j);
  }
  for (int j = 0; j < body::kNumJoints; ++j) {
    frame.smpl_joints.push_back({pose.positions_K.col(j), source, smpl_confidence[static_cast<size_t>(j)]});
  }
  for (int j = 0; j < fit::kKinectJointCount; ++j) {
    frame.camera_joints.push_back({camera_joints.col(j), source, confidence_of(f.skeleton, j)});
  }

  // II-B: the roll of each forearm from its IMU, the axis from the fit.
  for (const v1::Arm arm : {v1::LEFT, v1::RIGHT}) {
    const auto K_from_F = K_from_F_at(arm, f.t_us);
    if (!K_from_F) continue;
    const bool left = arm == v1::LEFT;
    const int elbow = left ? body::kLeftElbow : body::kRightElbow, wrist = left ? body::kLeftWrist : body::kRightWrist;
    const Eigen::Vector3d axis_K = (pose.positions_K.col(wrist) - pose.positions_K.col(elbow)).normalized();
    const Eigen::Quaterniond onto_fit =
        Eigen::Quaterniond::FromTwoVectors(*K_from_F * Eigen::Vector3d::UnitY(), axis_K);
    ForearmEstimate forearm{arm, (onto_fit * *K_from_F).normalized(), 0.0, v1::FUSED, 0.0};
    const int camera_wrist = left ? fit::kWristLeft : fit::kWristRight;
    forearm.confidence = confidence_of(f.skeleton, camera_wrist);
    try {
      fit::ArmRollOptions roll_options;
      // Paper 1's F (x dorsal, y along the forearm): z is the thumb side on the right forearm and
      // the little-finger side on the left (core/sim/forearm_strap.hpp).
      roll_options.thumb_F = left ? Eigen::Vector3d(-Eigen::Vector3d::UnitZ()) : Eigen::Vector3d::UnitZ();
      const fit::ForearmRoll roll = fit::forearm_roll(pose, left ? fit::ArmSide::kLeft : fit::ArmSide::kRight, *K_from_F,
                                                      Eigen::Quaterniond::Identity(), roll_options);
      if (roll.pronation_rad) forearm.pronation_rad = *roll.pronation_rad;
    } catch (const Error&) {
      forearm.confidence = 0.0;  // roll undefined (IMU thumb axis along the fitted forearm)
    }
    frame.forearms.push_back(forearm);
  }
  out.hand_on(std::move(fitted));
}

void BodyFitStage::finish(StageOutput& out) {
  if (!enabled_) {
    out.hand_on(FramesDone{FrameSource::kBodyFit, INT64_MAX});
    return;
  }
  if (!personalised_ && !calibration_frames_.empty()) personalise(out);
  fit_ready(true, out);
  for (const Eigen::VectorXd& theta : work_->smoother.flush()) emit_smoothed(theta, out);
  if (frames_without_skeleton_ > 0) {
    out.warn("FIT_NO_SKELETON", "skeleton",
             std::to_string(frames_without_skeleton_) + " depth frames had no skeleton of the fitted person: not fitted");
  }
  if (frames_without_imu_ > 0) {
    out.warn("FIT_NO_IMU", "fit", std::to_string(frames_without_imu_) + " of " + std::to_string(frames_fitted_) +
                                      " frames fitted without the forearm orientation of every arm IMU (none within " +
                                      format_double(options_.imu_wait_s) + " s of camera time, fit.imu_wait_s)");
  }
  if (frames_lost_ > 0) {
    out.warn("FIT_LOST", "fit", "tracking lost (energy above " + format_double(options_.lost_energy) + ") in " +
                                    std::to_string(frames_lost_) + " of " + std::to_string(frames_fitted_) + " frames");
  }
  if (work_->init) {
    v1::BodyShape& shape = *out.calibration().mutable_body_shape();
    shape.clear_betas();
    for (int i = 0; i < work_->beta.size(); ++i) shape.add_betas(work_->beta[i]);
    const fit::JointPose rest = fit::pose_joints(work_->rest_joints, work_->layout, work_->layout.zero());
    const auto length = [&](int a, int b) { return (rest.positions_K.col(a) - rest.positions_K.col(b)).norm(); };
    shape.set_upper_arm_length_left_m(length(body::kLeftShoulder, body::kLeftElbow));
    shape.set_upper_arm_length_right_m(length(body::kRightShoulder, body::kRightElbow));
    shape.set_forearm_length_left_m(length(body::kLeftElbow, body::kLeftWrist));
    shape.set_forearm_length_right_m(length(body::kRightElbow, body::kRightWrist));
    shape.set_shoulder_width_m(length(body::kLeftShoulder, body::kRightShoulder));
    shape.set_torso_length_m(length(body::kPelvis, body::kNeck));
    shape.set_estimated(work_->personalisation.has_value());
  }
  out.hand_on(FramesDone{FrameSource::kBodyFit, INT64_MAX});
}

}  // namespace posefuse::session
