// The forearm stage on posefuse-sim sessions (the body render: clothing, hands, torso and head
// near the arm, RGB with the strap), two ways:
//
//   build/bench/bench_sim_forearm replay SESSION.pfchunks GT_DIR OUT_DIR
//     the chunk file through SessionPipeline(make_default_stages()), results written to OUT_DIR
//     by the client's ResultWriter, then scored against GT_DIR (posefuse-score's table).
//     `--option KEY=VALUE` (repeatable) sets a header option, e.g. --option fit.enabled=true.
//   build/bench/bench_sim_forearm frames SESSION.pfchunks GT_DIR
//     per camera frame and arm: the forearm axis measured in depth (measure_arm_axes) and the
//     strap (detect_strap) against the simulator's truth (gt/camera_joints.csv, the strap centre
//     from gt/imu_positions.csv and gt/forearms.csv), and the II-J verdict with the truth's
//     K_from_F. A diagnostic: the truth only scores here, the methods never see it.
//   build/bench/bench_sim_forearm pose SESSION.pfchunks GT_DIR T0_S T1_S
//     per camera frame in [T0_S, T1_S] and arm: the calibration pose's forearm frame
//     (K_from_F_calibration_pose) from the axes measured in depth against the truth's K_from_F,
//     as a rotation vector in F (y: the roll about the forearm), with the measured upper arm's
//     and forearm's direction errors, split into the part towards the camera and the rest;
//     `slices`: also the upper arm's visible width and surface offset in 2 cm slices along the
//     true axis (its taper).
//   build/bench/bench_sim_forearm split RESULT_DIR GT_DIR DEVICE HOLD_T0_S HOLD_T1_S
//     one arm's K_from_F error (eq. 11: K_from_W * W_from_A * A_from_F) split into its factors:
//     the RMS with each factor replaced by the truth in turn, the calibration's error against the
//     truth over the hold [HOLD_T0_S, HOLD_T1_S] (mounting and strap slip then) with the part of
//     the calibration pose's frame, and bounds (slip only; the best constant A_from_F). RESULT_DIR
//     from `replay`; the truth only scores.
//
// SESSION and GT_DIR come from posefuse-sim (e.g. --options with motion = forearm_protocol,
// arm = both; --chunk-file SESSION --gt GT_DIR).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <deque>
#include <filesystem>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "bench_clock.hpp"
#include "client/result_writer.hpp"
#include "eval/result_score.hpp"
#include "forearm/forearm_orientation.hpp"
#include "forearm/occlusion_tests.hpp"
#include "forearm/strap_detection.hpp"
#include "forearm/upper_arm_depth.hpp"
#include "session/chunk_file.hpp"
#include "session/image_codec.hpp"
#include "session/pipeline.hpp"
#include "session/result_reader.hpp"
#include "session/session_inputs.hpp"
#include "session/stages/default_stages.hpp"

