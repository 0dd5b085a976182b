#pragma once
// Post-processing of paper 2 (IV-C): a moving average of the fitted poses over a window of
// consecutive depth frames (3 in the paper). Centred, so frame t's smoothed pose is known one
// frame later (window / 2 frames for longer windows); the raw poses are untouched and stay
// available to the caller. Averaging is over theta; before it, the pelvis rotation vector is
// unwrapped along the sequence (a rotation near 180 degrees has two representations 2 pi apart,
// and facing the camera is exactly there), so the average never mixes the two.
#include <Eigen/Core>
#include <deque>
#include <optional>
#include <vector>

#include "body/pose_parameters.hpp"

namespace posefuse::fit {

struct PoseSmoothingOptions {
  int window_frames = 3;  // odd, >= 1 (1 = no smoothing)
};

// Streaming: push each frame's fitted theta in time order; each push returns the smoothed pose of
// the frame window / 2 frames back once its window is complete; flush() returns the last ones.
// Within window / 2 frames of either end the window shrinks on both sides so that it stays
// centred: the first and the last frame are their own fitted poses.
class PoseSmoother {
 public:
  // Throws posefuse::Error "smoothing_options.window_frames" for an even or non-positive window.
  PoseSmoother(body::PoseLayout layout, const PoseSmoothingOptions& options = {});

  // Throws posefuse::Error "theta" for a wrong size or non-finite values.
  std::optional<Eigen::VectorXd> push(const Eigen::VectorXd& theta);
  std::vector<Eigen::VectorXd> flush();

 private:
  Eigen::VectorXd average_around(std::size_t centre) const;

  body::PoseLayout layout_;
  int half_;
  std::deque<Eigen::VectorXd> frames_;  // unwrapped raw poses still needed
  std::size_t next_ = 0;                // index in frames_ of the next frame to emit
};

// The whole sequence at once (same results as streaming).
std::vector<Eigen::VectorXd> smooth_poses(const body::PoseLayout& layout, const std::vector<Eigen::VectorXd>& thetas,
                                          const PoseSmoothingOptions& options = {});

}  // namespace posefuse::fit
