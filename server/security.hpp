#pragma once
// Transport security and bearer-token authentication of posefuse-server (docs/server.md
// "Security"). TLS and mutual TLS come from PEM files; tokens from a tokens file. Nothing here
// ever logs or returns a token or key.
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <grpcpp/grpcpp.h>

#include "server/server_options.hpp"
#include "server/tokens_file.hpp"

namespace posefuse::server {

// Reads a whole file for `flag`; throws posefuse::Error (field `flag`) when it cannot be read
// or is empty.
std::string read_security_file(const std::string& path, const std::string& flag);

// Insecure credentials without --tls-cert; otherwise TLS from --tls-cert/--tls-key, and with
// --tls-client-ca clients must present a certificate signed by that CA. Throws posefuse::Error
// naming the flag for an unreadable file or one that is not PEM of the expected kind.
std::shared_ptr<grpc::ServerCredentials> make_server_credentials(const ServerOptions& options);

// True when the --listen address `listen` (HOST:PORT, [IPV6]:PORT or unix:PATH) can be reached
// from this machine only: a 127.0.0.0/8 or ::1 address, localhost, or a Unix socket. Any other
// host, a name or an empty one (every interface) included, is beyond loopback.
bool listens_on_loopback_only(const std::string& listen);

// "plaintext", "tls" or "mutual-tls": what the server logs at start.
std::string transport_mode(const ServerOptions& options);

// The accepted bearer tokens. check() compares in time that does not depend on where a
// presented token differs from an accepted one.
class BearerTokens {
 public:
  // The tokens file at `path` (parse_tokens_file); also throws posefuse::Error (field
  // "--tokens-file") for an unreadable or empty file.
  static BearerTokens load(const std::string& path);
  explicit BearerTokens(std::vector<AcceptedToken> tokens);

  std::size_t size() const { return tokens_.size(); }
  // True when some token has a tenant: then each tenant's jobs by reference read only its own
  // folder of the recordings root, and tokens without a tenant cannot submit by reference.
  bool names_tenants() const;
  // The distinct tenants of the accepted tokens ("" among them for tokens without one).
  std::vector<std::string> tenants() const;
  // OK when the call carries `authorization: Bearer <accepted token>`, with that token's tenant
  // in `tenant`; UNAUTHENTICATED with a message that says what is missing otherwise (never
  // echoing what was sent).
  grpc::Status check(const grpc::CallbackServerContext& context, std::string& tenant) const;
  // The tenant of `token`, or nullopt when it is not accepted.
  std::optional<std::string> tenant_of(std::string_view token) const;
  bool accepts(std::string_view token) const { return tenant_of(token).has_value(); }

 private:
  std::vector<AcceptedToken> tokens_;
};

// OK when `tokens` is null (no token needed; tenant "") or the call carries an accepted one
// (its tenant in `tenant`); otherwise UNAUTHENTICATED, logged with the call's name and peer
// (never the token).
grpc::Status authenticate_call(const BearerTokens* tokens, const grpc::CallbackServerContext& context, const char* call,
                               std::string& tenant);

}  // namespace posefuse::server
