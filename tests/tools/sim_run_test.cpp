// posefuse-sim end to end: the session directory passes SessionValidator, gt/ has the client's
// result-file layout, the output is byte-identical for a seed (whatever the thread count), and
// the strap in the RGB frames sits on the forearm where the header's registration projects it.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <map>
#include <opencv2/imgcodecs.hpp>

#include "../scratch_dir.hpp"
#include "client/result_writer.hpp"
#include "common/error.hpp"
#include "raycast/depth_camera.hpp"
#include "session/chunk_file.hpp"
#include "session/directory_reader.hpp"
#include "session/file_bytes.hpp"
#include "session/image_codec.hpp"
#include "session/json_message.hpp"
#include "session/result_files.hpp"
#include "session/session_validator.hpp"
#include "sim/test_camera.hpp"
#include "tools/sim/sim_run.hpp"

using namespace posefuse;
namespace fs = std::filesystem;

namespace {

fs::path fresh_dir(const std::string& name) {
  return posefuse::testing::fresh_scratch_dir("posefuse_sim_run_test", name);
}

// A small, fast session: quarter-resolution depth, small colour.
sim::SimSessionOptions small_options() {
  sim::SimSessionOptions o;
  o.duration_s = 1.0;
  o.depth_intrinsics = sim::testing::quarter_kinect_intrinsics();
  o.color_camera.intrinsics = {240, 135, 132.0, 132.0, 119.5, 67.0, 0.0, 0.0, 0.0};
  o.seed = 7;
  return o;
}

std::map<std::string, std::string> tree(const fs::path& root) {
  std::map<std::string, std::string> files;
  for (const auto& entry : fs::recursive_directory_iterator(root)) {
    if (entry.is_regular_file()) {
      files[fs::relative(entry.path(), root).string()] = session::read_file_bytes(entry.path(), "tree");
    }
  }
  return files;
}

std::string first_line(const fs::path& path) {
  std::ifstream in(path);
  std::string line;
  std::getline(in, line);
  return line;
}

std::size_t line_count(const fs::path& path) {
  std::ifstream in(path);
  return static_cast<std::size_t>(std::count(std::istreambuf_iterator<char>(in), {}, '\n'));
}

class CollectingSink : public session::ChunkSink {
 public:
  void write(const session::SessionChunk& chunk) override { chunks.push_back(chunk); }
  void finish() override {}
  std::vector<session::SessionChunk> chunks;
};

}  // namespace

TEST(SimRun, DirectoryPassesValidatorWithEveryStream) {
  tools::SimRunRequest request;
  request.options = small_options();
  request.out_directory = fresh_dir("valid");
  request.contact_sheet = fresh_dir("valid_sheet.png");
  const tools::SimRunResult result = tools::run_simulation(request);
  EXPECT_EQ(result.frames, 31);
  EXPECT_EQ(result.gt_directory, *request.out_directory / "gt");

  session::DirectoryReader reader(*request.out_directory);
  session::SessionValidator validator;
  session::SessionChunk chunk;
  std::map<int, int> sync_kinds;
  while (reader.next(chunk)) {
    validator.check(chunk);
    if (chunk.has_sync_event()) ++sync_kinds[chunk.sync_event().kind()];
  }
  validator.finish();
  const v1::EndOfSession& counts = validator.counts();
  EXPECT_EQ(counts.depth_frames(), 31u);
  EXPECT_EQ(counts.body_index_frames(), 31u);
  EXPECT_EQ(counts.skeleton_frames(), 31u);
  EXPECT_EQ(counts.color_frames(), 31u);
  ASSERT_EQ(counts.imu_samples().size(), 3u);
  for (const auto& [device, samples] : counts.imu_samples()) {
    EXPECT_GT(samples, 70u) << device;  // 80 Hz for 1 s, minus packet loss
    EXPECT_LE(samples, 81u) << device;
  }
  EXPECT_EQ(counts.audio_frames(), 16000u);
  EXPECT_EQ(sync_kinds[v1::SyncEvent::BUZZER_STOP], 1);
  EXPECT_GE(sync_kinds[v1::SyncEvent::BLE_BROADCAST_RECEIPT], 9);  // 3 rounds x 3 devices at least
  const v1::SessionHeader& header = validator.header();
  EXPECT_EQ(header.color_intrinsics().width(), 240u);
  EXPECT_TRUE(header.has_color_from_depth());
  EXPECT_GT(fs::file_size(*request.contact_sheet), 10000u);
  EXPECT_FALSE(cv::imread(request.contact_sheet->string()).empty());
}

