#include "body/smpl_npz.hpp"

#include <cmath>

#include "common/error.hpp"

namespace posefuse::body {
namespace {

std::string shape_text(const std::vector<int64_t>& shape) {
  std::string text = "(";
  for (size_t i = 0; i < shape.size(); ++i) text += (i ? ", " : "") + std::to_string(shape[i]);
  return text + ")";
}

const NpyArray& require(const std::map<std::string, NpyArray>& arrays, const std::string& key) {
  const auto it = arrays.find(key);
  if (it == arrays.end()) throw Error(ErrorCode::kNotFound, key, "array missing from the SMPL .npz");
  return it->second;
}

// Checks the rank and the dimensions given as >= 0 (-1: any size >= 1).
void require_shape(const NpyArray& a, const std::string& key, std::vector<int64_t> expected) {
  bool ok = a.shape.size() == expected.size();
  for (size_t d = 0; ok && d < expected.size(); ++d) ok = expected[d] < 0 ? a.shape[d] >= 1 : a.shape[d] == expected[d];
  if (!ok) {
    std::string want = "(";
    for (size_t d = 0; d < expected.size(); ++d)
      want += (d ? ", " : "") + (expected[d] < 0 ? std::string("N") : std::to_string(expected[d]));
    throw_invalid(key, "shape " + shape_text(a.shape) + ", expected " + want + ")");
  }
}

int integer_at(const NpyArray& a, size_t i, const std::string& key) {
  const double value = a.values[i];
  if (!std::isfinite(value) || value != std::floor(value) || std::abs(value) > 2147483647.0)
    throw_invalid(key + "[" + std::to_string(i) + "]", "not an integer index: " + std::to_string(value));
  return static_cast<int>(value);
}

}  // namespace

std::shared_ptr<SmplModel> smpl_from_arrays(const std::map<std::string, NpyArray>& arrays) {
  auto model = std::make_shared<SmplModel>();
  const NpyArray& v_template = require(arrays, "v_template");
  require_shape(v_template, "v_template", {-1, 3});
  const int64_t v = v_template.shape[0];
  model->v_template = Eigen::Map<const Eigen::Matrix3Xd>(v_template.values.data(), 3, v);

  const NpyArray& shapedirs = require(arrays, "shapedirs");
  require_shape(shapedirs, "shapedirs", {v, 3, -1});
  const int64_t betas = shapedirs.shape[2];
  model->shapedirs = Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(
      shapedirs.values.data(), 3 * v, betas);

  if (arrays.count("posedirs")) {
    const NpyArray& posedirs = arrays.at("posedirs");
    require_shape(posedirs, "posedirs", {v, 3, kNumPoseFeatures});
    model->posedirs = Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(
        posedirs.values.data(), 3 * v, kNumPoseFeatures);
  }

  const NpyArray& regressor = require(arrays, "J_regressor");
  require_shape(regressor, "J_regressor", {kNumJoints, v});
  std::vector<Eigen::Triplet<double>> triplets;
  for (int j = 0; j < kNumJoints; ++j)
    for (int64_t i = 0; i < v; ++i)
      if (const double value = regressor.values[static_cast<size_t>(j * v + i)]; value != 0.0)
        triplets.emplace_back(j, static_cast<int>(i), value);
  model->J_regressor.resize(kNumJoints, v);
  model->J_regressor.setFromTriplets(triplets.begin(), triplets.end());

  const NpyArray& weights = require(arrays, "weights");
  require_shape(weights, "weights", {v, kNumJoints});
  triplets.clear();
  for (int64_t i = 0; i < v; ++i)
    for (int j = 0; j < kNumJoints; ++j)
      if (const double value = weights.values[static_cast<size_t>(i * kNumJoints + j)]; value != 0.0)
        triplets.emplace_back(static_cast<int>(i), j, value);
  model->weights.resize(v, kNumJoints);
  model->weights.setFromTriplets(triplets.begin(), triplets.end());

  const NpyArray& kintree = require(arrays, "kintree_table");
  require_shape(kintree, "kintree_table", {2, kNumJoints});
  for (int j = 0; j < kNumJoints; ++j) {
    // Row 0 holds parents (the root's is -1 or 2^32 - 1 as uint32), row 1 the joint ids.
    if (integer_at(kintree, static_cast<size_t>(kNumJoints + j), "kintree_table") != j)
      throw_invalid("kintree_table[1][" + std::to_string(j) + "]", "joint ids must be 0..23 in order");
    const double parent = kintree.values[static_cast<size_t>(j)];
    model->parents[j] =
        (parent == 4294967295.0 || parent == -1.0) ? -1 : integer_at(kintree, static_cast<size_t>(j), "kintree_table");
  }

  const NpyArray& faces = require(arrays, "f");
  require_shape(faces, "f", {-1, 3});
  model->faces.resize(3, faces.shape[0]);
  for (int64_t f = 0; f < faces.shape[0]; ++f)
    for (int k = 0; k < 3; ++k) model->faces(k, f) = integer_at(faces, static_cast<size_t>(3 * f + k), "f");

  validate(*model);
  return model;
}

std::shared_ptr<SmplModel> load_smpl_npz(const std::string& path) { return smpl_from_arrays(read_npz(path)); }

}  // namespace posefuse::body
