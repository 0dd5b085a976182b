#include "body/smpl_model.hpp"

#include <cmath>

#include "common/error.hpp"

namespace posefuse::body {

const std::array<const char*, kNumJoints>& smpl_joint_names() {
  static const std::array<const char*, kNumJoints> names = {
      "pelvis",     "left_hip",    "right_hip",    "spine1",      "left_knee",     "right_knee",
      "spine2",     "left_ankle",  "right_ankle",  "spine3",      "left_foot",     "right_foot",
      "neck",       "left_collar", "right_collar", "head",        "left_shoulder", "right_shoulder",
      "left_elbow", "right_elbow", "left_wrist",   "right_wrist", "left_hand",     "right_hand"};
  return names;
}

namespace {

void require_finite(const Eigen::Ref<const Eigen::MatrixXd>& m, const std::string& field) {
  for (Eigen::Index c = 0; c < m.cols(); ++c)
    for (Eigen::Index r = 0; r < m.rows(); ++r)
      if (!std::isfinite(m(r, c)))
        throw_invalid(field + "[" + std::to_string(r) + "," + std::to_string(c) + "]",
                      "not finite: " + std::to_string(m(r, c)));
}

void require_shape(Eigen::Index rows, Eigen::Index cols, Eigen::Index want_rows, Eigen::Index want_cols,
                   const std::string& field) {
  if (rows != want_rows || cols != want_cols)
    throw_invalid(field, "shape " + std::to_string(rows) + "x" + std::to_string(cols) + ", expected " +
                             std::to_string(want_rows) + "x" + std::to_string(want_cols));
}

}  // namespace

void validate(const SmplModel& model) {
  const Eigen::Index v = model.v_template.cols();
  if (v < 4) throw_invalid("v_template", "needs at least 4 vertices, has " + std::to_string(v));
  require_finite(model.v_template, "v_template");
  if (model.shapedirs.rows() != 3 * v)
    require_shape(model.shapedirs.rows(), model.shapedirs.cols(), 3 * v, model.shapedirs.cols(), "shapedirs");
  require_finite(model.shapedirs, "shapedirs");
  if (model.posedirs.cols() != 0) {
    require_shape(model.posedirs.rows(), model.posedirs.cols(), 3 * v, kNumPoseFeatures, "posedirs");
    require_finite(model.posedirs, "posedirs");
  }
  require_shape(model.J_regressor.rows(), model.J_regressor.cols(), kNumJoints, v, "J_regressor");
  for (int j = 0; j < kNumJoints; ++j) {
    double sum = 0;
    for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator it(model.J_regressor, j); it; ++it) {
      if (!std::isfinite(it.value())) throw_invalid("J_regressor[" + std::to_string(j) + "]", "not finite");
      sum += it.value();
    }
    if (std::abs(sum - 1.0) > 1e-3)
      throw_invalid("J_regressor[" + std::to_string(j) + "]", "row sums to " + std::to_string(sum) + ", expected 1");
  }
  require_shape(model.weights.rows(), model.weights.cols(), v, kNumJoints, "weights");
  for (Eigen::Index i = 0; i < v; ++i) {
    double sum = 0;
    for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator it(model.weights, i); it; ++it) {
      if (!std::isfinite(it.value()) || it.value() < -1e-9)
        throw_invalid("weights[" + std::to_string(i) + "]",
                      "weight " + std::to_string(it.value()) + " is negative or not finite");
      sum += it.value();
    }
    if (std::abs(sum - 1.0) > 1e-3)
      throw_invalid("weights[" + std::to_string(i) + "]", "row sums to " + std::to_string(sum) + ", expected 1");
  }
  for (int j = 0; j < kNumJoints; ++j)
    if (model.parents[j] != kSmplParents[j])
      throw_invalid("kintree_table[" + std::to_string(j) + "]",
                    "parent " + std::to_string(model.parents[j]) + " is not SMPL's " + std::to_string(kSmplParents[j]));
  if (model.faces.cols() < 4) throw_invalid("f", "needs at least 4 faces, has " + std::to_string(model.faces.cols()));
  for (Eigen::Index f = 0; f < model.faces.cols(); ++f)
    for (int k = 0; k < 3; ++k) {
      const int idx = model.faces(k, f);
      if (idx < 0 || idx >= v)
        throw_invalid("f[" + std::to_string(f) + "]",
                      "vertex index " + std::to_string(idx) + " outside [0, " + std::to_string(v) + ")");
    }
}

int dominant_joint(const SmplModel& model, int vertex) {
  int best = 0;
  double best_weight = -1;
  for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator it(model.weights, vertex); it; ++it)
    if (it.value() > best_weight) {
      best_weight = it.value();
      best = static_cast<int>(it.col());
    }
  return best;
}

}  // namespace posefuse::body
