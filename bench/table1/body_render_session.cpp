#include "body_render_session.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <optional>

#include "bench_clock.hpp"
#include "common/error.hpp"
#include "session/chunk_order.hpp"
#include "session/pipeline.hpp"
#include "session/stages/default_stages.hpp"

namespace posefuse::bench {

namespace {

struct ResultCollector : session::ResultSink {
  void emit(v1::FitResult&& result) override { results.push_back(std::move(result)); }
  std::vector<v1::FitResult> results;
};

// The simulator's chunks go straight into the pipeline on the writer's thread.
class PipelineChunkSink : public session::ChunkSink {
 public:
  PipelineChunkSink(ResultCollector& results, BodyRenderRun& run,
                    const std::map<std::string, std::string>& header_options, bool hold)
      : pipeline_(session::make_default_stages(), results), run_(run), header_options_(header_options), hold_(hold) {}
  void write(const v1::SessionChunk& chunk) override {
    if (hold_) {
      held_.push_back(chunk);
      return;
    }
    push(chunk);
  }
  // The held chunks in camera-time order (the truth's clocks), then pushed.
  void release(const sim::SimTruth& truth) {
    const auto camera_us = [&](const std::string& device_id, std::int64_t t_device_us) -> std::optional<std::int64_t> {
      for (const sim::SimDeviceTruth& d : truth.devices) {
        if (d.device_id != device_id || d.t_device_us.empty()) continue;
        const auto it = std::lower_bound(d.t_device_us.begin(), d.t_device_us.end(), t_device_us);
        const std::size_t i = std::min(static_cast<std::size_t>(it - d.t_device_us.begin()), d.t_device_us.size() - 1);
        return static_cast<std::int64_t>(std::llround(1e6 * d.t_camera_s[i]));
      }
      return std::nullopt;
    };
    std::vector<std::pair<std::int64_t, std::size_t>> order;  // camera time, held index
    for (std::size_t i = 0; i < held_.size(); ++i) {
      const v1::SessionChunk& c = held_[i];
      std::int64_t t = 0;
      if (c.has_header()) {
        t = std::numeric_limits<std::int64_t>::min();
      } else if (c.has_end()) {
        t = std::numeric_limits<std::int64_t>::max();
      } else if (c.has_imu() && c.imu().t_us_size() > 0) {
        t = camera_us(c.imu().device_id(), c.imu().t_us(c.imu().t_us_size() - 1)).value_or(0);
      } else if (c.has_sync_event()) {
        t = camera_us(c.sync_event().device_id(), c.sync_event().t_us()).value_or(c.sync_event().t_us());
      } else {
        t = session::chunk_order_key(c, held_.front().header()).t_us;  // the camera's own clock
      }
      order.emplace_back(t, i);
    }
    std::stable_sort(order.begin(), order.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
    for (const auto& [t, i] : order) push(held_[i]);
    held_.clear();
  }
  void finish() override {
    const double cpu0 = thread_cpu_seconds();
    pipeline_.close();
    run_.pipeline_cpu_s += thread_cpu_seconds() - cpu0;
  }

 private:
  void push(const v1::SessionChunk& chunk) {
    if (chunk.has_skeleton()) run_.sdk.push_back(chunk.skeleton());
    const double cpu0 = thread_cpu_seconds();
    if (chunk.has_header()) {
      v1::SessionChunk with_options = chunk;
      for (const auto& [key, value] : header_options_) (*with_options.mutable_header()->mutable_options())[key] = value;
      pipeline_.push(with_options);
    } else {
      pipeline_.push(chunk);
    }
    run_.pipeline_cpu_s += thread_cpu_seconds() - cpu0;
  }

  session::SessionPipeline pipeline_;
  BodyRenderRun& run_;
  std::map<std::string, std::string> header_options_;
  bool hold_;
  std::vector<v1::SessionChunk> held_;
};

// Index of the arm's IMU in SimTruth::devices (arm IMUs first, left before right).
std::size_t device_index(const sim::SimTruth& truth, int arm) {
  for (std::size_t d = 0; d < truth.devices.size(); ++d) {
    if (truth.devices[d].device_id == truth.arms[static_cast<std::size_t>(arm)].device_id) return d;
  }
  throw_invalid("arm", "has no IMU in the session");
}

}  // namespace

BodyRenderRun run_body_render_session(const sim::SimSessionOptions& options,
                                      const std::map<std::string, std::string>& header_options, bool live_order) {
  BodyRenderRun run;
  ResultCollector results;
  {
    PipelineChunkSink sink(results, run, header_options, live_order);
    run.truth = sim::simulate_session(options, sink);
    if (live_order) sink.release(run.truth);
    sink.finish();
  }
  run.results = std::move(results.results);
  return run;
}

bool has_arm(const BodyRenderRun& run, int arm) { return run.truth.arms.at(static_cast<std::size_t>(arm)).has_imu; }

Table1Truth body_render_truth(const BodyRenderRun& run, int arm) {
  const std::size_t a = static_cast<std::size_t>(arm), device = device_index(run.truth, arm);
  // Kinect v2 JointType: ElbowLeft 5, WristLeft 6, ElbowRight 9, WristRight 10.
  const int elbow = arm == 0 ? 5 : 9;
  Table1Truth out;
  out.sdk = run.sdk;
  for (const sim::SimFrameTruth& frame : run.truth.frames) {
    sim::ForearmTruth f;
    f.side = arm == 0 ? sim::BodySide::kLeft : sim::BodySide::kRight;
    f.K_from_F = frame.K_from_F[a];
    f.elbow_K_m = frame.camera_joints_K.col(elbow);
    f.wrist_K_m = frame.camera_joints_K.col(elbow + 1);
    f.strap_K_m = frame.strap_p_K[a];
    f.K_from_A = frame.K_from_imu.at(device);
    f.imu_K_m = frame.imu_p_K.at(device);
    f.visible_fraction = frame.forearm_visible_fraction[a];
    f.strap_visible = frame.strap_visible[a];
    f.occluded = f.visible_fraction < 0.5 || !f.strap_visible;
    out.frame_t_us.push_back(frame.t_us);
    out.forearm.push_back(f);
  }
  return out;
}

Table1Arm body_render_arm(const BodyRenderRun& run, int arm) {
  const sim::SimArmTruth& t = run.truth.arms.at(static_cast<std::size_t>(arm));
  return {arm == 0 ? v1::LEFT : v1::RIGHT, t.device_id, t.d_se_m, t.d_sw_m};
}

}  // namespace posefuse::bench
