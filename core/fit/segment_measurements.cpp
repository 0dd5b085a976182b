#include "fit/segment_measurements.hpp"

#include <cmath>

#include "common/error.hpp"
#include "fit/joint_kinematics.hpp"

namespace posefuse::fit {
namespace {

// One measurement is sum_t weight_t |mean(from_t) - mean(to_t)|.
struct Term {
  double weight;
  std::vector<int> from, to;
};
using Measurement = std::vector<Term>;

const std::array<Measurement, kBodySegmentCount>& measurements() {
  static const std::array<Measurement, kBodySegmentCount> m = [] {
    const Measurement upper_arm = {{0.5, {kShoulderLeft}, {kElbowLeft}}, {0.5, {kShoulderRight}, {kElbowRight}}};
    const Measurement forearm = {{0.5, {kElbowLeft}, {kWristLeft}}, {0.5, {kElbowRight}, {kWristRight}}};
    const Measurement hand = {{0.5, {kWristLeft}, {kHandTipLeft}}, {0.5, {kWristRight}, {kHandTipRight}}};
    Measurement whole_arm = upper_arm;
    whole_arm.insert(whole_arm.end(), forearm.begin(), forearm.end());
    whole_arm.insert(whole_arm.end(), hand.begin(), hand.end());
    return std::array<Measurement, kBodySegmentCount>{
        upper_arm,
        forearm,
        Measurement{{0.5, {kHipLeft}, {kKneeLeft}},
                    {0.5, {kHipRight}, {kKneeRight}},
                    {0.5, {kKneeLeft}, {kAnkleLeft}},
                    {0.5, {kKneeRight}, {kAnkleRight}}},
        Measurement{{1.0, {kHipLeft, kHipRight}, {kShoulderLeft, kShoulderRight}}},
        Measurement{{1.0, {kShoulderLeft}, {kShoulderRight}}},
        Measurement{{1.0, {kAnkleLeft, kAnkleRight}, {kHead}}},
        whole_arm,
    };
  }();
  return m;
}

template <typename PositionOf>
Eigen::Vector3d mean_of(const std::vector<int>& joints, PositionOf&& position) {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  for (int j : joints) sum += position(j);
  return sum / static_cast<double>(joints.size());
}

}  // namespace

const char* body_segment_name(BodySegment segment) {
  static constexpr const char* kNames[kBodySegmentCount] = {
      "upperArm", "forearm", "wholeLeg", "hipToShoulder", "shoulderToShoulder", "ankleToHead", "wholeArm"};
  return kNames[static_cast<int>(segment)];
}

const std::vector<int>& measured_camera_joints() {
  static const std::vector<int> joints = {kShoulderLeft, kShoulderRight, kElbowLeft,    kElbowRight, kWristLeft,
                                          kWristRight,   kHandTipLeft,   kHandTipRight, kHipLeft,    kHipRight,
                                          kKneeLeft,     kKneeRight,     kAnkleLeft,    kAnkleRight, kHead};
  return joints;
}

SegmentLengths measure_segments(const KinectSkeleton& skeleton_K) {
  SegmentLengths out{};
  auto position = [&](int j) -> Eigen::Vector3d { return skeleton_K[j]; };
  for (int s = 0; s < kBodySegmentCount; ++s)
    for (const Term& t : measurements()[s])
      out[s] += t.weight * (mean_of(t.from, position) - mean_of(t.to, position)).norm();
  return out;
}

ModelSegmentLengths::ModelSegmentLengths(const body::SmplModel& model, double head_above_skull_base_m) {
  if (!std::isfinite(head_above_skull_base_m)) throw_invalid("head_above_skull_base_m", "not finite");
  const Eigen::Matrix3Xd rest = rest_joints(model, Eigen::VectorXd());
  const Eigen::MatrixXd rest_dirs = rest_joint_shape_directions(model);
  num_betas_ = model.num_betas();
  // Camera joint = sum of weighted SMPL joints (+ a fixed offset for Head): linear in beta.
  struct Linear {
    int camera;
    std::vector<std::pair<int, double>> smpl;
  };
  const Linear map[] = {
      {kShoulderLeft, {{body::kLeftShoulder, 1}}},
      {kShoulderRight, {{body::kRightShoulder, 1}}},
      {kElbowLeft, {{body::kLeftElbow, 1}}},
      {kElbowRight, {{body::kRightElbow, 1}}},
      {kWristLeft, {{body::kLeftWrist, 1}}},
      {kWristRight, {{body::kRightWrist, 1}}},
      {kHandTipLeft, {{body::kLeftHand, 2}, {body::kLeftWrist, -1}}},
      {kHandTipRight, {{body::kRightHand, 2}, {body::kRightWrist, -1}}},
      {kHipLeft, {{body::kLeftHip, 1}}},
      {kHipRight, {{body::kRightHip, 1}}},
      {kKneeLeft, {{body::kLeftKnee, 1}}},
      {kKneeRight, {{body::kRightKnee, 1}}},
      {kAnkleLeft, {{body::kLeftAnkle, 1}}},
      {kAnkleRight, {{body::kRightAnkle, 1}}},
      {kHead, {{body::kHead, 1}}},
  };
  std::array<Eigen::Vector3d, kKinectJointCount> base;
  std::array<Eigen::Matrix3Xd, kKinectJointCount> directions;
  for (const Linear& l : map) {
    base[l.camera].setZero();
    directions[l.camera].setZero(3, num_betas_);
    for (const auto& [smpl, weight] : l.smpl) {
      base[l.camera] += weight * rest.col(smpl);
      directions[l.camera] += weight * rest_dirs.middleRows<3>(3 * smpl);
    }
  }
  // In the rest pose the head's up axis is the canonical y.
  base[kHead] += head_above_skull_base_m * Eigen::Vector3d::UnitY();
  for (int s = 0; s < kBodySegmentCount; ++s)
    for (const Term& t : measurements()[s]) {
      LinearTerm lt{s, t.weight, Eigen::Vector3d::Zero(), Eigen::Matrix3Xd::Zero(3, num_betas_)};
      for (int j : t.from) {
        lt.base += base[j] / static_cast<double>(t.from.size());
        lt.directions += directions[j] / static_cast<double>(t.from.size());
      }
      for (int j : t.to) {
        lt.base -= base[j] / static_cast<double>(t.to.size());
        lt.directions -= directions[j] / static_cast<double>(t.to.size());
      }
      terms_.push_back(std::move(lt));
    }
}

SegmentLengths ModelSegmentLengths::lengths(const Eigen::VectorXd& beta, Eigen::MatrixXd* jacobian) const {
  if (beta.size() > num_betas())
    throw_invalid("beta", "size " + std::to_string(beta.size()) + ", model has " + std::to_string(num_betas()));
  if (jacobian) jacobian->setZero(kBodySegmentCount, num_betas());
  SegmentLengths out{};
  for (const LinearTerm& t : terms_) {
    const Eigen::Vector3d d = t.base + t.directions.leftCols(beta.size()) * beta;
    const double length = d.norm();
    out[t.segment] += t.weight * length;
    if (jacobian && length > 0) jacobian->row(t.segment) += (t.weight / length) * d.transpose() * t.directions;
  }
  return out;
}

}  // namespace posefuse::fit
