#include "session/pipeline.hpp"

#include <algorithm>
#include <functional>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "common/number_text.hpp"

#include "session/result_encoder.hpp"
#include "session/stage_inputs.hpp"
#include "session/unknown_options.hpp"

namespace posefuse::session {

// The StageOutput the stages write to: forwards to the sink and counts warnings.
class SessionPipeline::Output : public StageOutput {
 public:
  explicit Output(SessionPipeline& pipeline) : pipeline_(pipeline) {}

  void emit(v1::FitResult&& result) override {
    if (result.has_warning()) ++pipeline_.warnings_;
    if (result.has_item_error()) ++pipeline_.item_errors_;
    if (result.has_recovered_segment()) ++pipeline_.recovered_segments_;
    if (result.has_frame() && result.frame().smpl_joints_size() > 0) ++pipeline_.frames_fitted_;
    pipeline_.sink_.emit(std::move(result));
  }
  void hand_on(StageValue&& value) override {
    // The client sees a value before the later stages' results that follow from it.
    if (std::optional<v1::FitResult> result = encode_value(value)) emit(std::move(*result));
    const std::size_t emitter = pipeline_.current_stage_;
    const ValueKind kind = kind_of(value);
    for (std::size_t next = emitter + 1; next < pipeline_.stages_.size(); ++next) {
      if (!pipeline_.consumes_[next].contains(kind)) continue;
      pipeline_.current_stage_ = next;
      try {
        pipeline_.stages_[next]->on_value(value, *this);
      } catch (const Error& error) {
        pipeline_.current_stage_ = emitter;
        pipeline_.item_error(error, error.field());
      }
    }
    pipeline_.current_stage_ = emitter;
  }
  void warn(const std::string& code, const std::string& field, const std::string& message) override {
    const std::uint64_t raised = ++pipeline_.warnings_per_kind_[{code, field}];
    if (raised > pipeline_.options_.max_warnings_per_kind) return;
    list(code, field, message);
  }
  void list(const std::string& code, const std::string& field, const std::string& message) {
    v1::FitResult result;
    v1::Warning& warning = *result.mutable_warning();
    warning.set_code(code);
    warning.set_field(field);
    warning.set_message(message);
    emit(std::move(result));
  }
  v1::CalibrationReport& calibration() override { return calibration_; }