TEST(SimRun, ChunkFilePassesValidatorAndGtGoesBeside) {
  tools::SimRunRequest request;
  request.options = small_options();
  request.options.color = false;
  request.chunk_file = fresh_dir("session.pfchunks");
  const tools::SimRunResult result = tools::run_simulation(request);
  EXPECT_EQ(result.gt_directory, fs::path(request.chunk_file->string() + ".gt"));
  EXPECT_TRUE(fs::exists(result.gt_directory / "smpl_joints.csv"));
  session::ChunkFileReader reader(*request.chunk_file);
  session::SessionValidator validator;
  session::SessionChunk chunk;
  std::uint64_t chunks = 0;
  while (reader.next(chunk)) {
    validator.check(chunk);
    ++chunks;
  }
  validator.finish();
  EXPECT_EQ(chunks, result.chunks);
  EXPECT_EQ(validator.counts().color_frames(), 0u);
}

TEST(SimRun, SameSeedSameBytesWhateverTheThreads) {
  tools::SimRunRequest a;
  a.options = small_options();
  a.options.threads = 1;
  a.out_directory = fresh_dir("same_a");
  tools::run_simulation(a);
  const auto tree_a = tree(*a.out_directory);
  EXPECT_GT(tree_a.size(), 100u);  // 31 frames x 3 image streams, CSVs, gt/
  for (const int threads : {2, 3}) {
    tools::SimRunRequest b = a;
    b.options.threads = threads;
    b.out_directory = fresh_dir("same_b" + std::to_string(threads));
    tools::run_simulation(b);
    const auto tree_b = tree(*b.out_directory);
    ASSERT_EQ(tree_a.size(), tree_b.size()) << threads << " threads";
    for (const auto& [name, bytes] : tree_a) {
      ASSERT_TRUE(tree_b.count(name)) << name;
      EXPECT_TRUE(bytes == tree_b.at(name)) << name << " differs with " << threads << " threads";
    }
  }

  tools::SimRunRequest c = a;
  c.options.seed = 8;
  c.out_directory = fresh_dir("other_seed");
  tools::run_simulation(c);
  const auto tree_c = tree(*c.out_directory);
  EXPECT_NE(tree_a.at("depth/500000.png"), tree_c.at("depth/500000.png"));
  EXPECT_NE(tree_a.at("imu/imu_right.csv"), tree_c.at("imu/imu_right.csv"));
  EXPECT_NE(tree_a.at("gt/truth.json"), tree_c.at("gt/truth.json"));
}

// The directory's depth and body index PNGs come straight from the frame threads, the chunk
// file's are zstd: both must hold the same frames.
TEST(SimRun, DirectoryAndChunkFileHoldTheSameDepthAndBodyIndex) {
  tools::SimRunRequest dir;
  dir.options = small_options();
  dir.options.color = false;
  dir.out_directory = fresh_dir("depth_dir");
  tools::SimRunRequest file = dir;
  file.out_directory.reset();
  file.chunk_file = fresh_dir("depth.pfchunks");
  tools::run_simulation(dir);
  tools::run_simulation(file);
  // The directory's PNG of a frame holds the chunk file's decoded pixels.
  const auto expect_same_as_directory = [&](const cv::Mat& from_file, const char* folder, std::int64_t t_us) {
    const fs::path png = *dir.out_directory / folder / (std::to_string(t_us) + ".png");
    const cv::Mat from_dir = cv::imread(png.string(), cv::IMREAD_UNCHANGED);
    ASSERT_EQ(from_dir.type(), from_file.type()) << png;
    EXPECT_EQ(cv::countNonZero(from_file != from_dir), 0) << png;
  };
  session::ChunkFileReader reader(*file.chunk_file);
  session::SessionChunk chunk;
  int depth_frames = 0;
  int body_index_frames = 0;
  while (reader.next(chunk)) {
    if (chunk.has_depth()) {
      ASSERT_EQ(chunk.depth().encoding(), v1::DepthFrame::ZSTD_U16_LE);
      expect_same_as_directory(session::decode_depth(chunk.depth(), "depth"), "depth", chunk.depth().t_us());
      ++depth_frames;
    }
    if (chunk.has_body_index()) {
      ASSERT_EQ(chunk.body_index().encoding(), v1::BodyIndexFrame::ZSTD_U8);
      expect_same_as_directory(session::decode_body_index(chunk.body_index(), "body_index"), "body_index",
                               chunk.body_index().t_us());
      ++body_index_frames;
    }
  }
  EXPECT_EQ(depth_frames, 31);
  EXPECT_EQ(body_index_frames, 31);
}

