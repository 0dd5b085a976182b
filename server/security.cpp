#include "server/security.hpp"

#include <arpa/inet.h>
#include <netinet/in.h>

#include <algorithm>

#include "common/error.hpp"
#include "server/log.hpp"
#include "session/file_bytes.hpp"

namespace posefuse::server {

namespace {

void require_pem(const std::string& text, std::string_view marker, const std::string& path, const std::string& flag,
                 const char* what) {
  if (text.find("-----BEGIN ") == std::string::npos || text.find(marker) == std::string::npos) {
    throw_invalid(flag, "'" + path + "' is not a PEM " + what);
  }
}

// Looks at every byte of `accepted` whatever `presented` holds, so the time taken tells nothing
// about how many leading characters matched.
bool equal_constant_time(std::string_view presented, std::string_view accepted) {
  unsigned char difference = presented.size() == accepted.size() ? 0 : 1;
  for (std::size_t i = 0; i < accepted.size(); ++i) {
    const unsigned char p = i < presented.size() ? static_cast<unsigned char>(presented[i]) : 0;
    difference |= static_cast<unsigned char>(p ^ static_cast<unsigned char>(accepted[i]));
  }
  return difference == 0;
}

grpc::Status unauthenticated(const std::string& why) {
  return grpc::Status(grpc::StatusCode::UNAUTHENTICATED,
                      why +
                          "; this server requires 'authorization: Bearer <token>' metadata "
                          "with a token from its --tokens-file");
}

}  // namespace

std::string read_security_file(const std::string& path, const std::string& flag) {
  std::string text = session::read_file_bytes(path, flag);
  if (text.empty()) throw_invalid(flag, "'" + path + "' is empty");
  return text;
}

std::shared_ptr<grpc::ServerCredentials> make_server_credentials(const ServerOptions& options) {
  if (options.tls_cert.empty()) return grpc::InsecureServerCredentials();
  grpc::SslServerCredentialsOptions::PemKeyCertPair pair;
  pair.cert_chain = read_security_file(options.tls_cert, "--tls-cert");
  require_pem(pair.cert_chain, "CERTIFICATE-----", options.tls_cert, "--tls-cert", "certificate");
  pair.private_key = read_security_file(options.tls_key, "--tls-key");
  require_pem(pair.private_key, "PRIVATE KEY-----", options.tls_key, "--tls-key", "private key");

  grpc::SslServerCredentialsOptions ssl(GRPC_SSL_DONT_REQUEST_CLIENT_CERTIFICATE);
  ssl.pem_key_cert_pairs.push_back(std::move(pair));
  if (!options.tls_client_ca.empty()) {
    ssl.pem_root_certs = read_security_file(options.tls_client_ca, "--tls-client-ca");
    require_pem(ssl.pem_root_certs, "CERTIFICATE-----", options.tls_client_ca, "--tls-client-ca", "CA certificate");
    ssl.client_certificate_request = GRPC_SSL_REQUEST_AND_REQUIRE_CLIENT_CERTIFICATE_AND_VERIFY;
  }
  return grpc::SslServerCredentials(ssl);
}

std::string transport_mode(const ServerOptions& options) {
  if (options.tls_cert.empty()) return "plaintext";
  return options.tls_client_ca.empty() ? "tls" : "mutual-tls";
}

BearerTokens BearerTokens::load(const std::string& path) {
  return BearerTokens(parse_tokens_file(read_security_file(path, "--tokens-file"), path));
}

BearerTokens::BearerTokens(std::vector<AcceptedToken> tokens) : tokens_(std::move(tokens)) {}

bool listens_on_loopback_only(const std::string& listen) {
  if (listen.rfind("unix:", 0) == 0 || listen.rfind("unix-abstract:", 0) == 0) return true;
  const std::size_t colon = listen.rfind(':');
  std::string host = colon == std::string::npos ? listen : listen.substr(0, colon);
  if (host.size() >= 2 && host.front() == '[' && host.back() == ']') host = host.substr(1, host.size() - 2);
  if (host == "localhost") return true;
  in_addr v4{};
  if (::inet_pton(AF_INET, host.c_str(), &v4) == 1) return (ntohl(v4.s_addr) >> 24) == 127;
  in6_addr v6{};
  if (::inet_pton(AF_INET6, host.c_str(), &v6) == 1) {
    if (IN6_IS_ADDR_LOOPBACK(&v6)) return true;
    return IN6_IS_ADDR_V4MAPPED(&v6) && v6.s6_addr[12] == 127;
  }
  return false;
}

bool BearerTokens::names_tenants() const {
  return std::any_of(tokens_.begin(), tokens_.end(), [](const AcceptedToken& t) { return !t.tenant.empty(); });
}

std::vector<std::string> BearerTokens::tenants() const {
  std::vector<std::string> names;
  for (const AcceptedToken& accepted : tokens_) {
    if (std::find(names.begin(), names.end(), accepted.tenant) == names.end()) names.push_back(accepted.tenant);
  }
  return names;
}

std::optional<std::string> BearerTokens::tenant_of(std::string_view token) const {
  const AcceptedToken* match = nullptr;
  for (const AcceptedToken& candidate : tokens_) {
    const bool equal = equal_constant_time(token, candidate.token);  // no early exit
    if (equal && !match) match = &candidate;
  }
  if (!match) return std::nullopt;
  return match->tenant;
}

grpc::Status BearerTokens::check(const grpc::CallbackServerContext& context, std::string& tenant) const {
  const auto& metadata = context.client_metadata();
  const auto found = metadata.find("authorization");
  if (found == metadata.end()) return unauthenticated("no bearer token");
  const std::string_view value(found->second.data(), found->second.size());
  constexpr std::string_view kScheme = "Bearer ";
  if (value.substr(0, kScheme.size()) != kScheme) {
    return unauthenticated("authorization metadata is not of the form 'Bearer <token>'");
  }
  std::optional<std::string> owner = tenant_of(value.substr(kScheme.size()));
  if (!owner) return unauthenticated("bearer token not accepted");
  tenant = std::move(*owner);
  return grpc::Status::OK;
}

grpc::Status authenticate_call(const BearerTokens* tokens, const grpc::CallbackServerContext& context, const char* call,
                               std::string& tenant) {
  tenant.clear();
  if (!tokens) return grpc::Status::OK;
  grpc::Status status = tokens->check(context, tenant);
  if (!status.ok()) {
    log_event("info", "call_unauthenticated", {{"call", call}, {"peer", context.peer()}});
  }
  return status;
}

}  // namespace posefuse::server
