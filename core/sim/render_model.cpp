#include "sim/render_model.hpp"

#include <cmath>
#include <limits>
#include <map>
#include <string>
#include <utility>

#include "common/error.hpp"
#include "sim/option_checks.hpp"
#include "sim/sim_rng.hpp"

namespace posefuse::sim {
namespace {

using body::Joint;

// Averages rows `a` and `b` of a dense matrix into a new row.
Eigen::MatrixXd with_midpoint_rows(const Eigen::MatrixXd& m, const std::vector<std::pair<int, int>>& edges,
                                   int old_vertices) {
  if (m.cols() == 0) return Eigen::MatrixXd(3 * (old_vertices + static_cast<int>(edges.size())), 0);
  Eigen::MatrixXd out(3 * (old_vertices + static_cast<int>(edges.size())), m.cols());
  out.topRows(3 * old_vertices) = m;
  for (std::size_t e = 0; e < edges.size(); ++e) {
    const auto [a, b] = edges[e];
    out.middleRows(3 * (old_vertices + static_cast<int>(e)), 3) =
        0.5 * (m.middleRows(3 * a, 3) + m.middleRows(3 * b, 3));
  }
  return out;
}

enum class Region { kTorso, kSleeve, kLegs, kShoes, kSkin, kHead };

Region region_of(int joint) {
  switch (joint) {
    case body::kPelvis:
    case body::kSpine1:
    case body::kSpine2:
    case body::kSpine3:
    case body::kLeftCollar:
    case body::kRightCollar: return Region::kTorso;
    case body::kLeftShoulder:
    case body::kRightShoulder: return Region::kSleeve;
    case body::kLeftHip:
    case body::kRightHip:
    case body::kLeftKnee:
    case body::kRightKnee: return Region::kLegs;
    case body::kLeftAnkle:
    case body::kRightAnkle:
    case body::kLeftFoot:
    case body::kRightFoot: return Region::kShoes;
    case body::kHead: return Region::kHead;
    default: return Region::kSkin;  // neck, elbows, wrists, hands
  }
}

Eigen::Matrix3Xd vertex_normals(const Eigen::Matrix3Xd& v, const Eigen::Matrix3Xi& faces) {
  Eigen::Matrix3Xd n = Eigen::Matrix3Xd::Zero(3, v.cols());
  for (int f = 0; f < faces.cols(); ++f) {
    const Eigen::Vector3d a = v.col(faces(0, f)), b = v.col(faces(1, f)), c = v.col(faces(2, f));
    const Eigen::Vector3d area_normal = (b - a).cross(c - a);  // counter-clockwise: outward
    for (int k = 0; k < 3; ++k) n.col(faces(k, f)) += area_normal;
  }
  for (int i = 0; i < n.cols(); ++i) {
    const double norm = n.col(i).norm();
    if (norm > 0) n.col(i) /= norm;
  }
  return n;
}

// Smooth random field in [0, 1]: a sum of plane waves with random directions and phases.
class FoldField {
 public:
  FoldField(double wavelength_m, std::uint64_t seed) {
    SimRng rng(seed, "clothing_folds");
    for (int i = 0; i < kWaves; ++i) {
      Eigen::Vector3d direction(rng.normal(), rng.normal(), rng.normal());
      direction.normalize();
      const double scale = 0.7 + 0.6 * rng.uniform();
      waves_[i] = direction * (2.0 * 3.14159265358979323846 / wavelength_m * scale);
      phases_[i] = 2.0 * 3.14159265358979323846 * rng.uniform();
    }
  }
  double operator()(const Eigen::Vector3d& p) const {
    double sum = 0;
    for (int i = 0; i < kWaves; ++i) sum += std::cos(waves_[i].dot(p) + phases_[i]);
    // The sum has standard deviation sqrt(kWaves / 2); map +-2 sigma onto [0, 1].
    const double x = 0.5 + 0.25 * sum / std::sqrt(0.5 * kWaves);
    return std::clamp(x, 0.0, 1.0);
  }

