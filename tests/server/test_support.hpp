#pragma once
// Small helpers shared by the server, job and client tests.
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include <grpcpp/grpcpp.h>
#include <gtest/gtest.h>

#include "posefuse/v1/results.pb.h"
#include "posefuse/v1/service.grpc.pb.h"

namespace posefuse::test {

// A fresh folder for the current test, removed afterwards.
class TempDir {
 public:
  TempDir()
      : path_(std::filesystem::temp_directory_path() /
              ("posefuse_test_" + std::to_string(::getpid()) + "_" + test_name())) {
    std::filesystem::remove_all(path_);
    std::filesystem::create_directories(path_);
  }
  ~TempDir() { std::filesystem::remove_all(path_); }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  const std::filesystem::path& path() const { return path_; }

 private:
  // One path component: a parameterised test's name ("Name/sqlite") would otherwise nest a
  // folder that removing the inner one leaves behind.
  static std::string test_name() {
    std::string name = ::testing::UnitTest::GetInstance()->current_test_info()->name();
    std::replace(name.begin(), name.end(), '/', '_');
    return name;
  }

  std::filesystem::path path_;
};

// A generous deadline that only guards against hangs.
inline void set_test_deadline(grpc::ClientContext& context) {
  context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(60));
}

// A Fit call that has sent its first chunk (the header) and so holds a session slot until
// cancel() or the server ends it.
class HeldFit {
 public:
  HeldFit(v1::PoseFuse::Stub& stub, const v1::SessionChunk& header) {
    set_test_deadline(context_);
    stream_ = stub.Fit(&context_);
    sent_ = stream_->Write(header);
  }
  bool sent() const { return sent_; }
  // Cancels the call: its status (CANCELLED unless the server ended it first).
  grpc::Status cancel() {
    context_.TryCancel();
    return stream_->Finish();
  }

 private:
  grpc::ClientContext context_;
  std::unique_ptr<grpc::ClientReaderWriter<v1::SessionChunk, v1::FitResult>> stream_;
  bool sent_ = false;
};

// Every message of a server stream, and its final status.
template <class Message, class Reader>
std::vector<Message> read_all(Reader& reader, grpc::Status& status) {
  std::vector<Message> messages;
  Message message;
  while (reader.Read(&message)) messages.push_back(message);
  status = reader.Finish();
  return messages;
}

// device_id -> number of W_from_A samples in the results.
inline std::map<std::string, std::size_t> orientation_samples(const std::vector<v1::FitResult>& results) {
  std::map<std::string, std::size_t> n;
  for (const auto& r : results) {
    if (r.has_imu_orientations()) {
      n[r.imu_orientations().device_id()] += r.imu_orientations().t_us_size();
    }
  }
  return n;
}

}  // namespace posefuse::test
