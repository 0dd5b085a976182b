// posefuse-server in process on 127.0.0.1:0, driven over a real gRPC channel.
// No timing assertions: waits are for conditions, with generous deadlines only against hangs.
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <functional>
#include <map>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <google/protobuf/descriptor.pb.h>
#include <gtest/gtest.h>

#include "client/demo_session.hpp"
#include "client/fit_call.hpp"
#include "posefuse/v1/service.grpc.pb.h"
#include "server/posefuse_server.hpp"
#include "server/session_memory.hpp"
#include "session/stage_inputs.hpp"
#include "tests/server/health_check.hpp"
#include "tests/server/http_client.hpp"
#include "tests/server/reflection_call.hpp"
#include "tests/server/test_support.hpp"

namespace posefuse::server {
namespace {

using Stream = grpc::ClientReaderWriter<v1::SessionChunk, v1::FitResult>;

struct CallResult {
  grpc::Status status;
  std::vector<v1::FitResult> results;

  std::map<std::string, std::size_t> orientation_samples() const { return test::orientation_samples(results); }
  std::vector<v1::ItemError> item_errors() const {
    std::vector<v1::ItemError> out;
    for (const auto& r : results) {
      if (r.has_item_error()) out.push_back(r.item_error());
    }
    return out;
  }
};

using test::set_test_deadline;

class ServerTest : public ::testing::Test {
 protected:
  void start(ServerOptions options = {}) {
    options.listen = "127.0.0.1:0";
    if (options.workers == 0) options.workers = 2;
    server_ = std::make_unique<PoseFuseServer>(options);
    address_ = "127.0.0.1:" + std::to_string(server_->port());
    channel_ = client::make_channel(address_);
    stub_ = v1::PoseFuse::NewStub(channel_);
  }

  // Sends `chunks` (while receiving) and returns the status and every result; `after_write`
  // runs after each chunk is written (a client's pace).
  CallResult fit(const std::vector<v1::SessionChunk>& chunks,
                 const std::function<void(const v1::SessionChunk&)>& after_write = {}) {
    grpc::ClientContext context;
    set_test_deadline(context);
    auto stream = stub_->Fit(&context);
    std::thread sender([&] {
      for (const auto& chunk : chunks) {
        if (!stream->Write(chunk)) return;
        if (after_write) after_write(chunk);
      }
      stream->WritesDone();
    });
    CallResult call;
    v1::FitResult result;
    while (stream->Read(&result)) call.results.push_back(result);
    sender.join();
    call.status = stream->Finish();
    return call;
  }