 private:
  static constexpr int kWaves = 8;
  Eigen::Vector3d waves_[kWaves];
  double phases_[kWaves] = {};
};

}  // namespace

void validate(const ClothingOptions& options) {
  if (options.subdivisions < 0 || options.subdivisions > 2) {
    throw_invalid("clothing.subdivisions", "is " + std::to_string(options.subdivisions) + ", must be 0..2");
  }
  require_non_negative(options.torso_offset_m, "clothing.torso_offset_m");
  require_non_negative(options.sleeve_offset_m, "clothing.sleeve_offset_m");
  require_non_negative(options.trousers_offset_m, "clothing.trousers_offset_m");
  require_non_negative(options.skin_offset_m, "clothing.skin_offset_m");
  require_positive(options.wavelength_m, "clothing.wavelength_m");
  for (double offset :
       {options.torso_offset_m, options.sleeve_offset_m, options.trousers_offset_m, options.skin_offset_m}) {
    if (offset > 0.1) throw_invalid("clothing offsets", "above 0.1 m: " + std::to_string(offset));
  }
}

body::SmplModel subdivide(const body::SmplModel& model) {
  const int v = model.num_vertices();
  std::map<std::pair<int, int>, int> midpoint;
  std::vector<std::pair<int, int>> edges;
  auto mid = [&](int a, int b) {
    const std::pair<int, int> key(std::min(a, b), std::max(a, b));
    const auto [it, inserted] = midpoint.emplace(key, v + static_cast<int>(edges.size()));
    if (inserted) edges.push_back(key);
    return it->second;
  };
  body::SmplModel out;
  out.faces.resize(3, 4 * model.num_faces());
  for (int f = 0; f < model.num_faces(); ++f) {
    const int a = model.faces(0, f), b = model.faces(1, f), c = model.faces(2, f);
    const int ab = mid(a, b), bc = mid(b, c), ca = mid(c, a);
    out.faces.col(4 * f) << a, ab, ca;
    out.faces.col(4 * f + 1) << ab, b, bc;
    out.faces.col(4 * f + 2) << ca, bc, c;
    out.faces.col(4 * f + 3) << ab, bc, ca;
  }
  const int n = v + static_cast<int>(edges.size());
  out.v_template.resize(3, n);
  out.v_template.leftCols(v) = model.v_template;
  for (std::size_t e = 0; e < edges.size(); ++e) {
    out.v_template.col(v + static_cast<int>(e)) =
        0.5 * (model.v_template.col(edges[e].first) + model.v_template.col(edges[e].second));
  }
  out.shapedirs = with_midpoint_rows(model.shapedirs, edges, v);
  out.posedirs = with_midpoint_rows(model.posedirs, edges, v);
  // Weights: dense per vertex, averaged (rows of the average still sum to one).
  const Eigen::MatrixXd weights = Eigen::MatrixXd(model.weights);
  Eigen::MatrixXd new_weights(n, body::kNumJoints);
  new_weights.topRows(v) = weights;
  for (std::size_t e = 0; e < edges.size(); ++e) {
    new_weights.row(v + static_cast<int>(e)) = 0.5 * (weights.row(edges[e].first) + weights.row(edges[e].second));
  }
  out.weights = new_weights.sparseView();
  // The regressor reads the original vertices, which keep their indices.
  Eigen::SparseMatrix<double, Eigen::RowMajor> regressor(body::kNumJoints, n);
  std::vector<Eigen::Triplet<double>> entries;
  for (int j = 0; j < model.J_regressor.outerSize(); ++j) {
    for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator it(model.J_regressor, j); it; ++it) {
      entries.emplace_back(j, static_cast<int>(it.col()), it.value());
    }
  }
  regressor.setFromTriplets(entries.begin(), entries.end());
  out.J_regressor = regressor;
  out.parents = model.parents;
  return out;
}

