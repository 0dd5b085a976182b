#pragma once
// A Table I session on the simulator's body render (bench_table1 --render body): posefuse-sim's
// session generator (core/sim/sim_session.hpp: the rendered body with clothing, hands, head and
// torso near the arms, RGB with the strap, both arm IMUs) streamed in-process through
// SessionPipeline(make_default_stages()) as it is rendered, so no session sits in memory (except
// with live_order, below); the truth per arm is what gt/ would hold.
#include <array>
#include <map>
#include <string>
#include <vector>

#include "posefuse/v1/results.pb.h"
#include "sim/sim_session.hpp"
#include "table1_errors.hpp"

namespace posefuse::bench {

struct BodyRenderRun {
  sim::SimTruth truth;
  std::vector<v1::FitResult> results;
  std::vector<v1::SkeletonFrame> sdk;  // the session's skeleton chunks
  double pipeline_cpu_s = 0.0;         // this thread's CPU inside the pipeline
};

// header_options are added to the session header's options (e.g. fit.enabled = true). With
// live_order the chunks are held until the session is simulated and then sent in the order a live
// recording would send them: by camera time, an IMU batch or sync event at the true camera time
// of its (last) sample, instead of posefuse-sim's order (each device's batches at its own clock's
// time, which puts them before or after every camera frame).
BodyRenderRun run_body_render_session(const sim::SimSessionOptions& options,
                                      const std::map<std::string, std::string>& header_options = {},
                                      bool live_order = false);

// Per arm with an IMU (0 left, 1 right): the frames' truth as Table1Truth (occluded as
// gt/occlusion.csv reads: most of the forearm hidden, or the strap) and the arm as Table1Arm.
bool has_arm(const BodyRenderRun& run, int arm);
Table1Truth body_render_truth(const BodyRenderRun& run, int arm);
Table1Arm body_render_arm(const BodyRenderRun& run, int arm);

}  // namespace posefuse::bench
