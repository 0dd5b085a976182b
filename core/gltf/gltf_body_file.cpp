#include "gltf/gltf_body_file.hpp"

#include <tiny_gltf.h>

#include <cstring>
#include <string>
#include <vector>

#include "common/error.hpp"

namespace posefuse::gltf {
namespace {

constexpr int kArrayBuffer = 34962, kElementArrayBuffer = 34963;
constexpr int kJointNode0 = 2;  // node 0: body, 1: camera_to_gltf, then the joints in SMPL order

// Appends data to buffer 0 as its own buffer view (4-byte aligned) and one accessor over it.
class BufferWriter {
 public:
  explicit BufferWriter(tinygltf::Model& model) : model_(model) { model_.buffers.resize(1); }

  int add(const void* data, size_t bytes, int component_type, int type, size_t count, int target,
          std::vector<double> min = {}, std::vector<double> max = {}) {
    std::vector<unsigned char>& buffer = model_.buffers[0].data;
    buffer.resize((buffer.size() + 3) / 4 * 4, 0);
    tinygltf::BufferView view;
    view.buffer = 0;
    view.byteOffset = buffer.size();
    view.byteLength = bytes;
    view.target = target;
    const auto* begin = static_cast<const unsigned char*>(data);
    buffer.insert(buffer.end(), begin, begin + bytes);
    model_.bufferViews.push_back(view);
    tinygltf::Accessor accessor;
    accessor.bufferView = static_cast<int>(model_.bufferViews.size()) - 1;
    accessor.componentType = component_type;
    accessor.type = type;
    accessor.count = count;
    accessor.minValues = std::move(min);
    accessor.maxValues = std::move(max);
    model_.accessors.push_back(accessor);
    return static_cast<int>(model_.accessors.size()) - 1;
  }

