// bench_server_memory_bomb: the server's memory under issue 24's memory bomb, at its default
// memory budget.
//
//   bench_server_memory_bomb [--sessions N,N,...] [--sizes WxH,WxH,...]
//
// A bomb is one Fit session with the body fit on and `fit.calibration_s = 30`, whose client sends
// one camera frame (depth, body index, skeleton) again and again 10 us apart: the fit's
// calibration window is counted in stream time, so the server keeps every frame until the
// session's memory budget (docs/server.md, "Bounded memory per session") ends it with
// RESOURCE_EXHAUSTED. Each row runs N bombs at once against a fresh posefuse-server in a child
// process with default ServerOptions (its budget is printed), each bomb sending frames worth
// twice the budget. Printed per row: the calls' final status codes, the server's largest VmRSS
// above idle (sampled every 10 ms) in all and per bomb, that against the budget, the server's
// CPU seconds and the wall time until the last call ended. A size beyond the header's pixel
// limit (session::kMaxDepthPixels) shows the refusal before any frame is kept.
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <map>
#include <string>
#include <thread>
#include <vector>

#include "bench/loopback_server.hpp"
#include "client/demo_session.hpp"
#include "common/error.hpp"
#include "posefuse/v1/service.grpc.pb.h"
#include "session/image_codec.hpp"

