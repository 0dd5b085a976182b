#include "fit/body_tracker.hpp"

#include <algorithm>
#include <future>
#include <utility>

#include "common/error.hpp"
#include "common/held_bytes.hpp"
#include "common/number_text.hpp"
#include "common/thread_cpu_time.hpp"
#include "fit/frame_fitter.hpp"
#include "fit/frame_observation.hpp"
#include "fit/height_shape.hpp"
#include "fit/joint_kinematics.hpp"
#include "fit/limb_bend.hpp"
#include "fit/personalisation.hpp"
#include "fit/shape_pose_refiner.hpp"
#include "fit/silhouette_cleanup.hpp"
#include "fit/skeleton_pose_init.hpp"

namespace posefuse::fit {

bool needs_skeleton_start(std::optional<double> previous_energy, double skeleton_start_energy) {
  return !previous_energy || skeleton_start_energy <= 0.0 || !(*previous_energy < skeleton_start_energy);
}

struct BodyTracker::Work {
  std::shared_ptr<const body::SmplModel> model;
  raycast::DepthCamera camera;
  // The tracker's poses are full body (48 DOF). While the camera shows neither leg bent, a frame is
  // fitted by paper 2's upper-body fit (40 DOF, the full body's first ones) with the legs straight;
  // once one bends, by the full body with the straight leg held (limb_bend.hpp).
  body::PoseLayout layout = body::PoseLayout::full_body();
  body::PoseLayout upper_layout = body::PoseLayout::upper_body();
  FitOptions fit_options;
  FrameFitter fitter;                      // upper body
  std::optional<FrameFitter> legs_fitter;  // full body, built when a leg first bends
  // The skeleton start's, when both starts run on two threads.
  std::optional<FrameFitter> second_fitter, second_legs_fitter;
  PoseSmoother smoother;
  Eigen::VectorXd beta;
  std::optional<Personalisation> personalisation;
  std::optional<Eigen::VectorXd> height_beta;  // the shape of the subject's measured height, if known
  std::optional<SkeletonPoseInitializer> init;
  Eigen::Matrix3Xd rest_joints;
  ObservationBuffers observation_buffers;  // the frames' preprocessing, reused from frame to frame

  Work(std::shared_ptr<const body::SmplModel> m, const raycast::DepthIntrinsics& intrinsics, const FitOptions& options,
       const PoseSmoothingOptions& smoothing)
      : model(std::move(m)),
        camera(intrinsics),
        fit_options(options),
        fitter(model, upper_layout, intrinsics, options),
        smoother(layout, smoothing),
        beta(Eigen::VectorXd::Zero(model->num_betas())) {}

  FrameFitter& built(std::optional<FrameFitter>& f, const body::PoseLayout& of) {
    if (!f) f.emplace(model, of, camera.intrinsics(), fit_options);
    return *f;
  }

  // Fits one start (a full-body theta) on this or the second thread's fitters; `held` are
  // held_leg_dofs(layout, bent).
  FitResult fit(const FrameObservation& observation, const Eigen::VectorXd& start, BentLegs bent,
                const std::vector<int>& held, bool second_thread) {
    if (bent.left || bent.right) {
      FrameFitter& f = built(second_thread ? second_legs_fitter : legs_fitter, layout);
      return f.fit(observation, start, beta, held);
    }
    FrameFitter& f = second_thread ? built(second_fitter, upper_layout) : fitter;
    FitResult result = f.fit(observation, start.head(upper_layout.size()), beta);
    Eigen::VectorXd theta = Eigen::VectorXd::Zero(layout.size());
    theta.head(upper_layout.size()) = result.theta;
    result.theta = std::move(theta);
    return result;
  }

