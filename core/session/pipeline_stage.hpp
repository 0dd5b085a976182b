#pragma once
// The interface every pipeline stage implements, and the output a stage writes its results to.
//
// A stage sees the session in time order as typed inputs (session_inputs.hpp), decoded once by
// the pipeline's FrameAssembler: start() with the header, then camera frames, IMU blocks, audio
// and clock events as they complete, and finish() once after the end marker. It hands typed
// values (stage_values.hpp) to the stages after it and emits what goes only to the client
// (frame results, recovered segments, warnings); it adds its part of the calibration report,
// which the pipeline sends once after every stage has finished. Stages hold all their state
// themselves (no globals), so many sessions run at once.
#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

#include "posefuse/v1/results.pb.h"
#include "posefuse/v1/session.pb.h"
#include "session/option_table.hpp"
#include "session/session_inputs.hpp"
#include "session/stage_values.hpp"

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
  // A value for the stages after this one (those whose consumes() names its kind), delivered
  // before this call returns; the client gets those it sees as FitResults (result_encoder.hpp).
  virtual void hand_on(StageValue&& value) = 0;
  virtual void warn(const std::string& code, const std::string& field, const std::string& message) = 0;
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
  // The kinds of value the stage reads from earlier stages and those it hands on. The pipeline
  // refuses an order in which a stage consumes a kind no earlier stage produces.
  virtual std::vector<ValueKind> consumes() const { return {}; }
  virtual std::vector<ValueKind> produces() const { return {}; }
  // The validated header. Throws posefuse::Error for options the stage cannot use; that ends
  // the session (the pipeline cannot run without the stage).
  virtual void start(const v1::SessionHeader& header, StageOutput& out) = 0;
  // The session's inputs, in stream order. A posefuse::Error thrown here becomes an ItemError
  // for this input and the session goes on, so a stage must leave its state consistent when it
  // throws.
  virtual void on_camera_frame(const CameraFrame& /*frame*/, StageOutput& /*out*/) {}
  virtual void on_imu(const ImuBlock& /*block*/, StageOutput& /*out*/) {}
  virtual void on_audio(const AudioBlock& /*audio*/, StageOutput& /*out*/) {}
  virtual void on_clock_event(const ClockEvent& /*event*/, StageOutput& /*out*/) {}
  // A value of a kind in consumes(), handed on by an earlier stage as it is handed on (before
  // that stage's call returns), so a stage sees an earlier stage's values for an input before
  // its own call for that input. Errors thrown here are item errors, as from the inputs.
  virtual void on_value(const StageValue& /*value*/, StageOutput& /*out*/) {}
  // After the end marker: emit what is left and add to out.calibration().
  virtual void finish(StageOutput& out) = 0;
  // The memory the stage holds for later (frames waiting for calibration or for another stream,
  // the history its end-of-session results need), for the session's memory budget
  // (PipelineOptions::max_held_bytes). Asked after every data chunk, so it must be cheap
  // (core/common/held_bytes.hpp).
  virtual std::size_t held_bytes() const { return 0; }
};

}  // namespace posefuse::session
