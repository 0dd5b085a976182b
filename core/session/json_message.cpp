#include "session/json_message.hpp"

#include <google/protobuf/descriptor.h>
#include <google/protobuf/io/coded_stream.h>
#include <google/protobuf/io/zero_copy_stream_impl_lite.h>
#include <google/protobuf/util/json_util.h>
#include <google/protobuf/util/type_resolver_util.h>
#include <memory>

#include "common/error.hpp"

namespace posefuse::session {

std::string message_to_json(const google::protobuf::Message& message) {
  google::protobuf::util::JsonPrintOptions options;
  options.add_whitespace = true;
  options.preserve_proto_field_names = true;
  // Map fields (header options, end counts, clock offsets) iterate in a per-instance random
  // order; converting a deterministic (key-sorted) binary form makes the JSON reproducible.
  std::string binary;
  {
    google::protobuf::io::StringOutputStream stream(&binary);
    google::protobuf::io::CodedOutputStream coded(&stream);
    coded.SetSerializationDeterministic(true);
    message.SerializeToCodedStream(&coded);
  }
  const std::string url_prefix = "type.googleapis.com";
  const std::unique_ptr<google::protobuf::util::TypeResolver> resolver(
      google::protobuf::util::NewTypeResolverForDescriptorPool(url_prefix, message.GetDescriptor()->file()->pool()));
  std::string json;
  const auto status = google::protobuf::util::BinaryToJsonString(
      resolver.get(), url_prefix + "/" + message.GetDescriptor()->full_name(), binary, &json, options);
  if (!status.ok()) {
    throw Error(ErrorCode::kInternal, message.GetTypeName(), "JSON: " + status.ToString());
  }
  return json;
}

void message_from_json(const std::string& json, const std::string& name, google::protobuf::Message& message) {
  google::protobuf::util::JsonParseOptions options;
  options.ignore_unknown_fields = false;
  const auto status = google::protobuf::util::JsonStringToMessage(json, &message, options);
  if (!status.ok()) throw_invalid(name, "not a valid " + message.GetTypeName() + ": " + std::string(status.message()));
}

}  // namespace posefuse::session
