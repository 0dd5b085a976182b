#include "server/reflection_service.hpp"

#include <set>

#include <google/protobuf/descriptor.h>
#include <google/protobuf/descriptor.pb.h>

#include "server/refused_call.hpp"

namespace posefuse::server {

namespace {

namespace pb = google::protobuf;
using reflection::ServerReflectionRequest;
using reflection::ServerReflectionResponse;

// `file` first, then every file it imports, directly or not, each once.
void add_file_with_imports(const pb::FileDescriptor* file, std::set<std::string>& sent,
                           reflection::FileDescriptorResponse& out) {
  if (!sent.insert(file->name()).second) return;
  pb::FileDescriptorProto proto;
  file->CopyTo(&proto);
  out.add_file_descriptor_proto(proto.SerializeAsString());
  for (int i = 0; i < file->dependency_count(); ++i) {
    add_file_with_imports(file->dependency(i), sent, out);
  }
}

void set_error(ServerReflectionResponse& response, grpc::StatusCode code, std::string message) {
  reflection::ErrorResponse& error = *response.mutable_error_response();
  error.set_error_code(static_cast<int>(code));
  error.set_error_message(std::move(message));
}

void answer_with_file(ServerReflectionResponse& response, const pb::FileDescriptor* file, const std::string& what) {
  if (!file) {
    set_error(response, grpc::StatusCode::NOT_FOUND, what + " not found");
    return;
  }
  std::set<std::string> sent;
  add_file_with_imports(file, sent, *response.mutable_file_descriptor_response());
}

// One request after another on one stream: read, answer, write, read the next.
class ReflectionStream : public grpc::ServerBidiReactor<ServerReflectionRequest, ServerReflectionResponse> {
 public:
  explicit ReflectionStream(const std::vector<std::string>& services) : services_(services) { StartRead(&request_); }
  void OnReadDone(bool ok) override {
    if (!ok) {
      Finish(grpc::Status::OK);  // the client has asked everything
      return;
    }
    response_ = answer_reflection_request(request_, services_);
    StartWrite(&response_);
  }
  void OnWriteDone(bool ok) override {
    if (!ok) {
      Finish(grpc::Status(grpc::StatusCode::CANCELLED, "stream broken"));
      return;
    }
    StartRead(&request_);
  }
  void OnDone() override { delete this; }

 private:
  const std::vector<std::string>& services_;
  ServerReflectionRequest request_;
  ServerReflectionResponse response_;
};

}  // namespace

ServerReflectionResponse answer_reflection_request(const ServerReflectionRequest& request,
                                                   const std::vector<std::string>& services) {
  const pb::DescriptorPool& pool = *pb::DescriptorPool::generated_pool();
  ServerReflectionResponse response;
  response.set_valid_host(request.host());
  *response.mutable_original_request() = request;
  switch (request.message_request_case()) {
    case ServerReflectionRequest::kListServices:
      for (const std::string& name : services) {
        response.mutable_list_services_response()->add_service()->set_name(name);
      }
      break;
    case ServerReflectionRequest::kFileByFilename:
      answer_with_file(response, pool.FindFileByName(request.file_by_filename()),
                       "file '" + request.file_by_filename() + "'");
      break;
    case ServerReflectionRequest::kFileContainingSymbol:
      answer_with_file(response, pool.FindFileContainingSymbol(request.file_containing_symbol()),
                       "symbol '" + request.file_containing_symbol() + "'");
      break;
    case ServerReflectionRequest::kFileContainingExtension: {
      const auto& wanted = request.file_containing_extension();
      const pb::Descriptor* type = pool.FindMessageTypeByName(wanted.containing_type());
      const pb::FieldDescriptor* extension =
          type ? pool.FindExtensionByNumber(type, wanted.extension_number()) : nullptr;
      answer_with_file(
          response, extension ? extension->file() : nullptr,
          "extension " + std::to_string(wanted.extension_number()) + " of '" + wanted.containing_type() + "'");
      break;
    }
    case ServerReflectionRequest::kAllExtensionNumbersOfType: {
      const pb::Descriptor* type = pool.FindMessageTypeByName(request.all_extension_numbers_of_type());
      if (!type) {
        set_error(response, grpc::StatusCode::NOT_FOUND,
                  "type '" + request.all_extension_numbers_of_type() + "' not found");
        break;
      }
      std::vector<const pb::FieldDescriptor*> extensions;
      pool.FindAllExtensions(type, &extensions);
      auto& numbers = *response.mutable_all_extension_numbers_response();
      numbers.set_base_type_name(type->full_name());
      for (const pb::FieldDescriptor* extension : extensions) {
        numbers.add_extension_number(extension->number());
      }
      break;
    }
    case ServerReflectionRequest::MESSAGE_REQUEST_NOT_SET:
      set_error(response, grpc::StatusCode::INVALID_ARGUMENT, "message_request: none set");
      break;
  }
  return response;
}

ReflectionService::ReflectionService(std::vector<std::string> services, const BearerTokens* tokens)
    : services_(std::move(services)), tokens_(tokens) {}

grpc::ServerBidiReactor<reflection::ServerReflectionRequest, reflection::ServerReflectionResponse>*
ReflectionService::ServerReflectionInfo(grpc::CallbackServerContext* context) {
  using Reactor = grpc::ServerBidiReactor<ServerReflectionRequest, ServerReflectionResponse>;
  std::string tenant;  // reflection is the same for every tenant
  if (grpc::Status denied = authenticate_call(tokens_, *context, "ServerReflectionInfo", tenant); !denied.ok()) {
    return new RefusedCall<Reactor>(std::move(denied));
  }
  return new ReflectionStream(services_);
}

}  // namespace posefuse::server