RenderModel make_render_model(const body::SmplModel& fitted, const Eigen::VectorXd& betas,
                              const ClothingOptions& options, std::uint64_t seed) {
  validate(options);
  body::validate(fitted);
  if (betas.size() > fitted.num_betas() || !betas.allFinite()) {
    throw_invalid("betas", "has " + std::to_string(betas.size()) + " values for a model with " +
                               std::to_string(fitted.num_betas()) + " or non-finite ones");
  }
  body::SmplModel surface = fitted;
  for (int level = 0; level < options.subdivisions; ++level) surface = subdivide(surface);
  const int s = surface.num_vertices();
  const int g = fitted.num_vertices();

  Eigen::VectorXd beta = Eigen::VectorXd::Zero(fitted.num_betas());
  beta.head(betas.size()) = betas;
  const auto shaped = [&](const body::SmplModel& m) {
    Eigen::Matrix3Xd v = m.v_template;
    if (m.num_betas() > 0) {
      const Eigen::VectorXd delta = m.shapedirs * beta;
      v += Eigen::Map<const Eigen::Matrix3Xd>(delta.data(), 3, m.num_vertices());
    }
    return v;
  };
  const Eigen::Matrix3Xd rest = shaped(surface);
  const Eigen::Matrix3Xd rest_fitted = shaped(fitted);
  const Eigen::Matrix3Xd rest_joints = (fitted.J_regressor * rest_fitted.transpose()).transpose();
  const Eigen::Matrix3Xd normals = vertex_normals(rest, surface.faces);

  RenderModel out;
  out.surface_vertices = s;
  out.material.resize(static_cast<std::size_t>(s + g));
  out.forearm_coordinate_m.assign(static_cast<std::size_t>(s + g), std::numeric_limits<float>::quiet_NaN());
  out.forearm_arm.assign(static_cast<std::size_t>(s + g), -1);

  // Per-vertex offset amplitude by region, smoothed over the mesh so that region borders do
  // not tear the surface.
  Eigen::VectorXd amplitude(s);
  for (int i = 0; i < s; ++i) {
    const int dominant = body::dominant_joint(surface, i);
    const Region region = region_of(dominant);
    const double a = region == Region::kTorso    ? options.torso_offset_m
                     : region == Region::kSleeve ? options.sleeve_offset_m
                     : region == Region::kLegs   ? options.trousers_offset_m
                                                 : options.skin_offset_m;
    amplitude[i] = a;
    Material material = Material::kSkin;
    if (region == Region::kTorso || region == Region::kSleeve) material = Material::kShirt;
    if (region == Region::kLegs) material = Material::kTrousers;
    if (region == Region::kShoes) material = Material::kShoes;
    // Hair: the top and back of the head.
    const Eigen::Vector3d from_head = rest.col(i) - rest_joints.col(body::kHead);
    if (region == Region::kHead && (from_head.y() > 0.02 || from_head.z() < -0.03)) material = Material::kHair;
    out.material[static_cast<std::size_t>(i)] = material;
    const bool left = dominant == body::kLeftElbow || dominant == body::kLeftWrist;
    const bool right = dominant == body::kRightElbow || dominant == body::kRightWrist;
    if (left || right) {
      const int elbow = left ? body::kLeftElbow : body::kRightElbow;
      const int wrist = left ? body::kLeftWrist : body::kRightWrist;
      const Eigen::Vector3d axis = (rest_joints.col(wrist) - rest_joints.col(elbow)).normalized();
      out.forearm_coordinate_m[static_cast<std::size_t>(i)] =
          static_cast<float>((rest.col(i) - rest_joints.col(elbow)).dot(axis));
      out.forearm_arm[static_cast<std::size_t>(i)] = left ? 0 : 1;
    }
  }
  std::vector<std::vector<int>> neighbours(static_cast<std::size_t>(s));
  for (int f = 0; f < surface.faces.cols(); ++f) {
    for (int k = 0; k < 3; ++k) {
      neighbours[static_cast<std::size_t>(surface.faces(k, f))].push_back(surface.faces((k + 1) % 3, f));
    }
  }
  for (int iteration = 0; iteration < 4; ++iteration) {
    Eigen::VectorXd smoothed = amplitude;
    for (int i = 0; i < s; ++i) {
      const auto& nb = neighbours[static_cast<std::size_t>(i)];
      if (nb.empty()) continue;
      double sum = amplitude[i];
      for (int j : nb) sum += amplitude[j];
      smoothed[i] = sum / static_cast<double>(nb.size() + 1);
    }
    amplitude = smoothed;
  }

  // The render model: offset surface vertices, then the ghosts the regressor reads.
  auto model = std::make_shared<body::SmplModel>();
  model->faces = surface.faces;
  model->parents = surface.parents;
  model->v_template.resize(3, s + g);
  const FoldField folds(options.wavelength_m, seed);
  for (int i = 0; i < s; ++i) {
    const double offset = options.enabled ? amplitude[i] * folds(rest.col(i)) : 0.0;
    model->v_template.col(i) = surface.v_template.col(i) + offset * normals.col(i);
  }
  model->v_template.rightCols(g) = fitted.v_template;
  model->shapedirs.resize(3 * (s + g), fitted.num_betas());
  model->shapedirs.topRows(3 * s) = surface.shapedirs;
  model->shapedirs.bottomRows(3 * g) = fitted.shapedirs;
  if (fitted.has_posedirs()) {
    model->posedirs.resize(3 * (s + g), fitted.posedirs.cols());
    model->posedirs.topRows(3 * s) = surface.posedirs;
    model->posedirs.bottomRows(3 * g) = fitted.posedirs;
  }
  std::vector<Eigen::Triplet<double>> weights, regressor;
  for (int i = 0; i < s; ++i) {
    for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator it(surface.weights, i); it; ++it) {
      weights.emplace_back(i, static_cast<int>(it.col()), it.value());
    }
  }
  for (int i = 0; i < g; ++i) {
    for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator it(fitted.weights, i); it; ++it) {
      weights.emplace_back(s + i, static_cast<int>(it.col()), it.value());
    }
    out.material[static_cast<std::size_t>(s + i)] = Material::kSkin;  // never rendered
  }
  for (int j = 0; j < fitted.J_regressor.outerSize(); ++j) {
    for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator it(fitted.J_regressor, j); it; ++it) {
      regressor.emplace_back(j, s + static_cast<int>(it.col()), it.value());
    }
  }
  model->weights.resize(s + g, body::kNumJoints);
  model->weights.setFromTriplets(weights.begin(), weights.end());
  model->J_regressor.resize(body::kNumJoints, s + g);
  model->J_regressor.setFromTriplets(regressor.begin(), regressor.end());
  body::validate(*model);
  out.model = std::move(model);
  return out;
}

}  // namespace posefuse::sim
