#include "session/json_message.hpp"

#include <google/protobuf/util/json_util.h>

#include "common/error.hpp"

namespace posefuse::session {

std::string message_to_json(const google::protobuf::Message& message) {
  google::protobuf::util::JsonPrintOptions options;
  options.add_whitespace = true;
  options.preserve_proto_field_names = true;
  std::string json;
  const auto status = google::protobuf::util::MessageToJsonString(message, &json, options);
  if (!status.ok()) {
    throw Error(ErrorCode::kInternal, message.GetTypeName(), "JSON: " + status.ToString());
  }
  return json;
}

void message_from_json(const std::string& json, const std::string& name,
                       google::protobuf::Message& message) {
  google::protobuf::util::JsonParseOptions options;
  options.ignore_unknown_fields = false;
  const auto status = google::protobuf::util::JsonStringToMessage(json, &message, options);
  if (!status.ok()) throw_invalid(name, "not a valid " + message.GetTypeName() + ": " +
                                            std::string(status.message()));
}

}  // namespace posefuse::session
