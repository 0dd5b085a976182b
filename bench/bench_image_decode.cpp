// Depth and body index decoding on a recorded session: per frame, the bytes on the wire and the
// CPU time of decode_depth / decode_body_index, the server's per-frame decode work.
//
//   build/bench/bench_image_decode FILE.pfchunks [repeats=5]
//
// Depth is decoded as the file holds it. Body index frames are decoded once, then re-encoded in
// every encoding this build knows and timed in each (zstd at levels 1 and 3), so one session
// compares them on the same pixels. CPU times are this thread's, the minimum over the repeats.
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "common/thread_cpu_time.hpp"
#include "session/chunk_file.hpp"
#include "session/image_codec.hpp"

namespace {

using namespace posefuse;

struct Frames {
  std::vector<v1::DepthFrame> depth;
  std::vector<v1::BodyIndexFrame> body_index;
};

Frames read_frames(const std::string& path) {
  session::ChunkFileReader reader(path);
  v1::SessionChunk chunk;
  Frames frames;
  while (reader.next(chunk)) {
    if (chunk.has_depth()) frames.depth.push_back(chunk.depth());
    if (chunk.has_body_index()) frames.body_index.push_back(chunk.body_index());
  }
  return frames;
}

// Minimum over `repeats` of the CPU seconds `decode_all` takes.
template <typename Decode>
double min_cpu_s(int repeats, Decode decode_all) {
  double best = 1e30;
  for (int r = 0; r < repeats; ++r) {
    const double start = thread_cpu_seconds();
    decode_all();
    best = std::min(best, thread_cpu_seconds() - start);
  }
  return best;
}

template <typename Frame>
double mean_bytes(const std::vector<Frame>& frames) {
  double total = 0;
  for (const Frame& f : frames) total += static_cast<double>(f.data().size());
  return total / static_cast<double>(frames.size());
}

template <typename Frame, typename Decode>
void row(const std::string& what, const std::vector<Frame>& frames, int repeats, Decode decode) {
  std::size_t checksum = 0;
  const double cpu_s = min_cpu_s(repeats, [&] {
    for (const Frame& f : frames) checksum += decode(f).total();
  });
  std::printf("| %-26s | %6zu | %10.0f | %11.1f |\n", what.c_str(), frames.size(), mean_bytes(frames),
              1e6 * cpu_s / static_cast<double>(frames.size()));
  if (checksum == 0) std::printf("(no pixels decoded)\n");
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: bench_image_decode FILE.pfchunks [repeats=5]\n");
    return 2;
  }
  const int repeats = argc > 2 ? std::atoi(argv[2]) : 5;
  const Frames frames = read_frames(argv[1]);
  if (frames.depth.empty() || frames.body_index.empty()) {
    std::fprintf(stderr, "%s has no depth or no body index frames\n", argv[1]);
    return 1;
  }
  std::printf("%s: %zu depth, %zu body index frames; decode CPU, min of %d runs\n", argv[1], frames.depth.size(),
              frames.body_index.size(), repeats);
  std::printf("| %-26s | %6s | %10s | %11s |\n", "frames (encoding)", "frames", "bytes/frame", "CPU us/frame");
  std::printf("|---|---|---|---|\n");
  row("depth " + v1::DepthFrame::Encoding_Name(frames.depth.front().encoding()), frames.depth, repeats,
      [](const v1::DepthFrame& f) { return session::decode_depth(f); });

  std::vector<cv::Mat> ids;
  for (const v1::BodyIndexFrame& f : frames.body_index) ids.push_back(session::decode_body_index(f));
  // Every encoding this build's proto knows, so that the same source runs against older builds.
  for (int e = 1; v1::BodyIndexFrame::Encoding_IsValid(e); ++e) {
    const auto encoding = static_cast<v1::BodyIndexFrame::Encoding>(e);
    const std::string name = v1::BodyIndexFrame::Encoding_Name(encoding);
    const bool zstd = name.rfind("ZSTD", 0) == 0;
    for (const int level : zstd ? std::vector<int>{1, 3} : std::vector<int>{0}) {
      std::vector<v1::BodyIndexFrame> encoded;
      for (std::size_t i = 0; i < ids.size(); ++i) {
        encoded.push_back(zstd ? session::encode_body_index(ids[i], encoding, frames.body_index[i].t_us(), level)
                               : session::encode_body_index(ids[i], encoding, frames.body_index[i].t_us()));
      }
      row("body index " + name + (zstd ? " level " + std::to_string(level) : ""), encoded, repeats,
          [](const v1::BodyIndexFrame& f) { return session::decode_body_index(f); });
    }
  }
  return 0;
}
