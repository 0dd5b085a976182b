// bench_server_capacity: how many live sessions with the body fit on one posefuse-server holds.
//
//   bench_server_capacity [--session FILE] [--duration-s S] [--sessions N,N,...] [--imu-batch K]
//                         [--option KEY=VALUE]...
//
// The session is a recorded chunk file (default build/demo/demo-session.pfchunks, which
// scripts/demo.sh writes: paper 1's protocol, both arms, depth + body index + skeleton + colour at
// 30 Hz, two wrist IMUs and the base IMU, audio and sync events) with `fit.enabled = true` set in
// its header, cut to its first --duration-s seconds (default 0: whole). Its chunks are sent as a
// clinic's client would: each when its last sample exists on its own clock (an IMU batch at its
// last sample, an audio chunk at its end), counted from that clock's first timestamp, because
// device clocks have offsets of their own; a chunk file written in another order (posefuse-sim
// orders by raw timestamps across clocks) is put in that order, each stream's own order kept.
// --imu-batch K re-cuts every IMU batch into batches of at most K samples (a device streaming
// more often); by default the recording's batches are sent as they are. --option sets a stage
// option in the header besides fit.enabled (e.g. fit.min_joint_step_m=0.002), as the client's does.
//
// Each row runs N such sessions at once, paced in real time, on a fresh server process (forked
// before any thread exists, default ServerOptions but max_sessions), clients as threads of this
// process with a connection each. Per row:
//  - server CPU per session-second: the server process's user + system CPU (/proc/PID/stat)
//    over the row, everything up to every call's final status, divided by N x session seconds;
//  - first result: when the first FrameResult arrived (the latest over the sessions). The
//    pipeline answers no frame before the forearm stage's calibration window has passed (with
//    the fit's personalisation), so the frames written before it are counted as held, not timed;
//  - result latency of the live frames (written after their session's first FrameResult): a
//    depth chunk's write -> the arrival of that frame's FrameResult (the frame's t_us), over all
//    sessions; frames that never got a FrameResult are counted;
//  - frames behind: depth frames written minus FrameResults received, when half the session has
//    been sent and when the last chunk has been sent (the largest over the N sessions); the
//    backlog grows when the second exceeds the first by more than one second of frames;
//  - RSS: the server's VmRSS, mean from 30 % to 90 % of the session, above idle, per session;
//    and per added session: the growth over the first row's, per session more than it ran (what
//    one more session costs once the server's own growth, stacks and arenas, is paid).
// The largest N with p95 latency <= 200 ms and no growing backlog is printed last.
//
// Offline: one session unpaced (written as fast as the server reads it; the same pipeline a
// batch job runs) on its own fresh server: depth frames per server CPU second, which is per core.
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "bench/loopback_server.hpp"
#include "client/recording.hpp"
#include "common/error.hpp"
#include "common/percentile.hpp"
#include "posefuse/v1/service.grpc.pb.h"
#include "session/session_validator.hpp"
#include "session/text_fields.hpp"

