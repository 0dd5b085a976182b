// The client library: reading recordings (directory and chunk file), the Fit call against an
// in-process server, result files, and error lines.
#include <filesystem>
#include <fstream>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "client/demo_session.hpp"
#include "client/fit_call.hpp"
#include "client/recording.hpp"
#include "client/result_writer.hpp"
#include "server/posefuse_server.hpp"
#include "session/file_bytes.hpp"
#include "tests/server/test_support.hpp"

namespace posefuse::client {
namespace {

namespace fs = std::filesystem;

class ClientTest : public ::testing::Test {
 protected:
  static server::ServerOptions one_worker_on_a_free_port() {
    server::ServerOptions options;
    options.listen = "127.0.0.1:0";
    options.workers = 1;
    return options;
  }

  static std::size_t line_count(const fs::path& path) {
    std::ifstream in(path);
    std::size_t n = 0;
    for (std::string line; std::getline(in, line);) ++n;
    return n;
  }

  test::TempDir temp_;
  const fs::path& dir_ = temp_.path();
};

TEST_F(ClientTest, RecordingReadsBothFormsWithProgress) {
  const std::uint64_t written = demo::write_demo_session(dir_ / "demo.pfchunks");
  demo::write_demo_session(dir_ / "demo_dir");
  for (const fs::path& path : {dir_ / "demo.pfchunks", dir_ / "demo_dir"}) {
    SCOPED_TRACE(path.string());
    Recording recording(path);
    session::SessionChunk chunk;
    std::uint64_t n = 0;
    double last_fraction = 0.0;
    while (recording.next(chunk)) {
      ++n;
      const double f = recording.fraction_read();
      EXPECT_GE(f, last_fraction);
      last_fraction = f;
    }
    EXPECT_EQ(n, written);
    EXPECT_DOUBLE_EQ(recording.fraction_read(), 1.0);
  }
}

TEST_F(ClientTest, RecordingPutsCommandLineOptionsIntoTheHeader) {
  demo::write_demo_session(dir_ / "demo.pfchunks");
  Recording recording(dir_ / "demo.pfchunks",
                      HeaderEdits{.options = {{"fit.enabled", "true"}, {"imu.tau_acc_s", "2.5"}}, .height_m = {}});
  session::SessionChunk chunk;
  std::uint64_t headers = 0;
  while (recording.next(chunk)) {
    if (!chunk.has_header()) continue;
    ++headers;
    EXPECT_EQ(chunk.header().options().at("fit.enabled"), "true");
    EXPECT_EQ(chunk.header().options().at("imu.tau_acc_s"), "2.5");
  }
  EXPECT_EQ(headers, 1u);
}

TEST_F(ClientTest, RecordingPutsTheCommandLineHeightIntoTheHeader) {
  demo::write_demo_session(dir_ / "demo.pfchunks");
  const auto header_of = [&](const HeaderEdits& edits) {
    Recording recording(dir_ / "demo.pfchunks", edits);
    session::SessionChunk chunk;
    while (recording.next(chunk)) {
      if (chunk.has_header()) return chunk.header();
    }
    ADD_FAILURE() << "no header";
    return v1::SessionHeader();
  };
  const v1::SessionHeader recorded = header_of({});
  const v1::SessionHeader edited = header_of(HeaderEdits{.options = {}, .height_m = 1.72});
  EXPECT_FALSE(recorded.has_height_m());
  ASSERT_TRUE(edited.has_height_m());
  EXPECT_EQ(edited.height_m(), 1.72);
  EXPECT_EQ(edited.options().size(), recorded.options().size());  // nothing else changed
  EXPECT_EQ(edited.depth_intrinsics().fx(), recorded.depth_intrinsics().fx());
}

TEST_F(ClientTest, HeightTextIsMetresWithinTheRecordableRange) {
  EXPECT_EQ(parse_height_m("1.72"), 1.72);
  EXPECT_EQ(parse_height_m("0.5"), 0.5);
  EXPECT_EQ(parse_height_m("2.5"), 2.5);
  for (const char* bad : {"", "tall", "1.72m", "nan", "inf", "0.49", "2.51", "-1.7", "172"}) {
    try {
      parse_height_m(bad);
      ADD_FAILURE() << "no error for '" << bad << "'";
    } catch (const Error& e) {
      EXPECT_EQ(e.field(), "--height") << bad;
      EXPECT_EQ(e.code(), ErrorCode::kInvalidArgument) << bad;
    }
  }
  try {
    parse_height_m("172");
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("1.72 for 172 cm"), std::string::npos) << e.what();
  }
}

// The height reaches the server's validator: one outside what a header may record ends the call
// with an error naming header.height_m.
TEST_F(ClientTest, FitSendsTheHeightToTheServer) {
  server::PoseFuseServer server(one_worker_on_a_free_port());
  demo::write_demo_session(dir_ / "demo.pfchunks");
  ResultWriter writer(dir_ / "out");
  const FitOutcome outcome = run_fit(make_channel("127.0.0.1:" + std::to_string(server.port())), dir_ / "demo.pfchunks",
                                     writer, {}, HeaderEdits{.options = {}, .height_m = 3.0});
  ASSERT_FALSE(outcome.local_error);
  EXPECT_FALSE(outcome.status.ok());
  EXPECT_NE(outcome.status.error_message().find("height_m"), std::string::npos) << outcome.status.error_message();
}

TEST_F(ClientTest, HeaderOptionTextIsKeyEqualsValue) {
  EXPECT_EQ(parse_header_option("fit.enabled=true"), std::make_pair(std::string("fit.enabled"), std::string("true")));
  EXPECT_EQ(parse_header_option("forearm.K_from_B=1,0,0,0"),
            std::make_pair(std::string("forearm.K_from_B"), std::string("1,0,0,0")));
  EXPECT_EQ(parse_header_option("a="), std::make_pair(std::string("a"), std::string()));
  for (const char* bad : {"fit.enabled", "=true", "fit.enabled = true", "fit.enabled=tr\tue", ""}) {
    try {
      parse_header_option(bad);
      ADD_FAILURE() << "no error for '" << bad << "'";
    } catch (const Error& e) {
      EXPECT_EQ(e.field(), "--option") << bad;
    }
  }
}

// The option reaches the server's stages: a value the body-fit stage refuses ends the call with
// an error naming that option.
TEST_F(ClientTest, FitSendsHeaderOptionsToTheServer) {
  server::PoseFuseServer server(one_worker_on_a_free_port());
  demo::write_demo_session(dir_ / "demo.pfchunks");
  ResultWriter writer(dir_ / "out");
  const FitOutcome outcome = run_fit(make_channel("127.0.0.1:" + std::to_string(server.port())), dir_ / "demo.pfchunks",
                                     writer, {}, HeaderEdits{.options = {{"fit.enabled", "yes"}}, .height_m = {}});
  ASSERT_FALSE(outcome.local_error);
  EXPECT_FALSE(outcome.status.ok());
  EXPECT_NE(outcome.status.error_message().find("fit.enabled"), std::string::npos) << outcome.status.error_message();
}

TEST_F(ClientTest, MissingRecordingIsNotFound) {
  try {
    Recording recording(dir_ / "nothing");
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kNotFound);
  }
}