  void set_shape(const Eigen::VectorXd& shape) {
    beta = shape;
    init.emplace(model, layout, beta);
    rest_joints = fit::rest_joints(*model, beta);
  }
};

BodyTracker::BodyTracker(std::shared_ptr<const body::SmplModel> model, const raycast::DepthIntrinsics& intrinsics,
                         const BodyTrackerOptions& options)
    : options_(options), work_(std::make_unique<Work>(std::move(model), intrinsics, options.fit, options.smoothing)) {
  // Here, so that a bad height is refused at once and a refused personalisation cannot fail on it.
  if (options.subject_height_m) work_->height_beta = shape_from_height(*work_->model, *options.subject_height_m);
}

BodyTracker::~BodyTracker() = default;

BodyTracker::Admitted BodyTracker::admit(BodyFitFrame&& frame) {
  if (!first_t_us_) first_t_us_ = frame.t_us;
  Admitted out;
  if (!personalised_) {
    if (static_cast<double>(frame.t_us - *first_t_us_) * 1e-6 < options_.calibration_s) {
      calibration_pixel_bytes_ +=
          posefuse::held_bytes(frame.frame.depth_mm) + posefuse::held_bytes(frame.frame.body_index);
      calibration_frames_.push_back(std::move(frame));
      return out;
    }
    out = personalise_now();
  }
  out.frames.push_back(std::move(frame));
  return out;
}

BodyTracker::Admitted BodyTracker::personalise_now() {
  Admitted out;
  if (personalised_ || calibration_frames_.empty()) return out;
  out.warnings = personalise();
  out.frames = std::move(calibration_frames_);
  calibration_frames_.clear();
  calibration_frames_.shrink_to_fit();
  calibration_pixel_bytes_ = 0;
  return out;
}

std::vector<FitWarning> BodyTracker::personalise() {
  personalised_ = true;
  std::vector<FitWarning> warnings;
  // The frames whose camera skeleton shows the controlled pose even taken as exact go in: an
  // elbow that looks bent is most often a large camera error, which would spoil the segment
  // lengths. Without such frames, those within what the camera's arm joint error allows
  // (ControlledPoseLimits); without those, all go in and the pose check says why.
  ControlledPoseLimits exact_camera;
  exact_camera.camera_arm_joint_error_m = 0.0;
  const auto in_pose = [&](const TrackedSkeleton& skeleton, const ControlledPoseLimits& limits) {
    try {
      check_controlled_pose({skeleton}, &work_->camera, limits);
      return true;
    } catch (const Error&) {
      return false;
    }
  };
  std::vector<const BodyFitFrame*> all_frames, strict_frames, tolerant_frames;
  for (const BodyFitFrame& f : calibration_frames_) {
    if (!f.skeleton) continue;
    all_frames.push_back(&f);
    if (in_pose(*f.skeleton, exact_camera)) strict_frames.push_back(&f);
    else if (in_pose(*f.skeleton, ControlledPoseLimits{})) tolerant_frames.push_back(&f);
  }
  const std::vector<const BodyFitFrame*>& chosen_frames = !strict_frames.empty()     ? strict_frames
                                                          : !tolerant_frames.empty() ? tolerant_frames
                                                                                     : all_frames;
  std::vector<TrackedSkeleton> skeletons;
  for (const BodyFitFrame* f : chosen_frames) skeletons.push_back(*f->skeleton);
  Eigen::VectorXd beta = Eigen::VectorXd::Zero(work_->model->num_betas());
  // III-B on the same frames' depth (cleaned as every fitted frame). A refusal of the fine tuning
  // fits the template shape: the rough shape alone (III-A) follows the camera skeleton's joint
  // errors and is further from the subject than the template (docs/fitting.md, "Personalisation").
  // The refiner's error is caught here, not in personalise().
  ShapePoseRefiner refiner;
  std::optional<Error> fine_error;
  if (options_.fine_shape) {
    std::vector<CalibrationFrame> depth_frames;
    for (const BodyFitFrame* f : chosen_frames) {
      depth_frames.push_back({f->frame, *f->skeleton});
      remove_off_body_depth(depth_frames.back().frame, depth_frames.back().skeleton, {}, &work_->camera);
    }
    refiner = [&, depth = make_depth_shape_refiner(work_->model, work_->camera, std::move(depth_frames))](
                  std::size_t frame_index, const Eigen::VectorXd& beta0, const Eigen::VectorXd& theta0) {
      try {
        return depth(frame_index, beta0, theta0);
      } catch (const Error& e) {
        fine_error = e;
        return ShapePoseFit{beta0, theta0, 0.0};
      }
    };
  }
  // Without a personalised shape: the template's, or the one the subject's measured height implies.
  const auto fallback = [&]() -> std::string {
    if (!work_->height_beta) {
      return "fitting the template shape (beta = 0; the subject's standing height, header.height_m or the client's "
             "--height, would shape it)";
    }
    beta = *work_->height_beta;
    return "fitting the shape of the subject's height (" + fixed_text(*options_.subject_height_m, 3) +
           " m, header.height_m)";
  };
  try {
    work_->personalisation = fit::personalise(work_->model, skeletons, &work_->camera, refiner);
    if (fine_error) {
      work_->personalisation.reset();
      warnings.push_back({"FIT_FINE_SHAPE", fine_error->field(),
                          std::string(fine_error->what()) + "; " + fallback() +
                              ": the rough shape alone is further from the subject's"});
    } else {
      beta = work_->personalisation->beta();
    }
  } catch (const Error& e) {
    warnings.push_back({"FIT_PERSONALISATION", e.field(), std::string(e.what()) + "; " + fallback()});
  }
  work_->set_shape(beta);
  return warnings;
}

BodyTracker::Output BodyTracker::fit(BodyFitFrame& frame, const ForearmOrientationAt& K_from_F_at) {
  Work& w = *work_;
  Output out;
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
    ForearmDirections directions;
    const auto left = K_from_F_at(ArmSide::kLeft, frame.t_us), right = K_from_F_at(ArmSide::kRight, frame.t_us);
    if (left) {
      directions.left_K = left->K_from_F * Eigen::Vector3d::UnitY();  // F's y: elbow -> wrist
      directions.left_weight = left->axis_weight;
    }
    if (right) {
      directions.right_K = right->K_from_F * Eigen::Vector3d::UnitY();
      directions.right_weight = right->axis_weight;
    }
    std::optional<KinectSkeleton> positions;
    if (frame.skeleton) {
      positions = frame.skeleton->positions_K;
      remove_off_body_depth(frame.frame, *frame.skeleton, {}, &w.camera);  // misaligned index, flying pixels
    }
    take(stats.cleanup_s);
    const FrameObservation& observation = prepare_observation(w.observation_buffers, frame.frame, w.camera, positions,
                                                              w.fit_options, directions, &stats.observation);
    lap = thread_cpu_seconds();

    // II-G: from the previous frame's pose and from the skeleton-built pose; the lower energy
    // wins. The skeleton start is fitted only when the previous one is missing or ends at
    // skeleton_start_energy or above (docs/fitting.md, "Start policy"); with the policy off both
    // always run, the skeleton start on a second thread.
    const Eigen::VectorXd previous = previous_theta_.value_or(Eigen::VectorXd());
    // The legs the camera does not show bent are straight in both starts.
    const BentLegs bent = camera_bent_legs(frame.skeleton ? &*frame.skeleton : nullptr);
    const std::vector<int> held = held_leg_dofs(w.layout, bent);
    const auto straighten_legs = [&held](Eigen::VectorXd& theta) {
      for (int d : held) theta[d] = 0;
    };
    // The previous-frame start, moved on by the last frames' velocity where that is trusted.
    Eigen::VectorXd previous_start = previous;
    if (previous.size() > 0 && before_last_fit_ && options_.extrapolation.velocity_gain > 0) {
      if (auto moved = extrapolate_start(w.layout, *before_last_fit_, {previous, previous_t_us_}, frame.t_us,
                                         options_.extrapolation)) {
        previous_start = std::move(*moved);
        stats.extrapolated = true;
      }
    }
    if (previous_start.size() > 0) straighten_legs(previous_start);
    std::optional<FitResult> best;
    const auto keep_lower = [&](FitResult&& result, bool from_previous) {
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
        straighten_legs(theta);
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
        auto job = std::async(std::launch::async, [&] {
          const double cpu_start = thread_cpu_seconds();
          FitResult result = w.fit(observation, *start, bent, held, true);
          return std::make_pair(std::move(result), thread_cpu_seconds() - cpu_start);
        });
        lap = thread_cpu_seconds();
        FitResult from_previous = w.fit(observation, previous_start, bent, held, false);
        take(stats.fit_previous_s);
        auto [from_skeleton, skeleton_cpu_s] = job.get();
        lap = thread_cpu_seconds();  // waiting is not work
        stats.fit_skeleton_s = skeleton_cpu_s;
        keep_lower(std::move(from_previous), true);
        keep_lower(std::move(from_skeleton), false);
      } else {
        keep_lower(w.fit(observation, previous_start, bent, held, false), true);
        take(stats.fit_previous_s);
      }
    } else {
      if (previous.size() > 0) {
        keep_lower(w.fit(observation, previous_start, bent, held, false), true);
        take(stats.fit_previous_s);
      }
      if (needs_skeleton_start(best ? std::optional<double>(best->energy.total()) : std::nullopt,
                               options_.skeleton_start_energy)) {
        if (const auto start = skeleton_start()) {
          keep_lower(w.fit(observation, *start, bent, held, false), false);
          take(stats.fit_skeleton_s);
        }
      }
    }
    const double energy = best->energy.total();
    // A velocity holds between two fits of the same track: the winner continued the previous pose.
    if (previous.size() > 0 && stats.previous_won) {
      before_last_fit_ = FittedPose{previous, previous_t_us_};
    } else {
      before_last_fit_.reset();
    }
    // Lost tracking is counted, and the next frame still starts from the lost pose: the start
    // policy adds the skeleton start after a fit at skeleton_start_energy or above, and the lower
    // energy wins. Dropping the previous pose threw away a good one whenever one frame's energy
    // jumped (single-frame depth or sampling outliers; behind the back the camera skeleton's
    // wrists are 12-15 cm off). On paper 1's protocol (seeds 1 / 2) keeping it took the arms' six
    // joints from 21.2 / 22.8 to 18.8 / 18.2 mm; restarting from the last pose below the threshold
    // plus the skeleton start gave 20.2 / 18.3 mm (docs/fitting.md, "Paper 1's protocol").
    if (energy > options_.lost_energy) ++frames_lost_;
    previous_theta_ = best->theta;
    previous_t_us_ = frame.t_us;
    fitted_.push_back({frame.t_us, *frame.skeleton, energy, directions.left_K || directions.right_K});
    ++frames_fitted_;
    out.fitted = true;
    if (const auto smoothed = w.smoother.push(best->theta)) out.frames.push_back(release(*smoothed, K_from_F_at));
    take(stats.post_s);
    if (record_stats_) stats_.push_back(stats);
  } catch (const Error& e) {
    out.warnings.push_back(
        {"FIT_FRAME", e.field(), "frame t_us=" + std::to_string(frame.t_us) + " not fitted: " + e.what()});
  }
  return out;
}

