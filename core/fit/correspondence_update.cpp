#include "fit/correspondence_update.hpp"

#include <Eigen/Geometry>
#include <random>

#include "common/error.hpp"

namespace posefuse::fit {
namespace {

bool is_limb_neck_or_head(int joint) {
  switch (joint) {
    case body::kLeftShoulder:
    case body::kRightShoulder:
    case body::kLeftElbow:
    case body::kRightElbow:
    case body::kLeftWrist:
    case body::kRightWrist:
    case body::kLeftHand:
    case body::kRightHand:
    case body::kNeck:
    case body::kHead: return true;
    default: return false;
  }
}

constexpr body::SurfacePoint centroid(int face) { return {face, 1.0 / 3, 1.0 / 3}; }

}  // namespace

double match_cost(const body::BodySurface& surface, const body::SurfacePoint& s, const Eigen::Vector3d& point_K,
                  const Eigen::Vector3d& normal_K, double inv_sigma_p2, double inv_sigma_n2) {
  return (surface.position(s) - point_K).squaredNorm() * inv_sigma_p2 +
         (surface.normal(s) - normal_K).squaredNorm() * inv_sigma_n2;
}

DiscreteCorrespondenceUpdate::DiscreteCorrespondenceUpdate(const body::SmplModel& model, const FitOptions& options)
    : max_climb_steps_(options.max_climb_steps) {
  validate(options);
  std::vector<double> face_weight(static_cast<size_t>(model.num_faces()));
  for (int f = 0; f < model.num_faces(); ++f) {
    const Eigen::Vector3d a = model.v_template.col(model.faces(0, f)), b = model.v_template.col(model.faces(1, f)),
                          c = model.v_template.col(model.faces(2, f));
    const double area = 0.5 * (b - a).cross(c - a).norm();
    face_weight[f] =
        area *
        (is_limb_neck_or_head(body::dominant_joint(model, model.faces(0, f))) ? options.limb_candidate_density : 1.0);
  }
  std::mt19937_64 rng(options.seed);
  std::discrete_distribution<int> pick(face_weight.begin(), face_weight.end());
  sets_.resize(static_cast<size_t>(options.num_candidate_sets));
  for (auto& set : sets_)
    for (int k = 0; k < options.candidates_per_set; ++k) set.push_back(centroid(pick(rng)));
}

int DiscreteCorrespondenceUpdate::update(const body::BodySurface& surface, const SampleTargets& targets,
                                         const std::vector<body::SurfacePoint>& ray_hits, int iteration,
                                         std::vector<body::SurfacePoint>& correspondences) {
  const std::vector<body::SurfacePoint>& candidates = candidate_set(iteration);
  const auto& points = *targets.points_K;
  const auto& normals = *targets.normals_K;
  if (points.size() != correspondences.size() || normals.size() != correspondences.size() ||
      (!ray_hits.empty() && ray_hits.size() != correspondences.size()))
    throw Error(ErrorCode::kInternal, "correspondences", "sizes of samples and correspondences differ");
  // The candidates' positions and normals are shared by all samples: compute them once.
  candidate_p_.resize(candidates.size());
  candidate_n_.resize(candidates.size());
  for (size_t k = 0; k < candidates.size(); ++k) {
    candidate_p_[k] = surface.position(candidates[k]);
    candidate_n_[k] = surface.normal(candidates[k]);
  }
  int changed = 0;
  for (size_t i = 0; i < correspondences.size(); ++i) {
    const auto cost = [&](const body::SurfacePoint& s) {
      return match_cost(surface, s, points[i], normals[i], targets.inv_sigma_p2, targets.inv_sigma_n2);
    };
    body::SurfacePoint best = correspondences[i];
    double best_cost = cost(best);
    bool moved = false;
    if (!ray_hits.empty() && ray_hits[i].face >= 0) {
      const double c = cost(ray_hits[i]);
      if (c < best_cost) {
        best_cost = c;
        best = ray_hits[i];
        moved = true;
      }
    }
    for (size_t k = 0; k < candidates.size(); ++k) {
      // The position part alone decides most candidates (the normal part only adds).
      const double position_cost = (candidate_p_[k] - points[i]).squaredNorm() * targets.inv_sigma_p2;
      if (!(position_cost < best_cost)) continue;
      const double c = position_cost + (candidate_n_[k] - normals[i]).squaredNorm() * targets.inv_sigma_n2;
      if (c < best_cost) {
        best_cost = c;
        best = candidates[k];
        moved = true;
      }
    }
    for (int step = 0; step < max_climb_steps_; ++step) {
      int next_face = -1;
      for (int e = 0; e < 3; ++e) {
        const int f = surface.adjacency()(e, best.face);
        if (f < 0) continue;
        const double c = cost(centroid(f));
        if (c < best_cost) {
          best_cost = c;
          next_face = f;
        }
      }
      if (next_face < 0) break;
      best = centroid(next_face);
      moved = true;
    }
    if (moved) {
      correspondences[i] = best;
      ++changed;
    }
  }
  return changed;
}

}  // namespace posefuse::fit
