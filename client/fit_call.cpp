#include "client/fit_call.hpp"

#include <atomic>
#include <mutex>
#include <thread>
#include <vector>

#include <grpcpp/support/client_interceptor.h>

#include "client/recording.hpp"
#include "posefuse/v1/service.grpc.pb.h"

namespace posefuse::client {

namespace {

const char* code_name(grpc::StatusCode code) {
  switch (code) {
    case grpc::StatusCode::OK: return "OK";
    case grpc::StatusCode::CANCELLED: return "CANCELLED";
    case grpc::StatusCode::UNKNOWN: return "UNKNOWN";
    case grpc::StatusCode::INVALID_ARGUMENT: return "INVALID_ARGUMENT";
    case grpc::StatusCode::DEADLINE_EXCEEDED: return "DEADLINE_EXCEEDED";
    case grpc::StatusCode::NOT_FOUND: return "NOT_FOUND";
    case grpc::StatusCode::ALREADY_EXISTS: return "ALREADY_EXISTS";
    case grpc::StatusCode::PERMISSION_DENIED: return "PERMISSION_DENIED";
    case grpc::StatusCode::RESOURCE_EXHAUSTED: return "RESOURCE_EXHAUSTED";
    case grpc::StatusCode::FAILED_PRECONDITION: return "FAILED_PRECONDITION";
    case grpc::StatusCode::ABORTED: return "ABORTED";
    case grpc::StatusCode::OUT_OF_RANGE: return "OUT_OF_RANGE";
    case grpc::StatusCode::UNIMPLEMENTED: return "UNIMPLEMENTED";
    case grpc::StatusCode::INTERNAL: return "INTERNAL";
    case grpc::StatusCode::UNAVAILABLE: return "UNAVAILABLE";
    case grpc::StatusCode::DATA_LOSS: return "DATA_LOSS";
    case grpc::StatusCode::UNAUTHENTICATED: return "UNAUTHENTICATED";
    default: return "UNKNOWN";
  }
}

// Adds `authorization: Bearer <token>` to every call's initial metadata. An interceptor rather
// than call credentials, because gRPC sends call credentials only over TLS and a token must
// also work behind a TLS-terminating proxy on a private network.
class BearerTokenInterceptor : public grpc::experimental::Interceptor {
 public:
  explicit BearerTokenInterceptor(const std::string& token) : value_("Bearer " + token) {}
  void Intercept(grpc::experimental::InterceptorBatchMethods* methods) override {
    if (methods->QueryInterceptionHookPoint(grpc::experimental::InterceptionHookPoints::PRE_SEND_INITIAL_METADATA)) {
      methods->GetSendInitialMetadata()->insert({"authorization", value_});
    }
    methods->Proceed();
  }

 private:
  std::string value_;
};

class BearerTokenInterceptorFactory : public grpc::experimental::ClientInterceptorFactoryInterface {
 public:
  explicit BearerTokenInterceptorFactory(std::string token) : token_(std::move(token)) {}
  grpc::experimental::Interceptor* CreateClientInterceptor(grpc::experimental::ClientRpcInfo*) override {
    return new BearerTokenInterceptor(token_);
  }