FittedBodyFrame BodyTracker::release(const Eigen::VectorXd& theta, const ForearmOrientationAt& K_from_F_at) {
  const Fitted f = std::move(fitted_.front());
  fitted_.pop_front();
  // The reported forearms turn the IMU's K_from_F onto the fitted axis: only where it is confident.
  const auto confident = [&](ArmSide side) -> std::optional<Eigen::Quaterniond> {
    const auto sample = K_from_F_at(side, f.t_us);
    if (!sample || sample->axis_weight < 1.0) return std::nullopt;
    return sample->K_from_F;
  };
  FittedBodyFrame out = make_fitted_body_frame(work_->rest_joints, work_->layout, theta, f.skeleton, work_->camera,
                                               {confident(ArmSide::kLeft), confident(ArmSide::kRight)});
  out.t_us = f.t_us;
  out.energy = f.energy;
  out.lost = f.energy > options_.lost_energy;
  // The smoothed pose averages the fits of its window (PoseSmoother: centred, shrinking at the
  // ends), so it carries part of any of their errors: it is trusted only where each of them is.
  const auto half = static_cast<std::size_t>(options_.smoothing.window_frames / 2);
  const std::size_t reach = std::min({half, released_energies_.size(), fitted_.size()});
  const auto trusted = [&](double energy) { return energy <= options_.trusted_energy; };
  bool window_trusted = trusted(f.energy);
  for (std::size_t k = 0; k < reach; ++k) {
    window_trusted =
        window_trusted && trusted(released_energies_[released_energies_.size() - 1 - k]) && trusted(fitted_[k].energy);
  }
  if (!window_trusted) {
    cap_confidence(out, untrusted_fit_confidence());
    if (!out.lost) ++frames_untrusted_;
  }
  released_energies_.push_back(f.energy);
  if (released_energies_.size() > half) released_energies_.pop_front();
  out.imu_used = f.imu_used;
  return out;
}

BodyTracker::Output BodyTracker::flush(const ForearmOrientationAt& K_from_F_at) {
  Output out;
  for (const Eigen::VectorXd& theta : work_->smoother.flush()) out.frames.push_back(release(theta, K_from_F_at));
  return out;
}

std::optional<std::int64_t> BodyTracker::oldest_held_t_us() const {
  std::optional<std::int64_t> oldest;
  if (!calibration_frames_.empty()) oldest = calibration_frames_.front().t_us;
  if (!fitted_.empty()) oldest = std::min(oldest.value_or(fitted_.front().t_us), fitted_.front().t_us);
  return oldest;
}

std::size_t BodyTracker::held_bytes() const {
  return posefuse::held_bytes(calibration_frames_) + calibration_pixel_bytes_ + posefuse::held_bytes(fitted_) +
         posefuse::held_bytes(stats_);
}

std::optional<FittedShape> BodyTracker::shape() const {
  if (!work_->init) return std::nullopt;
  const JointPose rest = pose_joints(work_->rest_joints, work_->layout, work_->layout.zero());
  return FittedShape{work_->beta, rest.positions_K, work_->personalisation.has_value()};
}

}  // namespace posefuse::fit