  // Waits until the server has admitted `n` sessions (false after 30 s).
  bool wait_for_active(unsigned n) {
    const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(30);
    while (server_->registry().active() != n) {
      if (std::chrono::steady_clock::now() > give_up) return false;
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    return true;
  }

  std::unique_ptr<PoseFuseServer> server_;
  std::string address_;
  std::shared_ptr<grpc::Channel> channel_;
  std::unique_ptr<v1::PoseFuse::Stub> stub_;
};

std::size_t nth_index(const std::vector<v1::SessionChunk>& chunks, v1::SessionChunk::ChunkCase kind, int n) {
  int seen = 0;
  for (std::size_t i = 0; i < chunks.size(); ++i) {
    if (chunks[i].chunk_case() == kind &&
        (kind != v1::SessionChunk::kImu || chunks[i].imu().device_id() == demo::kArmDevice)) {
      if (seen++ == n) return i;
    }
  }
  ADD_FAILURE() << "no such chunk";
  return 0;
}

TEST_F(ServerTest, DemoSessionFitReturnsAnOrientationForEveryImuSample) {
  start();
  const auto chunks = demo::make_demo_session();
  const CallResult call = fit(chunks);
  ASSERT_TRUE(call.status.ok()) << call.status.error_message();
  const auto samples = call.orientation_samples();
  EXPECT_EQ(samples.at(demo::kArmDevice), 800u);
  EXPECT_EQ(samples.at(demo::kBaseDevice), 800u);
  EXPECT_TRUE(call.item_errors().empty());
  ASSERT_FALSE(call.results.empty());
  ASSERT_TRUE(call.results.back().has_summary());
  EXPECT_EQ(call.results.back().summary().chunks(), chunks.size());
  EXPECT_EQ(call.results.back().summary().depth_frames(), 300u);
}

TEST_F(ServerTest, TightQueuesStillDeliverEveryResult) {
  ServerOptions options;
  options.max_queued_chunks = 1;
  options.max_queued_results = 1;
  start(options);
  const CallResult call = fit(demo::make_demo_session());
  ASSERT_TRUE(call.status.ok()) << call.status.error_message();
  EXPECT_EQ(call.orientation_samples().at(demo::kArmDevice), 800u);
  EXPECT_TRUE(call.results.back().has_summary());
}

TEST_F(ServerTest, MalformedChunksAreItemErrorsNamingTheFieldAndTheSessionCompletes) {
  start();
  auto chunks = demo::make_demo_session();
  const std::size_t nan_imu = nth_index(chunks, v1::SessionChunk::kImu, 3);
  chunks[nan_imu].mutable_imu()->set_acc_m_s2(7, std::nanf(""));
  const std::size_t bad_depth = nth_index(chunks, v1::SessionChunk::kDepth, 20);
  chunks[bad_depth].mutable_depth()->set_width(63);
  const std::size_t early = nth_index(chunks, v1::SessionChunk::kImu, 10);
  const std::size_t late = nth_index(chunks, v1::SessionChunk::kImu, 11);
  std::swap(chunks[early], chunks[late]);  // `late` now holds the earlier batch: out of order

  const CallResult call = fit(chunks);
  ASSERT_TRUE(call.status.ok()) << call.status.error_message();
  // Errors come in stream order: the swapped arm batches come before depth frame 20.
  ASSERT_LT(late, bad_depth);
  const auto errors = call.item_errors();
  ASSERT_GE(errors.size(), 3u);
  EXPECT_EQ(errors[0].field(), "chunk[" + std::to_string(nan_imu) + "].imu[2].acc_m_s2");
  EXPECT_EQ(errors[0].code(), "invalid argument");
  EXPECT_EQ(errors[1].field(), "chunk[" + std::to_string(late) + "].imu[0].t_us");
  EXPECT_EQ(errors[2].field(), "chunk[" + std::to_string(bad_depth) + "].depth.width");
  // Two arm batches of 32 were rejected; everything else was processed.
  EXPECT_EQ(call.orientation_samples().at(demo::kArmDevice), 800u - 64u);
  EXPECT_EQ(call.orientation_samples().at(demo::kBaseDevice), 800u);
  ASSERT_TRUE(call.results.back().has_summary());
  EXPECT_EQ(call.results.back().summary().depth_frames(), 299u);
}

TEST_F(ServerTest, UnknownEnumValueIsAnItemErrorNamingTheField) {
  start();
  auto chunks = demo::make_demo_session();
  const std::size_t skeleton = nth_index(chunks, v1::SessionChunk::kSkeleton, 4);
  // A value from a newer schema (or garbage): proto3 keeps it, the validator must reject it.
  chunks[skeleton].mutable_skeleton()->mutable_joints(3)->set_state(static_cast<v1::SkeletonJoint::State>(7));
  const CallResult call = fit(chunks);
  ASSERT_TRUE(call.status.ok()) << call.status.error_message();
  const auto errors = call.item_errors();
  ASSERT_GE(errors.size(), 1u);
  EXPECT_EQ(errors[0].field(), "chunk[" + std::to_string(skeleton) + "].skeleton.joints[3].state");
}

TEST_F(ServerTest, ManyConcurrentSessionsEachGetEveryResult) {
  ServerOptions options;
  options.max_sessions = 8;
  start(options);
  const auto chunks = demo::make_demo_session();
  std::vector<CallResult> calls(8);
  std::vector<std::thread> clients;
  for (auto& call : calls) clients.emplace_back([&] { call = fit(chunks); });
  for (auto& client : clients) client.join();
  for (const CallResult& call : calls) {
    ASSERT_TRUE(call.status.ok()) << call.status.error_message();
    EXPECT_EQ(call.orientation_samples().at(demo::kArmDevice), 800u);
    EXPECT_EQ(call.orientation_samples().at(demo::kBaseDevice), 800u);
    EXPECT_TRUE(call.results.back().has_summary());
  }
}

TEST_F(ServerTest, StreamWithoutHeaderIsInvalidArgument) {
  start();
  auto chunks = demo::make_demo_session();
  chunks.erase(chunks.begin());
  const CallResult call = fit(chunks);
  EXPECT_EQ(call.status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_EQ(call.status.error_message().rfind("chunk[0]: expected the header first", 0), 0u)
      << call.status.error_message();
}

TEST_F(ServerTest, StreamWithoutEndMarkerIsInvalidArgumentAfterTheResults) {
  start();
  auto chunks = demo::make_demo_session();
  chunks.pop_back();
  const CallResult call = fit(chunks);
  EXPECT_EQ(call.status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_EQ(call.status.error_message().rfind("end: ", 0), 0u) << call.status.error_message();
  EXPECT_EQ(call.orientation_samples().at(demo::kArmDevice), 800u);
}

TEST_F(ServerTest, OversizedMessageIsResourceExhausted) {
  ServerOptions options;
  options.max_message_mb = 1.0;
  start(options);
  auto chunks = demo::make_demo_session();
  const std::size_t depth = nth_index(chunks, v1::SessionChunk::kDepth, 0);
  chunks[depth].mutable_depth()->set_data(std::string(2 << 20, '\0'));
  const CallResult call = fit(chunks);
  EXPECT_EQ(call.status.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED) << call.status.error_message();
}

TEST_F(ServerTest, SessionsBeyondTheLimitAreRefusedWithResourceExhausted) {
  ServerOptions options;
  options.max_sessions = 2;
  start(options);
  const auto chunks = demo::make_demo_session();
  posefuse::test::HeldFit a(*stub_, chunks[0]), b(*stub_, chunks[0]);
  ASSERT_TRUE(a.sent());
  ASSERT_TRUE(b.sent());
  ASSERT_TRUE(wait_for_active(2));

  const CallResult refused = fit(chunks);
  EXPECT_EQ(refused.status.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED);
  EXPECT_TRUE(refused.results.empty());

  EXPECT_EQ(a.cancel().error_code(), grpc::StatusCode::CANCELLED);
  EXPECT_EQ(b.cancel().error_code(), grpc::StatusCode::CANCELLED);
}

TEST_F(ServerTest, ClientThatCancelsMidStreamFreesItsSlot) {
  ServerOptions options;
  options.max_sessions = 1;
  start(options);
  const auto chunks = demo::make_demo_session();
  {
    grpc::ClientContext context;
    set_test_deadline(context);
    auto stream = stub_->Fit(&context);
    // Send until the server has answered something (it is mid-session), then cancel.
    std::size_t i = 0;
    v1::FitResult result;
    for (; i < chunks.size() / 2; ++i) ASSERT_TRUE(stream->Write(chunks[i]));
    ASSERT_TRUE(stream->Read(&result));
    context.TryCancel();
    EXPECT_EQ(stream->Finish().error_code(), grpc::StatusCode::CANCELLED);
  }
  ASSERT_TRUE(server_->registry().wait_for_active_at_most(0, std::chrono::seconds(30)));
  const CallResult call = fit(chunks);
  EXPECT_TRUE(call.status.ok()) << call.status.error_message();
  EXPECT_EQ(call.orientation_samples().at(demo::kArmDevice), 800u);
}

// The lines of `log` with `event`.
std::vector<std::string> log_lines(const std::string& log, const std::string& event) {
  std::vector<std::string> lines;
  std::istringstream in(log);
  for (std::string line; std::getline(in, line);) {
    if (line.find(" event=" + event + " ") != std::string::npos) lines.push_back(line);
  }
  return lines;
}

TEST_F(ServerTest, ClientThatGoesAwayIsLoggedAndCountedAsCancelled) {
  ServerOptions options;
  options.metrics_listen = "127.0.0.1:0";
  start(options);
  auto chunks = demo::make_demo_session();
  // Several calls: the client's cancellation and the failed read it brings reach the server in
  // either order.
  constexpr int kCalls = 12;
  testing::internal::CaptureStderr();
  for (int call = 0; call < kCalls; ++call) {
    grpc::ClientContext context;
    set_test_deadline(context);
    auto stream = stub_->Fit(&context);
    // Mid-session, the server waiting for the next chunk: the client cancels (as a client
    // does that is stopped or loses its connection).
    for (std::size_t i = 0; i < chunks.size() / 2; ++i) ASSERT_TRUE(stream->Write(chunks[i]));
    v1::FitResult result;
    ASSERT_TRUE(stream->Read(&result));
    context.TryCancel();
    EXPECT_EQ(stream->Finish().error_code(), grpc::StatusCode::CANCELLED);
  }
  // Unlike a client that ends its stream without the end marker: a bad request.
  chunks.pop_back();
  EXPECT_EQ(fit(chunks).status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  ASSERT_TRUE(server_->registry().wait_for_active_at_most(0, std::chrono::seconds(30)));
  const std::string log = testing::internal::GetCapturedStderr();

  const std::vector<std::string> ends = log_lines(log, "session_end");
  ASSERT_EQ(ends.size(), static_cast<std::size_t>(kCalls + 1)) << log;
  for (int call = 0; call < kCalls; ++call) EXPECT_NE(ends[call].find(" status=CANCELLED "), std::string::npos) << log;
  EXPECT_NE(ends.back().find(" status=INVALID_ARGUMENT "), std::string::npos) << log;
  const std::vector<std::string> errors = log_lines(log, "session_error");
  ASSERT_EQ(errors.size(), 1u) << log;
  EXPECT_NE(errors[0].find(" field=end"), std::string::npos) << errors[0];
  const std::string metrics = test::http_get(server_->metrics_port(), "/metrics");
  for (const std::string& line : {"posefuse_sessions_finished_total{status=\"CANCELLED\"} " + std::to_string(kCalls),
                                  std::string("posefuse_sessions_finished_total{status=\"INVALID_ARGUMENT\"} 1")}) {
    EXPECT_NE(metrics.find("\n" + line + "\n"), std::string::npos) << line << " in\n" << metrics;
  }
}

TEST_F(ServerTest, IdleStreamIsEndedWithDeadlineExceeded) {
  ServerOptions options;
  options.idle_timeout_s = 0.2;
  start(options);
  const auto chunks = demo::make_demo_session();
  grpc::ClientContext context;
  set_test_deadline(context);
  auto stream = stub_->Fit(&context);
  ASSERT_TRUE(stream->Write(chunks[0]));
  // Send nothing more: the server ends the call.
  v1::FitResult result;
  while (stream->Read(&result)) {
  }
  const grpc::Status status = stream->Finish();
  EXPECT_EQ(status.error_code(), grpc::StatusCode::DEADLINE_EXCEEDED) << status.error_message();
  EXPECT_TRUE(server_->registry().wait_for_active_at_most(0, std::chrono::seconds(30)));
}

// Small rate options so that these tests are short: after 0.5 s a session must have delivered
// half as much recording as the wall time it took.
ServerOptions stream_rate_options() {
  ServerOptions options;
  options.min_stream_rate = 0.5;
  options.stream_rate_grace_s = 0.5;
  return options;
}

TEST_F(ServerTest, SlowSenderIsEndedWithDeadlineExceededAfterItsResults) {
  start(stream_rate_options());
  // Batches of 4 IMU samples at 80 Hz: 50 ms of recording each, sent every 250 ms (0.2x real
  // time), far below the 0.5x required; the idle timeout (60 s) never comes into it.
  demo::DemoSessionOptions session_options;
  session_options.imu_samples_per_batch = 4;
  const auto chunks = demo::make_demo_session(session_options);
  std::vector<v1::SessionChunk> trickle{chunks[0]};
  for (int n = 0; n < 150; ++n) trickle.push_back(chunks[nth_index(chunks, v1::SessionChunk::kImu, n)]);

  grpc::ClientContext context;
  set_test_deadline(context);
  auto stream = stub_->Fit(&context);
  std::atomic<bool> ended{false};
  std::atomic<std::size_t> batches_written{0};
  std::thread sender([&] {
    for (std::size_t i = 0; i < trickle.size() && !ended; ++i) {
      if (!stream->Write(trickle[i])) return;
      if (i > 0) ++batches_written;
      if (i >= 2) std::this_thread::sleep_for(std::chrono::milliseconds(250));  // the first two at once
    }
  });
  CallResult call;
  v1::FitResult result;
  while (stream->Read(&result)) call.results.push_back(result);
  ended = true;
  sender.join();
  call.status = stream->Finish();

  EXPECT_EQ(call.status.error_code(), grpc::StatusCode::DEADLINE_EXCEEDED) << call.status.error_message();
  const std::string& message = call.status.error_message();
  EXPECT_NE(message.find("x real time), below the required 0.5x"), std::string::npos) << message;
  EXPECT_NE(message.find("--min-stream-rate"), std::string::npos) << message;
  // Ended long before the trickle ran out, with an orientation for every batch the server took:
  // each batch sent at least up to the one that may have been in flight when the status came.
  EXPECT_LT(batches_written.load(), trickle.size() - 1);
  std::size_t orientation_batches = 0;
  for (const auto& r : call.results) {
    if (!r.has_imu_orientations()) continue;
    ++orientation_batches;
    EXPECT_EQ(r.imu_orientations().t_us_size(), 4);
  }
  EXPECT_GE(orientation_batches, 2u);
  EXPECT_GE(orientation_batches + 1, batches_written.load());
  EXPECT_TRUE(server_->registry().wait_for_active_at_most(0, std::chrono::seconds(30)));
}

// The memory bomb of a client that sends one camera frame again and again 10 us apart while
// fit.calibration_s (stream time) keeps them all: the session's memory budget ends it.
TEST_F(ServerTest, SessionHoldingMoreThanItsMemoryBudgetIsResourceExhaustedNamingTheFlag) {
  ServerOptions options;
  options.max_session_memory_mb = 8;
  start(options);
  demo::DemoSessionOptions session_options;
  session_options.depth_width = 512;
  session_options.depth_height = 424;
  const auto chunks = demo::make_demo_session(session_options);
  std::vector<v1::SessionChunk> bomb{chunks[0]};
  (*bomb[0].mutable_header()->mutable_options())["fit.enabled"] = "true";
  (*bomb[0].mutable_header()->mutable_options())["fit.calibration_s"] = "30";
  const v1::SessionChunk depth = chunks[nth_index(chunks, v1::SessionChunk::kDepth, 0)];
  const v1::SessionChunk body_index = chunks[nth_index(chunks, v1::SessionChunk::kBodyIndex, 0)];
  const v1::SessionChunk skeleton = chunks[nth_index(chunks, v1::SessionChunk::kSkeleton, 0)];
  ASSERT_EQ(depth.depth().t_us(), skeleton.skeleton().t_us());
  constexpr int kFrames = 200;  // 124 MiB of calibration frames at 651 KiB each
  for (int n = 0; n < kFrames; ++n) {
    const std::int64_t t_us = depth.depth().t_us() + 10 * n;
    bomb.push_back(depth);
    bomb.back().mutable_depth()->set_t_us(t_us);
    bomb.push_back(body_index);
    bomb.back().mutable_body_index()->set_t_us(t_us);
    bomb.push_back(skeleton);
    bomb.back().mutable_skeleton()->set_t_us(t_us);
  }
  const CallResult call = fit(bomb);
  EXPECT_EQ(call.status.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED) << call.status.error_message();
  const std::string& message = call.status.error_message();
  EXPECT_NE(message.find("beyond its memory budget of 8.0 MiB (--max-session-memory-mb): body_fit"), std::string::npos)
      << message;
  EXPECT_TRUE(call.item_errors().empty());
  EXPECT_TRUE(server_->registry().wait_for_active_at_most(0, std::chrono::seconds(30)));

  grpc::ClientContext context;
  set_test_deadline(context);
  v1::ServerInfo info;
  ASSERT_TRUE(stub_->GetServerInfo(&context, {}, &info).ok());
  EXPECT_EQ(info.limits().max_session_memory_bytes(), 8u << 20);
}

TEST_F(ServerTest, SenderAtRealTimeOrFasterKeepsTheMinimumStreamRate) {
  start(stream_rate_options());
  const auto chunks = demo::make_demo_session();
  // The first 1.5 s of camera frames as a live camera sends them (30 Hz), three grace periods,
  // then the rest as fast as the server takes it, as an upload of a finished recording does.
  int depth_frames = 0;
  const CallResult call = fit(chunks, [&](const v1::SessionChunk& chunk) {
    if (chunk.has_depth() && ++depth_frames <= 45) std::this_thread::sleep_for(std::chrono::microseconds(33'333));
  });
  ASSERT_TRUE(call.status.ok()) << call.status.error_message();
  EXPECT_EQ(call.orientation_samples().at(demo::kArmDevice), 800u);
  ASSERT_TRUE(call.results.back().has_summary());
}

TEST_F(ServerTest, HealthSaysServing) {
  start();
  grpc::health::v1::HealthCheckResponse response;
  const grpc::Status status = test::check_health(channel_, &response);
  ASSERT_TRUE(status.ok()) << status.error_message();
  EXPECT_EQ(response.status(), grpc::health::v1::HealthCheckResponse::SERVING);
}

// Server reflection (grpc.reflection.v1alpha) through its generated stub.
TEST_F(ServerTest, ReflectionListsTheServices) {
  start();
  grpc::reflection::v1alpha::ServerReflectionRequest request;
  request.set_list_services("*");
  grpc::reflection::v1alpha::ServerReflectionResponse response;
  const grpc::Status status = test::ask_reflection(channel_, request, &response);
  ASSERT_TRUE(status.ok()) << status.error_message();
  std::vector<std::string> names;
  for (const auto& service : response.list_services_response().service()) {
    names.push_back(service.name());
  }
  EXPECT_EQ(names, (std::vector<std::string>{"posefuse.v1.PoseFuse", "grpc.health.v1.Health",
                                             "grpc.reflection.v1alpha.ServerReflection"}));
}

TEST_F(ServerTest, ReflectionServesTheFilesOfASymbolWithTheirImports) {
  start();
  grpc::reflection::v1alpha::ServerReflectionRequest request;
  request.set_host("h");
  request.set_file_containing_symbol("posefuse.v1.PoseFuse.Fit");
  grpc::reflection::v1alpha::ServerReflectionResponse response;
  ASSERT_TRUE(test::ask_reflection(channel_, request, &response).ok());
  EXPECT_EQ(response.valid_host(), "h");
  EXPECT_EQ(response.original_request().file_containing_symbol(), "posefuse.v1.PoseFuse.Fit");
  std::vector<std::string> files;
  for (const std::string& bytes : response.file_descriptor_response().file_descriptor_proto()) {
    google::protobuf::FileDescriptorProto file;
    ASSERT_TRUE(file.ParseFromString(bytes));
    files.push_back(file.name());
  }
  ASSERT_FALSE(files.empty());
  EXPECT_EQ(files[0], "posefuse/v1/service.proto");
  for (const char* import : {"posefuse/v1/results.proto", "posefuse/v1/session.proto"}) {
    EXPECT_NE(std::find(files.begin(), files.end(), import), files.end()) << import;
  }
  // The health service is described too, and an unknown name is an error in the answer.
  request.set_file_containing_symbol("grpc.health.v1.Health");
  ASSERT_TRUE(test::ask_reflection(channel_, request, &response).ok());
  EXPECT_EQ(response.file_descriptor_response().file_descriptor_proto_size(), 1);
  request.set_file_by_filename("no/such.proto");
  ASSERT_TRUE(test::ask_reflection(channel_, request, &response).ok());
  EXPECT_EQ(response.error_response().error_code(), static_cast<int>(grpc::StatusCode::NOT_FOUND));
}

TEST_F(ServerTest, ServerInfoListsStagesOptionsAndLimits) {
  ServerOptions options;
  options.max_sessions = 3;
  options.max_upload_mb = 2.0;
  start(options);
  grpc::ClientContext context;
  set_test_deadline(context);
  v1::ServerInfo info;
  ASSERT_TRUE(stub_->GetServerInfo(&context, {}, &info).ok());
  EXPECT_EQ(info.api_version(), "posefuse.v1");
  ASSERT_EQ(info.stages_size(), 6);
  EXPECT_EQ(info.stages(0).name(), "imu_orientation");
  EXPECT_EQ(info.stages(1).name(), "forearm");
  EXPECT_EQ(info.stages(2).name(), "body_fit");
  EXPECT_EQ(info.stages(3).name(), "forearm_gaps");
  EXPECT_EQ(info.stages(4).name(), "frame_merge");
  EXPECT_EQ(info.stages(5).name(), "measures");
  ASSERT_EQ(info.options_size(), 45);
  EXPECT_EQ(info.options(34).key(), "measures.repetition_angle");
  EXPECT_EQ(info.options(34).default_value(), "auto");
  EXPECT_EQ(info.options(16).key(), "fit.enabled");
  EXPECT_EQ(info.options(16).default_value(), "true");
  EXPECT_EQ(info.options(22).key(), "fit.trusted_energy");
  EXPECT_EQ(info.options(22).default_value(), "10");
  EXPECT_EQ(info.options(24).key(), "fit.fine_shape");
  EXPECT_EQ(info.options(25).key(), "fit.lambda_imu");
  EXPECT_EQ(info.options(26).key(), "fit.skeleton_start_energy");
  EXPECT_EQ(info.options(26).default_value(), "45");
  EXPECT_EQ(info.options(28).key(), "fit.min_joint_step_m");
  EXPECT_EQ(info.options(29).key(), "fit.joint_step_stop_max_damping");
  EXPECT_EQ(info.options(29).default_value(), "30");
  EXPECT_EQ(info.options(0).key(), "imu.tau_acc_s");
  EXPECT_EQ(info.options(2).key(), "imu.mag_calibration.<device_id>");
  EXPECT_EQ(info.options(3).key(), "forearm.K_from_B");
  EXPECT_EQ(info.options(3).stage(), "forearm");
  EXPECT_EQ(info.options(7).key(), "forearm.axis");
  EXPECT_EQ(info.options(8).key(), "forearm.shoulder_sphere");
  EXPECT_EQ(info.options(9).key(), "forearm.upper_arm");
  EXPECT_EQ(info.options(10).key(), "forearm.buzzer_hz");
  EXPECT_EQ(info.options(10).default_value(), "2700");
  EXPECT_EQ(info.options(11).key(), "forearm.gap_anchor");
  EXPECT_EQ(info.options(11).default_value(), "auto");
  EXPECT_EQ(info.options(12).key(), "forearm.axis_correction");
  EXPECT_EQ(info.options(12).default_value(), "auto");
  EXPECT_EQ(info.limits().max_sessions(), 3u);
  EXPECT_EQ(info.limits().workers(), 2u);
  EXPECT_EQ(info.limits().max_upload_bytes(), 2u << 20);
  // --max-session-memory-mb 0: half the memory split between 3 sessions and 1 job.
  EXPECT_NEAR(static_cast<double>(info.limits().max_session_memory_bytes()),
              static_cast<double>(default_session_memory_bytes(usable_memory_bytes(), 3, 1)), 1.0);
  EXPECT_FALSE(info.jobs_supported());
}

TEST_F(ServerTest, JobCallsWithoutDataDirAreFailedPrecondition) {
  start();
  grpc::ClientContext context;
  set_test_deadline(context);
  v1::Job job;
  v1::GetJobRequest request;
  request.set_job_id("x");
  EXPECT_EQ(stub_->GetJob(&context, request, &job).error_code(), grpc::StatusCode::FAILED_PRECONDITION);
}

TEST_F(ServerTest, MetricsEndpointCountsSessionsAndStageCalls) {
  ServerOptions options;
  options.metrics_listen = "127.0.0.1:0";
  start(options);
  ASSERT_GT(server_->metrics_port(), 0);
  ASSERT_TRUE(fit(demo::make_demo_session()).status.ok());
  // The session's slot is released (and its end counted) right after the call.
  ASSERT_TRUE(server_->registry().wait_for_active_at_most(0, std::chrono::seconds(30)));

  const std::string response = test::http_get(server_->metrics_port(), "/metrics");
  EXPECT_EQ(response.rfind("HTTP/1.1 200 OK\r\n", 0), 0u) << response;
  EXPECT_NE(response.find("\nposefuse_sessions_finished_total{status=\"OK\"} 1\n"), std::string::npos) << response;
  EXPECT_NE(response.find("\nposefuse_sessions_in_flight 0\n"), std::string::npos);
  EXPECT_NE(response.find("\nposefuse_chunks_received_total 952\n"), std::string::npos);
  // start, one call per input the frame assembler hands on (camera frames, IMU blocks, audio,
  // clock events), finish.
  const std::size_t inputs = session::assemble_session(demo::make_demo_session()).inputs.size();
  EXPECT_NE(
      response.find("\nposefuse_stage_calls_total{stage=\"imu_orientation\"} " + std::to_string(inputs + 2) + "\n"),
      std::string::npos)
      << response;
  EXPECT_NE(response.find("\nposefuse_queued_chunks 0\n"), std::string::npos);
  EXPECT_EQ(test::http_get(server_->metrics_port(), "/other").rfind("HTTP/1.1 404", 0), 0u);
}

// The field of the error validate_options throws for `options` ("" when it accepts them).
std::string rejected_flag(const ServerOptions& options) {
  try {
    validate_options(options);
  } catch (const Error& e) {
    return e.field();
  }
  return "";
}

TEST(ServerOptions, BadValuesNameTheFlag) {
  ServerOptions options;
  options.max_sessions = 0;
  EXPECT_EQ(rejected_flag(options), "--max-sessions");
  options = ServerOptions{};
  options.tenant_max_sessions = options.max_sessions + 1;
  EXPECT_EQ(rejected_flag(options), "--tenant-max-sessions");
  options = ServerOptions{};
  options.listen = "0.0.0.0:0";
  EXPECT_EQ(rejected_flag(options), "--listen");
  options.insecure = true;
  EXPECT_EQ(rejected_flag(options), "");
  for (const double mb : {0.0, -1.0, 2e6, std::nan("")}) {
    options = ServerOptions{};
    options.max_upload_mb = mb;
    EXPECT_EQ(rejected_flag(options), "--max-upload-mb") << mb;
    options = ServerOptions{};
    options.max_spool_mb = mb;
    EXPECT_EQ(rejected_flag(options), "--max-spool-mb") << mb;
  }
  for (const double mb : {-1.0, 2e6, std::nan("")}) {
    options = ServerOptions{};
    options.max_session_memory_mb = mb;
    EXPECT_EQ(rejected_flag(options), "--max-session-memory-mb") << mb;
  }
  EXPECT_EQ(rejected_flag(ServerOptions{}), "");
}

TEST(ServerOptions, StreamRateOptionsNameTheFlag) {
  for (const double rate : {-0.1, std::nan(""), HUGE_VAL}) {
    ServerOptions options;
    options.min_stream_rate = rate;
    EXPECT_EQ(rejected_flag(options), "--min-stream-rate") << rate;
  }
  // A grace of 0 would end every session before its first data chunk arrived.
  for (const double grace_s : {0.0, -1.0, std::nan(""), HUGE_VAL}) {
    ServerOptions options;
    options.stream_rate_grace_s = grace_s;
    EXPECT_EQ(rejected_flag(options), "--stream-rate-grace-s") << grace_s;
  }
  ServerOptions off;
  off.min_stream_rate = 0.0;  // disables the rule
  EXPECT_EQ(rejected_flag(off), "");
}

TEST(ServerOptions, JobStoreRolesAndLeasesThatCannotWorkNameTheFlag) {
  const auto with = [](auto change) {
    ServerOptions options;
    options.data_dir = "/tmp/posefuse-data";
    change(options);
    return rejected_flag(options);
  };
  EXPECT_EQ(with([](ServerOptions& o) { o.job_store = "mysql:db"; }), "--job-store");
  EXPECT_EQ(with([](ServerOptions& o) {
              o.job_store = "host=/run/postgresql";
              o.data_dir = "";
            }),
            "--job-store");
  EXPECT_EQ(with([](ServerOptions& o) { o.role = "scheduler"; }), "--role");
  // API-only or worker-only replicas mean nothing on a store no other process sees.
  EXPECT_EQ(with([](ServerOptions& o) { o.role = "worker"; }), "--role");
  EXPECT_EQ(with([](ServerOptions& o) { o.job_heartbeat_s = o.job_lease_s; }), "--job-heartbeat-s");
  EXPECT_EQ(with([](ServerOptions& o) { o.job_lease_s = 0; }), "--job-lease-s");
  EXPECT_EQ(with([](ServerOptions& o) { o.job_max_attempts = 0; }), "--job-max-attempts");
  for (const double seconds : {-1.0, std::nan(""), HUGE_VAL}) {
    EXPECT_EQ(with([&](ServerOptions& o) { o.job_deadline_s = seconds; }), "--job-deadline-s") << seconds;
    EXPECT_EQ(with([&](ServerOptions& o) { o.job_stall_s = seconds; }), "--job-stall-s") << seconds;
  }
  EXPECT_EQ(with([](ServerOptions& o) { o.job_deadline_s = o.job_stall_s = 0; }), "");  // 0: off
  EXPECT_EQ(with([](ServerOptions& o) {
              o.job_store = "postgresql:///posefuse?host=/run/postgresql";
              o.role = "api";
            }),
            "");
}

}  // namespace
}  // namespace posefuse::server
