#pragma once
// SessionPipeline: runs one session's chunk stream through SessionValidator and the stages.
//
// Chunks arrive in stream order (push). Each is validated first:
//  - a chunk that fails validation is answered with an ItemError naming the field and skipped;
//    everything accepted before and after it is kept (the validator's state only advances on
//    accepted chunks);
//  - errors that make the session impossible are thrown as posefuse::Error and end it: no or an
//    invalid header, a stage that cannot start with the header's options, a chunk after the end
//    marker, input that stops without an end marker (close), more than max_item_errors bad
//    chunks (the recording is not worth going on with).
// Accepted data chunks go to the FrameAssembler, which decodes each once and hands the stages
// typed inputs as they complete (camera frames, IMU blocks, audio, clock events; a chunk it
// refuses is an ItemError too). Every input goes to every stage in order; a posefuse::Error from
// a stage is an ItemError for that input. A value a stage hands on (Stage::consumes) goes to the
// later stages that consume its kind at once, and to the client as a FitResult
// (result_encoder.hpp); the pipeline refuses, at construction, a stage order in which a stage
// consumes what no earlier stage produces: data flows one way, and no stage waits for a later one.
// Results a stage emits (warnings) go to the client, at most max_warnings_per_kind of one code
// and field (a problem that repeats every frame is listed that often, then counted: one warning
// after the stages finish says how many more were not listed). Progress results are emitted every
// progress_every_chunks chunks. After the end marker the assembler hands on what waits and its
// warnings, the stages finish in order, then the pipeline sends one CalibrationReport, a last
// Progress and the Summary.
//
// Not thread-safe: one session is processed in order on one thread (docs/architecture.md, Threads).
#include <chrono>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "common/error.hpp"
#include "session/frame_assembler.hpp"
#include "session/pipeline_stage.hpp"
#include "session/session_validator.hpp"

namespace posefuse::session {

struct PipelineOptions {
  std::uint64_t progress_every_chunks = 64;
  std::uint64_t max_item_errors = 100;
  // Warnings listed per code and field; the rest are counted (see above).
  std::uint64_t max_warnings_per_kind = 10;
  // The session's memory budget: the most the stages and the frame assembler may hold at once
  // (Stage::held_bytes), checked after every data chunk; beyond it the session ends with
  // kResourceExhausted naming what holds the most. 0: no budget (tools on trusted recordings).
  std::uint64_t max_held_bytes = 0;
  // How the budget's error names the setting that sets it (the server's flag).
  std::string max_held_bytes_setting = "max_held_bytes";
  // The caller's chunks received but not pushed yet (the server's queue), counted in the budget
  // as "queued chunks". May be empty; called on the pipeline's thread while others queue.
  std::function<std::uint64_t()> queued_chunk_bytes;
  // Called after every stage call (start, on_chunk, finish) with the stage's name and the wall
  // time it took, for metrics. May be empty.
  std::function<void(std::string_view stage, double seconds)> on_stage_time;
};

class SessionPipeline {
 public:
  SessionPipeline(std::vector<std::unique_ptr<Stage>> stages, ResultSink& sink, PipelineOptions options = {});
  ~SessionPipeline();
  SessionPipeline(const SessionPipeline&) = delete;
  SessionPipeline& operator=(const SessionPipeline&) = delete;

  // The next chunk of the stream. Throws posefuse::Error only for session-ending errors.
  void push(const v1::SessionChunk& chunk);
  // The input has ended. Throws kInvalidArgument (field "end") if the end marker never came.
  void close();

  bool ended() const { return ended_; }
  std::uint64_t chunks_received() const { return index_; }
  std::uint64_t item_errors() const { return item_errors_; }
  std::uint64_t warnings() const { return warnings_; }
  std::uint64_t depth_frames() const { return depth_frames_; }
  // Stream time of the data accepted so far (SessionValidator::stream_time_us).
  std::int64_t stream_time_us() const { return validator_.stream_time_us(); }
  // What the stages and the frame assembler hold now (PipelineOptions::max_held_bytes).
  std::uint64_t held_bytes() const;

 private:
  class Output;

  void item_error(const Error& error, const std::string& field);
  void process_data_chunk(const v1::SessionChunk& chunk, const std::string& field);
  // Hands each input to every stage in order.
  void deliver(const std::vector<SessionInput>& inputs);
  void end_session();
  // One warning per code and field whose repeats were not listed, saying how many.
  void warn_unlisted_repeats();
  // OPTION_UNKNOWN for each header option under a stage's prefix that no stage declares.
  void warn_unknown_options(const v1::SessionHeader& header);
  void emit_progress();
  void note_camera_time(const v1::SessionChunk& chunk);
  // Throws kResourceExhausted naming `field` when the session holds more than max_held_bytes.
  void check_memory_budget(const std::string& field) const;
  // Runs `call` on `stage`, reporting its duration to options_.on_stage_time.
  template <class Call>
  void timed(Stage& stage, Call&& call);

  std::vector<std::unique_ptr<Stage>> stages_;
  ResultSink& sink_;
  PipelineOptions options_;
  std::unique_ptr<Output> output_;
  SessionValidator validator_;
  std::unique_ptr<FrameAssembler> assembler_;  // made with the header
  std::vector<std::set<ValueKind>> consumes_;  // Stage::consumes() of each stage
  bool ended_ = false;
  std::uint64_t index_ = 0;  // chunks received, accepted or not
  std::uint64_t item_errors_ = 0;
  std::uint64_t warnings_ = 0;
  // Warnings raised per (code, field), listed or not.
  std::map<std::pair<std::string, std::string>, std::uint64_t> warnings_per_kind_;
  std::uint64_t depth_frames_ = 0;
  std::uint64_t recovered_segments_ = 0;
  std::uint64_t frames_fitted_ = 0;
  // The stage being called; values it hands on go to the stages after it.
  std::size_t current_stage_ = static_cast<std::size_t>(-1);
  std::optional<std::int64_t> first_camera_t_us_, last_camera_t_us_;
  std::chrono::steady_clock::time_point started_at_;
};

}  // namespace posefuse::session
