// `posefuse export --format gltf` on result directories of known poses (posed_results.hpp): the
// written file, read back with tinygltf and evaluated as glTF defines its node hierarchy and
// skinning, puts every joint where the fit put it and every vertex where SMPL's skinning does.
#include <gtest/gtest.h>
#include <tiny_gltf.h>

#include <Eigen/Geometry>
#include <cstring>
#include <string>
#include <vector>

#include "../imu/expect_error.hpp"
#include "../scratch_dir.hpp"
#include "gltf/gltf_body_file.hpp"
#include "opensim/export_results.hpp"
#include "opensim/ground_frame.hpp"
#include "posed_results.hpp"
#include "session/result_reader.hpp"

using namespace posefuse;

namespace {

std::filesystem::path fresh_dir(const std::string& name) {
  return posefuse::testing::fresh_scratch_dir("posefuse_gltf_export", name);
}

tinygltf::Model load_glb(const std::filesystem::path& file) {
  tinygltf::TinyGLTF loader;
  tinygltf::Model model;
  std::string error, warning;
  EXPECT_TRUE(loader.LoadBinaryFromFile(&model, &error, &warning, file.string())) << error;
  EXPECT_TRUE(error.empty()) << error;
  return model;
}

// An accessor's floats (or bytes, widened), tightly packed as the export writes them.
template <typename T>
std::vector<T> accessor_values(const tinygltf::Model& model, int index, int components) {
  const tinygltf::Accessor& accessor = model.accessors.at(static_cast<size_t>(index));
  const tinygltf::BufferView& view = model.bufferViews.at(static_cast<size_t>(accessor.bufferView));
  const unsigned char* data =
      model.buffers.at(static_cast<size_t>(view.buffer)).data.data() + view.byteOffset + accessor.byteOffset;
  std::vector<T> out(accessor.count * static_cast<size_t>(components));
  std::memcpy(out.data(), data, out.size() * sizeof(T));
  return out;
}

int node_named(const tinygltf::Model& model, const std::string& name) {
  for (size_t n = 0; n < model.nodes.size(); ++n)
    if (model.nodes[n].name == name) return static_cast<int>(n);
  ADD_FAILURE() << "no node " << name;
  return 0;
}

// Every node's global transform at keyframe `frame`: its TRS with the animated paths replaced by
// the samplers' outputs at that keyframe.
std::vector<Eigen::Isometry3d> global_transforms(const tinygltf::Model& model, size_t frame) {
  std::vector<Eigen::Vector3d> translation(model.nodes.size(), Eigen::Vector3d::Zero());
  std::vector<Eigen::Quaterniond> rotation(model.nodes.size(), Eigen::Quaterniond::Identity());
  std::vector<int> parent(model.nodes.size(), -1);
  for (size_t n = 0; n < model.nodes.size(); ++n) {
    const tinygltf::Node& node = model.nodes[n];
    EXPECT_TRUE(node.matrix.empty() && node.scale.empty());
    if (!node.translation.empty()) translation[n] = {node.translation[0], node.translation[1], node.translation[2]};
    if (!node.rotation.empty())
      rotation[n] = Eigen::Quaterniond(node.rotation[3], node.rotation[0], node.rotation[1], node.rotation[2]);
    for (int child : node.children) parent[static_cast<size_t>(child)] = static_cast<int>(n);
  }
  for (const tinygltf::AnimationChannel& channel : model.animations.at(0).channels) {
    const tinygltf::AnimationSampler& sampler = model.animations[0].samplers.at(static_cast<size_t>(channel.sampler));
    const auto n = static_cast<size_t>(channel.target_node);
    if (channel.target_path == "rotation") {
      const std::vector<float> q = accessor_values<float>(model, sampler.output, 4);
      rotation[n] = Eigen::Quaterniond(q[4 * frame + 3], q[4 * frame], q[4 * frame + 1], q[4 * frame + 2]);
    } else {
      EXPECT_EQ(channel.target_path, "translation");
      const std::vector<float> t = accessor_values<float>(model, sampler.output, 3);
      translation[n] = {t[3 * frame], t[3 * frame + 1], t[3 * frame + 2]};
    }
  }
  std::vector<Eigen::Isometry3d> global(model.nodes.size());
  // Parents come before their children in the export's node order.
  for (size_t n = 0; n < model.nodes.size(); ++n) {
    Eigen::Isometry3d local = Eigen::Isometry3d::Identity();
    local.translate(translation[n]).rotate(rotation[n].normalized());
    EXPECT_LT(parent[n], static_cast<int>(n));
    global[n] = parent[n] < 0 ? local : global[static_cast<size_t>(parent[n])] * local;
  }
  return global;
}

// The mesh's vertices skinned at keyframe `frame` as glTF defines it:
// sum_k w_k global(joint_k) inverse_bind(joint_k) v.
Eigen::Matrix3Xd skinned_vertices(const tinygltf::Model& model, size_t frame) {
  const std::vector<Eigen::Isometry3d> global = global_transforms(model, frame);
  const tinygltf::Skin& skin = model.skins.at(0);
  const std::vector<float> inverse_bind = accessor_values<float>(model, skin.inverseBindMatrices, 16);
  std::vector<Eigen::Matrix4d> joint_matrix;
  for (size_t j = 0; j < skin.joints.size(); ++j)
    joint_matrix.push_back(global[static_cast<size_t>(skin.joints[j])].matrix() *
                           Eigen::Map<const Eigen::Matrix4f>(&inverse_bind[16 * j]).cast<double>());
  const tinygltf::Primitive& primitive = model.meshes.at(0).primitives.at(0);
  const std::vector<float> positions = accessor_values<float>(model, primitive.attributes.at("POSITION"), 3);
  const std::vector<std::uint8_t> joints = accessor_values<std::uint8_t>(model, primitive.attributes.at("JOINTS_0"), 4);
  const std::vector<float> weights = accessor_values<float>(model, primitive.attributes.at("WEIGHTS_0"), 4);
  Eigen::Matrix3Xd out(3, static_cast<Eigen::Index>(positions.size() / 3));
  for (Eigen::Index v = 0; v < out.cols(); ++v) {
    Eigen::Matrix4d m = Eigen::Matrix4d::Zero();
    for (size_t k = 0; k < 4; ++k) m += weights[4 * v + k] * joint_matrix[joints[4 * v + k]];
    out.col(v) = (m * Eigen::Vector4d(positions[3 * v], positions[3 * v + 1], positions[3 * v + 2], 1.0)).head<3>();
  }
  return out;
}

// The export's glTF frame: glTF axes from the markers' ground.
Eigen::Isometry3d gltf_from_K(const std::filesystem::path& dir) {
  const opensim::GroundFrame ground = opensim::ground_frame(session::read_result_files(dir));
  Eigen::Isometry3d out = Eigen::Isometry3d::Identity();
  out.linear() = gltf::gltf_from_ground() * ground.G_from_K;
  out.translation() = -out.linear() * ground.origin_K;
  return out;
}

std::vector<gltf_fixture::Pose> moving_poses() {
  std::vector<gltf_fixture::Pose> poses;
  for (int f = 0; f < 5; ++f) poses.push_back(gltf_fixture::fixture_pose(f));
  return poses;
}

}  // namespace