namespace {

using namespace posefuse;
namespace fs = std::filesystem;
using geometry::Quat;
using geometry::Vec3;

// `options`: KEY=VALUE pairs set in the session header (e.g. fit.enabled=true), over the file's.
int replay(const fs::path& chunks, const fs::path& gt, const fs::path& out, const std::vector<std::string>& options) {
  const double cpu0 = bench::thread_cpu_seconds();
  const auto wall0 = bench::WallClock::now();
  fs::remove_all(out);
  {
    client::ResultWriter writer(out);
    client::ResultWriterSink results(writer);
    session::SessionPipeline pipeline(session::make_default_stages(), results);
    session::ChunkFileReader reader(chunks);
    v1::SessionChunk chunk;
    while (reader.next(chunk)) {
      if (chunk.has_header()) {
        for (const std::string& kv : options) {
          const auto eq = kv.find('=');
          if (eq == std::string::npos) throw std::invalid_argument("--option '" + kv + "': expected KEY=VALUE");
          (*chunk.mutable_header()->mutable_options())[kv.substr(0, eq)] = kv.substr(eq + 1);
        }
      }
      pipeline.push(chunk);
    }
    pipeline.close();
    writer.finish();
  }
  const double cpu_s = bench::thread_cpu_seconds() - cpu0, wall_s = 1e-3 * bench::wall_ms_since(wall0);
  std::printf("%s", eval::format_score_report(eval::score_directories(out, gt)).c_str());
  std::printf("\npipeline: %.2f s CPU (this thread), %.2f s wall\n", cpu_s, wall_s);
  return 0;
}

struct Truth {
  std::map<std::int64_t, std::map<int, Vec3>> joints;  // t -> Kinect joint -> p_K
  std::map<std::pair<std::int64_t, std::string>, Vec3> imu;
  std::map<std::pair<std::int64_t, int>, Quat> K_from_F;  // arm 0 left, 1 right
  std::map<std::pair<std::int64_t, int>, bool> occluded;
  double r_m[2] = {0.035, 0.035};
};

Truth read_truth(const fs::path& gt) {
  const session::ResultDirectory d = session::read_result_files(gt);
  Truth t;
  for (const auto& j : d.camera_joints) t.joints[j.t_us][j.joint] = j.p_K;
  for (const auto& p : d.imu_positions) t.imu[{p.t_us, p.device_id}] = p.p_K;
  for (const auto& f : d.forearms) t.K_from_F[{f.t_us, f.arm == v1::LEFT ? 0 : 1}] = f.K_from_F;
  if (d.calibration) {
    for (const auto& m : d.calibration->forearms()) t.r_m[m.arm() == v1::LEFT ? 0 : 1] = m.r_m();
  }
  // occlusion.csv: t_us,arm,forearm_visible_fraction,forearm_occluded,strap_visible
  if (FILE* f = std::fopen((gt / "occlusion.csv").c_str(), "r")) {
    char line[256];
    std::fgets(line, sizeof line, f);
    while (std::fgets(line, sizeof line, f)) {
      long long t_us = 0;
      char arm[16] = {};
      double fraction = 0;
      int occluded = 0, strap = 0;
      if (std::sscanf(line, "%lld,%15[^,],%lf,%d,%d", &t_us, arm, &fraction, &occluded, &strap) == 5) {
        t.occluded[{t_us, std::string(arm) == "LEFT" ? 0 : 1}] = occluded != 0 || strap == 0;
      }
    }
    std::fclose(f);
  }
  return t;
}

double along(const Vec3& p, const Vec3& elbow, const Vec3& wrist) {
  return (p - elbow).dot((wrist - elbow).normalized());
}

int frames(const fs::path& chunks, const fs::path& gt, std::optional<double> profile_t) {
  const Truth truth = read_truth(gt);
  session::ChunkFileReader reader(chunks);
  v1::SessionChunk chunk;
  forearm::StrapCameras cameras;
  std::optional<geometry::PixelRays> depth_rays;  // cameras.depth's
  std::map<std::int64_t, cv::Mat> depth, color;
  std::deque<v1::SkeletonFrame> skeletons;
  std::printf(
      "t_s arm occl | sdk_wrist_err axis_elbow_along axis_wrist_along axis_lat_err R | strap: miss frac "
      "along_err lat_err | d_se d_sw | strap_front_of_axis strap_axis_distance | check\n");
  const auto process = [&](const v1::SkeletonFrame& s) {
    const auto jt = truth.joints.find(s.t_us());
    if (jt == truth.joints.end()) return;
    const auto d = depth.find(s.t_us());
    auto c = color.lower_bound(s.t_us() - 20000);
    if (d == depth.end() || c == color.end() || std::abs(c->first - s.t_us()) > 20000) return;
    const forearm::DepthImageView mm{d->second.cols, d->second.rows, d->second.ptr<std::uint16_t>()};
    const forearm::GrayImageView gray{c->second.cols, c->second.rows, c->second.ptr<std::uint8_t>()};
    for (int arm = 0; arm < 2; ++arm) {
      const int js = arm == 0 ? 4 : 8;
      const Vec3 sh = {s.joints(js).position_m().x(), s.joints(js).position_m().y(), s.joints(js).position_m().z()};
      const Vec3 el = {s.joints(js + 1).position_m().x(), s.joints(js + 1).position_m().y(),
                       s.joints(js + 1).position_m().z()};
      const Vec3 wr = {s.joints(js + 2).position_m().x(), s.joints(js + 2).position_m().y(),
                       s.joints(js + 2).position_m().z()};
      const Vec3 t_el = jt->second.at(js + 1), t_wr = jt->second.at(js + 2);
      const std::string device = arm == 0 ? "imu_left" : "imu_right";
      const auto imu = truth.imu.find({s.t_us(), device});
      const auto q = truth.K_from_F.find({s.t_us(), arm});
      if (imu == truth.imu.end() || q == truth.K_from_F.end()) continue;
      const Vec3 t_strap = imu->second - q->second * Vec3(truth.r_m[arm], 0, 0);
      const bool occluded = truth.occluded.count({s.t_us(), arm}) ? truth.occluded.at({s.t_us(), arm}) : false;
      std::printf("%.3f %c %d | %+.3f ", 1e-6 * s.t_us(), arm == 0 ? 'L' : 'R', occluded ? 1 : 0,
                  along(wr, t_el, t_wr) - (t_wr - t_el).norm());
      const auto axes = forearm::measure_arm_axes(mm, *depth_rays, sh, el, wr);
      Vec3 m_el = el, m_wr = wr;
      if (axes) {
        m_el = axes->forearm.elbow_K;
        m_wr = axes->forearm.wrist_K;
        const Vec3 dir = (t_wr - t_el).normalized();
        const Vec3 off = m_el - t_el;
        std::printf("%+.3f %+.3f %.3f %.3f ", along(m_el, t_el, t_wr), along(m_wr, t_el, t_wr) - (t_wr - t_el).norm(),
                    (off - off.dot(dir) * dir).norm(), axes->forearm.radius_m);
      } else {
        std::printf("axis-none ");
      }
      if (axes && profile_t && std::abs(1e-6 * s.t_us() - *profile_t) < 0.017) {
        const Vec3 dir = (m_wr - m_el).normalized();
        const Vec3 ray = (0.5 * (m_el + m_wr)).normalized();
        const Vec3 lat = dir.cross(ray).normalized();
        const std::vector<Vec3> pts =
            forearm::depth_points_near_segment(mm, *depth_rays, m_el - 0.05 * dir, m_wr + 0.15 * dir, 0.09);
        const double tw = along(t_wr, m_el, m_wr);
        std::map<int, std::vector<double>> slices;
        std::map<int, std::vector<double>> depths;
        for (const Vec3& p : pts) {
          const Vec3 d = p - m_el;
          const double a = d.dot(dir);
          const Vec3 perp = d - a * dir;
          if (perp.norm() > 0.09) continue;
          slices[static_cast<int>(std::floor((a - tw) / 0.01))].push_back(perp.dot(lat));
          depths[static_cast<int>(std::floor((a - tw) / 0.01))].push_back(perp.dot(ray.cross(lat).cross(lat)));
        }
        std::printf("\n  profile (cm from the true wrist; measured wrist at %+.1f, elbow at %+.1f):\n",
                    100 * ((m_wr - m_el).norm() - tw), -100 * tw);
        for (auto& [k, v] : slices) {
          std::sort(v.begin(), v.end());
          const double lo = v[v.size() / 20], hi = v[v.size() - 1 - v.size() / 20];
          double dmin = 1e9, dmax = -1e9;
          for (double z : depths[k]) dmin = std::min(dmin, z), dmax = std::max(dmax, z);
          std::printf("  %+3d n=%3zu width=%.3f lat=[%+.3f %+.3f] depth_range=%.3f\n", k, v.size(), hi - lo, lo, hi,
                      dmax - dmin);
        }
      }
      const forearm::StrapDetection strap = forearm::detect_strap(gray, mm, cameras, m_el, m_wr);
      std::printf("| %d %.2f ", static_cast<int>(strap.miss), strap.fraction);
      if (strap.found()) {
        const Vec3 dir = (t_wr - t_el).normalized();
        const Vec3 e = strap.strap_K - t_strap;
        std::printf("%+.3f %.3f ", e.dot(dir), (e - e.dot(dir) * dir).norm());
        std::printf("| %.3f %.3f ", along(strap.strap_K, m_el, m_wr),
                    (m_wr - m_el).norm() - along(strap.strap_K, m_el, m_wr));
        {
          // The strap's offset from the measured axis towards the camera, and its distance from it.
          const Vec3 axis = (m_wr - m_el).normalized();
          const Vec3 off = strap.strap_K - m_el - (strap.strap_K - m_el).dot(axis) * axis;
          const Vec3 ray = strap.strap_K.normalized();
          const Vec3 to_camera = -(ray - ray.dot(axis) * axis).normalized();
          std::printf("| front %+.3f dist %.3f ", off.dot(to_camera), off.norm());
          // The same against the line from the measured elbow along the truth's forearm axis (the
          // IMU's, in the pipeline).
          const Vec3 imu_axis = q->second * Vec3::UnitY();
          const Vec3 imu_off = strap.strap_K - m_el - (strap.strap_K - m_el).dot(imu_axis) * imu_axis;
          const Vec3 imu_to_camera = -(ray - ray.dot(imu_axis) * imu_axis).normalized();
          std::printf("imu_front %+.3f imu_dist %.3f ", imu_off.dot(imu_to_camera), imu_off.norm());
        }
        const forearm::VisualCheck check = forearm::check_visual_forearm(m_el, m_wr, strap.strap_K, q->second);
        std::printf("| %s\n", forearm::visual_rejection_name(check.rejection));
      } else {
        std::printf("\n");
      }
    }
  };
  while (reader.next(chunk)) {
    switch (chunk.chunk_case()) {
      case v1::SessionChunk::kHeader:
        cameras.depth = session::pinhole_camera(chunk.header().depth_intrinsics());
        depth_rays.emplace(cameras.depth);
        cameras.color = session::pinhole_camera(chunk.header().color_intrinsics());
        {
          const auto& r = chunk.header().color_from_depth().rotation();
          const auto& t = chunk.header().color_from_depth().translation_m();
          cameras.color_from_depth = Quat(r.w(), r.x(), r.y(), r.z()).normalized();
          cameras.color_from_depth_m = Vec3(t.x(), t.y(), t.z());
        }
        break;
      case v1::SessionChunk::kDepth: depth[chunk.depth().t_us()] = session::decode_depth(chunk.depth()); break;
      case v1::SessionChunk::kColor: color[chunk.color().t_us()] = session::decode_color_gray(chunk.color()); break;
      case v1::SessionChunk::kSkeleton: skeletons.push_back(chunk.skeleton()); break;
      default: break;
    }
    // A skeleton is processed once both images of a later time have arrived.
    while (!skeletons.empty() && !depth.empty() && !color.empty() &&
           depth.rbegin()->first > skeletons.front().t_us() + 40000 &&
           color.rbegin()->first > skeletons.front().t_us() + 40000) {
      process(skeletons.front());
      const std::int64_t t = skeletons.front().t_us();
      skeletons.pop_front();
      std::erase_if(depth, [&](const auto& e) { return e.first < t - 100000; });
      std::erase_if(color, [&](const auto& e) { return e.first < t - 100000; });
    }
  }
  for (const auto& s : skeletons) process(s);
  return 0;
}

// Angle of `measured` from `truth` (unit directions), in degrees: towards the camera (the
// component of the difference along the viewing ray made perpendicular to the truth) and the rest.
std::pair<double, double> direction_error_deg(const Vec3& measured, const Vec3& truth, const Vec3& ray) {
  const Vec3 depth_axis = (ray - ray.dot(truth) * truth).normalized();
  const Vec3 side_axis = truth.cross(depth_axis);
  const double to_deg = 180.0 / 3.14159265358979323846;
  return {to_deg * std::atan2(measured.dot(depth_axis), measured.dot(truth)),
          to_deg * std::atan2(measured.dot(side_axis), measured.dot(truth))};
}

int pose_frames(const fs::path& chunks, const fs::path& gt, double t0_s, double t1_s, bool print_slices) {
  const Truth truth = read_truth(gt);
  session::ChunkFileReader reader(chunks);
  v1::SessionChunk chunk;
  std::optional<geometry::PixelRays> depth_rays;
  std::map<std::int64_t, cv::Mat> depth;
  std::printf(
      "t_s arm | upper_arm_err_deg depth side | forearm_err_deg depth side | pose_frame_err_F_deg x y z | "
      "upper_arm_R upper_arm_points\n");
  const auto vec = [](const v1::SkeletonJoint& j) {
    return Vec3(j.position_m().x(), j.position_m().y(), j.position_m().z());
  };
  while (reader.next(chunk)) {
    if (chunk.chunk_case() == v1::SessionChunk::kHeader)
      depth_rays.emplace(session::pinhole_camera(chunk.header().depth_intrinsics()));
    if (chunk.chunk_case() == v1::SessionChunk::kDepth)
      depth[chunk.depth().t_us()] = session::decode_depth(chunk.depth());
    if (chunk.chunk_case() != v1::SessionChunk::kSkeleton) continue;
    const v1::SkeletonFrame& s = chunk.skeleton();
    if (1e-6 * s.t_us() < t0_s || 1e-6 * s.t_us() > t1_s) continue;
    const auto jt = truth.joints.find(s.t_us());
    const auto d = depth.find(s.t_us());
    if (jt == truth.joints.end() || d == depth.end()) continue;
    const forearm::DepthImageView mm{d->second.cols, d->second.rows, d->second.ptr<std::uint16_t>()};
    for (int arm = 0; arm < 2; ++arm) {
      const int js = arm == 0 ? 4 : 8;
      const auto q = truth.K_from_F.find({s.t_us(), arm});
      if (q == truth.K_from_F.end()) continue;
      const Vec3 sh = vec(s.joints(js)), el = vec(s.joints(js + 1)), wr = vec(s.joints(js + 2));
      const Vec3 t_sh = jt->second.at(js), t_el = jt->second.at(js + 1), t_wr = jt->second.at(js + 2);
      const auto axes = forearm::measure_arm_axes(mm, *depth_rays, sh, el, wr);
      std::printf("%.3f %c | ", 1e-6 * s.t_us(), arm == 0 ? 'L' : 'R');
      if (!axes || !axes->upper_arm) {
        std::printf("%s\n", axes ? "no upper arm" : "no forearm");
        continue;
      }
      const Vec3 m_el = axes->forearm.elbow_K, m_wr = axes->forearm.wrist_K;
      const auto [ua_depth, ua_side] =
          direction_error_deg(axes->upper_arm->direction_K, (t_el - t_sh).normalized(), t_el.normalized());
      const auto [fa_depth, fa_side] =
          direction_error_deg((m_wr - m_el).normalized(), (t_wr - t_el).normalized(), t_el.normalized());
      std::printf("%+6.2f %+6.2f | %+6.2f %+6.2f | ", ua_depth, ua_side, fa_depth, fa_side);
      try {
        const Vec3 plane_shoulder = m_el - (sh - m_el).norm() * axes->upper_arm->direction_K;
        const Quat K_from_F = forearm::K_from_F_calibration_pose(plane_shoulder, m_el, m_wr);
        const Vec3 e =
            (180.0 / 3.14159265358979323846) * geometry::rotation_vector_from_quat(q->second.conjugate() * K_from_F);
        std::printf("%+6.2f %+6.2f %+6.2f | ", e.x(), e.y(), e.z());
      } catch (const Error& error) {
        std::printf("(%s) | ", error.what());
      }
      std::printf("%.3f %d\n", axes->upper_arm->radius_m, axes->upper_arm->points);
      if (print_slices) {
        // The upper arm's visible surface in 2 cm slices along the true axis: visible width and
        // the surface's mean offset from the true axis towards the camera.
        const Vec3 dir = (t_el - t_sh).normalized();
        const Vec3 to_camera = -(t_el - t_el.dot(dir) * dir).normalized();
        const Vec3 lat = dir.cross(to_camera);
        std::map<int, std::vector<std::pair<double, double>>> slices;
        for (const Vec3& p : forearm::depth_points_near_segment(mm, *depth_rays, t_sh, t_el, 0.09)) {
          const double a = (p - t_sh).dot(dir);
          slices[static_cast<int>(std::floor(a / 0.02))].push_back({(p - t_sh).dot(lat), (p - t_sh).dot(to_camera)});
        }
        for (const auto& [k, v] : slices) {
          double m = 0, m2 = 0, dz = 0;
          for (const auto& [l, z] : v) m += l / v.size(), m2 += l * l / v.size(), dz += z / v.size();
          std::printf("    slice %+3d cm n=%3zu width=%.3f lat_mean=%+.3f toward_camera=%+.3f\n", 2 * k, v.size(),
                      std::sqrt(12 * (m2 - m * m)), m, dz);
        }
      }
    }
    std::erase_if(depth, [&](const auto& e) { return e.first < s.t_us() - 100000; });
  }
  return 0;
}

Quat quat_of(const v1::Quaternion& q) { return Quat(q.w(), q.x(), q.y(), q.z()).normalized(); }

// Chordal mean of hemisphere-aligned unit quaternions.
Quat mean_of(const std::vector<Quat>& qs) {
  Eigen::Vector4d sum = Eigen::Vector4d::Zero();
  for (const Quat& q : qs) sum += geometry::to_wxyz(geometry::same_hemisphere(q, qs.front()));
  return geometry::from_wxyz(sum.normalized());
}

double deg_between(const Quat& a, const Quat& b) {
  return geometry::angle_between(a, b) * 180.0 / 3.14159265358979323846;
}

int split(const fs::path& result_dir, const fs::path& gt_dir, const std::string& device, double hold_t0_s,
          double hold_t1_s) {
  const session::ResultDirectory result = session::read_result_files(result_dir);
  const session::ResultDirectory truth = session::read_result_files(gt_dir);
  if (!result.calibration || !truth.calibration) throw std::runtime_error("calibration.json missing");
  const v1::Arm arm = device == "imu_left" ? v1::LEFT : v1::RIGHT;
  const auto A_from_F_of = [&](const v1::CalibrationReport& c) -> std::optional<Quat> {
    for (const v1::ForearmModel& f : c.forearms()) {
      if (f.arm() == arm) return quat_of(f.a_from_f());
    }
    return std::nullopt;
  };
  const Quat KW_e = quat_of(result.calibration->k_from_w()), KW_t = quat_of(truth.calibration->k_from_w());
  const std::optional<Quat> AF_e = A_from_F_of(*result.calibration), AF_mount = A_from_F_of(*truth.calibration);
  if (!AF_e || !AF_mount) throw std::runtime_error("no forearm calibration for " + device);
  const auto by_time = [](const std::vector<session::TimedOrientation>& rows) {
    std::map<std::int64_t, Quat> m;
    for (const auto& r : rows) m[r.t_us] = r.q;
    return m;
  };
  const auto WA_e = by_time(result.imu_orientations.at(device)), WA_t = by_time(truth.imu_orientations.at(device));
  const auto KF_e = by_time(result.forearm_orientations.at(device)),
             KF_t = by_time(truth.forearm_orientations.at(device));
  const auto nearest = [](const std::map<std::int64_t, Quat>& m, std::int64_t t,
                          std::int64_t tolerance) -> const Quat* {
    const Quat* best = nullptr;
    std::int64_t best_dt = tolerance + 1;
    auto it = m.lower_bound(t);
    for (int k = 0; k < 2; ++k) {
      if (it != m.end() && std::abs(it->first - t) < best_dt) best = &it->second, best_dt = std::abs(it->first - t);
      if (it == m.begin()) break;
      --it;
    }
    return best;
  };
  // gt/imu_samples/<device>.csv: t_device_us,t_camera_us,lost,... (each sample's true camera time).
  struct Row {
    std::int64_t t_camera_us;
    Quat WA_t, WA_e, KF_t, KF_e;
  };
  std::vector<Row> rows;
  FILE* f = std::fopen((gt_dir / "imu_samples" / (device + ".csv")).c_str(), "r");
  if (!f) throw std::runtime_error("no gt imu_samples for " + device);
  char line[512];
  std::fgets(line, sizeof line, f);
  while (std::fgets(line, sizeof line, f)) {
    long long t_device = 0, t_camera = 0;
    int lost = 0;
    if (std::sscanf(line, "%lld,%lld,%d", &t_device, &t_camera, &lost) != 3 || lost) continue;
    const auto wt = WA_t.find(t_device), we = WA_e.find(t_device);
    const Quat* kt = nearest(KF_t, t_camera, 1);
    const Quat* ke = nearest(KF_e, t_camera, 2000);
    if (wt == WA_t.end() || we == WA_e.end() || !kt || !ke) continue;
    rows.push_back({t_camera, wt->second, we->second, *kt, *ke});
  }
  std::fclose(f);
  if (rows.empty()) throw std::runtime_error("no samples matched");
  std::vector<Quat> hold_truth, hold_true_pose;
  for (const Row& r : rows) {
    if (r.t_camera_us < hold_t0_s * 1e6 || r.t_camera_us > hold_t1_s * 1e6) continue;
    hold_truth.push_back((KW_t * r.WA_t).conjugate() * r.KF_t);      // mounting and slip then
    hold_true_pose.push_back((KW_e * r.WA_e).conjugate() * r.KF_t);  // eq. 9 with the true pose frame
  }
  if (hold_truth.empty()) throw std::runtime_error("no samples in the hold");
  const Quat AF_hold = mean_of(hold_truth), AF_true_pose = mean_of(hold_true_pose);
  std::vector<Quat> all_true_pose;
  for (const Row& r : rows) all_true_pose.push_back((KW_e * r.WA_e).conjugate() * r.KF_t);
  const Quat AF_best = mean_of(all_true_pose);
  std::printf("%s: %zu samples, %zu in the hold %.2f-%.2f s\n", device.c_str(), rows.size(), hold_truth.size(),
              hold_t0_s, hold_t1_s);
  std::printf(
      "K_from_W error %.2f deg; A_from_F: %.2f deg from the mounting, %.2f from the truth over the hold "
      "(the hold's truth %.2f from the mounting);\n",
      deg_between(KW_e, KW_t), deg_between(*AF_e, *AF_mount), deg_between(*AF_e, AF_hold),
      deg_between(AF_hold, *AF_mount));
  const Vec3 pose_part =
      (180.0 / 3.14159265358979323846) * geometry::rotation_vector_from_quat(AF_true_pose.conjugate() * *AF_e);
  std::printf(
      "  of which the calibration pose's frame %.2f deg (in F: x %+.2f, y (roll) %+.2f, z %+.2f), "
      "K_from_A in the hold %.2f deg\n",
      pose_part.norm(), pose_part.x(), pose_part.y(), pose_part.z(), deg_between(AF_true_pose, AF_hold));
  const auto score = [&](const char* name, const auto& K_from_F_of) {
    double sum_sq = 0.0, max_deg = 0.0;
    Vec3 mean = Vec3::Zero();
    for (const Row& r : rows) {
      const Quat q = K_from_F_of(r);
      const double e = deg_between(r.KF_t, q);
      sum_sq += e * e;
      max_deg = std::max(max_deg, e);
      mean += (180.0 / 3.14159265358979323846) * geometry::rotation_vector_from_quat(r.KF_t.conjugate() * q);
    }
    mean /= static_cast<double>(rows.size());
    std::printf("  %-62s RMS %5.2f  max %5.2f  mean in F %+5.2f %+5.2f %+5.2f\n", name, std::sqrt(sum_sq / rows.size()),
                max_deg, mean.x(), mean.y(), mean.z());
  };
  std::printf("K_from_F error (deg), eq. 11 with:\n");
  score("the result file's K_from_F", [](const Row& r) { return r.KF_e; });
  score("all estimated", [&](const Row& r) { return Quat(KW_e * r.WA_e * *AF_e); });
  score("the true K_from_W", [&](const Row& r) { return Quat(KW_t * r.WA_e * *AF_e); });
  score("the true W_from_A", [&](const Row& r) { return Quat(KW_e * r.WA_t * *AF_e); });
  score("the true A_from_F (mounting, no slip)", [&](const Row& r) { return Quat(KW_e * r.WA_e * *AF_mount); });
  score("the truth's A_from_F over the hold", [&](const Row& r) { return Quat(KW_e * r.WA_e * AF_hold); });
  score("eq. 9 with the true pose frame", [&](const Row& r) { return Quat(KW_e * r.WA_e * AF_true_pose); });
  score("all true, A_from_F over the hold (the slip since)",
        [&](const Row& r) { return Quat(KW_t * r.WA_t * AF_hold); });
  score("all true, the mounting (the slip)", [&](const Row& r) { return Quat(KW_t * r.WA_t * *AF_mount); });
  score("the best constant A_from_F (a bound)", [&](const Row& r) { return Quat(KW_e * r.WA_e * AF_best); });
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    const std::string mode = argc > 1 ? argv[1] : "";
    if (mode == "replay" && argc >= 5) {
      std::vector<std::string> options;
      for (int i = 5; i + 1 < argc && std::string(argv[i]) == "--option"; i += 2) options.push_back(argv[i + 1]);
      if (argc == 5 + 2 * static_cast<int>(options.size())) return replay(argv[2], argv[3], argv[4], options);
    }
    if (mode == "frames" && (argc == 4 || argc == 5)) {
      return frames(argv[2], argv[3], argc == 5 ? std::optional<double>(std::stod(argv[4])) : std::nullopt);
    }
    if (mode == "split" && argc == 7) return split(argv[2], argv[3], argv[4], std::stod(argv[5]), std::stod(argv[6]));
    if (mode == "pose" && (argc == 6 || (argc == 7 && std::string(argv[6]) == "slices"))) {
      return pose_frames(argv[2], argv[3], std::stod(argv[4]), std::stod(argv[5]), argc == 7);
    }
    std::fprintf(stderr,
                 "usage: bench_sim_forearm replay SESSION.pfchunks GT_DIR OUT_DIR [--option KEY=VALUE]...\n"
                 "       bench_sim_forearm frames SESSION.pfchunks GT_DIR\n"
                 "       bench_sim_forearm pose SESSION.pfchunks GT_DIR T0_S T1_S [slices]\n"
                 "       bench_sim_forearm split RESULT_DIR GT_DIR DEVICE HOLD_T0_S HOLD_T1_S\n");
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_sim_forearm: %s\n", e.what());
    return 1;
  }
}
