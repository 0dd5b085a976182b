#pragma once
// Discrete correspondence update of paper 2, II-J (eq. 17).
//
// Each depth sample i keeps a correspondence nu_i on the model surface. Between LM iterations it
// may jump to a better point: the best of {nu_i, the model point seen along the sample's own
// camera ray (Embree, ours), the pre-randomised candidate set U^cand_{t % 10}}, followed by the
// adjacent-face climb: compare with the centroids of the 3 faces around nu_i's face and move
// while one matches better. "Better" is eq. 17's cost |S_p - p|^2 / sigma_p^2 + |S_n - n|^2 / sigma_n^2.
#include <Eigen/Core>
#include <vector>

#include "body/smpl_model.hpp"
#include "body/surface.hpp"
#include "fit/fit_options.hpp"

namespace posefuse::fit {

// Cost of eq. 17 for one sample at surface point s.
double match_cost(const body::BodySurface& surface, const body::SurfacePoint& s, const Eigen::Vector3d& point_K,
                  const Eigen::Vector3d& normal_K, double inv_sigma_p2, double inv_sigma_n2);

// The pre-randomised candidate sets U^cand: num_candidate_sets sets of candidates_per_set face
// centroids, faces drawn with probability proportional to their rest area times
// limb_candidate_density for faces of the upper limbs, neck and head (by the skinning joint with
// the largest weight at the face's first corner). Deterministic for options.seed.
struct SampleTargets {
  const std::vector<Eigen::Vector3d>* points_K;
  const std::vector<Eigen::Vector3d>* normals_K;
  double inv_sigma_p2, inv_sigma_n2;
};

class DiscreteCorrespondenceUpdate {
 public:
  DiscreteCorrespondenceUpdate(const body::SmplModel& model, const FitOptions& options);

  const std::vector<body::SurfacePoint>& candidate_set(int iteration) const {
    return sets_[static_cast<size_t>(iteration) % sets_.size()];
  }

  // Replaces each nu_i by the best of nu_i, ray_hits[i] (face < 0: none; may be empty) and the
  // candidate set of `iteration`, then climbs over adjacent faces (at most max_climb_steps
  // moves). Returns how many correspondences changed.
  int update(const body::BodySurface& surface, const SampleTargets& targets,
             const std::vector<body::SurfacePoint>& ray_hits, int iteration,
             std::vector<body::SurfacePoint>& correspondences);

 private:
  std::vector<std::vector<body::SurfacePoint>> sets_;
  int max_climb_steps_;
  std::vector<Eigen::Vector3d> candidate_p_, candidate_n_;  // work space
};

}  // namespace posefuse::fit