namespace {

using namespace posefuse;
using Clock = std::chrono::steady_clock;

constexpr double kLatencyLimitMs = 200.0;

struct Session {
  std::vector<v1::SessionChunk> chunks;  // header, data chunks in sending order, end marker
  std::vector<double> send_at_s;         // per chunk, from the session's start
  int depth_frames = 0;
  double duration_s = 0.0;
};

// The clock a data chunk's timestamps are on, and its first and last timestamp there.
struct ChunkTime {
  std::string clock;
  std::int64_t first_us = 0, last_us = 0;
};

ChunkTime chunk_time(const v1::SessionChunk& chunk) {
  switch (chunk.chunk_case()) {
    case v1::SessionChunk::kDepth: return {"camera", chunk.depth().t_us(), chunk.depth().t_us()};
    case v1::SessionChunk::kBodyIndex: return {"camera", chunk.body_index().t_us(), chunk.body_index().t_us()};
    case v1::SessionChunk::kSkeleton: return {"camera", chunk.skeleton().t_us(), chunk.skeleton().t_us()};
    case v1::SessionChunk::kColor: return {"camera", chunk.color().t_us(), chunk.color().t_us()};
    case v1::SessionChunk::kImu: {
      const auto& t = chunk.imu().t_us();
      return {"device/" + chunk.imu().device_id(), t.empty() ? 0 : t[0], t.empty() ? 0 : t[t.size() - 1]};
    }
    case v1::SessionChunk::kAudio: {
      const v1::AudioChunk& audio = chunk.audio();
      const std::uint64_t frames = audio.pcm_s16le().size() / (2u * std::max(1u, audio.channels()));
      const auto length_us = static_cast<std::int64_t>(
          std::llround(1e6 * static_cast<double>(frames) / std::max(1u, audio.sample_rate_hz())));
      return {"camera", audio.t_us(), audio.t_us() + length_us};
    }
    case v1::SessionChunk::kSyncEvent: {
      const v1::SyncEvent& event = chunk.sync_event();
      return {event.device_id() == "camera" ? "camera" : "device/" + event.device_id(), event.t_us(), event.t_us()};
    }
    default: return {};
  }
}

// Batches of at most `samples` samples (in order) from one batch.
std::vector<v1::SessionChunk> recut_imu(const v1::SessionChunk& chunk, int samples) {
  const v1::ImuBatch& batch = chunk.imu();
  std::vector<v1::SessionChunk> out;
  for (int begin = 0; begin < batch.t_us_size(); begin += samples) {
    const int end = std::min(batch.t_us_size(), begin + samples);
    v1::SessionChunk piece;
    v1::ImuBatch& part = *piece.mutable_imu();
    part.set_device_id(batch.device_id());
    for (int i = begin; i < end; ++i) {
      part.add_t_us(batch.t_us(i));
      for (int axis = 0; axis < 3; ++axis) {
        part.add_gyr_rad_s(batch.gyr_rad_s(3 * i + axis));
        part.add_acc_m_s2(batch.acc_m_s2(3 * i + axis));
        if (batch.mag_ut_size() == 3 * batch.t_us_size()) part.add_mag_ut(batch.mag_ut(3 * i + axis));
      }
    }
    out.push_back(std::move(piece));
  }
  return out;
}

Session load_session(const std::string& path, double duration_s, int imu_batch,
                     std::map<std::string, std::string> header_options) {
  header_options.emplace("fit.enabled", "true");
  client::Recording recording(path, client::HeaderEdits{.options = std::move(header_options), .height_m = {}});
  v1::SessionChunk chunk;
  if (!recording.next(chunk) || !chunk.has_header()) throw Error(ErrorCode::kInvalidArgument, path, "no header first");
  const v1::SessionChunk header = chunk;
  struct Timed {
    v1::SessionChunk chunk;
    ChunkTime time;
  };
  std::vector<Timed> data;
  std::map<std::string, std::int64_t> clock_first_us;
  while (recording.next(chunk)) {
    if (chunk.has_end()) break;
    std::vector<v1::SessionChunk> pieces;
    if (chunk.has_imu() && imu_batch > 0) pieces = recut_imu(chunk, imu_batch);
    else pieces.push_back(chunk);
    for (auto& piece : pieces) {
      const ChunkTime time = chunk_time(piece);
      auto [it, added] = clock_first_us.emplace(time.clock, time.first_us);
      if (!added) it->second = std::min(it->second, time.first_us);
      data.push_back({std::move(piece), time});
    }
  }
  std::vector<std::pair<double, std::size_t>> order;  // (send at, index)
  for (std::size_t i = 0; i < data.size(); ++i) {
    const double at_s = 1e-6 * static_cast<double>(data[i].time.last_us - clock_first_us.at(data[i].time.clock));
    if (duration_s <= 0.0 || at_s < duration_s) order.emplace_back(at_s, i);
  }
  // Stable: chunks of one instant keep the recording's order (depth before its body index).
  std::stable_sort(order.begin(), order.end(), [](const auto& a, const auto& b) { return a.first < b.first; });

  Session out;
  session::SessionValidator validator;  // checks the order kept and counts for the end marker
  out.chunks.push_back(header);
  out.send_at_s.push_back(0.0);
  validator.check(header);
  for (const auto& [at_s, i] : order) {
    validator.check(data[i].chunk);
    if (data[i].chunk.has_depth()) ++out.depth_frames;
    out.chunks.push_back(std::move(data[i].chunk));
    out.send_at_s.push_back(at_s);
    out.duration_s = std::max(out.duration_s, at_s);
  }
  v1::SessionChunk end;
  *end.mutable_end() = validator.counts();
  out.chunks.push_back(end);
  out.send_at_s.push_back(out.duration_s);
  return out;
}

struct CallOutcome {
  grpc::Status status;
  std::vector<double> latencies_ms;  // per live depth frame with a FrameResult
  int frames_without_result = 0;
  int held_frames = 0;                  // written before the first FrameResult arrived
  double first_result_s = NAN;          // the first FrameResult's arrival, from the session's start
  int behind_half = 0, behind_end = 0;  // depth frames written minus FrameResults received
};

// One Fit call; `paced`: each chunk waits for its send_at_s.
CallOutcome run_session(v1::PoseFuse::Stub& stub, const Session& session, bool paced) {
  grpc::ClientContext context;
  auto stream = stub.Fit(&context);
  std::mutex mu;
  std::map<std::int64_t, Clock::time_point> written;  // depth t_us -> write
  std::map<std::int64_t, Clock::time_point> arrived;  // FrameResult t_us -> arrival
  std::atomic<int> frames_written{0}, results{0};
  CallOutcome outcome;
  const Clock::time_point start = Clock::now();
  std::thread sender([&] {
    bool half_noted = false;
    for (std::size_t i = 0; i < session.chunks.size(); ++i) {
      const auto& chunk = session.chunks[i];
      if (paced) {
        std::this_thread::sleep_until(
            start + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(session.send_at_s[i])));
      }
      if (!half_noted && session.send_at_s[i] >= 0.5 * session.duration_s) {
        half_noted = true;
        outcome.behind_half = frames_written.load() - results.load();
      }
      if (chunk.has_end()) outcome.behind_end = frames_written.load() - results.load();
      if (chunk.has_depth()) {
        std::lock_guard lock(mu);
        written[chunk.depth().t_us()] = Clock::now();
      }
      if (!stream->Write(chunk)) return;
      if (chunk.has_depth()) ++frames_written;
    }
    stream->WritesDone();
  });
  v1::FitResult result;
  while (stream->Read(&result)) {
    if (!result.has_frame()) continue;
    const Clock::time_point now = Clock::now();
    std::lock_guard lock(mu);
    arrived.emplace(result.frame().t_us(), now);
    ++results;
  }
  sender.join();
  outcome.status = stream->Finish();
  Clock::time_point first_result = Clock::time_point::max();
  for (const auto& [t_us, at] : arrived) first_result = std::min(first_result, at);
  if (!arrived.empty()) outcome.first_result_s = std::chrono::duration<double>(first_result - start).count();
  for (const auto& [t_us, at] : written) {
    const auto it = arrived.find(t_us);
    if (it == arrived.end()) ++outcome.frames_without_result;
    else if (at < first_result) ++outcome.held_frames;
    else outcome.latencies_ms.push_back(std::chrono::duration<double, std::milli>(it->second - at).count());
  }
  return outcome;
}