TEST_F(ClientTest, FitWritesResultFiles) {
  server::PoseFuseServer server(one_worker_on_a_free_port());
  demo::write_demo_session(dir_ / "demo");

  ResultWriter writer(dir_ / "out");
  const FitOutcome outcome = run_fit(make_channel("127.0.0.1:" + std::to_string(server.port())), dir_ / "demo", writer);
  ASSERT_FALSE(outcome.local_error) << outcome.local_error->what();
  ASSERT_TRUE(outcome.status.ok()) << outcome.status.error_message();
  EXPECT_EQ(outcome.progress.chunks_sent, 952u);
  EXPECT_EQ(outcome.progress.depth_frames_sent, 300u);
  EXPECT_DOUBLE_EQ(outcome.progress.fraction_read, 1.0);
  EXPECT_EQ(writer.orientation_samples(), 1600u);
  // Header row + one row per sample.
  EXPECT_EQ(line_count(dir_ / "out" / "imu_orientations" / "arm_left.csv"), 801u);
  EXPECT_EQ(line_count(dir_ / "out" / "imu_orientations" / "base.csv"), 801u);
  // The demo has arm IMUs but no camera alignment (forearm.K_from_B): the forearm stage says so.
  // Its depth frames hold no body for the fit (on by default): ten frames' warnings are listed,
  // then how many more.
  const std::string warnings = session::read_file_bytes(dir_ / "out" / "warnings.txt", "w");
  EXPECT_NE(warnings.find("FOREARM_NO_CAMERA_ALIGNMENT"), std::string::npos);
  EXPECT_NE(warnings.find("290 more FIT_FRAME warnings"), std::string::npos);
  EXPECT_LE(line_count(dir_ / "out" / "warnings.txt"), 15u);
  const std::string calibration = session::read_file_bytes(dir_ / "out" / "calibration.json", "c");
  EXPECT_NE(calibration.find("\"gyro_bias_rad_s\""), std::string::npos);
  ASSERT_NE(writer.summary(), nullptr);
  EXPECT_EQ(writer.summary()->depth_frames(), 300u);
}

