#pragma once
// Soft-tissue wobble under fast motion (issue 4, "model mismatch"): the flesh of a body segment
// lags behind its bone and swings back, a damped spring driven by the segment's acceleration.
//
// Per SMPL joint j, its segment's centre c_j(t) (the mean of the joint and its children, e.g.
// shoulder and elbow for the upper arm) is followed in the inertial Body frame at 1 kHz. The
// tissue's displacement x_j relative to the bone obeys
//     x'' + 2 zeta omega x' + omega^2 x = -gain * c_j''          (omega = 2 pi frequency_hz)
// from rest (x = x' = 0 at the first time), integrated by semi-implicit Euler (omega dt = 0.025:
// stable, within 0.1 % of the exact frequency). A body at rest or moving at constant velocity
// has c_j'' = 0 and no wobble; a sudden stop rings down with time constant 1 / (zeta omega).
// The displacement is bounded smoothly: x * max / sqrt(max^2 + |x|^2), |.| < max_displacement_m.
//
// A surface vertex v moves by sum_j w_vj * looseness(j) * x_j, with w_vj its skinning weights
// (rows sum to 1) and looseness in [0, 1] per segment (upper arms, belly and chest loosest;
// forearms a little; hands, feet and head not at all), so no vertex moves more than
// max_displacement_m. The joints, the skeleton and the IMUs never see it: only the rendered
// surface wobbles.
#include <cstdint>
#include <functional>
#include <vector>

#include <Eigen/Core>
#include <Eigen/SparseCore>

namespace posefuse::sim {

struct SoftTissueOptions {
  bool enabled = true;
  double frequency_hz = 4.0;          // natural frequency of flesh on the upper arm and belly
  double damping_ratio = 0.25;        // zeta: about three visible swings after a stop
  double gain = 0.3;                  // share of the segment's acceleration that drives the flesh
  double max_displacement_m = 0.015;  // bound on any vertex's wobble
};

// kInvalidArgument naming the field ("soft_tissue.<field>").
void validate(const SoftTissueOptions& options);

// How loose the flesh of joint j's segment is, in [0, 1].
double soft_tissue_looseness(int joint);

// Segment displacements (3 x 24, Body frame) at each of `times_s` (increasing), for joint
// positions `joints_at(t)` (3 x 24, an inertial frame) defined a few ms around [times.front(),
// times.back()]. All zero when disabled. Throws kInvalidArgument "times_s" for unsorted or
// non-finite times, "joints_at" for a wrong size or non-finite positions.
std::vector<Eigen::Matrix3Xd> segment_wobble(const std::function<Eigen::Matrix3Xd(double)>& joints_at,
                                             const std::vector<double>& times_s, const SoftTissueOptions& options);

// Applies segment displacements to a mesh: per vertex the weighted sum above, precomputed as a
// sparse (surface vertices x 24) matrix of w_vj * looseness(j). Vertices from surface_vertices
// on (the render model's ghosts) are left alone.
class SoftTissueSkin {
 public:
  SoftTissueSkin(const Eigen::SparseMatrix<double, Eigen::RowMajor>& weights, int surface_vertices);

  // vertices (3 x V, V >= surface_vertices) += rotation * displacement of each vertex;
  // `segment_displacement` is 3 x 24 in the frame that `rotation` maps to the vertices' frame.
  void apply(const Eigen::Matrix3Xd& segment_displacement, const Eigen::Matrix3d& rotation,
             Eigen::Matrix3Xd& vertices) const;

  const Eigen::SparseMatrix<double, Eigen::RowMajor>& loads() const { return loads_; }

 private:
  Eigen::SparseMatrix<double, Eigen::RowMajor> loads_;  // surface vertices x 24
};

}  // namespace posefuse::sim
