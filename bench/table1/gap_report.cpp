#include "gap_report.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>

#include "body/smpl_model.hpp"
#include "common/error.hpp"
#include "forearm/gap_input.hpp"
#include "forearm/occlusion_tests.hpp"
#include "sim/camera_skeleton.hpp"

namespace posefuse::bench {

namespace {

using geometry::Vec3;

Vec3 vec(const v1::Vec3& v) { return {v.x(), v.y(), v.z()}; }

// The truth's IMU position and velocity at any time inside the frames (linear between frames;
// velocity by central differences at the frames).
struct TruthTrack {
  const Table1Truth& truth;
  double t_s(std::size_t f) const { return static_cast<double>(truth.frame_t_us[f]) * 1e-6; }
  const Vec3& p(std::size_t f) const { return truth.forearm[f].imu_K_m; }
  Vec3 v(std::size_t f) const {
    const std::size_t a = f == 0 ? 0 : f - 1, b = std::min(f + 1, truth.frame_t_us.size() - 1);
    return (p(b) - p(a)) / (t_s(b) - t_s(a));
  }
  template <typename F>
  auto at(std::int64_t t_us, F value) const {
    const auto& t = truth.frame_t_us;
    const auto it = std::upper_bound(t.begin(), t.end(), t_us);
    const std::size_t b = std::clamp<std::size_t>(static_cast<std::size_t>(it - t.begin()), 1, t.size() - 1), a = b - 1;
    const double w = std::clamp(static_cast<double>(t_us - t[a]) / static_cast<double>(t[b] - t[a]), 0.0, 1.0);
    return ((1.0 - w) * value(a) + w * value(b)).eval();
  }
  Vec3 position(std::int64_t t_us) const {
    return at(t_us, [&](std::size_t f) { return p(f); });
  }
  Vec3 velocity(std::int64_t t_us) const {
    return at(t_us, [&](std::size_t f) { return v(f); });
  }
};

void print_boundary(const char* side, const std::vector<forearm::TrackSample>& track, const TruthTrack& truth,
                    std::int64_t t_us, int direction) {
  const std::int64_t window_us = 500000;
  double worst = 0.0;
  std::int64_t worst_t = 0;
  for (const forearm::TrackSample& s : track) {
    const std::int64_t d = (s.t_us - t_us) * direction;
    if (d < 0 || d > window_us) continue;
    const double e = (s.p_K - truth.position(s.t_us)).norm();
    if (e > worst) worst = e, worst_t = s.t_us;
  }
  try {
    const forearm::BoundaryState b = forearm::fit_boundary_line(track, t_us, direction, 0.5);
    const Vec3 v_true = truth.velocity(t_us);
    std::printf(
        " %s: %d samples, p err %.0f mm, v err %.2f m/s (|v| true %.2f, fit %.2f), worst sample %.0f mm at "
        "%+.2f s;",
        side, b.sample_count, 1e3 * (b.p_K - truth.position(t_us)).norm(), (b.v_K - v_true).norm(), v_true.norm(),
        b.v_K.norm(), 1e3 * worst, 1e-6 * static_cast<double>(worst_t - t_us));
  } catch (const Error&) {
    std::printf(" %s: no fit;", side);
  }
}

// The recovered trajectory's acceleration minus the truth's (both second differences at the
// truth's frame times, the recovery read linearly between its samples), mean per 0.5 s bin: where
// the inertial part goes wrong.
void print_acceleration_error(const v1::RecoveredSegment& s, const TruthTrack& truth) {
  const auto recovered = [&](std::int64_t t_us) {
    const auto& samples = s.samples();
    int k = 0;
    while (k + 2 < samples.size() && samples[k + 1].t_us() <= t_us) ++k;
    const double w = std::clamp(
        static_cast<double>(t_us - samples[k].t_us()) / static_cast<double>(samples[k + 1].t_us() - samples[k].t_us()),
        0.0, 1.0);
    return ((1.0 - w) * vec(samples[k].imu_m()) + w * vec(samples[k + 1].imu_m())).eval();
  };
  std::printf("    acceleration error (recovered - truth), m/s^2, mean per 0.5 s bin from the start [x y z]:");
  const std::int64_t h = 33333, bin = 500000;
  for (std::int64_t b0 = s.t_start_us() + h; b0 + h < s.t_end_us(); b0 += bin) {
    Vec3 sum = Vec3::Zero();
    int n = 0;
    for (std::int64_t t = b0; t < std::min(b0 + bin, s.t_end_us() - h); t += h) {
      const Vec3 a_rec = (recovered(t + h) - 2.0 * recovered(t) + recovered(t - h)) / (1e-12 * h * h);
      const Vec3 a_true = (truth.position(t + h) - 2.0 * truth.position(t) + truth.position(t - h)) / (1e-12 * h * h);
      sum += a_rec - a_true;
      ++n;
    }
    if (n > 0) std::printf(" [%+.2f %+.2f %+.2f]", sum.x() / n, sum.y() / n, sum.z() / n);
  }
  std::printf("\n");
}

// The elbows the smoother's anchor can follow, against the truth's elbow, mean distance per 0.5 s
// bin from the gap's start: the body fit's (SMPL joint, with its mean energy) and the camera
// skeleton's. Where the anchor pulls the recovery off.
void print_elbow_error(const v1::RecoveredSegment& s, const Table1Truth& truth,
                       const std::vector<v1::FitResult>& results, v1::Arm arm) {
  const bool left = arm == v1::LEFT;
  const int smpl_elbow = left ? body::kLeftElbow : body::kRightElbow,
            smpl_wrist = left ? body::kLeftWrist : body::kRightWrist;
  const int sdk_elbow = left ? geometry::kElbowLeft : geometry::kElbowRight;
  const auto truth_at = [&](std::int64_t t_us) -> const sim::ForearmTruth* {
    const auto f = std::lower_bound(truth.frame_t_us.begin(), truth.frame_t_us.end(), t_us);
    if (f == truth.frame_t_us.end() || *f != t_us) return nullptr;
    return &truth.forearm[static_cast<std::size_t>(f - truth.frame_t_us.begin())];
  };
  const std::int64_t bin = 500000;
  const auto bins = static_cast<std::size_t>((s.t_end_us() - s.t_start_us()) / bin + 1);
  std::vector<double> fit_sum(bins, 0.0), energy_sum(bins, 0.0), sdk_sum(bins, 0.0), angle_sum(bins, 0.0);
  std::vector<int> fit_n(bins, 0), sdk_n(bins, 0);
  const auto bin_of = [&](std::int64_t t_us) -> long {
    if (t_us < s.t_start_us() || t_us > s.t_end_us()) return -1;
    return static_cast<long>((t_us - s.t_start_us()) / bin);
  };
  for (const v1::FitResult& r : results) {
    if (!r.has_frame() || r.frame().smpl_joints_size() <= smpl_wrist) continue;
    const long b = bin_of(r.frame().t_us());
    const sim::ForearmTruth* t = truth_at(r.frame().t_us());
    if (b < 0 || !t) continue;
    const Vec3 elbow = vec(r.frame().smpl_joints(smpl_elbow).position_m());
    const Vec3 wrist = vec(r.frame().smpl_joints(smpl_wrist).position_m());
    fit_sum[static_cast<std::size_t>(b)] += (elbow - t->elbow_K_m).norm();
    energy_sum[static_cast<std::size_t>(b)] += r.frame().fit_energy();
    angle_sum[static_cast<std::size_t>(b)] +=
        forearm::forearm_direction_angle(elbow, wrist, t->K_from_F) * 180.0 / std::numbers::pi;
    ++fit_n[static_cast<std::size_t>(b)];
  }
  for (const v1::SkeletonFrame& k : truth.sdk) {
    const long b = bin_of(k.t_us());
    const sim::ForearmTruth* t = truth_at(k.t_us());
    if (b < 0 || !t || k.joints_size() <= sdk_elbow) continue;
    sdk_sum[static_cast<std::size_t>(b)] += (vec(k.joints(sdk_elbow).position_m()) - t->elbow_K_m).norm();
    ++sdk_n[static_cast<std::size_t>(b)];
  }
  std::printf("    elbow error, mm, mean per 0.5 s bin from the start, fit (energy, forearm axis error deg) / SDK:");
  for (std::size_t b = 0; b < bins; ++b) {
    if (fit_n[b] > 0) {
      std::printf(" %.0f (%.0f, %.0f)", 1e3 * fit_sum[b] / fit_n[b], energy_sum[b] / fit_n[b], angle_sum[b] / fit_n[b]);
    } else {
      std::printf(" -");
    }
    if (sdk_n[b] > 0) std::printf(" / %.0f", 1e3 * sdk_sum[b] / sdk_n[b]);
    std::printf(";");
  }
  std::printf("\n");
}

}  // namespace

void print_gap_report(const Table1Truth& truth, const std::vector<v1::FitResult>& results, const Table1Arm& arm) {
  const TruthTrack truth_track{truth};
  std::vector<forearm::TrackSample> track;
  for (const v1::FitResult& r : results) {
    if (!r.has_frame()) continue;
    for (const v1::ImuPosition& p : r.frame().imu_positions()) {
      if (p.device_id() == arm.device_id && p.source() == v1::VISUAL) {
        track.push_back({r.frame().t_us(), vec(p.position_m()), true});
      }
    }
  }
  // VISUAL samples far from the truth, or where the truth says the strap is hidden: false strap
  // detections (or true ones the truth's occlusion test calls hidden).
  for (const forearm::TrackSample& v : track) {
    const auto f = std::lower_bound(truth.frame_t_us.begin(), truth.frame_t_us.end(), v.t_us);
    const bool hidden = f != truth.frame_t_us.end() && *f == v.t_us &&
                        truth.forearm[static_cast<std::size_t>(f - truth.frame_t_us.begin())].occluded;
    const double e = (v.p_K - truth_track.position(v.t_us)).norm();
    if (hidden || e > 0.04) {
      std::printf("VISUAL at %.2f s: error %.0f mm%s\n", 1e-6 * static_cast<double>(v.t_us), 1e3 * e,
                  hidden ? ", truth: occluded" : "");
    }
  }
  std::printf("gaps of %s (per recovered segment; errors against the truth; + times are after the gap's start):\n",
              arm.device_id.c_str());
  for (const v1::FitResult& r : results) {
    if (!r.has_recovered_segment() || r.recovered_segment().arm() != arm.arm) continue;
    const v1::RecoveredSegment& s = r.recovered_segment();
    const char* method = s.method() == v1::RecoveredSegment::PAPER ? "paper" : "smoother";
    double peak = 0.0, sum2 = 0.0;
    std::int64_t peak_t = s.t_start_us();
    for (const auto& sample : s.samples()) {
      const double e = (vec(sample.imu_m()) - truth_track.position(sample.t_us())).norm();
      sum2 += e * e;
      if (e > peak) peak = e, peak_t = sample.t_us();
    }
    const double length_s = 1e-6 * static_cast<double>(s.t_end_us() - s.t_start_us());
    std::printf("  %s %.2f-%.2f s (%.2f s): RMS %.0f mm, peak %.0f mm at +%.2f s; ends %.0f / %.0f mm\n", method,
                1e-6 * static_cast<double>(s.t_start_us()), 1e-6 * static_cast<double>(s.t_end_us()), length_s,
                1e3 * std::sqrt(sum2 / std::max(1, s.samples_size())), 1e3 * peak,
                1e-6 * static_cast<double>(peak_t - s.t_start_us()),
                1e3 * (vec(s.samples(0).imu_m()) - truth_track.position(s.samples(0).t_us())).norm(),
                1e3 * (vec(s.samples(s.samples_size() - 1).imu_m()) -
                       truth_track.position(s.samples(s.samples_size() - 1).t_us()))
                          .norm());
    if (s.method() != v1::RecoveredSegment::SMOOTHER) continue;
    if (length_s > 1.0) {
      print_acceleration_error(s, truth_track);
      print_elbow_error(s, truth, results, arm.arm);
    }
    std::printf("   ");
    print_boundary("entry", track, truth_track, s.t_start_us(), -1);
    print_boundary("exit", track, truth_track, s.t_end_us(), +1);
    std::printf("\n");
  }
}

}  // namespace posefuse::bench
