// Image decoding on a recorded session: per frame, the bytes on the wire and the CPU time of
// decode_depth / decode_body_index and of the colour frame, the server's per-frame decode work.
//
//   build/bench/bench_image_decode FILE.pfchunks [repeats=5]
//
// Depth is decoded as the file holds it. Body index frames are decoded once, then re-encoded in
// every encoding this build knows and timed in each (zstd at levels 1 and 3), so one session
// compares them on the same pixels. Colour (session/color_image.hpp): the whole frame to grey,
// the check on arrival alone, and the check plus both forearms' strap rectangles
// (forearm::strap_profile_rect from the camera skeleton's elbows and wrists nearest in time; the
// stage's own come from the depth-measured axis, a few pixels away). CPU times are this
// thread's, the minimum over the repeats.
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "common/thread_cpu_time.hpp"
#include "forearm/strap_detection.hpp"
#include "geometry/kinect_joints.hpp"
#include "session/chunk_file.hpp"
#include "session/color_image.hpp"
#include "session/image_codec.hpp"
#include "session/session_inputs.hpp"

namespace {

using namespace posefuse;

struct Frames {
  v1::SessionHeader header;
  std::vector<v1::DepthFrame> depth;
  std::vector<v1::BodyIndexFrame> body_index;
  std::vector<v1::ColorFrame> color;
  std::vector<v1::SkeletonFrame> skeletons;
};

Frames read_frames(const std::string& path) {
  session::ChunkFileReader reader(path);
  v1::SessionChunk chunk;
  Frames frames;
  while (reader.next(chunk)) {
    if (chunk.has_depth()) frames.depth.push_back(chunk.depth());
    if (chunk.has_body_index()) frames.body_index.push_back(chunk.body_index());
    if (chunk.has_header()) frames.header = chunk.header();
    if (chunk.has_color()) frames.color.push_back(chunk.color());
    if (chunk.has_skeleton()) frames.skeletons.push_back(chunk.skeleton());
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

void print_row(const std::string& what, std::size_t frames, double bytes, double cpu_s) {
  std::printf("| %-32s | %6zu | %10.0f | %11.1f |\n", what.c_str(), frames, bytes,
              1e6 * cpu_s / static_cast<double>(frames));
}

template <typename Frame, typename Decode>
void row(const std::string& what, const std::vector<Frame>& frames, int repeats, Decode decode) {
  std::size_t checksum = 0;
  const double cpu_s = min_cpu_s(repeats, [&] {
    for (const Frame& f : frames) checksum += decode(f).total();
  });
  print_row(what, frames.size(), mean_bytes(frames), cpu_s);
  if (checksum == 0) std::printf("(no pixels decoded)\n");
}

geometry::Vec3 joint_K(const v1::SkeletonFrame& skeleton, geometry::KinectJoint joint) {
  const auto& p = skeleton.joints(static_cast<int>(joint)).position_m();
  return {p.x(), p.y(), p.z()};
}

// Both forearms' strap rectangles for each colour frame (none where a forearm leaves the image),
// decoded in one pass as the forearm stage does.
std::vector<std::vector<geometry::PixelRect>> forearm_rects(const Frames& frames) {
  const session::SessionCameras cameras = session::session_cameras(frames.header);
  forearm::StrapCameras strap;
  strap.depth = cameras.depth;
  strap.color = *cameras.color;
  strap.color_from_depth = cameras.color_from_depth;
  strap.color_from_depth_m = cameras.color_from_depth_m;
  std::vector<std::vector<geometry::PixelRect>> rects;
  std::size_t s = 0;
  for (const v1::ColorFrame& color : frames.color) {
    while (s + 1 < frames.skeletons.size() && std::llabs(frames.skeletons[s + 1].t_us() - color.t_us()) <=
                                                  std::llabs(frames.skeletons[s].t_us() - color.t_us())) {
      ++s;
    }
    std::vector<geometry::PixelRect>& frame_rects = rects.emplace_back();
    if (frames.skeletons.empty() || frames.skeletons[s].joints_size() != geometry::kKinectJointCount) continue;
    for (const geometry::KinectArmJoints& arm : {geometry::kLeftArmJoints, geometry::kRightArmJoints}) {
      const geometry::PixelRect rect = forearm::strap_profile_rect(strap, joint_K(frames.skeletons[s], arm.elbow),
                                                                   joint_K(frames.skeletons[s], arm.wrist));
      if (!rect.empty()) frame_rects.push_back(rect);
    }
  }
  return rects;
}

void color_rows(const Frames& frames, int repeats) {
  row("colour " + v1::ColorFrame::Encoding_Name(frames.color.front().encoding()) + " whole, to grey", frames.color,
      repeats, [](const v1::ColorFrame& f) { return session::decode_color_gray(f); });
  std::size_t checked = 0;
  const double check_s = min_cpu_s(repeats, [&] {
    for (const v1::ColorFrame& f : frames.color) checked += session::ColorImage::from_frame(f).held_bytes();
  });
  print_row("colour check on arrival", frames.color.size(), mean_bytes(frames.color), check_s);
  const std::vector<std::vector<geometry::PixelRect>> rects = forearm_rects(frames);
  double area = 0;
  std::size_t counted = 0;
  for (const auto& frame_rects : rects)
    for (const geometry::PixelRect& r : frame_rects) {
      area += static_cast<double>(r.col1 - r.col0 + 1) * (r.row1 - r.row0 + 1);
      ++counted;
    }
  cv::Mat gray;
  const double rects_s = min_cpu_s(repeats, [&] {
    for (std::size_t i = 0; i < frames.color.size(); ++i) {
      const session::ColorImage image = session::ColorImage::from_frame(frames.color[i]);
      image.decode_gray(rects[i], gray);
    }
  });
  print_row("colour check + forearm rects", frames.color.size(), mean_bytes(frames.color), rects_s);
  const double pixels = static_cast<double>(frames.color.front().width()) * frames.color.front().height();
  std::printf("forearm rectangles: %.2f per frame, mean %.1f %% of the frame's pixels each\n",
              static_cast<double>(counted) / static_cast<double>(frames.color.size()),
              counted ? 100.0 * area / static_cast<double>(counted) / pixels : 0.0);
  if (checked == 0) std::printf("(nothing checked)\n");
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
  std::printf("| %-32s | %6s | %10s | %11s |\n", "frames (encoding)", "frames", "bytes/frame", "CPU us/frame");
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
  if (!frames.color.empty() && frames.header.has_color_intrinsics()) color_rows(frames, repeats);
  return 0;
}
