#pragma once
// A small random SMPL-format model for derivative tests: every joint owns a few vertices,
// each vertex blends up to three joints, and optional random pose correctives.
#include <memory>
#include <random>

#include "body/smpl_model.hpp"

namespace posefuse::body::testing {

inline std::shared_ptr<SmplModel> random_model(int vertices_per_joint, int num_betas, bool with_posedirs,
                                               unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> uni(-1.0, 1.0);
  auto m = std::make_shared<SmplModel>();
  const int v = vertices_per_joint * kNumJoints;
  m->v_template.resize(3, v);
  for (int i = 0; i < v; ++i) m->v_template.col(i) = 0.5 * Eigen::Vector3d(uni(rng), uni(rng), uni(rng));
  m->shapedirs.resize(3 * v, num_betas);
  for (int r = 0; r < 3 * v; ++r)
    for (int b = 0; b < num_betas; ++b) m->shapedirs(r, b) = 0.02 * uni(rng);
  if (with_posedirs) {
    m->posedirs.resize(3 * v, kNumPoseFeatures);
    for (int r = 0; r < 3 * v; ++r)
      for (int c = 0; c < kNumPoseFeatures; ++c) m->posedirs(r, c) = 0.01 * uni(rng);
  }
  std::vector<Eigen::Triplet<double>> reg, w;
  for (int j = 0; j < kNumJoints; ++j)
    for (int k = 0; k < vertices_per_joint; ++k) {
      const int i = j * vertices_per_joint + k;
      reg.emplace_back(j, i, 1.0 / vertices_per_joint);
      const int a = j, b = (j + 5) % kNumJoints, c = (j + 11) % kNumJoints;
      const double wa = 0.5 + 0.3 * (uni(rng) + 1) / 2, wb = (1 - wa) * 0.7;
      w.emplace_back(i, a, wa);
      w.emplace_back(i, b, wb);
      w.emplace_back(i, c, 1 - wa - wb);
    }
  m->J_regressor.resize(kNumJoints, v);
  m->J_regressor.setFromTriplets(reg.begin(), reg.end());
  m->weights.resize(v, kNumJoints);
  m->weights.setFromTriplets(w.begin(), w.end());
  m->faces.resize(3, v - 2);
  for (int f = 0; f < v - 2; ++f) m->faces.col(f) = Eigen::Vector3i(f, f + 1, f + 2);
  return m;
}

}  // namespace posefuse::body::testing
