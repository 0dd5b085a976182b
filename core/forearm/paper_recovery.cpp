#include "forearm/paper_recovery.hpp"

#include <vector>

namespace posefuse::forearm {

namespace {

// Trapezoidal integral of `rate` over `t_us` from `initial`, then bent by
// (final_value - end) (t_i - t_0) / (t_n - t_0) so that it ends at `final_value`
// (II-L.1 for velocity, II-L.2 for position).
std::vector<Vec3> integrate_to_end(const std::vector<std::int64_t>& t_us, const Vec3& initial,
                                   const std::vector<Vec3>& rate, const Vec3& final_value) {
  const std::size_t n = t_us.size();
  std::vector<Vec3> out(n);
  out[0] = initial;
  for (std::size_t i = 1; i < n; ++i) {
    const double dt = static_cast<double>(t_us[i] - t_us[i - 1]) * 1e-6;
    out[i] = out[i - 1] + 0.5 * (rate[i - 1] + rate[i]) * dt;
  }
  const Vec3 drift = final_value - out[n - 1];
  const double duration = static_cast<double>(t_us[n - 1] - t_us[0]);
  for (std::size_t i = 0; i < n; ++i) {
    out[i] += drift * (static_cast<double>(t_us[i] - t_us[0]) / duration);
  }
  return out;
}

}  // namespace

RecoveredGap recover_gap_paper(const GapRecoveryInput& input, const GapSpan& gap, const PaperRecoveryOptions& options) {
  const ArmTimeline arm = checked_gap_timeline(input, gap);

  // II-K.1: p0, v0 from the 500 ms before the gap; pn, vn from the 500 ms after it.
  const BoundaryState entry = fit_boundary_line(input.track, gap.t_start_us, -1, options.boundary_window_s);
  const BoundaryState exit = fit_boundary_line(input.track, gap.t_end_us, +1, options.boundary_window_s);

  RecoveredGap out;
  out.span = gap;
  out.t_us.push_back(gap.t_start_us);
  for (std::int64_t t : arm.arm_times_between(gap.t_start_us, gap.t_end_us)) out.t_us.push_back(t);
  out.t_us.push_back(gap.t_end_us);
  const std::size_t n = out.t_us.size();
  std::vector<Vec3> acc(n);
  for (std::size_t i = 0; i < n; ++i) {
    acc[i] = arm.net_acceleration_K(static_cast<double>(out.t_us[i]));  // eq. 12
  }
  // II-L.1: integrate from v0, then add (vn - vn') (t_i - t0) / (tn - t0).
  const std::vector<Vec3> vel = integrate_to_end(out.t_us, entry.v_K, acc, exit.v_K);
  // II-L.2: integrate from p0, then add (pn - pn') (t_i - t0) / (tn - t0).
  std::vector<Vec3> pos = integrate_to_end(out.t_us, entry.p_K, vel, exit.p_K);

  // II-L.3: shortest translation that puts the elbow d_ul from the shoulder (eq. 13).
  if (options.apply_shoulder_sphere) {
    for (std::size_t i = 0; i < n; ++i) {
      const double t = static_cast<double>(out.t_us[i]);
      pos[i] = snap_to_sphere(pos[i], arm.sphere_centre_K(t), input.model.d_ul_m);
    }
  }
  out.p_K = std::move(pos);
  return out;
}

}  // namespace posefuse::forearm
