#include "body_render_session.hpp"

#include <cstddef>

#include "bench_clock.hpp"
#include "common/error.hpp"
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
  PipelineChunkSink(ResultCollector& results, BodyRenderRun& run, const std::map<std::string, std::string>& header_options)
      : pipeline_(session::make_default_stages(), results), run_(run), header_options_(header_options) {}
  void write(const v1::SessionChunk& chunk) override {
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
  void finish() override {
    const double cpu0 = thread_cpu_seconds();
    pipeline_.close();
    run_.pipeline_cpu_s += thread_cpu_seconds() - cpu0;
  }

 private:
  session::SessionPipeline pipeline_;
  BodyRenderRun& run_;
  std::map<std::string, std::string> header_options_;
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
                                      const std::map<std::string, std::string>& header_options) {
  BodyRenderRun run;
  ResultCollector results;
  {
    PipelineChunkSink sink(results, run, header_options);
    run.truth = sim::simulate_session(options, sink);
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