TEST(SimRun, GtHasTheClientResultFilesColumns) {
  tools::SimRunRequest request;
  request.options = small_options();
  request.options.color = false;
  request.out_directory = fresh_dir("columns");
  const tools::SimRunResult result = tools::run_simulation(request);
  const fs::path gt = result.gt_directory;

  // What the client writes for a frame with every kind of entry.
  const fs::path client_dir = fresh_dir("client_results");
  client::ResultWriter writer(client_dir);
  v1::FitResult frame;
  frame.mutable_frame()->set_t_us(0);
  frame.mutable_frame()->add_smpl_joints();
  frame.mutable_frame()->add_camera_joints();
  frame.mutable_frame()->add_forearms()->set_arm(v1::LEFT);
  frame.mutable_frame()->add_imu_positions()->set_device_id("imu_left");
  writer.write(frame);
  v1::FitResult orientations;
  orientations.mutable_imu_orientations()->set_device_id("imu_left");
  orientations.mutable_imu_orientations()->add_t_us(0);
  for (double c : {1.0, 0.0, 0.0, 0.0}) orientations.mutable_imu_orientations()->add_w_from_a(c);
  orientations.mutable_imu_orientations()->add_uncertainty_rad(0.0);
  orientations.mutable_imu_orientations()->add_confidence(1.0);
  writer.write(orientations);
  v1::FitResult forearm;
  forearm.mutable_forearm_orientations()->set_device_id("imu_left");
  forearm.mutable_forearm_orientations()->add_t_us(0);
  for (double c : {1.0, 0.0, 0.0, 0.0}) forearm.mutable_forearm_orientations()->add_k_from_f(c);
  forearm.mutable_forearm_orientations()->add_pronation_rad(0.0);
  forearm.mutable_forearm_orientations()->add_uncertainty_rad(0.0);
  forearm.mutable_forearm_orientations()->add_confidence(1.0);
  writer.write(forearm);
  v1::FitResult calibration;
  calibration.mutable_calibration()->add_forearms()->set_arm(v1::LEFT);
  writer.write(calibration);
  writer.finish();

  namespace layout = session::result_layout;
  for (const char* name :
       {layout::kSmplJointsCsv, layout::kCameraJointsCsv, layout::kForearmsCsv, layout::kImuPositionsCsv,
        "imu_orientations/imu_left.csv", "forearm_orientations/imu_left.csv"}) {
    ASSERT_TRUE(fs::exists(gt / name)) << name;
    ASSERT_TRUE(fs::exists(client_dir / name)) << name;
    EXPECT_EQ(first_line(gt / name), first_line(client_dir / name)) << name;
  }
  EXPECT_TRUE(fs::exists(gt / layout::kCalibrationJson));
  EXPECT_TRUE(fs::exists(client_dir / layout::kCalibrationJson));
  // Rows: one per frame x joint / arm / device; every sample the right IMU took.
  EXPECT_EQ(line_count(gt / layout::kSmplJointsCsv), 1 + 31u * 24);
  EXPECT_EQ(line_count(gt / layout::kCameraJointsCsv), 1 + 31u * 25);
  EXPECT_EQ(line_count(gt / layout::kForearmsCsv), 1 + 31u * 2);
  EXPECT_EQ(line_count(gt / layout::kImuPositionsCsv), 1 + 31u * 3);
  EXPECT_EQ(line_count(gt / "occlusion.csv"), 1 + 31u * 2);
  EXPECT_EQ(line_count(gt / "imu_orientations/imu_right.csv"), line_count(gt / "imu_samples/imu_right.csv"));
  EXPECT_EQ(line_count(gt / "forearm_orientations/imu_right.csv"), line_count(gt / "imu_samples/imu_right.csv"));
  EXPECT_FALSE(fs::exists(gt / "forearm_orientations/imu_base.csv"));
  v1::CalibrationReport report;
  session::message_from_json(session::read_file_bytes(gt / layout::kCalibrationJson, "calibration"), "calibration",
                             report);
  ASSERT_EQ(report.forearms_size(), 2);
  EXPECT_DOUBLE_EQ(report.forearms(1).d_se_m(), request.options.strap_to_elbow_m);
  EXPECT_EQ(report.clock_offset_us().size(), 3u);
}

