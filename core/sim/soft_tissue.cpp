#include "sim/soft_tissue.hpp"

#include <cmath>
#include <numbers>
#include <string>

#include "body/smpl_model.hpp"
#include "common/error.hpp"
#include "sim/option_checks.hpp"

namespace posefuse::sim {

namespace {

using std::numbers::pi;
constexpr double kStepS = 1e-3;

// Centre of each joint's segment: the joint and its children averaged (the joint alone at a leaf).
Eigen::Matrix3Xd segment_centres(const Eigen::Matrix3Xd& joints) {
  Eigen::Matrix3Xd sum = joints;
  Eigen::VectorXd count = Eigen::VectorXd::Ones(body::kNumJoints);
  for (int j = 1; j < body::kNumJoints; ++j) {
    const int parent = body::kSmplParents[static_cast<std::size_t>(j)];
    sum.col(parent) += joints.col(j);
    count[parent] += 1.0;
  }
  for (int j = 0; j < body::kNumJoints; ++j) sum.col(j) /= count[j];
  return sum;
}

Eigen::Matrix3Xd centres_at(const std::function<Eigen::Matrix3Xd(double)>& joints_at, double t) {
  const Eigen::Matrix3Xd joints = joints_at(t);
  if (joints.cols() != body::kNumJoints || !joints.allFinite()) {
    throw_invalid("joints_at", "at t = " + std::to_string(t) + " s: not 24 finite joint positions");
  }
  return segment_centres(joints);
}

Eigen::Matrix3Xd bounded(const Eigen::Matrix3Xd& x, double max_m) {
  Eigen::Matrix3Xd out = x;
  for (int j = 0; j < x.cols(); ++j) {
    out.col(j) *= max_m / std::sqrt(max_m * max_m + x.col(j).squaredNorm());
  }
  return out;
}

}  // namespace

void validate(const SoftTissueOptions& o) {
  require_positive(o.frequency_hz, "soft_tissue.frequency_hz");
  if (o.frequency_hz > 50.0)
    throw_invalid("soft_tissue.frequency_hz", "is " + std::to_string(o.frequency_hz) + ", must be <= 50 Hz");
  require_positive(o.damping_ratio, "soft_tissue.damping_ratio");
  require_non_negative(o.gain, "soft_tissue.gain");
  require_non_negative(o.max_displacement_m, "soft_tissue.max_displacement_m");
  if (o.max_displacement_m > 0.1) {
    throw_invalid("soft_tissue.max_displacement_m",
                  "is " + std::to_string(o.max_displacement_m) + ", must be <= 0.1 m");
  }
}

double soft_tissue_looseness(int joint) {
  switch (joint) {
    case body::kSpine1:
    case body::kSpine2: return 1.0;  // belly
    case body::kLeftShoulder:
    case body::kRightShoulder: return 1.0;  // upper arms
    case body::kPelvis: return 0.8;
    case body::kSpine3: return 0.7;  // chest
    case body::kLeftHip:
    case body::kRightHip: return 0.6;  // thighs
    case body::kLeftCollar:
    case body::kRightCollar: return 0.5;
    case body::kLeftKnee:
    case body::kRightKnee: return 0.4;  // calves
    case body::kLeftElbow:
    case body::kRightElbow: return 0.3;  // forearms
    case body::kNeck: return 0.2;
    default: return 0.0;  // head, hands, feet: skin on bone
  }
}

std::vector<Eigen::Matrix3Xd> segment_wobble(const std::function<Eigen::Matrix3Xd(double)>& joints_at,
                                             const std::vector<double>& times_s, const SoftTissueOptions& o) {
  validate(o);
  for (std::size_t i = 0; i < times_s.size(); ++i) {
    if (!std::isfinite(times_s[i]) || (i > 0 && times_s[i] < times_s[i - 1])) {
      throw_invalid("times_s", "entry " + std::to_string(i) + " is not finite or goes back in time");
    }
  }
  std::vector<Eigen::Matrix3Xd> out(times_s.size(), Eigen::Matrix3Xd::Zero(3, body::kNumJoints));
  if (!o.enabled || times_s.empty() || o.gain == 0.0 || o.max_displacement_m == 0.0) return out;
  const double omega = 2 * pi * o.frequency_hz, two_zeta_omega = 2 * o.damping_ratio * omega;
  Eigen::Matrix3Xd x = Eigen::Matrix3Xd::Zero(3, body::kNumJoints), v = x;
  const double t0 = times_s.front();
  // Centres at the step before, at and after the current one (second differences).
  Eigen::Matrix3Xd before = centres_at(joints_at, t0 - kStepS), now = centres_at(joints_at, t0);
  std::size_t next = 0;
  for (std::int64_t k = 0; next < times_s.size(); ++k) {
    const double t = t0 + static_cast<double>(k) * kStepS;
    const Eigen::Matrix3Xd after = centres_at(joints_at, t + kStepS);
    // The state at t; requested times in [t, t + step) are interpolated with the next state.
    const Eigen::Matrix3Xd accel = (after - 2 * now + before) / (kStepS * kStepS);
    const Eigen::Matrix3Xd x_t = x;
    v += kStepS * (-o.gain * accel - two_zeta_omega * v - omega * omega * x);
    x += kStepS * v;
    while (next < times_s.size() && times_s[next] < t + kStepS) {
      const double s = (times_s[next] - t) / kStepS;
      out[next] = bounded((1 - s) * x_t + s * x, o.max_displacement_m);
      ++next;
    }
    before = now;
    now = after;
  }
  return out;
}

SoftTissueSkin::SoftTissueSkin(const Eigen::SparseMatrix<double, Eigen::RowMajor>& weights, int surface_vertices) {
  if (weights.cols() != body::kNumJoints || surface_vertices < 0 || surface_vertices > weights.rows()) {
    throw_invalid("weights", "must be V x 24 with at least surface_vertices rows");
  }
  loads_.resize(surface_vertices, body::kNumJoints);
  std::vector<Eigen::Triplet<double>> entries;
  for (int v = 0; v < surface_vertices; ++v) {
    for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator it(weights, v); it; ++it) {
      const double load = it.value() * soft_tissue_looseness(static_cast<int>(it.col()));
      if (load != 0.0) entries.emplace_back(v, static_cast<int>(it.col()), load);
    }
  }
  loads_.setFromTriplets(entries.begin(), entries.end());
}

void SoftTissueSkin::apply(const Eigen::Matrix3Xd& segment_displacement, const Eigen::Matrix3d& rotation,
                           Eigen::Matrix3Xd& vertices) const {
  if (segment_displacement.cols() != body::kNumJoints || vertices.cols() < loads_.rows()) {
    throw_invalid("vertices", "segment displacements must be 3 x 24 and the mesh cover the surface vertices");
  }
  if (segment_displacement.isZero(0.0)) return;  // still body or wobble off
  const Eigen::Matrix3Xd turned = rotation * segment_displacement;
  for (int v = 0; v < loads_.rows(); ++v) {
    for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator it(loads_, v); it; ++it) {
      vertices.col(v) += it.value() * turned.col(it.col());
    }
  }
}

}  // namespace posefuse::sim
