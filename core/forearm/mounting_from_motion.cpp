#include "forearm/mounting_from_motion.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "common/number_text.hpp"
#include "common/percentile.hpp"

namespace posefuse::forearm {

namespace {

constexpr double kPi = std::numbers::pi;

double wrap(double angle) { return std::remainder(angle, 2.0 * kPi); }

double deg(double rad) { return rad * 180.0 / kPi; }

std::string degrees_text(double rad) { return fixed_text(deg(rad), 0); }

bool usable(const MountingFrame& f) {
  return f.K_from_A.coeffs().allFinite() && f.K_from_A.norm() > 0.5 && f.forearm_K.allFinite() &&
         f.forearm_K.norm() > 1e-6;
}

std::vector<MountingFrame> usable_frames(const std::vector<MountingFrame>& all) {
  std::vector<MountingFrame> frames;
  for (const MountingFrame& f : all) {
    if (usable(f)) frames.push_back(f);
  }
  return frames;
}

// The forearm axis in A fitted to frames: the normalised sum of each frame's forearm direction
// turned into A, the residuals (in a plane normal to it), their RMS angle, and how far the
// forearm turned in K (RMS angle from its mean direction).
struct AxisFit {
  bool defined = false;
  Vec3 y_A = Vec3::UnitY();
  std::vector<Eigen::Vector2d> residuals;
  double residual_rms = 0.0;
  double spread_rms = 0.0;
};

AxisFit fit_axis(const std::vector<MountingFrame>& frames) {
  AxisFit fit;
  std::vector<Vec3> axis_A;
  Vec3 sum_A = Vec3::Zero(), sum_K = Vec3::Zero();
  for (const MountingFrame& f : frames) {
    axis_A.push_back(f.K_from_A.normalized().conjugate() * f.forearm_K.normalized());
    sum_A += axis_A.back();
    sum_K += f.forearm_K.normalized();
  }
  const double n = static_cast<double>(frames.size());
  if (frames.empty() || sum_A.norm() < 1e-9 * n) return fit;
  fit.defined = true;
  fit.y_A = sum_A.normalized();
  const Quat A_from_B = Quat::FromTwoVectors(Vec3::UnitY(), fit.y_A);
  const Vec3 e1 = A_from_B * Vec3::UnitX(), e2 = A_from_B * Vec3::UnitZ();
  const Vec3 mean_K = sum_K.normalized();
  double residual_sq = 0.0, spread_sq = 0.0;
  for (std::size_t i = 0; i < frames.size(); ++i) {
    fit.residuals.emplace_back(axis_A[i].dot(e1), axis_A[i].dot(e2));
    residual_sq += fit.residuals.back().squaredNorm();
    const double turned = std::acos(std::clamp(mean_K.dot(frames[i].forearm_K.normalized()), -1.0, 1.0));
    spread_sq += turned * turned;
  }
  fit.residual_rms = std::sqrt(residual_sq / n);
  fit.spread_rms = std::sqrt(spread_sq / n);
  return fit;
}

// The middle of the shortest arc holding every angle: opposite the widest gap between them.
double arc_centre(std::vector<double> angles) {
  for (double& a : angles) a = std::fmod(std::fmod(a, 2.0 * kPi) + 2.0 * kPi, 2.0 * kPi);
  std::sort(angles.begin(), angles.end());
  double widest = angles.front() + 2.0 * kPi - angles.back();
  double start = angles.front();  // the arc starts after the widest gap
  for (std::size_t i = 1; i < angles.size(); ++i) {
    if (angles[i] - angles[i - 1] > widest) {
      widest = angles[i] - angles[i - 1];
      start = angles[i];
    }
  }
  return wrap(start + 0.5 * (2.0 * kPi - widest));
}

}  // namespace

std::optional<Quat> K_from_neutral_forearm(const Vec3& upper_arm_K, const Vec3& forearm_K, Side side,
                                           double min_flexion_rad) {
  if (!upper_arm_K.allFinite() || !forearm_K.allFinite() || upper_arm_K.norm() < 1e-6 || forearm_K.norm() < 1e-6) {
    return std::nullopt;
  }
  const Vec3 y = forearm_K.normalized();
  const Vec3 normal = upper_arm_K.normalized().cross(y);
  // |sin| of the flexion: a folded elbow (near 180 degrees) has no plane either.
  if (normal.norm() < std::sin(min_flexion_rad)) return std::nullopt;
  const Vec3 x = (side == Side::kRight ? 1.0 : -1.0) * normal.normalized();
  Eigen::Matrix3d K_from_N;
  K_from_N.col(0) = x;
  K_from_N.col(1) = y;
  K_from_N.col(2) = x.cross(y);
  return Quat(K_from_N).normalized();
}

std::optional<std::string> imu_on_other_arm(const std::vector<MountingFrame>& own,
                                            const std::vector<MountingFrame>& other,
                                            const MountingFromMotionOptions& options) {
  const auto scatter = [&](const std::vector<MountingFrame>& all) -> std::optional<double> {
    const std::vector<MountingFrame> frames = usable_frames(all);
    if (frames.size() < options.min_frames) return std::nullopt;
    const AxisFit fit = fit_axis(frames);
    if (!fit.defined) return std::nullopt;
    return fit.residual_rms;
  };
  const std::optional<double> own_rms = scatter(own), other_rms = scatter(other);
  if (!own_rms || !other_rms) return std::nullopt;
  // What the own forearm adds beyond the other's scatter must itself exceed what the depth axis's
  // error can explain: forearms that move alike (parallel, turning about their own axes) differ
  // by no more than that, and then the depth's noise alone would decide.
  const double excess_sq = *own_rms * *own_rms - *other_rms * *other_rms;
  const double bound = options.max_axis_residual_rad;
  if (excess_sq <= bound * bound) return std::nullopt;
  return "the forearm axes seen by the camera, turned into the IMU's frame, scatter " + degrees_text(*own_rms) +
         " deg RMS and the other forearm's " + degrees_text(*other_rms) +
         " deg: " + degrees_text(std::sqrt(excess_sq)) + " deg RMS more than the other arm explains (bound " +
         degrees_text(bound) + " deg), the IMU turns with the other arm";
}

std::optional<MountingEstimate> estimate_mounting(const std::vector<MountingFrame>& all_frames, Side side,
                                                  const MountingFromMotionOptions& options, std::string& why_not) {
  std::vector<MountingFrame> frames = usable_frames(all_frames);
  std::sort(frames.begin(), frames.end(),
            [](const MountingFrame& a, const MountingFrame& b) { return a.t_us < b.t_us; });
  if (frames.size() < options.min_frames) {
    why_not = "the forearm axis was measured at " + std::to_string(frames.size()) + " frames; need " +
              std::to_string(options.min_frames);
    return std::nullopt;
  }

  AxisFit fit = fit_axis(frames);
  if (!fit.defined) {
    why_not = "the forearm axes seen by the camera, turned into the IMU's frame, have no mean direction";
    return std::nullopt;
  }
  std::size_t outliers = 0;
  if (fit.residual_rms > options.max_axis_residual_rad) {
    // Some frames' forearm axis may be poor (the forearm pointing at the camera, merged with the
    // body) or the IMU's orientation momentarily wrong: keep the frames a robust 3-sigma rule
    // (median + 3 x 1.4826 MAD of the residual angles) accepts, if they are a majority.
    std::vector<double> angle;
    for (const Eigen::Vector2d& r : fit.residuals) angle.push_back(r.norm());
    std::vector<double> sorted = angle;
    std::sort(sorted.begin(), sorted.end());
    const double median = percentile(sorted, 0.5);
    std::vector<double> deviation;
    for (double a : angle) deviation.push_back(std::abs(a - median));
    std::sort(deviation.begin(), deviation.end());
    const double cut = median + 3.0 * 1.4826 * percentile(deviation, 0.5);
    std::vector<MountingFrame> inliers;
    for (std::size_t i = 0; i < frames.size(); ++i) {
      if (angle[i] <= cut) inliers.push_back(frames[i]);
    }
    const AxisFit inlier_fit =
        2 * inliers.size() > frames.size() && inliers.size() >= options.min_frames ? fit_axis(inliers) : AxisFit{};
    // The agreeing frames must show the IMU turning with the forearm: their axes in A scatter at
    // most half as much as the forearm turned in K (the IMU's rotation explains at least three
    // quarters of it). A still IMU's axes in A scatter exactly as much as the forearm turned.
    if (!inlier_fit.defined || inlier_fit.residual_rms > options.max_axis_residual_rad ||
        inlier_fit.residual_rms > 0.5 * inlier_fit.spread_rms) {
      why_not = "the forearm axes seen by the camera, turned into the IMU's frame, scatter " +
                degrees_text(fit.residual_rms) + " deg RMS (bound " + degrees_text(options.max_axis_residual_rad) +
                " deg; the forearm turned " + degrees_text(fit.spread_rms) +
                " deg RMS in the camera) and no majority of the frames agrees: the IMU does not turn with this "
                "forearm, or its orientation or the camera's forearm axis is wrong";
      return std::nullopt;
    }
    outliers = frames.size() - inliers.size();
    frames = std::move(inliers);
    fit = inlier_fit;
  }
  const Vec3& y_A = fit.y_A;
  const Quat A_from_B = Quat::FromTwoVectors(Vec3::UnitY(), y_A);  // B: any frame with y along y_A
  MountingEstimate estimate;
  estimate.frames = frames.size();
  estimate.outlier_frames = outliers;
  estimate.seconds = 1e-6 * static_cast<double>(frames.back().t_us - frames.front().t_us);
  estimate.axis_spread_rad = fit.spread_rms;
  // Trusted as one frame's depth axis agrees, not as the mean of independent ones: the depth
  // axis's error depends on the pose and recurs with it as the motion repeats, so it does not
  // average out (docs/forearm.md, "Mounting from motion").
  estimate.axis_rms_rad = fit.residual_rms;

  // The roll: psi with A_from_F = A_from_B * Ry(psi). The nominal mounting is A_from_F = I.
  const double nominal_psi = twist_about_y(A_from_B.conjugate());
  std::vector<double> phi;
  for (const MountingFrame& f : frames) {
    if (!f.upper_arm_K) continue;
    const std::optional<Quat> K_from_N =
        K_from_neutral_forearm(*f.upper_arm_K, f.forearm_K, side, options.min_flexion_rad);
    if (!K_from_N) continue;
    phi.push_back(twist_about_y((f.K_from_A.normalized() * A_from_B).conjugate() * *K_from_N));
  }
  estimate.hinge_frames = phi.size();
  double psi = nominal_psi;
  estimate.roll_rms_rad = options.nominal_roll_rms_rad;
  estimate.roll_limit = "no frame with the elbow flexed by " + degrees_text(options.min_flexion_rad) +
                        " deg or more and the upper arm measured: the roll is the nominal mounting's (+-" +
                        degrees_text(options.nominal_roll_rms_rad) + " deg RMS)";
  if (phi.size() >= options.min_frames) {
    const double centre = arc_centre(phi);
    std::vector<double> deviation, step;
    for (std::size_t i = 0; i < phi.size(); ++i) {
      deviation.push_back(wrap(phi[i] - centre));
      if (i > 0) step.push_back(wrap(phi[i] - phi[i - 1]));
    }
    std::sort(deviation.begin(), deviation.end());
    const double low = percentile(deviation, 0.025), high = percentile(deviation, 0.975);
    // Frame-to-frame noise widens the seen span; the forearm turned at least the span less it.
    double step_sq = 0.0;
    for (double s : step) step_sq += s * s;
    const double noise = step.empty() ? 0.0 : std::sqrt(step_sq / static_cast<double>(step.size()) / 2.0);
    estimate.twist_span_rad = std::max(0.0, high - low - 4.0 * noise);
    const double width = 2.0 * options.max_twist_rad - estimate.twist_span_rad;
    if (width <= 0.0) {
      estimate.roll_limit = "the hinge plane turned " + degrees_text(high - low) +
                            " deg about the forearm, more than a forearm can: the IMU slipped or is not on this "
                            "arm; the roll is the nominal mounting's";
    } else {
      // Every hinge frame: psi within max_twist of phi; the feasible interval's middle.
      const double middle = wrap(centre + 0.5 * (low + high));
      const double from_middle = std::clamp(wrap(nominal_psi - middle), -0.5 * width, 0.5 * width);
      psi = wrap(middle + from_middle);
      const double interval_rms = width / std::sqrt(12.0);
      estimate.roll_rms_rad = 1.0 / std::sqrt(1.0 / (interval_rms * interval_rms) +
                                              1.0 / (options.nominal_roll_rms_rad * options.nominal_roll_rms_rad));
      estimate.roll_from_hinge = true;
      estimate.roll_limit = "the forearm turned " + degrees_text(estimate.twist_span_rad) + " deg of the " +
                            degrees_text(2.0 * options.max_twist_rad) + " deg it can: the roll is known to +-" +
                            degrees_text(0.5 * width) + " deg";
    }
  } else if (!phi.empty()) {
    estimate.roll_limit = "the elbow was flexed at " + std::to_string(phi.size()) + " frames (need " +
                          std::to_string(options.min_frames) + "): the roll is the nominal mounting's (+-" +
                          degrees_text(options.nominal_roll_rms_rad) + " deg RMS)";
  }
  const Quat A_from_F = (A_from_B * Quat(Eigen::AngleAxisd(psi, Vec3::UnitY()))).normalized();
  estimate.F_from_A = A_from_F.conjugate();
  return estimate;
}

}  // namespace posefuse::forearm
