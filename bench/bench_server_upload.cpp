// bench_server_upload: posefuse-server over loopback with 30 Hz 512x424 depth sessions.
//
//   bench_server_upload [--duration-s S] [--sessions N,N,...] [--repeats R]
//
// The server runs in a child process (fork before any thread exists), so that its resident
// memory (VmRSS from /proc/<pid>/status) is the server's alone; the clients are threads of this
// process, one channel (one TCP connection) per session. Sessions: the demo session's header,
// IMU streams (2 devices, 80 Hz, batches of 32) and skeletons at 512x424, with depth and body
// index frames from the camera simulator (core/sim: body model, room, depth noise; 31 frames
// simulated, then reused in a cycle with the session's timestamps), depth encoded either as
// the simulator does (zstd) or raw (the largest a client sends).
//
// Tables:
//  1. upload throughput: one session sent as fast as the server takes it, by Fit (results read
//     while sending; the time runs until the final status) and by SubmitJob upload (until the
//     job is returned: spooled to disk, not yet run); MB/s of serialised chunks, depth frames/s,
//     times real time; the server's peak VmRSS above idle during the call. Best of --repeats.
//  2. N concurrent Fit sessions paced at real time, each row on a fresh server process (each chunk sent when its
//  stream's clock says
//     it was recorded): latency of every per-item result (an ImuOrientationBatch answering an
//     ImuBatch: its send -> its arrival; the pipeline has no per-depth-frame result yet), median
//     and p95 over all sessions; how long after the last chunk the call ended; the server's
//     VmRSS above idle at steady state, per session.
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "bench/loopback_server.hpp"
#include "body/pose_parameters.hpp"
#include "client/demo_session.hpp"
#include "client/fit_call.hpp"
#include "posefuse/v1/service.grpc.pb.h"
#include "session/image_codec.hpp"
#include "session/text_fields.hpp"
#include "sim/camera_session.hpp"

namespace {

using namespace posefuse;
namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;
using bench::new_stub;
using bench::rss_mib;
using bench::ServerProcess;

// Samples a process's VmRSS every 5 ms while alive; peak() is the largest seen.
class RssMonitor {
 public:
  explicit RssMonitor(pid_t pid) : pid_(pid), thread_([this] { run(); }) {}
  ~RssMonitor() {
    stop_ = true;
    thread_.join();
  }
  double peak() const { return peak_.load(); }

