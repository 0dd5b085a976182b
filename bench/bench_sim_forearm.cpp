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
#include "forearm/occlusion_tests.hpp"
#include "forearm/strap_detection.hpp"
#include "forearm/upper_arm_depth.hpp"
#include "session/chunk_file.hpp"
#include "session/image_codec.hpp"
#include "session/pipeline.hpp"
#include "session/result_reader.hpp"
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

geometry::PinholeCamera pinhole(const v1::CameraIntrinsics& c) {
  return {static_cast<int>(c.width()), static_cast<int>(c.height()), c.fx(), c.fy(), c.cx(), c.cy(),
          c.k1(), c.k2(), c.k3(), c.p1(), c.p2()};
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
  std::map<std::int64_t, cv::Mat> depth, color;
  std::deque<v1::SkeletonFrame> skeletons;
  std::printf("t_s arm occl | sdk_wrist_err axis_elbow_along axis_wrist_along axis_lat_err R | strap: miss frac "
              "along_err lat_err | d_se d_sw | check\n");
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
      const auto axes = forearm::measure_arm_axes(mm, cameras.depth, sh, el, wr);
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
            forearm::depth_points_near_segment(mm, cameras.depth, m_el - 0.05 * dir, m_wr + 0.15 * dir, 0.09);
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
        std::printf("| %.3f %.3f ", along(strap.strap_K, m_el, m_wr), (m_wr - m_el).norm() - along(strap.strap_K, m_el, m_wr));
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
        cameras.depth = pinhole(chunk.header().depth_intrinsics());
        cameras.color = pinhole(chunk.header().color_intrinsics());
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
    std::fprintf(stderr,
                 "usage: bench_sim_forearm replay SESSION.pfchunks GT_DIR OUT_DIR [--option KEY=VALUE]...\n"
                 "       bench_sim_forearm frames SESSION.pfchunks GT_DIR\n");
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_sim_forearm: %s\n", e.what());
    return 1;
  }
}