 private:
  tinygltf::Model& model_;
};

std::vector<double> quaternion_xyzw(const Eigen::Quaterniond& q) { return {q.x(), q.y(), q.z(), q.w()}; }
std::vector<double> vector_of(const Eigen::Vector3d& v) { return {v.x(), v.y(), v.z()}; }

int add_mesh(const SkinnedMesh& mesh, BufferWriter& writer, tinygltf::Model& model) {
  const auto n = static_cast<size_t>(mesh.positions.cols());
  const Eigen::Vector3f lo = mesh.positions.rowwise().minCoeff(), hi = mesh.positions.rowwise().maxCoeff();
  tinygltf::Primitive primitive;
  primitive.mode = TINYGLTF_MODE_TRIANGLES;
  primitive.attributes["POSITION"] =
      writer.add(mesh.positions.data(), n * 12, TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_VEC3, n, kArrayBuffer,
                 {lo.x(), lo.y(), lo.z()}, {hi.x(), hi.y(), hi.z()});
  primitive.attributes["NORMAL"] =
      writer.add(mesh.normals.data(), n * 12, TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_VEC3, n, kArrayBuffer);
  primitive.attributes["JOINTS_0"] =
      writer.add(mesh.joints.data(), n * 4, TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE, TINYGLTF_TYPE_VEC4, n, kArrayBuffer);
  primitive.attributes["WEIGHTS_0"] =
      writer.add(mesh.weights.data(), n * 16, TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_VEC4, n, kArrayBuffer);
  primitive.indices = writer.add(mesh.indices.data(), mesh.indices.size() * 4, TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT,
                                 TINYGLTF_TYPE_SCALAR, mesh.indices.size(), kElementArrayBuffer);
  tinygltf::Mesh gltf_mesh;
  gltf_mesh.name = "body";
  gltf_mesh.primitives.push_back(primitive);
  model.meshes.push_back(gltf_mesh);
  return static_cast<int>(model.meshes.size()) - 1;
}

void add_skeleton(const SkinnedMesh& mesh, const BodyPose& first, const Eigen::Isometry3d& gltf_from_K,
                  BufferWriter& writer, tinygltf::Model& model) {
  tinygltf::Node top;
  top.name = "camera_to_gltf";
  top.rotation = quaternion_xyzw(Eigen::Quaterniond(gltf_from_K.linear()).normalized());
  top.translation = vector_of(gltf_from_K.translation());
  top.children = {kJointNode0 + body::kPelvis};
  model.nodes.push_back(top);

  tinygltf::Skin skin;
  skin.name = "smpl";
  skin.skeleton = kJointNode0 + body::kPelvis;
  std::vector<float> inverse_bind(16 * body::kNumJoints, 0.0f);
  for (int j = 0; j < body::kNumJoints; ++j) {
    const int parent = body::kSmplParents[static_cast<size_t>(j)];
    tinygltf::Node node;
    node.name = body::smpl_joint_names()[static_cast<size_t>(j)];
    node.rotation = quaternion_xyzw(first.local[static_cast<size_t>(j)]);
    node.translation = vector_of(parent < 0 ? first.pelvis_K
                                            : Eigen::Vector3d(mesh.rest_joints.col(j) - mesh.rest_joints.col(parent)));
    for (int child = 0; child < body::kNumJoints; ++child)
      if (body::kSmplParents[static_cast<size_t>(child)] == j) node.children.push_back(kJointNode0 + child);
    model.nodes.push_back(node);
    skin.joints.push_back(kJointNode0 + j);
    float* m = &inverse_bind[16 * static_cast<size_t>(j)];  // column major
    m[0] = m[5] = m[10] = m[15] = 1.0f;
    for (int c = 0; c < 3; ++c) m[12 + c] = static_cast<float>(-mesh.rest_joints(c, j));
  }
  skin.inverseBindMatrices = writer.add(inverse_bind.data(), inverse_bind.size() * 4, TINYGLTF_COMPONENT_TYPE_FLOAT,
                                        TINYGLTF_TYPE_MAT4, body::kNumJoints, 0);
  model.skins.push_back(skin);
}

void add_animation(const BodyAnimation& animation, BufferWriter& writer, tinygltf::Model& model) {
  const size_t n = animation.frames.size();
  std::vector<float> times(n);
  for (size_t f = 0; f < n; ++f) times[f] = static_cast<float>(animation.frames[f].t_s);
  const int input = writer.add(times.data(), n * 4, TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_SCALAR, n, 0,
                               {times.front()}, {times.back()});
  tinygltf::Animation gltf_animation;
  gltf_animation.name = "fitted_motion";
  // Keyframe times start at 0; the camera-clock time of the first one lets a reader line the
  // animation up with the other files.
  tinygltf::Value::Object extras;
  extras["first_frame_camera_time_s"] = tinygltf::Value(static_cast<double>(animation.t0_us) * 1e-6);
  gltf_animation.extras = tinygltf::Value(extras);
  const auto add_channel = [&](int node, const char* path, int output) {
    tinygltf::AnimationSampler sampler;
    sampler.input = input;
    sampler.output = output;
    sampler.interpolation = "LINEAR";
    gltf_animation.samplers.push_back(sampler);
    tinygltf::AnimationChannel channel;
    channel.sampler = static_cast<int>(gltf_animation.samplers.size()) - 1;
    channel.target_node = node;
    channel.target_path = path;
    gltf_animation.channels.push_back(channel);
  };
  for (int j = 0; j < body::kNumJoints; ++j) {
    std::vector<float> xyzw;
    xyzw.reserve(4 * n);
    Eigen::Quaternionf previous = Eigen::Quaternionf::Identity();
    for (const BodyPose& pose : animation.frames) {
      Eigen::Quaternionf q = pose.local[static_cast<size_t>(j)].cast<float>().normalized();
      // q and -q are one rotation; keeping neighbours in one hemisphere makes every player's
      // interpolation take the short way.
      if (q.dot(previous) < 0) q.coeffs() = -q.coeffs();
      previous = q;
      xyzw.insert(xyzw.end(), {q.x(), q.y(), q.z(), q.w()});
    }
    add_channel(kJointNode0 + j, "rotation",
                writer.add(xyzw.data(), xyzw.size() * 4, TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_VEC4, n, 0));
  }
  std::vector<float> pelvis;
  pelvis.reserve(3 * n);
  for (const BodyPose& pose : animation.frames)
    for (int c = 0; c < 3; ++c) pelvis.push_back(static_cast<float>(pose.pelvis_K[c]));
  add_channel(kJointNode0 + body::kPelvis, "translation",
              writer.add(pelvis.data(), pelvis.size() * 4, TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_VEC3, n, 0));
  model.animations.push_back(gltf_animation);
}

}  // namespace

Eigen::Matrix3d gltf_from_ground() {
  Eigen::Matrix3d m;
  m << 0, 0, -1,  //
      0, 1, 0,    //
      1, 0, 0;
  return m;
}

GltfSummary write_gltf_body(const SkinnedMesh& mesh, const BodyAnimation& animation,
                            const Eigen::Isometry3d& gltf_from_K, std::ostream& out) {
  tinygltf::Model model;
  model.asset.version = "2.0";
  model.asset.generator = "posefuse export (docs/exports.md)";
  BufferWriter writer(model);

  tinygltf::Node body_node;
  body_node.name = "body";
  body_node.mesh = add_mesh(mesh, writer, model);
  body_node.skin = 0;
  model.nodes.push_back(body_node);
  add_skeleton(mesh, animation.frames.front(), gltf_from_K, writer, model);
  add_animation(animation, writer, model);

  tinygltf::Scene scene;
  scene.name = "posefuse";
  scene.nodes = {0, 1};
  model.scenes.push_back(scene);
  model.defaultScene = 0;

  tinygltf::TinyGLTF writer_gltf;
  if (!writer_gltf.WriteGltfSceneToStream(&model, out, false, true))
    throw Error(ErrorCode::kInternal, "glb", "tinygltf could not write the glTF file");
  return {static_cast<int>(animation.frames.size()), static_cast<int>(mesh.positions.cols()),
          static_cast<int>(mesh.indices.size() / 3)};
}

}  // namespace posefuse::gltf