 private:
  void run() {
    while (!stop_) {
      const double rss = rss_mib(pid_);
      if (rss > peak_.load()) peak_ = rss;
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
  }
  pid_t pid_;
  std::atomic<bool> stop_{false};
  std::atomic<double> peak_{0.0};
  std::thread thread_;
};

// ---------------------------------------------------------------------------------------------
// Sessions

struct Session {
  std::vector<v1::SessionChunk> chunks;
  std::vector<double> send_at_s;  // when each chunk is recorded, seconds from the session start
  std::uint64_t bytes = 0;        // serialised chunks
  int depth_frames = 0;
  double duration_s = 0.0;
};

// Depth and body index frames of the simulator at the demo header's intrinsics.
std::vector<v1::SessionChunk> simulated_camera_frames(const v1::CameraIntrinsics& k) {
  sim::CameraSessionOptions options;
  options.intrinsics.width = static_cast<int>(k.width());
  options.intrinsics.height = static_cast<int>(k.height());
  options.intrinsics.fx = k.fx();
  options.intrinsics.fy = k.fy();
  options.intrinsics.cx = k.cx();
  options.intrinsics.cy = k.cy();
  options.intrinsics.k1 = options.intrinsics.k2 = options.intrinsics.k3 = 0.0;
  options.duration_s = 1.0;
  const body::PoseLayout layout = body::PoseLayout::full_body();
  const auto result = sim::simulate_camera_session(options, layout, sim::arm_raising_sequence(layout, 4.0));
  std::vector<v1::SessionChunk> frames;
  for (const auto& chunk : result.chunks) {
    if (chunk.has_depth() || chunk.has_body_index()) frames.push_back(chunk);
  }
  return frames;
}

Session make_session(double duration_s, bool raw_depth, const std::vector<v1::SessionChunk>& sim) {
  demo::DemoSessionOptions options;
  options.duration_s = duration_s;
  options.depth_width = 512;
  options.depth_height = 424;
  Session out;
  out.chunks = demo::make_demo_session(options);
  out.duration_s = duration_s;
  std::size_t depth_i = 0, body_i = 0;
  std::vector<const v1::SessionChunk*> sim_depth, sim_body;
  for (const auto& chunk : sim) (chunk.has_depth() ? sim_depth : sim_body).push_back(&chunk);
  std::map<std::string, std::int64_t> first_t_us;  // per stream
  double last_s = 0.0;
  for (auto& chunk : out.chunks) {
    if (chunk.has_depth()) {
      const std::int64_t t_us = chunk.depth().t_us();
      const v1::DepthFrame& frame = sim_depth[depth_i++ % sim_depth.size()]->depth();
      *chunk.mutable_depth() =
          raw_depth ? session::encode_depth(session::decode_depth(frame), v1::DepthFrame::RAW_U16_LE, t_us) : frame;
      chunk.mutable_depth()->set_t_us(t_us);
      ++out.depth_frames;
    } else if (chunk.has_body_index()) {
      const std::int64_t t_us = chunk.body_index().t_us();
      *chunk.mutable_body_index() = sim_body[body_i++ % sim_body.size()]->body_index();
      chunk.mutable_body_index()->set_t_us(t_us);
    }
    // When the chunk exists: its stream's clock since that stream's first chunk (an IMU batch
    // when its last sample is in), kept in stream order.
    std::string stream;
    std::int64_t t_us = 0;
    if (chunk.has_imu()) {
      stream = chunk.imu().device_id();
      t_us = chunk.imu().t_us(chunk.imu().t_us_size() - 1);
    } else if (chunk.has_depth() || chunk.has_body_index() || chunk.has_skeleton()) {
      stream = "camera";
      t_us = chunk.has_depth()        ? chunk.depth().t_us()
             : chunk.has_body_index() ? chunk.body_index().t_us()
                                      : chunk.skeleton().t_us();
    }
    if (!stream.empty()) {
      const std::int64_t first = first_t_us.emplace(stream, t_us).first->second;
      last_s = std::max(last_s, 1e-6 * static_cast<double>(t_us - first));
    }
    out.send_at_s.push_back(last_s);
    out.bytes += chunk.ByteSizeLong();
  }
  return out;
}

// ---------------------------------------------------------------------------------------------
// Calls

struct FitOutcome {
  bool ok = false;
  std::string error;
  double seconds = 0.0;              // first write -> final status
  double after_last_chunk_s = 0.0;   // last write -> final status
  std::vector<double> latencies_ms;  // per ImuOrientationBatch
};

// One Fit call; `paced`: each chunk waits for its send_at_s.
FitOutcome run_fit(v1::PoseFuse::Stub& stub, const Session& session, bool paced) {
  grpc::ClientContext context;
  auto stream = stub.Fit(&context);
  std::mutex mu;
  std::map<std::pair<std::string, std::int64_t>, Clock::time_point> sent;  // IMU batch -> time
  Clock::time_point last_write;
  const Clock::time_point start = Clock::now();
  std::thread sender([&] {
    for (std::size_t i = 0; i < session.chunks.size(); ++i) {
      const auto& chunk = session.chunks[i];
      if (paced) {
        std::this_thread::sleep_until(
            start + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(session.send_at_s[i])));
      }
      if (chunk.has_imu()) {
        std::lock_guard lock(mu);
        sent[{chunk.imu().device_id(), chunk.imu().t_us(0)}] = Clock::now();
      }
      if (!stream->Write(chunk)) return;
    }
    last_write = Clock::now();
    stream->WritesDone();
  });
  FitOutcome outcome;
  v1::FitResult result;
  while (stream->Read(&result)) {
    if (!result.has_imu_orientations() || result.imu_orientations().t_us_size() == 0) continue;
    const Clock::time_point now = Clock::now();
    std::lock_guard lock(mu);
    const auto it = sent.find({result.imu_orientations().device_id(), result.imu_orientations().t_us(0)});
    if (it != sent.end()) {
      outcome.latencies_ms.push_back(std::chrono::duration<double, std::milli>(now - it->second).count());
    }
  }
  sender.join();
  const grpc::Status status = stream->Finish();
  const Clock::time_point end = Clock::now();
  outcome.ok = status.ok();
  outcome.error = status.error_message();
  outcome.seconds = std::chrono::duration<double>(end - start).count();
  outcome.after_last_chunk_s = std::chrono::duration<double>(end - last_write).count();
  return outcome;
}

// SubmitJob by upload; seconds until the job is returned.
double run_upload(v1::PoseFuse::Stub& stub, const Session& session, std::string& error) {
  grpc::ClientContext context;
  v1::Job job;
  const Clock::time_point start = Clock::now();
  auto writer = stub.SubmitJob(&context, &job);
  v1::SubmitJobRequest request;
  request.mutable_spec()->set_upload(true);
  writer->Write(request);
  for (const auto& chunk : session.chunks) {
    *request.mutable_chunk() = chunk;
    if (!writer->Write(request)) break;
  }
  writer->WritesDone();
  const grpc::Status status = writer->Finish();
  error = status.ok() ? "" : status.error_message();
  return std::chrono::duration<double>(Clock::now() - start).count();
}

double percentile(std::vector<double> values, double p) {
  if (values.empty()) return NAN;
  std::sort(values.begin(), values.end());
  const auto index = static_cast<std::size_t>(std::ceil(p * static_cast<double>(values.size()))) - 1;
  return values[std::min(index, values.size() - 1)];
}

}  // namespace