TEST(SimRun, StrapPixelsLieOnTheProjectedForearm) {
  sim::SimSessionOptions o = small_options();
  o.color_camera = sim::ColorCameraOptions();  // 960 x 540
  o.color_camera.noise_sigma = 0;
  o.color_camera.jpeg_quality = 100;
  o.strap_slip.enabled = false;
  CollectingSink sink;
  const sim::SimTruth truth = sim::simulate_session(o, sink);
  const v1::SessionHeader& header = sink.chunks.front().header();
  // The colour camera exactly as a reader of the recording sees it: header fields only.
  const auto& ci = header.color_intrinsics();
  const raycast::DepthCamera color_camera({static_cast<int>(ci.width()), static_cast<int>(ci.height()), ci.fx(),
                                           ci.fy(), ci.cx(), ci.cy(), ci.k1(), ci.k2(), ci.k3()});
  const auto& r = header.color_from_depth().rotation();
  const auto& t = header.color_from_depth().translation_m();
  Eigen::Isometry3d C_from_K = Eigen::Isometry3d::Identity();
  C_from_K.linear() = Eigen::Quaterniond(r.w(), r.x(), r.y(), r.z()).toRotationMatrix();
  C_from_K.translation() = Eigen::Vector3d(t.x(), t.y(), t.z());

  int frame = 0, checked_frames = 0;
  for (const auto& chunk : sink.chunks) {
    if (!chunk.has_color()) continue;
    const sim::SimFrameTruth& gt = truth.frames[static_cast<std::size_t>(frame++)];
    ASSERT_EQ(gt.t_us, chunk.color().t_us());
    const std::string& bytes = chunk.color().data();
    const cv::Mat image = cv::imdecode(
        cv::Mat(1, static_cast<int>(bytes.size()), CV_8U, const_cast<char*>(bytes.data())), cv::IMREAD_COLOR);
    ASSERT_FALSE(image.empty());
    const auto pelvis_uv = color_camera.project(C_from_K * gt.smpl_joints_K.col(body::kPelvis));
    ASSERT_TRUE(pelvis_uv);
    std::array<int, 2> strap_pixels = {0, 0};
    int stray = 0;
    for (int row = 0; row < static_cast<int>(std::lround((*pelvis_uv)[1])); ++row) {
      for (int col = 0; col < image.cols; ++col) {
        const cv::Vec3b p = image.at<cv::Vec3b>(row, col);
        const int high = std::max({p[0], p[1], p[2]}), low = std::min({p[0], p[1], p[2]});
        if (high > 20 || high - low > 6) continue;  // the strap is near-black and grey
        // Distance to each projected forearm (elbow -> wrist) and position along it.
        bool on_a_forearm = false;
        for (int arm = 0; arm < 2; ++arm) {
          const Eigen::Vector3d elbow =
              C_from_K * gt.smpl_joints_K.col(arm == 0 ? body::kLeftElbow : body::kRightElbow);
          const Eigen::Vector3d wrist =
              C_from_K * gt.smpl_joints_K.col(arm == 0 ? body::kLeftWrist : body::kRightWrist);
          const auto e = color_camera.project(elbow), w = color_camera.project(wrist);
          if (!e || !w) continue;
          const Eigen::Vector2d d = *w - *e, q = Eigen::Vector2d(col, row) - *e;
          const double along = q.dot(d) / d.squaredNorm();
          const double across = std::abs(d.x() * q.y() - d.y() * q.x()) / d.norm();
          const double forearm_m = (wrist - elbow).norm();
          const double px_per_m = ci.fx() / elbow.z();
          const double strap_lo = (o.strap_to_elbow_m - 0.5 * o.color_camera.strap_width_m) / forearm_m;
          const double strap_hi = (o.strap_to_elbow_m + 0.5 * o.color_camera.strap_width_m) / forearm_m;
          // A forearm is about 4 cm in radius: allow 6 cm plus 2 px, and 1.5 px along the bone.
          const double slack = 1.5 / d.norm();
          if (across <= 0.06 * px_per_m + 2 && along >= strap_lo - slack && along <= strap_hi + slack) {
            on_a_forearm = true;
            ++strap_pixels[static_cast<std::size_t>(arm)];
          }
        }
        if (!on_a_forearm) ++stray;
      }
    }
    EXPECT_EQ(stray, 0) << "frame " << frame;
    if (gt.strap_visible[0] && gt.strap_visible[1]) {
      EXPECT_GT(strap_pixels[0], 15) << "frame " << frame;
      EXPECT_GT(strap_pixels[1], 15) << "frame " << frame;
      ++checked_frames;
    }
  }
  EXPECT_GT(checked_frames, 20);
}

TEST(SimRun, BadRequestsAreRejected) {
  tools::SimRunRequest none;
  none.options = small_options();
  try {
    tools::run_simulation(none);
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kInvalidArgument);
    EXPECT_EQ(e.field(), "--out/--chunk-file");
  }
  tools::SimRunRequest busy;
  busy.options = small_options();
  busy.out_directory = fresh_dir("busy");
  busy.gt_directory = fresh_dir("busy_gt");
  fs::create_directories(*busy.gt_directory);
  session::write_file_bytes(*busy.gt_directory / "x", "x");
  try {
    tools::run_simulation(busy);
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kFailedPrecondition);
  }
  EXPECT_FALSE(fs::exists(*busy.out_directory));  // nothing written before the check
}