TEST(GltfExport, WritesBodyGlbWithOneKeyframePerFittedFrame) {
  const auto dir = fresh_dir("default_name");
  gltf_fixture::write_posed_results(dir, moving_poses(), {.t0_us = 7'000'000});
  const opensim::ExportReport report = opensim::export_results(dir, opensim::ExportFormat::kGltf);
  EXPECT_EQ(report.file, dir / "body.glb");
  EXPECT_EQ(opensim::export_format("gltf"), opensim::ExportFormat::kGltf);
  EXPECT_TRUE(report.warnings.empty()) << report.warnings.front();
  EXPECT_NE(report.summary.find("5 frames of 24 joints"), std::string::npos) << report.summary;
  const tinygltf::Model model = load_glb(report.file);
  ASSERT_EQ(model.animations.size(), 1u);
  ASSERT_EQ(model.skins.size(), 1u);
  EXPECT_EQ(model.skins[0].joints.size(), 24u);
  EXPECT_EQ(model.animations[0].channels.size(), 25u);  // 24 rotations, the pelvis translation
  const std::vector<float> times = accessor_values<float>(model, model.animations[0].samplers[0].input, 1);
  ASSERT_EQ(times.size(), 5u);
  for (size_t f = 0; f < times.size(); ++f) EXPECT_NEAR(times[f], 0.033333 * static_cast<double>(f), 1e-6);
  EXPECT_DOUBLE_EQ(model.animations[0].extras.Get("first_frame_camera_time_s").GetNumberAsDouble(), 7.0);
}

