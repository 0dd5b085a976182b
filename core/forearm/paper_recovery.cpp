#include "forearm/paper_recovery.hpp"

#include <string>

#include "common/error.hpp"

namespace posefuse::forearm {

void require_gap_boundaries(const GapSpan& gap) {
  if (gap.t_start_us < 0) throw_precondition("track.before_gap", "the gap starts the track: no visible sample before it");
  if (gap.t_end_us < 0) throw_precondition("track.after_gap", "the gap ends the track: no visible sample after it");
}

RecoveredGap recover_gap_paper(const GapRecoveryInput& input, const GapSpan& gap,
                               const PaperRecoveryOptions& options) {
  validate(input);
  require_gap_boundaries(gap);
  const ArmTimeline arm(input);
  arm.require_coverage(gap.t_start_us, gap.t_end_us, "arm");

  // II-K.1: p0, v0 from the 500 ms before the gap; pn, vn from the 500 ms after it.
  const BoundaryState entry = fit_boundary_line(input.track, gap.t_start_us, -1, options.boundary_window_s);
  const BoundaryState exit = fit_boundary_line(input.track, gap.t_end_us, +1, options.boundary_window_s);

  RecoveredGap out;
  out.span = gap;
  out.t_us.push_back(gap.t_start_us);
  for (std::int64_t t : arm.arm_times_between(gap.t_start_us, gap.t_end_us)) out.t_us.push_back(t);
  out.t_us.push_back(gap.t_end_us);
  const std::size_t n = out.t_us.size();
  const double duration = static_cast<double>(gap.t_end_us - gap.t_start_us) * 1e-6;
  std::vector<double> fraction(n);  // (t_i - t_0) / (t_n - t_0)
  std::vector<Vec3> acc(n), vel(n), pos(n);
  for (std::size_t i = 0; i < n; ++i) {
    fraction[i] = static_cast<double>(out.t_us[i] - gap.t_start_us) * 1e-6 / duration;
    acc[i] = arm.net_acceleration_K(static_cast<double>(out.t_us[i]));  // eq. 12
  }

  // II-L.1: integrate from v0, then add (vn - vn') (t_i - t0) / (tn - t0).
  vel[0] = entry.v_K;
  for (std::size_t i = 1; i < n; ++i) {
    const double dt = static_cast<double>(out.t_us[i] - out.t_us[i - 1]) * 1e-6;
    vel[i] = vel[i - 1] + 0.5 * (acc[i - 1] + acc[i]) * dt;
  }
  const Vec3 velocity_drift = exit.v_K - vel[n - 1];
  for (std::size_t i = 0; i < n; ++i) vel[i] += velocity_drift * fraction[i];

  // II-L.2: integrate from p0, then add (pn - pn') (t_i - t0) / (tn - t0).
  pos[0] = entry.p_K;
  for (std::size_t i = 1; i < n; ++i) {
    const double dt = static_cast<double>(out.t_us[i] - out.t_us[i - 1]) * 1e-6;
    pos[i] = pos[i - 1] + 0.5 * (vel[i - 1] + vel[i]) * dt;
  }
  const Vec3 position_drift = exit.p_K - pos[n - 1];
  for (std::size_t i = 0; i < n; ++i) pos[i] += position_drift * fraction[i];

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
