#pragma once
// How the client reaches a secured posefuse-server (docs/server.md "Security"): TLS that
// verifies the server against a CA file, an optional client certificate for mutual TLS, and a
// bearer token sent as `authorization: Bearer <token>` metadata on every call.
#include <string>

namespace posefuse::client {

struct ChannelSecurity {
  std::string ca_pem;           // empty: plaintext (unless a client certificate is given)
  std::string cert_chain_pem;   // client certificate, for mutual TLS
  std::string private_key_pem;  // its key
  std::string bearer_token;     // empty: none sent

  bool tls() const { return !ca_pem.empty() || !cert_chain_pem.empty(); }
};

// Builds it from the client's options. Empty paths are not given. The token comes from
// `token_file` (the first line that is neither blank nor a '#' comment, trimmed) or else from
// `token_env` (the value of POSEFUSE_TOKEN; may be null). Throws posefuse::Error naming the
// option ("--tls-ca", ...) for an unreadable or empty file, or a certificate without a key.
ChannelSecurity load_channel_security(const std::string& ca_file, const std::string& cert_file,
                                      const std::string& key_file, const std::string& token_file,
                                      const char* token_env);

}  // namespace posefuse::client