struct Row {
  int sessions = 0;
  double cpu_per_session_s = 0.0;  // server CPU s per session-second
  double p50_ms = NAN, p95_ms = NAN, max_ms = NAN;
  int frames = 0, held = 0, without_result = 0;
  double first_result_s = 0.0;  // the latest over the sessions
  int behind_half = 0, behind_end = 0;
  double rss_per_session_mib = NAN;
  bool holds = false;
};

Row run_row(const bench::ServerProcess& server, const Session& session, int n) {
  std::vector<std::unique_ptr<v1::PoseFuse::Stub>> stubs;
  for (int i = 0; i < n; ++i) stubs.push_back(bench::new_stub(server.port));
  const double idle_rss = bench::rss_mib(server.pid);
  const double cpu_before = bench::process_cpu_s(server.pid);
  std::vector<CallOutcome> outcomes(static_cast<std::size_t>(n));
  std::atomic<bool> done{false};
  double steady_rss = NAN;
  std::thread sampler([&] {
    std::this_thread::sleep_for(std::chrono::duration<double>(0.3 * session.duration_s));
    double sum = 0.0;
    int count = 0;
    const auto until = Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                          std::chrono::duration<double>(0.6 * session.duration_s));
    while (!done && Clock::now() < until) {
      sum += bench::rss_mib(server.pid);
      ++count;
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
    if (count > 0) steady_rss = sum / count;
  });
  std::vector<std::thread> clients;
  for (int i = 0; i < n; ++i) {
    clients.emplace_back([&, i] {
      const auto k = static_cast<std::size_t>(i);
      outcomes[k] = run_session(*stubs[k], session, true);
    });
  }
  for (auto& client : clients) client.join();
  done = true;
  sampler.join();
  Row row;
  row.sessions = n;
  row.cpu_per_session_s = (bench::process_cpu_s(server.pid) - cpu_before) / (n * session.duration_s);
  std::vector<double> latencies;
  for (const auto& outcome : outcomes) {
    if (!outcome.status.ok()) {
      throw Error(ErrorCode::kInternal, "Fit", "a paced session failed: " + outcome.status.error_message());
    }
    latencies.insert(latencies.end(), outcome.latencies_ms.begin(), outcome.latencies_ms.end());
    row.without_result += outcome.frames_without_result;
    row.held += outcome.held_frames;
    row.first_result_s = std::max(row.first_result_s, outcome.first_result_s);
    row.behind_half = std::max(row.behind_half, outcome.behind_half);
    row.behind_end = std::max(row.behind_end, outcome.behind_end);
  }
  row.frames = static_cast<int>(latencies.size());
  if (!latencies.empty()) {
    std::sort(latencies.begin(), latencies.end());
    row.p50_ms = percentile(latencies, 0.5);
    row.p95_ms = percentile(latencies, 0.95);
    row.max_ms = latencies.back();
  }
  row.rss_per_session_mib = (steady_rss - idle_rss) / n;
  const int one_second_of_frames = static_cast<int>(std::lround(session.depth_frames / session.duration_s));
  row.holds = row.p95_ms <= kLatencyLimitMs && row.behind_end - row.behind_half <= one_second_of_frames;
  return row;
}

}  // namespace

