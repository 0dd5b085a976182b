// Discrete correspondence update (paper 2, II-J, eq. 17).
#include "fit/correspondence_update.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>

#include "body/template_generator.hpp"
#include "model_frames.hpp"

namespace posefuse::fit {
namespace {

struct PosedSurface {
  std::shared_ptr<const body::SmplModel> model = body::make_template(body::Sex::kFemale);
  body::PoseLayout layout = body::PoseLayout::upper_body();
  body::BodyEvaluator eval{model, layout};
  body::BodySurface surface{model->faces, model->num_vertices()};
  std::vector<body::SurfacePoint> truth;
  std::vector<Eigen::Vector3d> points, normals;

  explicit PosedSurface(int samples) {
    eval.evaluate(Eigen::VectorXd::Zero(10), testing::facing_pose(layout, 2.0, 1), body::Derivatives::kNone);
    surface.update(eval.vertices());
    std::mt19937 rng(9);
    std::uniform_real_distribution<double> uni(0.05, 0.45);
    for (int i = 0; i < samples; ++i) {
      const body::SurfacePoint s{static_cast<int>(rng() % model->num_faces()), uni(rng), uni(rng)};
      truth.push_back(s);
      points.push_back(surface.position(s));
      normals.push_back(surface.normal(s));
    }
  }
};

TEST(FitCorrespondenceUpdate, CandidatesAndClimbNeverRaiseTheCostAndFindTheSurfaceNearby) {
  PosedSurface m(200);
  const FitOptions options;
  DiscreteCorrespondenceUpdate update(*m.model, options);
  EXPECT_EQ(update.candidate_set(3).size(), static_cast<size_t>(options.candidates_per_set));
  const SampleTargets targets{&m.points, &m.normals, 1 / (options.sigma_p_m * options.sigma_p_m),
                              1 / (options.sigma_n * options.sigma_n)};
  // Start every correspondence on one face, far from most samples.
  std::vector<body::SurfacePoint> nu(m.points.size(), body::SurfacePoint{0, 1.0 / 3, 1.0 / 3});
  std::vector<double> before(nu.size());
  for (size_t i = 0; i < nu.size(); ++i)
    before[i] = match_cost(m.surface, nu[i], m.points[i], m.normals[i], targets.inv_sigma_p2, targets.inv_sigma_n2);
  for (int iteration = 0; iteration < 3; ++iteration) update.update(m.surface, targets, {}, iteration, nu);
  std::vector<double> distance;
  for (size_t i = 0; i < nu.size(); ++i) {
    const double after =
        match_cost(m.surface, nu[i], m.points[i], m.normals[i], targets.inv_sigma_p2, targets.inv_sigma_n2);
    EXPECT_LE(after, before[i]) << i;
    distance.push_back((m.surface.position(nu[i]) - m.points[i]).norm());
  }
  std::sort(distance.begin(), distance.end());
  // Face centroids only: within about a face's size of the sample for most of them.
  EXPECT_LT(distance[distance.size() / 2], 0.03);
}

TEST(FitCorrespondenceUpdate, RayHitAtTheSampleIsTaken) {
  PosedSurface m(50);
  DiscreteCorrespondenceUpdate update(*m.model, FitOptions{});
  const SampleTargets targets{&m.points, &m.normals, 1e5, 16};
  std::vector<body::SurfacePoint> nu(m.points.size(), body::SurfacePoint{0, 1.0 / 3, 1.0 / 3});
  update.update(m.surface, targets, m.truth, 0, nu);
  for (size_t i = 0; i < nu.size(); ++i) EXPECT_LT((m.surface.position(nu[i]) - m.points[i]).norm(), 1e-9) << i;
}

}  // namespace
}  // namespace posefuse::fit
