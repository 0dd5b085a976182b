#pragma once
// The interface every pipeline stage implements (IMU orientation now; forearm recovery and body
// fitting later), and the output a stage writes its results to.
//
// A stage sees the validated session in stream order: start() with the header, on_chunk() for
// every accepted data chunk, finish() once after the end marker. It emits results as soon as it
// knows them and adds its part of the calibration report, which the pipeline sends once after
// every stage has finished. Stages hold all their state themselves (no globals), so many
// sessions run at once.
#include <string>
#include <string_view>
#include <vector>

#include "posefuse/v1/results.pb.h"
#include "posefuse/v1/session.pb.h"
#include "session/option_table.hpp"

namespace posefuse::session {

// Where results go (the server's stream, a test's vector, a file writer).
class ResultSink {
 public:
  virtual ~ResultSink() = default;
  virtual void emit(v1::FitResult&& result) = 0;
};

// What a stage writes to. Owned by the pipeline; counts warnings for the summary.
class StageOutput {
 public:
  virtual ~StageOutput() = default;
  virtual void emit(v1::FitResult&& result) = 0;
  virtual void warn(const std::string& code, const std::string& field,
                    const std::string& message) = 0;
  // The session's calibration report, filled by the stages in finish() and sent after them.
  virtual v1::CalibrationReport& calibration() = 0;
};

class Stage {
 public:
  virtual ~Stage() = default;
  // Stable name used in logs, metrics and ServerInfo, e.g. "imu_orientation".
  virtual std::string_view name() const = 0;
  // One line: what the stage computes and from what.
  virtual std::string_view description() const = 0;
  // The SessionHeader.options keys it reads (listed by the server's GetServerInfo).
  virtual const OptionTable& options() const {
    static const OptionTable none;
    return none;
  }
  // The validated header. Throws posefuse::Error for options the stage cannot use; that ends
  // the session (the pipeline cannot run without the stage).
  virtual void start(const v1::SessionHeader& header, StageOutput& out) = 0;
  // One validated data chunk, in stream order. A posefuse::Error thrown here becomes an
  // ItemError for this chunk and the session goes on, so a stage must leave its state
  // consistent when it throws.
  virtual void on_chunk(const v1::SessionChunk& chunk, StageOutput& out) = 0;
  // After the end marker: emit what is left and add to out.calibration().
  virtual void finish(StageOutput& out) = 0;
  // A result emitted by a stage that runs before this one, as it is emitted (e.g. the IMU
  // orientations the forearm stage builds on). Called before the emitting stage returns, so a
  // stage sees an earlier stage's results for a chunk before its own on_chunk for that chunk.
  // Errors thrown here are item errors, as from on_chunk.
  virtual void on_result(const v1::FitResult& /*result*/, StageOutput& /*out*/) {}

  // Results of the stages after this one, for a stage that refines its own output with them (the
  // forearm stage's gap recovery with the body fit's elbows). Asked once after start(). They are
  // queued and delivered in emission order after the stage call that caused them returns, never
  // from inside this stage's own emit, so a stage is not re-entered. The last of them come after
  // this stage's finish(): finish_late() is then called, after every stage has finished and every
  // later result has been delivered, for what waited on them. Errors are item errors there too.
  virtual bool wants_later_results() const { return false; }
  virtual void on_later_result(const v1::FitResult& /*result*/, StageOutput& /*out*/) {}
  virtual void finish_late(StageOutput& /*out*/) {}
};

}  // namespace posefuse::session
