#include "session/stage_inputs.hpp"

#include <memory>
#include <string>
#include <type_traits>
#include <variant>

#include "common/error.hpp"
#include "session/session_validator.hpp"

namespace posefuse::session {

void deliver_input(Stage& stage, const SessionInput& input, StageOutput& out) {
  std::visit(
      [&](const auto& in) {
        using Input = std::decay_t<decltype(in)>;
        if constexpr (std::is_same_v<Input, CameraFrame>) stage.on_camera_frame(in, out);
        if constexpr (std::is_same_v<Input, ImuBlock>) stage.on_imu(in, out);
        if constexpr (std::is_same_v<Input, AudioBlock>) stage.on_audio(in, out);
        if constexpr (std::is_same_v<Input, ClockEvent>) stage.on_clock_event(in, out);
      },
      input);
}

AssembledSession assemble_session(const std::vector<v1::SessionChunk>& chunks) {
  AssembledSession session;
  SessionValidator validator;
  std::unique_ptr<FrameAssembler> assembler;
  for (std::size_t i = 0; i < chunks.size(); ++i) {
    const v1::SessionChunk& chunk = chunks[i];
    validator.check(chunk);
    if (chunk.has_header()) {
      session.header = chunk.header();
      assembler = std::make_unique<FrameAssembler>(chunk.header());
    } else if (!chunk.has_end()) {
      assembler->add(chunk, validator.take_decoded_image(), "chunk[" + std::to_string(i) + "]", session.inputs);
    }
  }
  if (!assembler) throw_invalid("chunks", "no header");
  assembler->finish(session.inputs, session.warnings);
  return session;
}

}  // namespace posefuse::session
