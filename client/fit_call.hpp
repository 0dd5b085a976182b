#pragma once
// The client side of a Fit call: streams a recording to the server on one thread while the
// calling thread receives results and hands them to a ResultWriter.
#include <chrono>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>

#include <grpcpp/grpcpp.h>

#include "client/channel_security.hpp"
#include "client/recording.hpp"
#include "client/result_writer.hpp"
#include "common/error.hpp"

namespace posefuse::client {

struct FitProgress {
  std::uint64_t chunks_sent = 0;
  std::uint64_t depth_frames_sent = 0;
  double fraction_read = -1.0;  // of the recording; negative when unknown
  double elapsed_s = 0.0;
};

struct FitOutcome {
  grpc::Status status;               // the call's status from the server
  std::optional<Error> local_error;  // the recording could not be read, or results not written
  FitProgress progress;              // final counts
  std::uint64_t results_received = 0;
};

// Streams `recording` over `channel` and writes results with `writer`. `on_progress` is called
// from the receiving thread now and then (at most every 200 ms). `header_edits` replace the
// recording's own header values (see Recording). Never throws for server-side problems: look at
// the outcome.
FitOutcome run_fit(const std::shared_ptr<grpc::Channel>& channel, const std::filesystem::path& recording,
                   ResultWriter& writer, const std::function<void(const FitProgress&)>& on_progress = {},
                   const HeaderEdits& header_edits = {});

// A channel to `address` (host:port) with the client's message size limits, secured as
// `security` says (plaintext, no token by default).
std::shared_ptr<grpc::Channel> make_channel(const std::string& address, const ChannelSecurity& security = {});

// One readable line for a failed call, e.g.
// "server 127.0.0.1:50051: INVALID_ARGUMENT: chunk[0].header.depth_intrinsics.fx: ...".
std::string status_line(const grpc::Status& status, const std::string& address);

}  // namespace posefuse::client