TEST(GltfExport, JointNodesFollowTheFittedJointsInTheGltfFrame) {
  const auto dir = fresh_dir("joints");
  const std::vector<gltf_fixture::Pose> poses = moving_poses();
  gltf_fixture::write_posed_results(dir, poses);
  const tinygltf::Model model = load_glb(opensim::export_results(dir, opensim::ExportFormat::kGltf).file);
  const session::ResultDirectory results = session::read_result_files(dir);
  const Eigen::Isometry3d to_gltf = gltf_from_K(dir);
  for (size_t f = 0; f < poses.size(); ++f) {
    const std::vector<Eigen::Isometry3d> global = global_transforms(model, f);
    for (int j = 0; j < body::kNumJoints; ++j) {
      const session::JointRow& row = results.smpl_joints[f * body::kNumJoints + static_cast<size_t>(j)];
      ASSERT_EQ(row.joint, j);
      const Eigen::Vector3d node =
          global[static_cast<size_t>(node_named(model, body::smpl_joint_names()[j]))].translation();
      EXPECT_LT((node - to_gltf * row.p_K).norm(), 1e-3) << "frame " << f << " joint " << j;
    }
  }
  // glTF's y is up: the subject stands with the head above the pelvis above the ankles.
  const std::vector<Eigen::Isometry3d> first = global_transforms(model, 0);
  const auto y = [&](const char* name) {
    return first[static_cast<size_t>(node_named(model, name))].translation().y();
  };
  EXPECT_GT(y("head"), y("pelvis") + 0.4);
  EXPECT_GT(y("pelvis"), y("left_ankle") + 0.6);
}

TEST(GltfExport, SkinnedMeshMatchesTheModelsOwnSkinning) {
  const auto dir = fresh_dir("skinning");
  const std::vector<gltf_fixture::Pose> poses = moving_poses();
  gltf_fixture::write_posed_results(dir, poses);
  const tinygltf::Model model = load_glb(opensim::export_results(dir, opensim::ExportFormat::kGltf).file);
  const Eigen::Isometry3d to_gltf = gltf_from_K(dir);
  body::BodyEvaluator evaluator(gltf_fixture::fixture_model(), body::PoseLayout::all_joints());
  for (size_t f = 0; f < poses.size(); ++f) {
    gltf_fixture::evaluate(evaluator, gltf_fixture::fixture_beta(), poses[f]);
    const Eigen::Matrix3Xd skinned = skinned_vertices(model, f);
    ASSERT_EQ(skinned.cols(), evaluator.vertices().cols());
    const double worst = (skinned - to_gltf * evaluator.vertices()).colwise().norm().maxCoeff();
    EXPECT_LT(worst, 1e-3) << "frame " << f;
  }
}