namespace posefuse {
namespace {

using Clock = std::chrono::steady_clock;

struct Size {
  std::uint32_t width = 0, height = 0;
};

std::vector<Size> parse_sizes(const std::string& text) {
  std::vector<Size> sizes;
  for (std::size_t begin = 0; begin <= text.size();) {
    const std::size_t end = std::min(text.find(',', begin), text.size());
    const std::string item = text.substr(begin, end - begin);
    unsigned width = 0, height = 0;
    char tail = 0;
    if (std::sscanf(item.c_str(), "%ux%u%c", &width, &height, &tail) != 2 || width == 0 || height == 0 ||
        width > 16384 || height > 16384)
      throw Error(ErrorCode::kInvalidArgument, "--sizes", "'" + item + "' is not WxH (1..16384 each)");
    sizes.push_back({width, height});
    begin = end + 1;
  }
  return sizes;
}

// The bomb: the demo session's header (fit on, a 30 s calibration window) and its first camera
// frame `frames` times, 10 us apart. A size beyond the server's pixel limit, which the demo
// session refuses to make, is claimed by a 512x424 session's header.
std::vector<v1::SessionChunk> make_bomb(const Size& size, int frames) {
  const bool too_large = std::uint64_t{size.width} * size.height > session::kMaxDepthPixels;
  demo::DemoSessionOptions options;
  options.duration_s = 0.2;
  options.depth_width = too_large ? 512 : size.width;
  options.depth_height = too_large ? 424 : size.height;
  const std::vector<v1::SessionChunk> session = demo::make_demo_session(options);
  const auto first = [&](v1::SessionChunk::ChunkCase kind) {
    for (const v1::SessionChunk& chunk : session)
      if (chunk.chunk_case() == kind) return chunk;
    throw Error(ErrorCode::kInternal, "demo session", "has no chunk of kind " + std::to_string(kind));
  };
  std::vector<v1::SessionChunk> bomb{session.front()};
  (*bomb[0].mutable_header()->mutable_options())["fit.enabled"] = "true";
  (*bomb[0].mutable_header()->mutable_options())["fit.calibration_s"] = "30";
  if (too_large) {
    bomb[0].mutable_header()->mutable_depth_intrinsics()->set_width(size.width);
    bomb[0].mutable_header()->mutable_depth_intrinsics()->set_height(size.height);
  }
  const v1::SessionChunk depth = first(v1::SessionChunk::kDepth);
  const v1::SessionChunk body_index = first(v1::SessionChunk::kBodyIndex);
  const v1::SessionChunk skeleton = first(v1::SessionChunk::kSkeleton);
  for (int n = 0; n < frames; ++n) {
    const std::int64_t t_us = depth.depth().t_us() + 10 * n;
    bomb.push_back(depth);
    bomb.back().mutable_depth()->set_t_us(t_us);
    bomb.push_back(body_index);
    bomb.back().mutable_body_index()->set_t_us(t_us);
    bomb.push_back(skeleton);
    bomb.back().mutable_skeleton()->set_t_us(t_us);
  }
  return bomb;
}

grpc::Status send(v1::PoseFuse::Stub& stub, const std::vector<v1::SessionChunk>& chunks) {
  grpc::ClientContext context;
  auto stream = stub.Fit(&context);
  std::thread sender([&] {
    for (const v1::SessionChunk& chunk : chunks)
      if (!stream->Write(chunk)) break;
    stream->WritesDone();
  });
  v1::FitResult result;
  while (stream->Read(&result)) {
  }
  sender.join();
  return stream->Finish();
}

std::uint64_t budget_bytes(int port) {
  auto stub = bench::new_stub(port);
  grpc::ClientContext context;
  v1::ServerInfo info;
  const grpc::Status status = stub->GetServerInfo(&context, {}, &info);
  if (!status.ok()) throw Error(ErrorCode::kInternal, "GetServerInfo", status.error_message());
  return info.limits().max_session_memory_bytes();
}

int run(int argc, char** argv) {
  std::vector<int> concurrency = {1, 4};
  std::vector<Size> sizes = {{512, 424}, {1024, 1024}, {2048, 2048}};
  for (int i = 1; i < argc; i += 2) {
    const std::string flag = argv[i];
    if (i + 1 < argc && flag == "--sessions") concurrency = bench::parse_int_list(argv[i + 1], flag);
    else if (i + 1 < argc && flag == "--sizes") sizes = parse_sizes(argv[i + 1]);
    else {
      std::fprintf(stderr, "usage: bench_server_memory_bomb [--sessions N,N,...] [--sizes WxH,WxH,...]\n");
      return 2;
    }
  }
  // Every server is forked before this process starts a thread (bench/loopback_server.hpp).
  std::vector<bench::ServerProcess> servers;
  for (std::size_t k = 0; k < sizes.size() * concurrency.size(); ++k)
    servers.push_back(bench::start_server_process(server::ServerOptions()));
  const auto stop_all = [&] {
    for (const auto& s : servers) bench::stop_server_process(s);
  };
  try {
    const double budget_mib = static_cast<double>(budget_bytes(servers.front().port)) / (1 << 20);
    std::printf("posefuse-server under memory bombs (default options: budget %.0f MiB per session, load average %s)\n",
                budget_mib, bench::load_average().c_str());
    std::printf(
        "| frame | frames per bomb | bombs | final status | peak RSS above idle MiB | per bomb MiB | per bomb / budget "
        "| server CPU s | wall s |\n|---|---:|---:|---|---:|---:|---:|---:|---:|\n");
    std::size_t next_server = 0;
    for (const Size& size : sizes) {
      // Frames worth twice the budget: depth (2 bytes) and body index (1 byte) per pixel.
      const double frame_bytes = 3.0 * size.width * size.height;
      const int frames = static_cast<int>(std::ceil(2.0 * budget_mib * (1 << 20) / frame_bytes));
      const std::vector<v1::SessionChunk> bomb = make_bomb(size, frames);
      for (int n : concurrency) {
        const bench::ServerProcess& server = servers[next_server++];
        std::vector<std::unique_ptr<v1::PoseFuse::Stub>> stubs;
        for (int k = 0; k < n; ++k) stubs.push_back(bench::new_stub(server.port));
        const double idle_mib = bench::rss_mib(server.pid);
        const double cpu_before = bench::process_cpu_s(server.pid);
        std::atomic<bool> done{false};
        double peak_mib = idle_mib;
        std::thread sampler([&] {
          while (!done.load()) {
            peak_mib = std::max(peak_mib, bench::rss_mib(server.pid));
            std::this_thread::sleep_for(std::chrono::milliseconds(10));
          }
        });
        const Clock::time_point start = Clock::now();
        std::vector<grpc::Status> statuses(static_cast<std::size_t>(n));
        std::vector<std::thread> clients;
        for (int k = 0; k < n; ++k)
          clients.emplace_back([&, k] { statuses[static_cast<std::size_t>(k)] = send(*stubs[k], bomb); });
        for (std::thread& t : clients) t.join();
        const double wall_s = std::chrono::duration<double>(Clock::now() - start).count();
        done = true;
        sampler.join();
        std::map<std::string, int> codes;
        for (const grpc::Status& s : statuses) ++codes[s.ok() ? "OK" : std::to_string(s.error_code())];
        std::string status_text;
        for (const auto& [code, count] : codes)
          status_text += (status_text.empty() ? "" : ", ") + std::to_string(count) + " x " +
                         (code == "8"   ? "RESOURCE_EXHAUSTED"
                          : code == "3" ? "INVALID_ARGUMENT"
                                        : code);
        const double above_mib = peak_mib - idle_mib;
        std::printf("| %ux%u | %d | %d | %s | %.1f | %.1f | %.2f | %.2f | %.2f |\n", size.width, size.height, frames, n,
                    status_text.c_str(), above_mib, above_mib / n, above_mib / n / budget_mib,
                    bench::process_cpu_s(server.pid) - cpu_before, wall_s);
        std::fflush(stdout);
        for (const grpc::Status& s : statuses)
          if (!s.ok()) {
            std::printf("  first refusal: %s\n", s.error_message().substr(0, 300).c_str());
            break;
          }
      }
    }
  } catch (const Error& e) {
    stop_all();
    std::fprintf(stderr, "bench_server_memory_bomb: %s\n", e.what());
    return 1;
  }
  stop_all();
  return 0;
}

}  // namespace
}  // namespace posefuse

int main(int argc, char** argv) { return posefuse::run(argc, argv); }