TEST_F(ClientTest, ForearmResultsGoToCsvFiles) {
  ResultWriter writer(dir_ / "out");
  v1::FitResult orientations;
  v1::ForearmOrientationBatch& batch = *orientations.mutable_forearm_orientations();
  batch.set_device_id("arm_r");
  batch.set_arm(v1::RIGHT);
  for (int i = 0; i < 3; ++i) {
    batch.add_t_us(1000 + 12500 * i);
    for (const double v : {1.0, 0.0, 0.0, 0.0}) batch.add_k_from_f(v);
    batch.add_pronation_rad(0.1 * i);
    batch.add_uncertainty_rad(0.05);
    batch.add_confidence(0.9);
  }
  writer.write(orientations);
  v1::FitResult frame;
  frame.mutable_frame()->set_t_us(33333);
  v1::ImuPosition& p = *frame.mutable_frame()->add_imu_positions();
  p.set_device_id("arm_r");
  p.mutable_position_m()->set_z(2.0);
  p.set_source(v1::PREDICTED);
  writer.write(frame);
  v1::FitResult segment;
  v1::RecoveredSegment& s = *segment.mutable_recovered_segment();
  s.set_device_id("arm_r");
  s.set_method(v1::RecoveredSegment::SMOOTHER);
  s.add_samples()->set_t_us(5);
  s.add_samples()->set_t_us(6);
  writer.write(segment);
  writer.finish();
  EXPECT_EQ(writer.forearm_samples(), 3u);
  EXPECT_EQ(line_count(dir_ / "out" / "forearm_orientations" / "arm_r.csv"), 4u);
  EXPECT_EQ(line_count(dir_ / "out" / "imu_positions.csv"), 2u);
  EXPECT_NE(session::read_file_bytes(dir_ / "out" / "imu_positions.csv", "p").find("33333,arm_r,0,0,2,PREDICTED"),
            std::string::npos);
  EXPECT_EQ(line_count(dir_ / "out" / "recovered_segments.csv"), 3u);
  EXPECT_NE(session::read_file_bytes(dir_ / "out" / "recovered_segments.csv", "s").find("arm_r,SMOOTHER"),
            std::string::npos);
  // A malformed batch (3 samples, 2 angles) is refused with the field named.
  batch.mutable_pronation_rad()->RemoveLast();
  try {
    writer.write(orientations);
    ADD_FAILURE() << "accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.field(), "forearm_orientations.K_from_F");
  }
}

TEST_F(ClientTest, UnreachableServerGivesOneReadableLine) {
  demo::write_demo_session(dir_ / "demo.pfchunks");
  ResultWriter writer(dir_ / "out");
  // Port 1 on loopback: nothing listens there.
  const FitOutcome outcome = run_fit(make_channel("127.0.0.1:1"), dir_ / "demo.pfchunks", writer);
  EXPECT_EQ(outcome.status.error_code(), grpc::StatusCode::UNAVAILABLE);
  const std::string line = status_line(outcome.status, "127.0.0.1:1");
  EXPECT_EQ(line.rfind("cannot reach the server at 127.0.0.1:1", 0), 0u) << line;
  EXPECT_EQ(line.find('\n'), std::string::npos);
}

TEST_F(ClientTest, ServerErrorLineCarriesCodeAndField) {
  const grpc::Status status(grpc::StatusCode::INVALID_ARGUMENT,
                            "chunk[0].header.depth_intrinsics.fx: is -1, must be > 0");
  EXPECT_EQ(status_line(status, "h:1"),
            "server h:1: INVALID_ARGUMENT: chunk[0].header.depth_intrinsics.fx: is -1, must be > 0");
}

TEST_F(ClientTest, ResultWriterRejectsUnsafeDeviceIds) {
  ResultWriter writer(dir_ / "out");
  v1::FitResult result;
  result.mutable_imu_orientations()->set_device_id("../escape");
  result.mutable_imu_orientations()->add_t_us(1);
  for (int k = 0; k < 4; ++k) result.mutable_imu_orientations()->add_w_from_a(k == 0 ? 1.0 : 0.0);
  EXPECT_THROW(writer.write(result), Error);
  EXPECT_FALSE(fs::exists(dir_ / "escape.csv"));
}

}  // namespace
}  // namespace posefuse::client