 private:
  std::string token_;
};

bool tls_failure(const std::string& message) {
  for (const char* sign : {"ssl", "SSL", "handshake", "Handshake", "TLS", "certificate"}) {
    if (message.find(sign) != std::string::npos) return true;
  }
  return false;
}

}  // namespace

std::shared_ptr<grpc::Channel> make_channel(const std::string& address, const ChannelSecurity& security) {
  grpc::ChannelArguments args;
  args.SetMaxReceiveMessageSize(64 << 20);
  std::shared_ptr<grpc::ChannelCredentials> credentials = grpc::InsecureChannelCredentials();
  if (security.tls()) {
    grpc::SslCredentialsOptions ssl;
    ssl.pem_root_certs = security.ca_pem;  // empty: the system's trusted CAs
    ssl.pem_cert_chain = security.cert_chain_pem;
    ssl.pem_private_key = security.private_key_pem;
    credentials = grpc::SslCredentials(ssl);
  }
  std::vector<std::unique_ptr<grpc::experimental::ClientInterceptorFactoryInterface>> interceptors;
  if (!security.bearer_token.empty()) {
    interceptors.push_back(std::make_unique<BearerTokenInterceptorFactory>(security.bearer_token));
  }
  return grpc::experimental::CreateCustomChannelWithInterceptors(address, credentials, args, std::move(interceptors));
}

std::string status_line(const grpc::Status& status, const std::string& address) {
  if (status.error_code() == grpc::StatusCode::UNAUTHENTICATED) {
    return "server " + address + " refused the call: UNAUTHENTICATED: " + status.error_message() +
           " (pass a valid token with --token-file FILE or POSEFUSE_TOKEN)";
  }
  if (status.error_code() == grpc::StatusCode::UNAVAILABLE && tls_failure(status.error_message())) {
    return "TLS handshake with the server at " + address + " failed (" + status.error_message() +
           "); check --tls-ca (the CA that signed the server's certificate) and, for mutual "
           "TLS, --tls-cert/--tls-key";
  }
  if (status.error_code() == grpc::StatusCode::UNAVAILABLE) {
    return "cannot reach the server at " + address + " (UNAVAILABLE: " + status.error_message() +
           "); is posefuse-server running (and if it uses TLS, was --tls-ca given)?";
  }
  return "server " + address + ": " + code_name(status.error_code()) + ": " + status.error_message();
}

FitOutcome run_fit(const std::shared_ptr<grpc::Channel>& channel, const std::filesystem::path& recording,
                   ResultWriter& writer, const std::function<void(const FitProgress&)>& on_progress,
                   const HeaderEdits& header_edits) {
  FitOutcome outcome;
  std::unique_ptr<Recording> source;
  try {
    source = std::make_unique<Recording>(recording, header_edits);
  } catch (const Error& error) {
    outcome.local_error = error;
    return outcome;
  }

  auto stub = v1::PoseFuse::NewStub(channel);
  grpc::ClientContext context;
  auto stream = stub->Fit(&context);
  const auto started = std::chrono::steady_clock::now();

  std::atomic<std::uint64_t> chunks_sent{0}, depth_frames_sent{0};
  std::atomic<double> fraction{-1.0};
  std::mutex error_mu;
  std::optional<Error> read_error;
  // The sender: Write blocks while gRPC's flow control holds it back (server back-pressure).
  std::thread sender([&] {
    try {
      session::SessionChunk chunk;
      while (source->next(chunk)) {
        if (!stream->Write(chunk)) return;  // the server ended the call; Finish says why
        chunks_sent.fetch_add(1);
        if (chunk.has_depth()) depth_frames_sent.fetch_add(1);
        fraction.store(source->fraction_read());
      }
      stream->WritesDone();
    } catch (const Error& error) {
      std::lock_guard lock(error_mu);
      read_error = error;
      context.TryCancel();
    }
  });

  auto progress_now = [&] {
    return FitProgress{chunks_sent.load(), depth_frames_sent.load(), fraction.load(),
                       std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count()};
  };
  auto last_report = started;
  v1::FitResult result;
  while (stream->Read(&result)) {
    ++outcome.results_received;
    if (!outcome.local_error) {
      try {
        writer.write(result);
      } catch (const Error& error) {
        outcome.local_error = error;
        context.TryCancel();
      }
    }
    const auto now = std::chrono::steady_clock::now();
    if (on_progress && now - last_report >= std::chrono::milliseconds(200)) {
      last_report = now;
      on_progress(progress_now());
    }
  }
  sender.join();
  outcome.status = stream->Finish();
  outcome.progress = progress_now();
  if (read_error && !outcome.local_error) outcome.local_error = read_error;
  if (!outcome.local_error && outcome.status.ok()) {
    try {
      writer.finish();
    } catch (const Error& error) {
      outcome.local_error = error;
    }
  }
  return outcome;
}

}  // namespace posefuse::client
