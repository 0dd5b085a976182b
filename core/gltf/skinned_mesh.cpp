#include "gltf/skinned_mesh.hpp"

#include <algorithm>
#include <memory>
#include <utility>

#include "body/body_evaluator.hpp"
#include "body/surface.hpp"

namespace posefuse::gltf {

SkinnedMesh skinned_mesh(const body::SmplModel& model, const Eigen::VectorXd& beta) {
  // The evaluator at theta = 0 gives the shaped rest mesh and joints (no pose correctives at rest).
  const body::PoseLayout layout = body::PoseLayout::all_joints();
  body::BodyEvaluator evaluator(std::make_shared<const body::SmplModel>(model), layout);
  evaluator.evaluate(beta, Eigen::VectorXd::Zero(layout.size()), body::Derivatives::kNone);
  body::BodySurface surface(model.faces, model.num_vertices());
  surface.update(evaluator.vertices());

  SkinnedMesh mesh;
  const int n = model.num_vertices();
  mesh.positions = evaluator.vertices().cast<float>();
  mesh.normals.resize(3, n);
  for (int v = 0; v < n; ++v) {
    const Eigen::Vector3d normal = surface.vertex_normals().col(v);
    mesh.normals.col(v) = (normal.norm() > 0 ? normal.normalized() : Eigen::Vector3d::UnitY()).cast<float>();
  }
  mesh.indices.reserve(3 * static_cast<size_t>(model.num_faces()));
  for (int f = 0; f < model.num_faces(); ++f)
    for (int c = 0; c < 3; ++c) mesh.indices.push_back(static_cast<std::uint32_t>(model.faces(c, f)));
  mesh.rest_joints = evaluator.rest_joints();

  mesh.joints.setZero(4, n);
  mesh.weights.setZero(4, n);
  for (int v = 0; v < n; ++v) {
    std::vector<std::pair<double, int>> influences;  // (weight, joint)
    for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator it(model.weights, v); it; ++it)
      if (it.value() > 0) influences.emplace_back(it.value(), static_cast<int>(it.col()));
    std::sort(influences.begin(), influences.end(), [](const auto& a, const auto& b) { return a.first > b.first; });
    if (influences.size() > 4) {
      ++mesh.dropped_influences;
      influences.resize(4);
    }
    double total = 0;
    for (const auto& influence : influences) total += influence.first;
    float sum = 0;
    for (size_t k = 0; k < influences.size(); ++k) {
      mesh.joints(static_cast<Eigen::Index>(k), v) = static_cast<std::uint8_t>(influences[k].second);
      // The last weight takes what the others leave, so that they sum to 1 in float as glTF asks.
      const float w = k + 1 < influences.size() ? static_cast<float>(influences[k].first / total) : 1.0f - sum;
      mesh.weights(static_cast<Eigen::Index>(k), v) = w;
      sum += w;
    }
  }
  return mesh;
}

}  // namespace posefuse::gltf
