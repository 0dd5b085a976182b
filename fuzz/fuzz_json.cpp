// The directory form's JSON reader (session/json_message.*, header.json and end.json) on
// arbitrary text: byte 0 picks SessionHeader or EndOfSession, the rest is the JSON. A message
// that parses is written back (message_to_json) and must read back to the same message; a
// header that parses also goes through validate_header.
#include <cstddef>
#include <cstdint>
#include <string>

#include <google/protobuf/util/message_differencer.h>

#include "common/error.hpp"
#include "seeds.hpp"
#include "session/json_message.hpp"
#include "session/session_validator.hpp"

using namespace posefuse;

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  fuzz::init_harness([] {
    const auto session = fuzz::tiny_session();
    return fuzz::Seeds{{"header.json", std::string(1, '\0') + session::message_to_json(session.front().header())},
                       {"end.json", std::string(1, '\1') + session::message_to_json(session.back().end())}};
  });
  return 0;
}

namespace {

template <typename Message>
void round_trip(const std::string& json, const char* name) {
  Message message;
  session::message_from_json(json, name, message);
  Message again;
  session::message_from_json(session::message_to_json(message), name, again);
  // proto3 JSON writes no field at its default, so -0.0 comes back as an unset 0: the values are
  // the same, which is what the round trip must keep.
  google::protobuf::util::MessageDifferencer same_values;
  same_values.set_message_field_comparison(google::protobuf::util::MessageDifferencer::EQUIVALENT);
  same_values.set_float_comparison(google::protobuf::util::MessageDifferencer::APPROXIMATE);
  if (!same_values.Compare(message, again)) {
    fuzz::invariant_failed(std::string(name) + ": JSON round trip changed the message");
  }
  if constexpr (std::is_same_v<Message, v1::SessionHeader>) session::validate_header(message);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  const std::string json(reinterpret_cast<const char*>(data) + 1, size - 1);
  try {
    if (data[0] & 1) round_trip<v1::EndOfSession>(json, "end.json");
    else round_trip<v1::SessionHeader>(json, "header.json");
  } catch (const Error&) {
  }
  return 0;
}
