// Sweeps the built-in template's closed mesh along the skeleton (see template_generator.hpp).
//
// Orientation rule used throughout: a ring is listed counter-clockwise about the direction in
// which its tube continues (right-handed frame e1, e2, u with e1 x e2 = u). stitch(a, b) joins
// ring a to the next ring b along u and yields outward-facing triangles.
#include <cmath>
#include <numbers>
#include <span>
#include <tuple>

#include "body/template_generator.hpp"
#include "body/template_parts.hpp"
#include "common/error.hpp"

namespace posefuse::body {
namespace {

using Eigen::Vector3d;
using std::numbers::pi;

struct MeshBuilder {
  std::vector<Vector3d> vertices;
  std::vector<BodyPart> parts;
  std::vector<Eigen::Vector3i> faces;
  BodyPart part = BodyPart::kTorso;

  int add(const Vector3d& p) {
    vertices.push_back(p);
    parts.push_back(part);
    return static_cast<int>(vertices.size()) - 1;
  }
  // n vertices at c + r1 cos(psi) e1 + r2 sin(psi) e2, psi = psi0 + 2 pi m / n.
  std::vector<int> ring(const Vector3d& c, const Vector3d& e1, const Vector3d& e2, double r1, double r2, int n,
                        double psi0) {
    std::vector<int> ids(n);
    for (int m = 0; m < n; ++m) {
      const double psi = psi0 + 2 * pi * m / n;
      ids[m] = add(c + r1 * std::cos(psi) * e1 + r2 * std::sin(psi) * e2);
    }
    return ids;
  }
  // Zipper strip between two rings whose first vertices correspond.
  void stitch(const std::vector<int>& a, const std::vector<int>& b) {
    const int na = static_cast<int>(a.size()), nb = static_cast<int>(b.size());
    int i = 0, j = 0;
    while (i < na || j < nb) {
      const bool advance_a = j == nb || (i < na && (i + 1) * nb <= (j + 1) * na);
      if (advance_a) {
        faces.emplace_back(a[i], a[(i + 1) % na], b[j % nb]);
        ++i;
      } else {
        faces.emplace_back(b[j], a[i % na], b[(j + 1) % nb]);
        ++j;
      }
    }
  }
  void cap_end(const std::vector<int>& a, int pole) {
    const int n = static_cast<int>(a.size());
    for (int i = 0; i < n; ++i) faces.emplace_back(a[i], a[(i + 1) % n], pole);
  }
};

// Torso stations from the crotch (0) to the shoulder top (8): half width (x), front and back
// depth (z), metres, before torso_girth.
struct Station {
  double half_width, front, back;
};
constexpr std::array<Station, 9> kMaleTorso = {{{0.150, 0.085, 0.095},
                                                {0.175, 0.095, 0.115},
                                                {0.165, 0.100, 0.105},
                                                {0.145, 0.105, 0.090},
                                                {0.150, 0.110, 0.095},
                                                {0.160, 0.115, 0.100},
                                                {0.170, 0.110, 0.100},
                                                {0.185, 0.085, 0.090},
                                                {0.160, 0.060, 0.070}}};
constexpr std::array<Station, 9> kFemaleTorso = {{{0.150, 0.080, 0.095},
                                                  {0.180, 0.090, 0.120},
                                                  {0.160, 0.090, 0.100},
                                                  {0.125, 0.085, 0.080},
                                                  {0.135, 0.100, 0.085},
                                                  {0.145, 0.125, 0.090},
                                                  {0.150, 0.105, 0.085},
                                                  {0.165, 0.080, 0.080},
                                                  {0.140, 0.055, 0.065}}};

// Limb rings: fraction along the segment, radii (two axes) before limb_girth.
struct LimbRing {
  double t, r1, r2;
};
constexpr LimbRing kUpperArm[] = {
    {0.0, 0.062, 0.060}, {0.3, 0.050, 0.052}, {0.6, 0.045, 0.047}, {0.85, 0.040, 0.043}, {1.0, 0.036, 0.040}};
constexpr LimbRing kForearm[] = {{0.15, 0.040, 0.045}, {0.5, 0.034, 0.040}, {0.8, 0.026, 0.033}, {1.0, 0.020, 0.029}};
constexpr LimbRing kThigh[] = {
    {0.3, 0.078, 0.082}, {0.5, 0.070, 0.074}, {0.75, 0.060, 0.063}, {0.92, 0.054, 0.056}, {1.0, 0.050, 0.052}};
constexpr LimbRing kShin[] = {
    {0.12, 0.050, 0.053}, {0.35, 0.050, 0.058}, {0.6, 0.040, 0.045}, {0.85, 0.032, 0.036}, {1.0, 0.032, 0.036}};
// Hand orb rings: fraction of the radius along the arm (from the orb centre).
constexpr double kOrbRings[] = {-0.7, -0.35, 0.0, 0.4, 0.75, 0.93};
// Head rings: fraction of the vertical radius from the head centre.
constexpr double kHeadRings[] = {-0.75, -0.45, -0.1, 0.25, 0.55, 0.8, 0.94};

constexpr int kTorsoRing = 20, kLimbRing = 12, kNeckRing = 10;

// Removes vertices no face uses and renumbers.
void compact(MeshBuilder& b) {
  std::vector<int> remap(b.vertices.size(), -1);
  for (const auto& f : b.faces)
    for (int k = 0; k < 3; ++k) remap[f[k]] = 0;
  std::vector<Vector3d> kept;
  std::vector<BodyPart> kept_parts;
  for (size_t i = 0; i < remap.size(); ++i)
    if (remap[i] == 0) {
      remap[i] = static_cast<int>(kept.size());
      kept.push_back(b.vertices[i]);
      kept_parts.push_back(b.parts[i]);
    }
  for (auto& f : b.faces)
    for (int k = 0; k < 3; ++k) f[k] = remap[f[k]];
  b.vertices = std::move(kept);
  b.parts = std::move(kept_parts);
}

}  // namespace

TemplateGeometry build_template_geometry(const BodyDimensions& d) {
  return build_template_geometry_with_parts(d).geometry;
}

LabelledTemplateGeometry build_template_geometry_with_parts(const BodyDimensions& d) {
  const bool male = d.sex == Sex::kMale;
  const auto& torso = male ? kMaleTorso : kFemaleTorso;
  const double hand_radius = male ? 0.045 : 0.040;
  const double hand_reach = male ? 0.070 : 0.062;  // wrist -> orb centre
  const Vector3d ex = Vector3d::UnitX(), ey = Vector3d::UnitY(), ez = Vector3d::UnitZ();

  // Skeleton (SMPL T-pose, floor y = 0).
  Eigen::Matrix3Xd joints(3, kNumJoints), bone_ends(3, kNumJoints);
  const double knee_y = d.ankle_height + d.shin, hip_y = knee_y + d.thigh;
  const double pelvis_y = hip_y + d.hip_drop;
  const Vector3d pelvis(0, pelvis_y, 0);
  const Vector3d spine1 = pelvis + d.pelvis_to_spine1 * ey;
  const Vector3d spine2 = spine1 + d.spine1_to_spine2 * ey;
  const Vector3d spine3 = spine2 + d.spine2_to_spine3 * ey;
  const Vector3d neck = spine3 + d.spine3_to_neck * ey;
  const Vector3d head = neck + d.neck_to_head * d.head_scale * ey;
  const Vector3d head_radii = d.head_scale * (male ? Vector3d(0.078, 0.110, 0.098) : Vector3d(0.072, 0.100, 0.090));
  const Vector3d head_centre = head + d.head_scale * Vector3d(0, 0.05, 0.01);
  joints.col(kPelvis) = pelvis;
  joints.col(kSpine1) = spine1;
  joints.col(kSpine2) = spine2;
  joints.col(kSpine3) = spine3;
  joints.col(kNeck) = neck;
  joints.col(kHead) = head;
  bone_ends.col(kPelvis) = spine1;
  bone_ends.col(kSpine1) = spine2;
  bone_ends.col(kSpine2) = spine3;
  bone_ends.col(kSpine3) = neck;
  bone_ends.col(kNeck) = head;
  bone_ends.col(kHead) = head_centre + head_radii.y() * ey;
  for (int side : {+1, -1}) {
    const bool left = side > 0;
    const Vector3d hip(side * d.hip_half_width, hip_y, 0);
    const Vector3d knee(hip.x(), knee_y, 0), ankle(hip.x(), d.ankle_height, 0);
    const Vector3d foot(hip.x(), 0.02, 0.12), toe(hip.x(), 0.01, 0.17);
    const Vector3d collar = spine3 + Vector3d(side * d.collar_side, d.collar_up, 0);
    const Vector3d shoulder = collar + side * d.collar_to_shoulder * ex;
    const Vector3d elbow = shoulder + side * d.upper_arm * ex;
    const Vector3d wrist = elbow + side * d.forearm * ex;
    const Vector3d hand = wrist + side * hand_reach * ex;
    joints.col(left ? kLeftHip : kRightHip) = hip;
    joints.col(left ? kLeftKnee : kRightKnee) = knee;
    joints.col(left ? kLeftAnkle : kRightAnkle) = ankle;
    joints.col(left ? kLeftFoot : kRightFoot) = foot;
    joints.col(left ? kLeftCollar : kRightCollar) = collar;
    joints.col(left ? kLeftShoulder : kRightShoulder) = shoulder;
    joints.col(left ? kLeftElbow : kRightElbow) = elbow;
    joints.col(left ? kLeftWrist : kRightWrist) = wrist;
    joints.col(left ? kLeftHand : kRightHand) = hand;
    bone_ends.col(left ? kLeftHip : kRightHip) = knee;
    bone_ends.col(left ? kLeftKnee : kRightKnee) = ankle;
    bone_ends.col(left ? kLeftAnkle : kRightAnkle) = foot;
    bone_ends.col(left ? kLeftFoot : kRightFoot) = toe;
    bone_ends.col(left ? kLeftCollar : kRightCollar) = shoulder;
    bone_ends.col(left ? kLeftShoulder : kRightShoulder) = elbow;
    bone_ends.col(left ? kLeftElbow : kRightElbow) = wrist;
    bone_ends.col(left ? kLeftWrist : kRightWrist) = hand;
    bone_ends.col(left ? kLeftHand : kRightHand) = hand + side * hand_radius * ex;
  }
  const double shoulder_y = joints(1, kLeftShoulder);

  MeshBuilder b;
  // Torso: rings in horizontal planes, e1 = z (front), e2 = x (left), u = +y.
  const double crotch_y = hip_y - 0.075;
  const std::array<double, 9> station_y = {crotch_y,           hip_y,      pelvis_y,
                                           spine1.y() + 0.02,  spine2.y(), spine3.y() + 0.02,
                                           shoulder_y - 0.075, shoulder_y, shoulder_y + 0.05};
  std::array<std::vector<int>, 9> rings;
  for (int s = 0; s < 9; ++s) {
    double half_width = d.torso_girth * torso[s].half_width;
    if (s <= 2) half_width += d.hip_extra_width;
    if (s >= 6) half_width += d.shoulder_extra_width;
    rings[s].resize(kTorsoRing);
    for (int k = 0; k < kTorsoRing; ++k) {
      const double psi = 2 * pi * k / kTorsoRing;
      const double depth = d.torso_girth * (std::cos(psi) >= 0 ? torso[s].front : torso[s].back);
      rings[s][k] = b.add(Vector3d(0, station_y[s], 0) + depth * std::cos(psi) * ez + half_width * std::sin(psi) * ex);
    }
  }
  // Shoulder openings: quads between stations 6-8 in columns 3..7 (left) and 13..17 (right).
  auto in_opening = [](int s, int k) { return s >= 6 && ((k >= 3 && k < 7) || (k >= 13 && k < 17)); };
  for (int s = 0; s < 8; ++s)
    for (int k = 0; k < kTorsoRing; ++k) {
      if (in_opening(s, k)) continue;
      const int k1 = (k + 1) % kTorsoRing;
      const auto &lo = rings[s], &hi = rings[s + 1];
      b.faces.emplace_back(lo[k], lo[k1], hi[k]);
      b.faces.emplace_back(hi[k], lo[k1], hi[k1]);
    }

  // Arms: the opening's boundary, counter-clockwise about the arm direction, starting at the top.
  for (int side : {+1, -1}) {
    const bool left = side > 0;
    b.part = left ? BodyPart::kLeftArm : BodyPart::kRightArm;
    const int c = left ? 5 : 15;  // torso column facing the arm
    const auto &top = rings[8], &mid = rings[7], &low = rings[6];
    std::vector<int> opening = {top[c], top[c - 1], top[c - 2], mid[c - 2], low[c - 2], low[c - 1],
                                low[c], low[c + 1], low[c + 2], mid[c + 2], top[c + 2], top[c + 1]};
    const Vector3d e1 = ey, e2 = side * ez;  // e1 x e2 = side * x, the arm direction
    const Vector3d shoulder = joints.col(left ? kLeftShoulder : kRightShoulder);
    const Vector3d root = shoulder - side * 0.02 * ex;
    const double root_r1 = male ? 0.068 : 0.060, root_r2 = male ? 0.062 : 0.055;
    for (int m = 0; m < kLimbRing; ++m) {
      const double psi = 2 * pi * m / kLimbRing;
      b.vertices[opening[m]] = root + root_r1 * std::cos(psi) * e1 + root_r2 * std::sin(psi) * e2;
      b.parts[opening[m]] = b.part;
    }
    std::vector<int> previous = opening;
    auto limb = [&](const Vector3d& from, const Vector3d& to, std::span<const LimbRing> table) {
      for (const LimbRing& r : table) {
        auto next = b.ring(from + r.t * (to - from), e1, e2, d.limb_girth * r.r1, d.limb_girth * r.r2, kLimbRing, 0);
        b.stitch(previous, next);
        previous = std::move(next);
      }
    };
    const Vector3d elbow = joints.col(left ? kLeftElbow : kRightElbow);
    const Vector3d wrist = joints.col(left ? kLeftWrist : kRightWrist);
    limb(shoulder, elbow, kUpperArm);
    limb(elbow, wrist, kForearm);
    const Vector3d orb = joints.col(left ? kLeftHand : kRightHand);
    for (double f : kOrbRings) {
      const double r = hand_radius * std::sqrt(1 - f * f);
      auto next = b.ring(orb + side * f * hand_radius * ex, e1, e2, r, r, kLimbRing, 0);
      b.stitch(previous, next);
      previous = std::move(next);
    }
    b.cap_end(previous, b.add(orb + side * hand_radius * ex));
  }

  // Legs: the crotch vertex splits the bottom torso ring (front column 0, back column 10).
  b.part = BodyPart::kTorso;
  const int crotch = b.add(Vector3d(0, crotch_y - 0.01, -0.005));
  for (int side : {+1, -1}) {
    const bool left = side > 0;
    b.part = left ? BodyPart::kLeftLeg : BodyPart::kRightLeg;
    const auto& bottom = rings[0];
    std::vector<int> previous = {crotch};
    if (left)
      for (int k = 10; k >= 0; --k) previous.push_back(bottom[k]);
    else
      for (int k = 20; k >= 10; --k) previous.push_back(bottom[k % kTorsoRing]);
    // e1 = x, e2 = z, u = -y; the crotch vertex lies on the inner side of each leg.
    const Vector3d e1 = ex, e2 = ez;
    const double psi0 = left ? pi : 0.0;
    auto limb = [&](const Vector3d& from, const Vector3d& to, std::span<const LimbRing> table, const Vector3d& offset) {
      for (const LimbRing& r : table) {
        auto next = b.ring(from + r.t * (to - from) + offset, e1, e2, d.limb_girth * r.r1, d.limb_girth * r.r2,
                           kLimbRing, psi0);
        b.stitch(previous, next);
        previous = std::move(next);
      }
    };
    const Vector3d hip = joints.col(left ? kLeftHip : kRightHip);
    const Vector3d knee = joints.col(left ? kLeftKnee : kRightKnee);
    const Vector3d ankle = joints.col(left ? kLeftAnkle : kRightAnkle);
    limb(hip, knee, kThigh, Vector3d(side * 0.008, 0, 0));  // thighs apart at the crotch
    limb(knee, ankle, kShin, Vector3d(0, 0, -0.004));
    // Foot: horizontal rings that reach forward to the toes and back to the heel.
    const std::array<Vector3d, 3> foot_rings = {Vector3d(0.042, 0.045, 0.075), Vector3d(0.047, 0.020, 0.115),
                                                Vector3d(0.044, 0.005, 0.110)};
    const std::array<double, 3> foot_forward = {0.025, 0.045, 0.045};
    for (int r = 0; r < 3; ++r) {
      auto next = b.ring(Vector3d(ankle.x(), foot_rings[r].y(), foot_forward[r]), e1, e2, foot_rings[r].x(),
                         foot_rings[r].z(), kLimbRing, psi0);
      b.stitch(previous, next);
      previous = std::move(next);
    }
    b.cap_end(previous, b.add(Vector3d(ankle.x(), 0.0, 0.045)));
  }

  // Neck and head: e1 = z, e2 = x, u = +y, continuing the top torso ring.
  b.part = BodyPart::kHead;
  std::vector<int> previous = rings[8];
  for (const auto& [centre, r1, r2] :
       {std::tuple{Vector3d(neck + Vector3d(0, 0.02, -0.01)), 0.055, 0.060},
        std::tuple{Vector3d(neck + d.head_scale * Vector3d(0, 0.05, 0.0)), 0.052, 0.055}}) {
    auto next = b.ring(centre, ez, ex, r1, r2, kNeckRing, 0);
    b.stitch(previous, next);
    previous = std::move(next);
  }
  for (double f : kHeadRings) {
    const double s = std::sqrt(1 - f * f);
    auto next =
        b.ring(head_centre + f * head_radii.y() * ey, ez, ex, s * head_radii.z(), s * head_radii.x(), kLimbRing, 0);
    b.stitch(previous, next);
    previous = std::move(next);
  }
  b.cap_end(previous, b.add(head_centre + head_radii.y() * ey));

  compact(b);
  LabelledTemplateGeometry out;
  out.geometry.vertices.resize(3, static_cast<Eigen::Index>(b.vertices.size()));
  for (size_t i = 0; i < b.vertices.size(); ++i)
    out.geometry.vertices.col(static_cast<Eigen::Index>(i)) = b.vertices[i];
  out.geometry.faces.resize(3, static_cast<Eigen::Index>(b.faces.size()));
  for (size_t f = 0; f < b.faces.size(); ++f) out.geometry.faces.col(static_cast<Eigen::Index>(f)) = b.faces[f];
  out.geometry.joints = joints;
  out.geometry.bone_ends = bone_ends;
  out.parts = std::move(b.parts);
  return out;
}

}  // namespace posefuse::body