// Only the left elbow bends, 90 deg about SMPL's y (the T-pose's forearm, along +x, turns to the
// front, +z): the forearm's vertices turn rigidly about the elbow and the forearm ends up
// perpendicular to the upper arm.
TEST(GltfExport, ElbowAt90DegreesTurnsTheForearmAboutTheElbow) {
  const auto dir = fresh_dir("elbow");
  gltf_fixture::Pose pose;
  pose.rotation_vectors.col(body::kPelvis) = Eigen::Vector3d(0, M_PI, 0);  // facing a level camera
  pose.translation = Eigen::Vector3d(0, 0, 2.5);
  gltf_fixture::Pose bent = pose;
  bent.rotation_vectors.col(body::kLeftElbow) = Eigen::Vector3d(0, -M_PI / 2, 0);
  gltf_fixture::write_posed_results(dir, {pose, bent});
  const tinygltf::Model model = load_glb(opensim::export_results(dir, opensim::ExportFormat::kGltf).file);
  const Eigen::Isometry3d to_gltf = gltf_from_K(dir);

  const std::vector<Eigen::Isometry3d> global = global_transforms(model, 1);
  const auto at = [&](const char* name) { return global[static_cast<size_t>(node_named(model, name))].translation(); };
  const Eigen::Vector3d upper_arm = at("left_elbow") - at("left_shoulder");
  const Eigen::Vector3d forearm = at("left_wrist") - at("left_elbow");
  EXPECT_NEAR(std::acos(upper_arm.normalized().dot(forearm.normalized())), M_PI / 2, 1e-4);
  // The body faces glTF's +z (the camera) and the forearm points to the subject's front.
  EXPECT_GT(forearm.normalized().z(), 0.999);

  // Straight: the rest mesh moved rigidly by the root; bent: the forearm's vertices turned.
  const Eigen::Matrix3Xd straight = skinned_vertices(model, 0), turned = skinned_vertices(model, 1);
  const tinygltf::Primitive& primitive = model.meshes[0].primitives[0];
  const std::vector<std::uint8_t> joints = accessor_values<std::uint8_t>(model, primitive.attributes.at("JOINTS_0"), 4);
  const std::vector<float> weights = accessor_values<float>(model, primitive.attributes.at("WEIGHTS_0"), 4);
  const Eigen::Matrix3d root = to_gltf.linear() * Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitY()).toRotationMatrix();
  const Eigen::Matrix3d turn = root * Eigen::AngleAxisd(-M_PI / 2, Eigen::Vector3d::UnitY()).toRotationMatrix() *
                               root.transpose();  // the elbow's turn, in glTF
  // The forearm's vertices: skinned only to the elbow and the joints below it (whose own
  // rotations are identity here).
  const auto below_elbow = [](int joint) {
    return joint == body::kLeftElbow || joint == body::kLeftWrist || joint == body::kLeftHand;
  };
  int forearm_vertices = 0;
  for (Eigen::Index v = 0; v < straight.cols(); ++v) {
    bool forearm_only = true;
    for (Eigen::Index k = 0; k < 4; ++k)
      forearm_only = forearm_only && (weights[4 * v + k] == 0 || below_elbow(joints[4 * v + k]));
    if (!forearm_only) continue;
    ++forearm_vertices;
    const Eigen::Vector3d expected = at("left_elbow") + turn * (straight.col(v) - at("left_elbow"));
    EXPECT_LT((turned.col(v) - expected).norm(), 1e-4) << "vertex " << v;
  }
  EXPECT_GT(forearm_vertices, 10);
}

// q and -q are one rotation, and the fitted rotations may come with either sign; the keyframes
// stay in one hemisphere so that a player's interpolation takes the short way.
TEST(GltfExport, RotationKeyframesStayInOneHemisphere) {
  const auto dir = fresh_dir("hemisphere");
  const std::vector<gltf_fixture::Pose> poses = moving_poses();
  gltf_fixture::write_posed_results(dir, poses, {.flip_odd_frames = true});
  const tinygltf::Model model = load_glb(opensim::export_results(dir, opensim::ExportFormat::kGltf).file);
  for (const tinygltf::AnimationChannel& channel : model.animations.at(0).channels) {
    if (channel.target_path != "rotation") continue;
    const std::vector<float> q =
        accessor_values<float>(model, model.animations[0].samplers[static_cast<size_t>(channel.sampler)].output, 4);
    for (size_t f = 1; f < poses.size(); ++f) {
      const Eigen::Vector4f a(&q[4 * (f - 1)]), b(&q[4 * f]);
      EXPECT_GT(a.dot(b), 0.9f) << model.nodes[static_cast<size_t>(channel.target_node)].name << " frame " << f;
    }
  }
}

TEST(GltfExport, WithoutFittedRotationsNamesTheMissingFile) {
  const auto dir = fresh_dir("no_rotations");
  gltf_fixture::write_posed_results(dir, moving_poses(), {.with_rotations = false});
  posefuse::testing::expect_error([&] { opensim::export_results(dir, opensim::ExportFormat::kGltf); },
                                  ErrorCode::kFailedPrecondition, "smpl_joint_rotations.csv", "body fit");
  EXPECT_FALSE(std::filesystem::exists(dir / "body.glb"));
}

TEST(GltfExport, WithoutABodyModelAssumesTheMaleTemplateAndSaysSo) {
  const auto dir = fresh_dir("no_body_model");
  // The calibration report of an older server: no body model, no betas.
  gltf_fixture::write_posed_results(dir, moving_poses(), {.with_shape = false});
  const opensim::ExportReport report = opensim::export_results(dir, opensim::ExportFormat::kGltf);
  ASSERT_EQ(report.warnings.size(), 2u);
  EXPECT_NE(report.warnings[0].find("male template is assumed"), std::string::npos) << report.warnings[0];
  EXPECT_NE(report.warnings[1].find("mean shape"), std::string::npos) << report.warnings[1];
}
