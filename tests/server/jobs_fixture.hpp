#pragma once
// The batch-job tests' fixture: a real posefuse server on 127.0.0.1:0 with a data dir and a
// recordings root (holding the demo session as demo.pfchunks) in a fresh folder, and the calls
// the tests make through it.
#include <filesystem>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "client/demo_session.hpp"
#include "client/fit_call.hpp"
#include "posefuse/v1/service.grpc.pb.h"
#include "server/posefuse_server.hpp"
#include "tests/server/test_support.hpp"

namespace posefuse::server {

namespace fs = std::filesystem;
using posefuse::test::set_test_deadline;

class JobsTest : public ::testing::Test {
 protected:
  void SetUp() override {
    fs::create_directories(dir_ / "recordings");
    demo::write_demo_session(dir_ / "recordings" / "demo.pfchunks");
  }

  void start(ServerOptions options = {}, JobStoreFactory make_store = {}) {
    options.listen = "127.0.0.1:0";
    if (options.workers == 0) options.workers = 2;
    options.data_dir = (dir_ / "data").string();
    options.recordings_root = (dir_ / "recordings").string();
    server_ = std::make_unique<PoseFuseServer>(options, std::move(make_store));
    channel_ = client::make_channel("127.0.0.1:" + std::to_string(server_->port()));
    stub_ = v1::PoseFuse::NewStub(channel_);
  }

  grpc::Status submit(const std::string& uri, v1::Job& job) {
    v1::JobSpec spec;
    spec.set_label("test");
    spec.set_recording_uri(uri);
    return submit_spec(spec, job);
  }
  grpc::Status submit_spec(const v1::JobSpec& spec, v1::Job& job) {
    grpc::ClientContext context;
    set_test_deadline(context);
    auto writer = stub_->SubmitJob(&context, &job);
    v1::SubmitJobRequest request;
    *request.mutable_spec() = spec;
    writer->Write(request);
    writer->WritesDone();
    return writer->Finish();
  }

  // The demo session through Fit: its status, and whether the summary came.
  grpc::Status fit_demo(bool& summary) {
    grpc::ClientContext context;
    set_test_deadline(context);
    auto stream = stub_->Fit(&context);
    const auto chunks = demo::make_demo_session();
    std::thread sender([&] {
      for (const auto& chunk : chunks) {
        if (!stream->Write(chunk)) return;
      }
      stream->WritesDone();
    });
    summary = false;
    v1::FitResult result;
    while (stream->Read(&result)) summary = summary || result.has_summary();
    sender.join();
    return stream->Finish();
  }

  // Every state WatchJob reports until the job has finished.
  std::vector<v1::Job> watch(const std::string& id) {
    grpc::ClientContext context;
    set_test_deadline(context);
    v1::WatchJobRequest request;
    request.set_job_id(id);
    grpc::Status status;
    auto states = posefuse::test::read_all<v1::Job>(*stub_->WatchJob(&context, request), status);
    EXPECT_TRUE(status.ok()) << status.error_message();
    return states;
  }

  // An upload call after its spec and the first `count` of `chunks` (fewer when the server ends
  // the call early), still open: the test sends more or closes it.
  struct OpenUpload {
    grpc::ClientContext context;
    v1::Job job;
    std::unique_ptr<grpc::ClientWriter<v1::SubmitJobRequest>> writer;
    bool send(const v1::SessionChunk& chunk) {
      v1::SubmitJobRequest request;
      *request.mutable_chunk() = chunk;
      return writer->Write(request);
    }
    grpc::Status close() {
      writer->WritesDone();
      return writer->Finish();
    }
  };
  std::unique_ptr<OpenUpload> open_upload(const std::vector<v1::SessionChunk>& chunks, std::size_t count) {
    auto call = std::make_unique<OpenUpload>();
    set_test_deadline(call->context);
    call->writer = stub_->SubmitJob(&call->context, &call->job);
    v1::SubmitJobRequest request;
    request.mutable_spec()->set_label("uploaded");
    request.mutable_spec()->set_upload(true);
    bool open = call->writer->Write(request);
    for (std::size_t i = 0; open && i < count; ++i) open = call->send(chunks[i]);
    return call;
  }

  // SubmitJob by upload: the spec, then `chunks`.
  grpc::Status upload(const std::vector<v1::SessionChunk>& chunks, v1::Job& job) {
    const auto call = open_upload(chunks, chunks.size());
    const grpc::Status status = call->close();
    job = call->job;
    return status;
  }

  // A refused upload: `code`, a message starting with `prefix`, no job and no file left.
  void expect_refused(const grpc::Status& status, grpc::StatusCode code, const std::string& prefix) {
    EXPECT_EQ(status.error_code(), code) << status.error_message();
    EXPECT_EQ(status.error_message().rfind(prefix, 0), 0u) << status.error_message();
    EXPECT_EQ(job_count(), 0u);
    EXPECT_EQ(files_in_spool(), 0u);
  }

  std::size_t files_in_spool() const {
    std::size_t n = 0;
    for ([[maybe_unused]] const auto& entry : fs::directory_iterator(dir_ / "data" / "uploads")) ++n;
    return n;
  }

  std::size_t job_count() {
    grpc::ClientContext context;
    set_test_deadline(context);
    v1::ListJobsResponse listing;
    EXPECT_TRUE(stub_->ListJobs(&context, {}, &listing).ok());
    return static_cast<std::size_t>(listing.jobs_size());
  }

  std::vector<v1::FitResult> results(const std::string& id, grpc::Status* status = nullptr) {
    grpc::ClientContext context;
    set_test_deadline(context);
    v1::GetJobResultsRequest request;
    request.set_job_id(id);
    grpc::Status ignored;
    return posefuse::test::read_all<v1::FitResult>(*stub_->GetJobResults(&context, request),
                                                   status ? *status : ignored);
  }

  posefuse::test::TempDir temp_;
  const fs::path& dir_ = temp_.path();
  std::unique_ptr<PoseFuseServer> server_;
  std::shared_ptr<grpc::Channel> channel_;
  std::unique_ptr<v1::PoseFuse::Stub> stub_;
};

}  // namespace posefuse::server