int main(int argc, char** argv) {
  double duration_s = 10.0;
  std::vector<int> concurrency = {1, 4, 16};
  int repeats = 3;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string flag = argv[i];
    if (flag == "--duration-s") duration_s = session::parse_double(argv[i + 1], flag);
    else if (flag == "--sessions") concurrency = bench::parse_int_list(argv[i + 1], flag);
    else if (flag == "--repeats") repeats = static_cast<int>(session::parse_uint64(argv[i + 1], flag));
    else {
      std::fprintf(stderr, "usage: bench_server_upload [--duration-s S] [--sessions N,N] [--repeats R]\n");
      return 2;
    }
  }

  const fs::path data_dir = fs::temp_directory_path() / ("posefuse_bench_server_" + std::to_string(getpid()));
  fs::create_directories(data_dir);
  // Before any thread exists in this process (the simulator and gRPC start some): one server
  // for table 1 and a fresh one for each row of table 2, so that memory left cached by earlier
  // calls does not hide what the sessions of that row take.
  std::vector<ServerProcess> servers;
  for (std::size_t i = 0; i <= concurrency.size(); ++i) {
    server::ServerOptions options;
    options.max_sessions = 256;
    options.data_dir = (data_dir / std::to_string(i)).string();
    options.max_upload_mb = 1 << 16;
    options.max_spool_mb = 1 << 20;  // many long uploads at once: the quota is not what is measured
    servers.push_back(bench::start_server_process(options));
  }
  const ServerProcess& server = servers[0];
  auto stop_all = [&] {
    for (const auto& s : servers) bench::stop_server_process(s);
  };

  demo::DemoSessionOptions probe;
  probe.depth_width = 512;
  probe.depth_height = 424;
  const v1::CameraIntrinsics k = demo::make_demo_session(probe)[0].header().depth_intrinsics();
  const std::vector<v1::SessionChunk> sim_frames = simulated_camera_frames(k);
  const Session zstd = make_session(duration_s, false, sim_frames);
  const Session raw = make_session(duration_s, true, sim_frames);
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  const double idle_rss = rss_mib(server.pid);

  std::printf("posefuse-server over loopback (server in its own process, %u CPUs here, load %s)\n",
              std::thread::hardware_concurrency(), bench::load_average().c_str());
  std::printf(
      "session: %.0f s, %d depth frames 512x424 at 30 Hz + body index + skeleton, "
      "2 IMUs at 80 Hz; server idle VmRSS %.1f MiB\n\n",
      duration_s, zstd.depth_frames, idle_rss);

  std::printf("1. upload throughput, one session as fast as possible (best of %d)\n", repeats);
  std::printf(
      "| depth encoding | call | MB | seconds | MB/s | depth frames/s | x real time | server peak RSS above idle MiB "
      "|\n");
  std::printf("|---|---|---:|---:|---:|---:|---:|---:|\n");
  for (const auto* session : {&zstd, &raw}) {
    const char* encoding = session == &zstd ? "zstd (simulator)" : "raw";
    for (const char* call : {"Fit", "SubmitJob upload"}) {
      double best_s = INFINITY, peak = 0.0;
      for (int r = 0; r < repeats; ++r) {
        auto stub = new_stub(server.port);
        const double before = rss_mib(server.pid);
        RssMonitor monitor(server.pid);
        double seconds = 0.0;
        std::string error;
        if (std::string(call) == "Fit") {
          const FitOutcome outcome = run_fit(*stub, *session, false);
          seconds = outcome.seconds;
          error = outcome.error;
        } else {
          seconds = run_upload(*stub, *session, error);
        }
        if (!error.empty()) {
          std::fprintf(stderr, "bench: %s failed: %s\n", call, error.c_str());
          stop_all();
          return 1;
        }
        best_s = std::min(best_s, seconds);
        peak = std::max(peak, monitor.peak() - before);
      }
      const double mb = static_cast<double>(session->bytes) / 1e6;
      std::printf("| %s | %s | %.1f | %.2f | %.1f | %.0f | %.1f | %.1f |\n", encoding, call, mb, best_s, mb / best_s,
                  session->depth_frames / best_s, duration_s / best_s, peak);
    }
  }

  std::printf("\n2. concurrent Fit sessions paced at real time (zstd depth), per-item result latency\n");
  std::printf(
      "| sessions | results | latency median ms | latency p95 ms | call end after last chunk, max s | server RSS above "
      "idle MiB | per session MiB |\n");
  std::printf("|---:|---:|---:|---:|---:|---:|---:|\n");
  for (std::size_t row = 0; row < concurrency.size(); ++row) {
    const int n = concurrency[row];
    const ServerProcess& fresh = servers[row + 1];
    std::vector<std::unique_ptr<v1::PoseFuse::Stub>> stubs;
    for (int i = 0; i < n; ++i) stubs.push_back(new_stub(fresh.port));
    const double before = rss_mib(fresh.pid);
    std::vector<FitOutcome> outcomes(static_cast<std::size_t>(n));
    std::atomic<bool> done{false};
    double steady_rss = 0.0;
    std::thread sampler([&] {
      // Steady state: from 30 % to 90 % of the session, the mean of samples every 50 ms.
      std::this_thread::sleep_for(std::chrono::duration<double>(0.3 * duration_s));
      double sum = 0.0;
      int count = 0;
      const auto until =
          Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(0.6 * duration_s));
      while (!done && Clock::now() < until) {
        sum += rss_mib(fresh.pid);
        ++count;
        std::this_thread::sleep_for(std::chrono::milliseconds(50));
      }
      steady_rss = count ? sum / count : NAN;
    });
    std::vector<std::thread> clients;
    for (int i = 0; i < n; ++i) {
      clients.emplace_back(
          [&, i] { outcomes[static_cast<std::size_t>(i)] = run_fit(*stubs[static_cast<std::size_t>(i)], zstd, true); });
    }
    for (auto& client : clients) client.join();
    done = true;
    sampler.join();
    std::vector<double> latencies;
    double worst_end = 0.0;
    for (const auto& outcome : outcomes) {
      if (!outcome.ok) {
        std::fprintf(stderr, "bench: a paced Fit failed: %s\n", outcome.error.c_str());
        stop_all();
        return 1;
      }
      latencies.insert(latencies.end(), outcome.latencies_ms.begin(), outcome.latencies_ms.end());
      worst_end = std::max(worst_end, outcome.after_last_chunk_s);
    }
    std::printf("| %d | %zu | %.2f | %.2f | %.2f | %.1f | %.2f |\n", n, latencies.size(), percentile(latencies, 0.5),
                percentile(latencies, 0.95), worst_end, steady_rss - before, (steady_rss - before) / n);
  }

  stop_all();
  fs::remove_all(data_dir);
  return 0;
}