 private:
  SessionPipeline& pipeline_;
  v1::CalibrationReport calibration_;
};

SessionPipeline::SessionPipeline(std::vector<std::unique_ptr<Stage>> stages, ResultSink& sink, PipelineOptions options)
    : stages_(std::move(stages)),
      sink_(sink),
      options_(options),
      output_(std::make_unique<Output>(*this)),
      started_at_(std::chrono::steady_clock::now()) {
  std::set<ValueKind> produced_before;
  for (const auto& stage : stages_) {
    const std::vector<ValueKind> consumed = stage->consumes();
    for (const ValueKind kind : consumed) {
      if (!produced_before.contains(kind)) {
        throw Error(ErrorCode::kInternal, "stages",
                    "stage '" + std::string(stage->name()) + "' consumes " + value_kind_name(kind) +
                        ", which no stage before it produces (data flows one way: a stage reads only "
                        "what earlier stages hand on)");
      }
    }
    consumes_.emplace_back(consumed.begin(), consumed.end());
    for (const ValueKind kind : stage->produces()) produced_before.insert(kind);
  }
}

SessionPipeline::~SessionPipeline() = default;

template <class Call>
void SessionPipeline::timed(Stage& stage, Call&& call) {
  if (!options_.on_stage_time) {
    call();
    return;
  }
  const auto start = std::chrono::steady_clock::now();
  call();  // a throwing stage call is not timed: it is counted as an item error instead
  options_.on_stage_time(stage.name(), std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
}

void SessionPipeline::warn_unknown_options(const v1::SessionHeader& header) {
  std::vector<const OptionTable*> tables;
  for (const auto& stage : stages_) tables.push_back(&stage->options());
  for (const UnknownOption& option : unknown_stage_options(header, tables)) {
    output_->warn("OPTION_UNKNOWN", option_field(option.key),
                  "is not an option of this server's stages (`posefuse info` lists them); ignored, the defaults "
                  "stand" +
                      (option.closest.empty() ? std::string() : "; did you mean '" + option.closest + "'?"));
  }
}

void SessionPipeline::push(const v1::SessionChunk& chunk) {
  const std::uint64_t index = index_++;
  const std::string field = "chunk[" + std::to_string(index) + "]";
  if (ended_) {
    throw_invalid(field, "chunk after the end marker (a session ends with exactly one)");
  }
  try {
    validator_.check(chunk);
  } catch (const Error& error) {
    // Without a valid header nothing else can be interpreted: the session cannot go on.
    if (!validator_.has_header()) throw;
    item_error(error, error.field());
    // An end marker whose counts disagree still ends the stream (the disagreement was reported;
    // chunks rejected above are one honest cause of it).
    if (chunk.has_end()) end_session();
    return;
  }

  if (chunk.has_header()) {
    assembler_ = std::make_unique<FrameAssembler>(chunk.header());
    for (current_stage_ = 0; current_stage_ < stages_.size(); ++current_stage_) {
      Stage& stage = *stages_[current_stage_];
      timed(stage, [&] { stage.start(chunk.header(), *output_); });
    }
    warn_unknown_options(chunk.header());
    return;
  }
  if (chunk.has_end()) {
    end_session();
    return;
  }
  process_data_chunk(chunk, field);
  // Item errors from stages go through item_error too.
  if (index_ % options_.progress_every_chunks == 0) emit_progress();
}

void SessionPipeline::process_data_chunk(const v1::SessionChunk& chunk, const std::string& field) {
  std::vector<SessionInput> ready;
  try {
    assembler_->add(chunk, validator_.take_decoded_image(), field, ready);
  } catch (const Error& error) {
    item_error(error, error.field());
    return;
  }
  note_camera_time(chunk);
  if (chunk.has_depth()) ++depth_frames_;
  deliver(ready);
  check_memory_budget(field);
}

std::uint64_t SessionPipeline::held_bytes() const {
  std::uint64_t held = assembler_ ? assembler_->held_bytes() : 0;
  for (const auto& stage : stages_) held += stage->held_bytes();
  return held;
}

void SessionPipeline::check_memory_budget(const std::string& field) const {
  if (options_.max_held_bytes == 0) return;
  const std::uint64_t queued = options_.queued_chunk_bytes ? options_.queued_chunk_bytes() : 0;
  const std::uint64_t held = held_bytes() + queued;
  if (held <= options_.max_held_bytes) return;
  std::vector<std::pair<std::uint64_t, std::string>> holders;
  holders.emplace_back(queued, "queued chunks");
  if (assembler_) holders.emplace_back(assembler_->held_bytes(), "frame assembly");
  for (const auto& stage : stages_) holders.emplace_back(stage->held_bytes(), std::string(stage->name()));
  std::sort(holders.begin(), holders.end(), std::greater<>());
  const auto mib = [](std::uint64_t bytes) { return fixed_text(static_cast<double>(bytes) / (1 << 20), 1) + " MiB"; };
  std::string parts;
  for (const auto& [bytes, holder] : holders) {
    if (bytes < (1 << 20) / 10) continue;  // shown as 0.0 MiB
    parts += (parts.empty() ? "" : ", ") + holder + " " + mib(bytes);
  }
  throw Error(ErrorCode::kResourceExhausted, field,
              "the session holds " + mib(held) + " for later frames, beyond its memory budget of " +
                  mib(options_.max_held_bytes) + " (" + options_.max_held_bytes_setting + "): " + parts +
                  ". Stages keep frames by stream time (fit.calibration_s, fit.imu_wait_s, "
                  "forearm.calibration_s), so a long window, large images or frames far closer together "
                  "than a camera sends them fill it");
}

void SessionPipeline::deliver(const std::vector<SessionInput>& inputs) {
  for (const SessionInput& input : inputs) {
    for (current_stage_ = 0; current_stage_ < stages_.size(); ++current_stage_) {
      Stage& stage = *stages_[current_stage_];
      try {
        timed(stage, [&] { deliver_input(stage, input, *output_); });
      } catch (const Error& error) {
        item_error(error, error.field());
      }
    }
  }
}

void SessionPipeline::item_error(const Error& error, const std::string& field) {
  v1::FitResult result;
  v1::ItemError& item = *result.mutable_item_error();
  item.set_code(error_code_name(error.code()));
  item.set_field(field);
  // Error::what() is "field: message"; the message alone, since the field is separate.
  const std::string what = error.what();
  const std::string prefix = error.field() + ": ";
  item.set_message(what.rfind(prefix, 0) == 0 ? what.substr(prefix.size()) : what);
  output_->emit(std::move(result));
  if (item_errors_ > options_.max_item_errors) {
    throw Error(ErrorCode::kInvalidArgument, "chunks",
                std::to_string(item_errors_) + " chunks or items rejected (limit " +
                    std::to_string(options_.max_item_errors) + "); the last: " + field + ": " + item.message());
  }
}

void SessionPipeline::end_session() {
  ended_ = true;
  if (assembler_) {
    std::vector<SessionInput> ready;
    std::vector<AssemblyWarning> warnings;
    assembler_->finish(ready, warnings);
    deliver(ready);
    current_stage_ = stages_.size();
    for (const AssemblyWarning& w : warnings) output_->warn(w.code, w.field, w.message);
  }
  for (std::size_t i = 0; i < stages_.size(); ++i) {
    current_stage_ = i;
    timed(*stages_[i], [&] { stages_[i]->finish(*output_); });
  }
  current_stage_ = stages_.size();  // the pipeline's own results go to no stage
  warn_unlisted_repeats();
  v1::FitResult calibration;
  *calibration.mutable_calibration() = output_->calibration();
  output_->emit(std::move(calibration));
  emit_progress();

  v1::FitResult result;
  v1::Summary& summary = *result.mutable_summary();
  summary.set_chunks(index_);
  summary.set_depth_frames(depth_frames_);
  summary.set_frames_fitted(frames_fitted_);  // FrameResults with body-model joints
  summary.set_recovered_segments(recovered_segments_);
  summary.set_warnings(warnings_);
  summary.set_item_errors(item_errors_);
  if (first_camera_t_us_) {
    summary.set_stream_duration_s(static_cast<double>(*last_camera_t_us_ - *first_camera_t_us_) * 1e-6);
  }
  summary.set_processing_duration_s(
      std::chrono::duration<double>(std::chrono::steady_clock::now() - started_at_).count());
  output_->emit(std::move(result));
}

void SessionPipeline::warn_unlisted_repeats() {
  for (const auto& [kind, raised] : warnings_per_kind_) {
    if (raised <= options_.max_warnings_per_kind) continue;
    const auto& [code, field] = kind;
    output_->list(code, field,
                  std::to_string(raised - options_.max_warnings_per_kind) + " more " + code + " warnings for " + field +
                      " were not listed (" + std::to_string(raised) + " in all; the first " +
                      std::to_string(options_.max_warnings_per_kind) + " are)");
  }
}

void SessionPipeline::close() {
  if (ended_) return;
  throw_invalid("end", "the stream stopped after " + std::to_string(index_) +
                           " chunks without an end marker (truncated upload or recording?)");
}

void SessionPipeline::emit_progress() {
  v1::FitResult result;
  v1::Progress& progress = *result.mutable_progress();
  progress.set_chunks_processed(index_);
  progress.set_frames_processed(depth_frames_);
  progress.set_stream_t_us(last_camera_t_us_.value_or(0));
  output_->emit(std::move(result));
}

void SessionPipeline::note_camera_time(const v1::SessionChunk& chunk) {
  std::optional<std::int64_t> t_us;
  switch (chunk.chunk_case()) {
    case v1::SessionChunk::kDepth: t_us = chunk.depth().t_us(); break;
    case v1::SessionChunk::kBodyIndex: t_us = chunk.body_index().t_us(); break;
    case v1::SessionChunk::kSkeleton: t_us = chunk.skeleton().t_us(); break;
    case v1::SessionChunk::kColor: t_us = chunk.color().t_us(); break;
    case v1::SessionChunk::kAudio: t_us = chunk.audio().t_us(); break;
    default: break;  // IMU and sync events are on their devices' clocks
  }
  if (!t_us) return;
  if (!first_camera_t_us_ || *t_us < *first_camera_t_us_) first_camera_t_us_ = t_us;
  if (!last_camera_t_us_ || *t_us > *last_camera_t_us_) last_camera_t_us_ = t_us;
}

}  // namespace posefuse::session
