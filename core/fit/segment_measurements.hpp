#pragma once
// The 7 body measurements of paper 2's rough shape estimation (III-A, eq. 18), taken the same way
// from a camera skeleton (K_l) and from the body model's rest joints for a shape beta (L_l(beta)):
//   upperArm            mean of both Shoulder->Elbow
//   forearm             mean of both Elbow->Wrist
//   wholeLeg            mean Hip->Knee + mean Knee->Ankle
//   hipToShoulder       mean of the hips -> mean of the shoulders
//   shoulderToShoulder  ShoulderLeft -> ShoulderRight
//   ankleToHead         mean of the ankles -> Head
//   wholeArm            upperArm + forearm + mean Wrist->HandTip (the hand length)
// On the model side the camera joints are SMPL joints (Head = head joint + head_above_skull_base_m
// up the head, HandTip = hand + (hand - wrist): the simulator's camera skeleton, see
// core/sim/camera_skeleton.hpp), in the rest pose, where they are linear in beta.
#include <Eigen/Core>
#include <array>
#include <vector>

#include "body/smpl_model.hpp"
#include "fit/tracked_skeleton.hpp"

namespace posefuse::fit {

enum class BodySegment : int {
  kUpperArm,
  kForearm,
  kWholeLeg,
  kHipToShoulder,
  kShoulderToShoulder,
  kAnkleToHead,
  kWholeArm,
};
inline constexpr int kBodySegmentCount = 7;
const char* body_segment_name(BodySegment segment);  // the paper's names, e.g. "upperArm"
using SegmentLengths = std::array<double, kBodySegmentCount>;

// The camera joints the measurements use.
const std::vector<int>& measured_camera_joints();

// K_l from one camera skeleton (positions only; the caller checks tracking).
SegmentLengths measure_segments(const KinectSkeleton& skeleton_K);

// L_l(beta) and its gradient for one model.
class ModelSegmentLengths {
 public:
  ModelSegmentLengths(const body::SmplModel& model, double head_above_skull_base_m);

  int num_betas() const { return num_betas_; }
  // Lengths for beta (zero padded to the model's betas); `jacobian` (7 x B), when given, gets
  // d L / d beta.
  SegmentLengths lengths(const Eigen::VectorXd& beta, Eigen::MatrixXd* jacobian = nullptr) const;

 private:
  // Each measurement term weight * |mean(from) - mean(to)| with the difference linear in beta:
  // base + directions * beta (directions 3 x B). Precomputed: gradient descent calls this ~10^5 times.
  struct LinearTerm {
    int segment;
    double weight;
    Eigen::Vector3d base;
    Eigen::Matrix3Xd directions;
  };
  std::vector<LinearTerm> terms_;
  int num_betas_ = 0;
};

}  // namespace posefuse::fit
