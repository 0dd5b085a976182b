// Turns the template geometry into an SMPL-format model: shape directions as exact mesh
// differences, skinning weights from bone distances, and a joint regressor fitted so that the
// regressed joints equal the generator's joints for every shape.
#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <numeric>

#include "body/template_generator.hpp"
#include "body/template_parts.hpp"
#include "common/error.hpp"

namespace posefuse::body {
namespace {

// Stature: one unit scales the whole body about the floor point below the pelvis by 4 %.
constexpr double kStatureScalePerUnit = 0.04;

const std::array<ShapeDirectionInfo, kTemplateNumBetas> kDirections = {{
    {"stature", "uniform scale about the floor point: every joint distance +4 %"},
    {"torso_length", "pelvis->neck +25 mm (pelvis->spine1 +6, spine1->spine2 +8, spine2->spine3 +4, spine3->neck +7)"},
    {"leg_length", "hip->knee +15 mm, knee->ankle +15 mm"},
    {"upper_arm_length", "shoulder->elbow +15 mm"},
    {"forearm_length", "elbow->wrist +12 mm"},
    {"shoulder_width", "collar->shoulder +12 mm per side (shoulder to shoulder +24 mm)"},
    {"hip_width", "hip to hip +16 mm, lower torso 8 mm wider per side"},
    {"torso_girth", "torso cross-sections +8 %, joints unchanged"},
    {"limb_girth", "arm and leg cross-sections +10 %, joints unchanged"},
    {"head_size", "head +6 %, neck->head +6 %"},
}};

constexpr int kMaxInfluences = 4;

// Weights along a chain of joints: joint k owns the bone from position[k] to position[k+1];
// around each inner joint the weight passes linearly from parent to child bone over
// [position - half_width, position + half_width]. s and positions run along the chain.
struct ChainJoint {
  int joint;
  double position, half_width;
};
void add_chain_weights(double s, std::initializer_list<ChainJoint> chain, double share,
                       Eigen::Ref<Eigen::RowVectorXd, 0, Eigen::InnerStride<>> w) {
  const ChainJoint* c = chain.begin();
  const int n = static_cast<int>(chain.size());
  double previous_t = 1.0;  // share already passed from bone 0 onwards
  for (int k = 1; k <= n; ++k) {
    const double t = k == n ? 0.0 : std::clamp((s - c[k].position + c[k].half_width) / (2 * c[k].half_width), 0.0, 1.0);
    w[c[k - 1].joint] += share * (previous_t - t);
    previous_t = t;
  }
}

double ramp(double x) { return std::clamp(x, 0.0, 1.0); }

// Skinning weights from the construction: each part blends the joints of its own chain along
// the limb axis, with linear blend zones a few centimetres wide around every joint; the lower
// torso blends into the hips and the upper torso around the shoulders into the collars. Two
// passes of mesh smoothing remove the steps where parts meet; at most 4 joints per vertex.
Eigen::MatrixXd skinning_weights(const LabelledTemplateGeometry& g) {
  const auto& v = g.geometry.vertices;
  const auto& j = g.geometry.joints;
  const Eigen::Index n = v.cols();
  Eigen::MatrixXd w = Eigen::MatrixXd::Zero(n, kNumJoints);
  const double crotch_y = j(1, kLeftHip) - 0.075, pelvis_y = j(1, kPelvis);
  for (Eigen::Index i = 0; i < n; ++i) {
    const Eigen::Vector3d p = v.col(i);
    const int side = p.x() >= 0 ? 1 : -1;
    auto row = w.row(i);
    auto spine_chain = [&](double share) {
      add_chain_weights(p.y(),
                        {{kPelvis, pelvis_y, 0},
                         {kSpine1, j(1, kSpine1), 0.05},
                         {kSpine2, j(1, kSpine2), 0.04},
                         {kSpine3, j(1, kSpine3), 0.03},
                         {kNeck, j(1, kNeck), 0.03},
                         {kHead, j(1, kHead), 0.03}},
                        share, row);
    };
    switch (g.parts[i]) {
      case BodyPart::kTorso:
      case BodyPart::kHead: {
        const double hip = 0.6 * ramp((pelvis_y - p.y()) / (pelvis_y - crotch_y));
        const double left_share = ramp(0.5 + p.x() / 0.1);
        row[kLeftHip] += hip * left_share;
        row[kRightHip] += hip * (1 - left_share);
        const int shoulder = side > 0 ? kLeftShoulder : kRightShoulder;
        const double collar =
            g.parts[i] == BodyPart::kTorso ? 0.6 * ramp(1 - (p - j.col(shoulder)).norm() / 0.12) : 0.0;
        row[side > 0 ? kLeftCollar : kRightCollar] += collar;
        spine_chain(1 - hip - collar);
        break;
      }
      case BodyPart::kLeftArm:
      case BodyPart::kRightArm: {
        const bool left = g.parts[i] == BodyPart::kLeftArm;
        const double s = left ? p.x() : -p.x();
        auto at = [&](int joint) { return left ? j(0, joint) : -j(0, joint); };
        const int collar = left ? kLeftCollar : kRightCollar, shoulder = left ? kLeftShoulder : kRightShoulder;
        const int elbow = left ? kLeftElbow : kRightElbow, wrist = left ? kLeftWrist : kRightWrist;
        const int hand = left ? kLeftHand : kRightHand;
        add_chain_weights(s,
                          {{collar, at(collar), 0},
                           {shoulder, at(shoulder), 0.05},
                           {elbow, at(elbow), 0.04},
                           {wrist, at(wrist), 0.03},
                           {hand, at(hand), 0.02}},
                          1.0, row);
        break;
      }
      case BodyPart::kLeftLeg:
      case BodyPart::kRightLeg: {
        const bool left = g.parts[i] == BodyPart::kLeftLeg;
        const int hip = left ? kLeftHip : kRightHip, knee = left ? kLeftKnee : kRightKnee;
        const int ankle = left ? kLeftAnkle : kRightAnkle, foot = left ? kLeftFoot : kRightFoot;
        const double toes = ramp((p.z() - 0.06) / 0.06) * ramp((j(1, ankle) - p.y()) / 0.03);
        add_chain_weights(-p.y(), {{hip, -j(1, hip), 0}, {knee, -j(1, knee), 0.05}, {ankle, -j(1, ankle), 0.03}},
                          1 - toes, row);
        row[foot] += toes;
        break;
      }
    }
  }
  std::vector<std::vector<int>> neighbours(n);
  const auto& faces = g.geometry.faces;
  for (Eigen::Index f = 0; f < faces.cols(); ++f)
    for (int k = 0; k < 3; ++k) neighbours[faces(k, f)].push_back(faces((k + 1) % 3, f));
  for (int iteration = 0; iteration < 2; ++iteration) {
    Eigen::MatrixXd smoothed = w;
    for (Eigen::Index i = 0; i < n; ++i) {
      Eigen::RowVectorXd mean = Eigen::RowVectorXd::Zero(kNumJoints);
      for (int nb : neighbours[i]) mean += w.row(nb);
      smoothed.row(i) = 0.5 * w.row(i) + 0.5 * mean / static_cast<double>(neighbours[i].size());
    }
    w = smoothed;
  }
  for (Eigen::Index i = 0; i < n; ++i) {
    std::array<int, kNumJoints> order;
    std::iota(order.begin(), order.end(), 0);
    std::sort(order.begin(), order.end(), [&](int a, int b) { return w(i, a) > w(i, b); });
    for (int r = kMaxInfluences; r < kNumJoints; ++r) w(i, order[r]) = 0;
    for (int r = 0; r < kMaxInfluences; ++r)
      if (w(i, order[r]) < 1e-3) w(i, order[r]) = 0;
    w.row(i) /= w.row(i).sum();
  }
  return w;
}

// Regressor row for one joint: weights on nearby vertices that reproduce the joint at rest and
// its displacement along every shape direction (minimum norm, preferring close vertices).
Eigen::VectorXd regress_joint(int joint, const Eigen::Matrix3Xd& vertices, const Eigen::MatrixXd& shapedirs,
                              const Eigen::Matrix3Xd& joints, const Eigen::MatrixXd& joint_dirs) {
  constexpr int kSupport = 80;
  const Eigen::Index n = vertices.cols();
  const Eigen::Vector3d target = joints.col(joint);
  std::vector<int> order(n);
  std::iota(order.begin(), order.end(), 0);
  std::partial_sort(order.begin(), order.begin() + kSupport, order.end(), [&](int a, int b) {
    return (vertices.col(a) - target).squaredNorm() < (vertices.col(b) - target).squaredNorm();
  });
  order.resize(kSupport);
  const int num_betas = static_cast<int>(shapedirs.cols());
  const int rows = 3 * (1 + num_betas) + 1;
  Eigen::MatrixXd a(rows, kSupport);
  Eigen::VectorXd rhs(rows);
  const double scale = (vertices.col(order[kSupport / 4]) - target).norm();
  Eigen::VectorXd preference(kSupport);
  for (int c = 0; c < kSupport; ++c) {
    const int i = order[c];
    preference[c] = std::exp(-(vertices.col(i) - target).squaredNorm() / (scale * scale));
    a.block<3, 1>(0, c) = vertices.col(i) - target;  // centred for conditioning
    for (int s = 0; s < num_betas; ++s) a.block<3, 1>(3 + 3 * s, c) = shapedirs.block<3, 1>(3 * i, s);
    a(rows - 1, c) = 1.0;
  }
  rhs.setZero();
  for (int s = 0; s < num_betas; ++s) rhs.segment<3>(3 + 3 * s) = joint_dirs.block<3, 1>(3 * joint, s);
  rhs[rows - 1] = 1.0;
  const Eigen::MatrixXd weighted = a * preference.asDiagonal();
  const Eigen::VectorXd z = weighted.completeOrthogonalDecomposition().solve(rhs);
  const Eigen::VectorXd local = preference.asDiagonal() * z;
  const double residual = (a * local - rhs).cwiseAbs().maxCoeff();
  if (residual > 1e-9)
    throw Error(ErrorCode::kInternal, std::string("template.J_regressor[") + smpl_joint_names()[joint] + "]",
                "cannot reproduce the joint, residual " + std::to_string(residual));
  Eigen::VectorXd row = Eigen::VectorXd::Zero(n);
  for (int c = 0; c < kSupport; ++c) row[order[c]] = local[c];
  return row;
}

}  // namespace

BodyDimensions default_dimensions(Sex sex) {
  BodyDimensions d;
  d.sex = sex;
  if (sex == Sex::kFemale) {
    d.ankle_height = 0.07;
    d.shin = 0.37;
    d.thigh = 0.37;
    d.hip_drop = 0.08;
    d.hip_half_width = 0.09;
    d.pelvis_to_spine1 = 0.10;
    d.spine1_to_spine2 = 0.12;
    d.spine2_to_spine3 = 0.06;
    d.spine3_to_neck = 0.18;
    d.neck_to_head = 0.09;
    d.collar_side = 0.065;
    d.collar_up = 0.13;
    d.collar_to_shoulder = 0.09;
    d.upper_arm = 0.26;
    d.forearm = 0.23;
    d.limb_girth = 0.92;
  }
  return d;
}

const std::array<ShapeDirectionInfo, kTemplateNumBetas>& template_shape_directions() { return kDirections; }

BodyDimensions apply_shape_direction(const BodyDimensions& base, int direction, double amount) {
  BodyDimensions d = base;
  switch (direction) {
    case 0: break;  // stature: a uniform scale, see make_template
    case 1:
      d.pelvis_to_spine1 += 0.006 * amount;
      d.spine1_to_spine2 += 0.008 * amount;
      d.spine2_to_spine3 += 0.004 * amount;
      d.spine3_to_neck += 0.007 * amount;
      break;
    case 2:
      d.thigh += 0.015 * amount;
      d.shin += 0.015 * amount;
      break;
    case 3: d.upper_arm += 0.015 * amount; break;
    case 4: d.forearm += 0.012 * amount; break;
    case 5:
      d.collar_to_shoulder += 0.012 * amount;
      d.shoulder_extra_width += 0.012 * amount;
      break;
    case 6:
      d.hip_half_width += 0.008 * amount;
      d.hip_extra_width += 0.008 * amount;
      break;
    case 7: d.torso_girth += 0.08 * amount; break;
    case 8: d.limb_girth += 0.10 * amount; break;
    case 9: d.head_scale += 0.06 * amount; break;
    default: throw_invalid("direction", std::to_string(direction) + " outside [0, 10)");
  }
  return d;
}

std::shared_ptr<SmplModel> make_template(Sex sex) {
  const BodyDimensions base = default_dimensions(sex);
  const LabelledTemplateGeometry rest = build_template_geometry_with_parts(base);
  const Eigen::Matrix3Xd& v = rest.geometry.vertices;
  const Eigen::Index n = v.cols();

  auto model = std::make_shared<SmplModel>();
  model->v_template = v;
  model->faces = rest.geometry.faces;
  model->shapedirs.resize(3 * n, kTemplateNumBetas);
  Eigen::MatrixXd joint_dirs(3 * kNumJoints, kTemplateNumBetas);
  for (int s = 0; s < kTemplateNumBetas; ++s) {
    Eigen::Matrix3Xd dv, dj;
    if (s == 0) {
      dv = kStatureScalePerUnit * v;
      dj = kStatureScalePerUnit * rest.geometry.joints;
    } else {
      const TemplateGeometry shaped = build_template_geometry(apply_shape_direction(base, s, 1.0));
      if (shaped.faces != rest.geometry.faces)
        throw Error(ErrorCode::kInternal, "template.faces", "topology changed with shape " + std::to_string(s));
      dv = shaped.vertices - v;
      dj = shaped.joints - rest.geometry.joints;
    }
    model->shapedirs.col(s) = Eigen::Map<const Eigen::VectorXd>(dv.data(), 3 * n);
    joint_dirs.col(s) = Eigen::Map<const Eigen::VectorXd>(dj.data(), 3 * kNumJoints);
  }

  std::vector<Eigen::Triplet<double>> regressor;
  for (int j = 0; j < kNumJoints; ++j) {
    const Eigen::VectorXd row = regress_joint(j, v, model->shapedirs, rest.geometry.joints, joint_dirs);
    for (Eigen::Index i = 0; i < n; ++i)
      if (row[i] != 0.0) regressor.emplace_back(j, static_cast<int>(i), row[i]);
  }
  model->J_regressor.resize(kNumJoints, n);
  model->J_regressor.setFromTriplets(regressor.begin(), regressor.end());

  const Eigen::MatrixXd weights = skinning_weights(rest);
  model->weights = weights.sparseView();
  validate(*model);
  return model;
}

std::shared_ptr<const SmplModel> shared_template(Sex sex) {
  // Function-local statics: each built on its first use, thread-safe.
  if (sex == Sex::kMale) {
    static const std::shared_ptr<const SmplModel> male = make_template(Sex::kMale);
    return male;
  }
  static const std::shared_ptr<const SmplModel> female = make_template(Sex::kFemale);
  return female;
}

}  // namespace posefuse::body
