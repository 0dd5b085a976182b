#pragma once
// Protobuf messages <-> the directory form's JSON files (header.json, end.json), using
// protobuf's canonical JSON mapping with the .proto field names.
#include <string>

#include <google/protobuf/message.h>

namespace posefuse::session {

std::string message_to_json(const google::protobuf::Message& message);
// Unknown fields are an error. Throws kInvalidArgument naming `name` (e.g. "header.json").
void message_from_json(const std::string& json, const std::string& name, google::protobuf::Message& message);

}  // namespace posefuse::session
