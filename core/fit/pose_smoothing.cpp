#include "fit/pose_smoothing.hpp"

#include <cmath>
#include <numbers>
#include <string>

#include "common/error.hpp"

namespace posefuse::fit {

PoseSmoother::PoseSmoother(body::PoseLayout layout, const PoseSmoothingOptions& options)
    : layout_(std::move(layout)), half_(options.window_frames / 2) {
  if (options.window_frames < 1 || options.window_frames % 2 == 0)
    throw_invalid("smoothing_options.window_frames",
                  "must be odd and positive, got " + std::to_string(options.window_frames));
}

std::optional<Eigen::VectorXd> PoseSmoother::push(const Eigen::VectorXd& theta) {
  if (theta.size() != layout_.size())
    throw_invalid("theta", "size " + std::to_string(theta.size()) + ", layout has " + std::to_string(layout_.size()));
  if (!theta.allFinite()) throw_invalid("theta", "not finite");
  Eigen::VectorXd unwrapped = theta;
  if (!frames_.empty()) {
    // The pelvis rotation vector w and (|w| - 2 pi) w / |w| are the same rotation: take the one
    // nearer the previous frame's.
    const std::vector<int>& pelvis = layout_.dofs_of_joint(body::kPelvis);
    Eigen::Vector3d w = Eigen::Vector3d::Zero(), previous = Eigen::Vector3d::Zero();
    for (int d : pelvis)
      if (layout_.dof(d).kind == body::DofKind::kRotation) {
        w += theta[d] * layout_.dof(d).axis;
        previous += frames_.back()[d] * layout_.dof(d).axis;
      }
    const double angle = w.norm();
    if (angle > 1e-9) {
      // Candidates differ by whole turns along the axis; the nearest to the previous one wins.
      const double along = previous.dot(w / angle);
      const double turns = std::round((along - angle) / (2 * std::numbers::pi));
      const Eigen::Vector3d nearest = w * ((angle + turns * 2 * std::numbers::pi) / angle);
      if ((nearest - previous).squaredNorm() < (w - previous).squaredNorm())
        for (int d : pelvis)
          if (layout_.dof(d).kind == body::DofKind::kRotation) unwrapped[d] = nearest.dot(layout_.dof(d).axis);
    }
  }
  frames_.push_back(std::move(unwrapped));
  if (frames_.size() < next_ + half_ + 1) return std::nullopt;
  Eigen::VectorXd out = average_around(next_++);
  // Keep the frames the next window still needs (and the last one, for unwrapping).
  while (next_ > static_cast<std::size_t>(half_) && frames_.size() > 1) {
    frames_.pop_front();
    --next_;
  }
  return out;
}

std::vector<Eigen::VectorXd> PoseSmoother::flush() {
  std::vector<Eigen::VectorXd> out;
  while (next_ < frames_.size()) out.push_back(average_around(next_++));
  frames_.clear();
  next_ = 0;
  return out;
}

Eigen::VectorXd PoseSmoother::average_around(std::size_t centre) const {
  // Near the ends the window shrinks on both sides, so it stays centred: a one-sided window lags
  // (or leads) a moving body by half a frame per frame it leaves out.
  const std::size_t half = std::min({static_cast<std::size_t>(half_), centre, frames_.size() - 1 - centre});
  const std::size_t first = centre - half;
  const std::size_t last = centre + half;
  Eigen::VectorXd sum = Eigen::VectorXd::Zero(layout_.size());
  for (std::size_t i = first; i <= last; ++i) sum += frames_[i];
  return sum / static_cast<double>(last - first + 1);
}

std::vector<Eigen::VectorXd> smooth_poses(const body::PoseLayout& layout, const std::vector<Eigen::VectorXd>& thetas,
                                          const PoseSmoothingOptions& options) {
  PoseSmoother smoother(layout, options);
  std::vector<Eigen::VectorXd> out;
  for (const Eigen::VectorXd& theta : thetas)
    if (auto smoothed = smoother.push(theta)) out.push_back(std::move(*smoothed));
  for (Eigen::VectorXd& smoothed : smoother.flush()) out.push_back(std::move(smoothed));
  return out;
}

}  // namespace posefuse::fit