int main(int argc, char** argv) {
  std::string path = "build/demo/demo-session.pfchunks";
  double duration_s = 0.0;
  std::vector<int> concurrency = {1, 2, 4};
  int imu_batch = 0;
  std::map<std::string, std::string> header_options;
  for (int i = 1; i < argc; i += 2) {
    const std::string flag = i + 1 < argc ? argv[i] : "";
    if (flag == "--session") path = argv[i + 1];
    else if (flag == "--duration-s") duration_s = session::parse_double(argv[i + 1], flag);
    else if (flag == "--sessions") concurrency = bench::parse_int_list(argv[i + 1], flag);
    else if (flag == "--imu-batch") imu_batch = static_cast<int>(session::parse_uint64(argv[i + 1], flag));
    else if (flag == "--option") {
      try {
        auto [key, value] = client::parse_header_option(argv[i + 1]);
        header_options.insert_or_assign(std::move(key), std::move(value));
      } catch (const Error& error) {
        std::fprintf(stderr, "bench: %s\n", error.what());
        return 2;
      }
    } else {
      std::fprintf(stderr,
                   "usage: bench_server_capacity [--session FILE] [--duration-s S] [--sessions N,N,...] "
                   "[--imu-batch K] [--option KEY=VALUE]...\n");
      return 2;
    }
  }

  // Before any thread exists in this process: a fresh server per row and one for the offline run,
  // so that what a row leaves cached does not hide what the next takes.
  server::ServerOptions options;
  options.max_sessions = 256;
  std::vector<bench::ServerProcess> servers;
  for (std::size_t i = 0; i <= concurrency.size(); ++i) servers.push_back(bench::start_server_process(options));
  const auto stop_all = [&] {
    for (const auto& s : servers) bench::stop_server_process(s);
  };

  Session session;
  try {
    session = load_session(path, duration_s, imu_batch, header_options);
  } catch (const Error& error) {
    std::fprintf(stderr, "bench: %s (scripts/demo.sh writes the default session)\n", error.what());
    stop_all();
    return 1;
  }
  std::printf("posefuse-server capacity, body fit on (server in its own process, %u CPUs, load average %s)\n",
              std::thread::hardware_concurrency(), bench::load_average().c_str());
  for (const auto& [key, value] : header_options) std::printf("option %s = %s\n", key.c_str(), value.c_str());
  std::printf("session: %s, first %.1f s, %d depth frames, %zu chunks, IMU batches %s\n\n", path.c_str(),
              session.duration_s, session.depth_frames, session.chunks.size(),
              imu_batch > 0 ? ("of at most " + std::to_string(imu_batch) + " samples").c_str() : "as recorded");

  std::printf("Paced in real time, N sessions at once (fresh server per row)\n");
  std::printf(
      "| sessions | server CPU s per session-s | first result s | held frames | live frames | latency p50 ms | p95 ms "
      "| max ms | frames without result | frames behind at half / end | RSS per session MiB | RSS per added session "
      "MiB | holds |\n");
  std::printf("|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|\n");
  int largest = 0;
  std::optional<Row> first_row;
  try {
    for (std::size_t r = 0; r < concurrency.size(); ++r) {
      const Row row = run_row(servers[r], session, concurrency[r]);
      if (!first_row) first_row = row;
      const int added = row.sessions - first_row->sessions;
      char added_mib[32] = "-";
      if (added > 0)
        std::snprintf(
            added_mib, sizeof added_mib, "%.1f",
            (row.rss_per_session_mib * row.sessions - first_row->rss_per_session_mib * first_row->sessions) / added);
      std::printf("| %d | %.3f | %.2f | %d | %d | %.1f | %.1f | %.1f | %d | %d / %d | %.1f | %s | %s |\n", row.sessions,
                  row.cpu_per_session_s, row.first_result_s, row.held, row.frames, row.p50_ms, row.p95_ms, row.max_ms,
                  row.without_result, row.behind_half, row.behind_end, row.rss_per_session_mib, added_mib,
                  row.holds ? "yes" : "no");
      std::fflush(stdout);
      if (row.holds) largest = std::max(largest, row.sessions);
    }
  } catch (const Error& error) {
    std::fprintf(stderr, "bench: %s\n", error.what());
    stop_all();
    return 1;
  }
  std::printf("\nlargest N holding p95 <= %.0f ms with no growing backlog: %d\n\n", kLatencyLimitMs, largest);

  const bench::ServerProcess& offline = servers.back();
  auto stub = bench::new_stub(offline.port);
  const double cpu_before = bench::process_cpu_s(offline.pid);
  const Clock::time_point start = Clock::now();
  const CallOutcome outcome = run_session(*stub, session, false);
  const double wall_s = std::chrono::duration<double>(Clock::now() - start).count();
  const double cpu_s = bench::process_cpu_s(offline.pid) - cpu_before;
  stop_all();
  if (!outcome.status.ok()) {
    std::fprintf(stderr, "bench: the offline session failed: %s\n", outcome.status.error_message().c_str());
    return 1;
  }
  std::printf("Offline (unpaced), one session\n");
  std::printf("| depth frames | server CPU s | wall s | frames per CPU second (per core) | frames per wall second |\n");
  std::printf("|---:|---:|---:|---:|---:|\n");
  std::printf("| %d | %.2f | %.2f | %.1f | %.1f |\n", session.depth_frames, cpu_s, wall_s, session.depth_frames / cpu_s,
              session.depth_frames / wall_s);
  return 0;
}
