#include "fit/rough_shape.hpp"

#include <Eigen/Geometry>
#include <cmath>
#include <numbers>
#include <string>
#include <tuple>

#include "common/error.hpp"

namespace posefuse::fit {
namespace {

constexpr double kDeg = std::numbers::pi / 180;

double angle_deg(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return std::atan2(a.cross(b).norm(), a.dot(b)) / kDeg;
}

void validate(const RoughShapeOptions& o) {
  auto positive = [](double v, const char* name) {
    if (!std::isfinite(v) || v <= 0)
      throw_invalid(std::string("rough_options.") + name, "must be positive, got " + std::to_string(v));
  };
  positive(o.initial_step, "initial_step");
  positive(o.min_step, "min_step");
  positive(o.length_unit_m, "length_unit_m");
  positive(o.max_abs_beta, "max_abs_beta");
  if (o.max_iterations < 1) throw_invalid("rough_options.max_iterations", "must be at least 1");
  if (!std::isfinite(o.min_gradient_norm) || o.min_gradient_norm < 0)
    throw_invalid("rough_options.min_gradient_norm", "must be finite and non-negative");
}

void check_frame(const TrackedSkeleton& s, const std::string& frame, const raycast::DepthCamera* camera,
                 const ControlledPoseLimits& limits) {
  for (int j : measured_camera_joints()) {
    const std::string why = joint_unusable_reason(s, j, false);
    const std::string field = frame + "." + kinect_joint_name(j);
    if (!why.empty()) throw_precondition(field, why + ": the controlled pose needs the whole body tracked and in view");
    if (!camera) continue;
    const auto uv = camera->project(s.positions_K[j]);
    const double m = limits.image_margin_px;
    if (!uv || uv->x() < m || uv->y() < m || uv->x() > camera->width() - 1 - m || uv->y() > camera->height() - 1 - m)
      throw_precondition(field, "outside the image: the subject must be fully in view");
  }
  const auto& p = s.positions_K;
  auto too_bent = [&](const char* name, int a, int b, int c, double max_deg, double joint_error_m) {
    const double bend = limb_bend_deg(p[a], p[b], p[c]);
    const double allowed = max_deg + bend_from_offset_deg(p[a], p[b], p[c], joint_error_m);
    if (bend > allowed) {
      std::string why = "bent " + std::to_string(std::lround(bend)) + " deg, at most " +
                        std::to_string(std::lround(allowed)) + " deg in the controlled pose";
      if (joint_error_m > 0)
        why += " (" + std::to_string(std::lround(max_deg)) + " plus what a camera joint error of " +
               std::to_string(std::lround(joint_error_m * 100)) + " cm allows)";
      throw_precondition(frame + ".pose." + name, why);
    }
  };
  too_bent("left_knee", kHipLeft, kKneeLeft, kAnkleLeft, limits.max_knee_bend_deg, 0.0);
  too_bent("right_knee", kHipRight, kKneeRight, kAnkleRight, limits.max_knee_bend_deg, 0.0);
  const double arm_error_m = limits.camera_arm_joint_error_m;
  too_bent("left_elbow", kShoulderLeft, kElbowLeft, kWristLeft, limits.max_elbow_bend_deg, arm_error_m);
  too_bent("right_elbow", kShoulderRight, kElbowRight, kWristRight, limits.max_elbow_bend_deg, arm_error_m);
  const Eigen::Vector3d down = 0.5 * (p[kHipLeft] + p[kHipRight]) - 0.5 * (p[kShoulderLeft] + p[kShoulderRight]);
  for (const auto& [name, shoulder, elbow] :
       {std::tuple{"left_arm", kShoulderLeft, kElbowLeft}, std::tuple{"right_arm", kShoulderRight, kElbowRight}}) {
    const double abduction = angle_deg(p[elbow] - p[shoulder], down);
    if (abduction < limits.min_arm_abduction_deg || abduction > limits.max_arm_abduction_deg)
      throw_precondition(frame + ".pose." + name,
                         "held " + std::to_string(std::lround(abduction)) +
                             " deg from the trunk, the controlled pose needs " +
                             std::to_string(std::lround(limits.min_arm_abduction_deg)) + " to " +
                             std::to_string(std::lround(limits.max_arm_abduction_deg)) + " deg");
  }
  const Eigen::Vector3d shoulders = (p[kShoulderLeft] - p[kShoulderRight]).normalized();
  const double turn = std::asin(std::min(1.0, std::abs(shoulders.z()))) / kDeg;
  if (turn > limits.max_turn_deg)
    throw_precondition(frame + ".pose.facing", "turned " + std::to_string(std::lround(turn)) +
                                                   " deg away from the camera, at most " +
                                                   std::to_string(std::lround(limits.max_turn_deg)) + " deg");
}

double energy_of(const SegmentLengths& model, const SegmentLengths& measured) {
  double e = 0;
  for (int s = 0; s < kBodySegmentCount; ++s) e += (model[s] - measured[s]) * (model[s] - measured[s]);
  return e;
}

}  // namespace

const char* rough_shape_stop_name(RoughShapeStop stop) {
  switch (stop) {
    case RoughShapeStop::kStepBelowMinimum: return "step below minimum";
    case RoughShapeStop::kConverged: return "converged";
    case RoughShapeStop::kMaxIterations: return "max iterations";
  }
  return "?";
}

void check_controlled_pose(const std::vector<TrackedSkeleton>& frames, const raycast::DepthCamera* camera,
                           const ControlledPoseLimits& limits) {
  if (!(limits.camera_arm_joint_error_m >= 0 && limits.camera_arm_joint_error_m < 1))
    throw_invalid("pose_limits.camera_arm_joint_error_m", "must be in [0, 1) m");
  if (frames.empty()) throw_invalid("calibration_frames", "empty: personalisation needs frames of the controlled pose");
  for (size_t i = 0; i < frames.size(); ++i)
    check_frame(frames[i], "calibration_frames[" + std::to_string(i) + "]", camera, limits);
}

RoughShapeResult estimate_rough_shape(const body::SmplModel& model, const std::vector<TrackedSkeleton>& frames,
                                      const raycast::DepthCamera* camera, const RoughShapeOptions& options) {
  validate(options);
  check_controlled_pose(frames, camera, options.pose);
  RoughShapeResult r;
  for (const TrackedSkeleton& f : frames) {
    const SegmentLengths one = measure_segments(f.positions_K);
    for (int s = 0; s < kBodySegmentCount; ++s) r.measured[s] += one[s] / static_cast<double>(frames.size());
  }
  const ModelSegmentLengths lengths(model, options.head_above_skull_base_m);
  const int betas = lengths.num_betas();

  // E_s and its gradient 2 J^T (L - K) (eq. 18; analytic instead of the paper's autodiff).
  Eigen::MatrixXd jacobian;
  auto evaluate = [&](const Eigen::VectorXd& beta, Eigen::VectorXd* gradient) {
    const SegmentLengths l = lengths.lengths(beta, gradient ? &jacobian : nullptr);
    const double unit = 1.0 / options.length_unit_m;
    if (gradient) {
      Eigen::VectorXd residual(kBodySegmentCount);
      for (int s = 0; s < kBodySegmentCount; ++s) residual[s] = (l[s] - r.measured[s]) * unit;
      *gradient = 2 * unit * jacobian.transpose() * residual;
    }
    return energy_of(l, r.measured) * unit * unit;
  };

  r.beta = Eigen::VectorXd::Zero(betas);
  Eigen::VectorXd gradient;
  double energy = evaluate(r.beta, &gradient);
  r.initial_energy = energy * options.length_unit_m * options.length_unit_m;
  const double largest = jacobian.colwise().norm().maxCoeff();
  for (int b = 0; b < betas; ++b)
    if (jacobian.col(b).norm() <= 1e-9 * largest) r.unconstrained_betas.push_back(b);
  double step = options.initial_step;
  // Eq. 19 with the paper's step rule.
  for (r.iterations = 0; r.iterations < options.max_iterations; ++r.iterations) {
    if (step < options.min_step) {
      r.stop = RoughShapeStop::kStepBelowMinimum;
      break;
    }
    // Projected gradient: components pushing a beta further past its bound do not count.
    Eigen::VectorXd projected = gradient;
    for (int b = 0; b < betas; ++b)
      if ((r.beta[b] >= options.max_abs_beta && gradient[b] < 0) ||
          (r.beta[b] <= -options.max_abs_beta && gradient[b] > 0))
        projected[b] = 0;
    if (projected.norm() <= options.min_gradient_norm) {
      r.stop = RoughShapeStop::kConverged;
      break;
    }
    const Eigen::VectorXd candidate =
        (r.beta - step * gradient).cwiseMax(-options.max_abs_beta).cwiseMin(options.max_abs_beta);
    const double candidate_energy = evaluate(candidate, nullptr);
    if (candidate_energy < energy) {
      r.beta = candidate;
      energy = evaluate(r.beta, &gradient);
    } else {
      step *= 0.5;
    }
  }
  r.energy = energy * options.length_unit_m * options.length_unit_m;
  r.final_step = step;
  r.model = lengths.lengths(r.beta);
  return r;
}

}  // namespace posefuse::fit
