#pragma once
// The tokens file's text (docs/server.md "Security") parsed into accepted tokens and their
// tenants, apart from gRPC so that the parser can be fuzzed on its own (fuzz/fuzz_server_files).
#include <cstddef>
#include <string>
#include <vector>

namespace posefuse::server {

// An accepted token and the tenant it belongs to. Jobs belong to the tenant that submitted
// them and are visible to that tenant's tokens only; "" is the tenant of tokens listed without
// one (and of every call on a server without tokens).
struct AcceptedToken {
  std::string token;
  std::string tenant;
};

// Tokens this short are refused: they could be guessed.
constexpr std::size_t kMinTokenLength = 16;

// One token per line, optionally followed by whitespace and its tenant
// ([A-Za-z0-9_.-]{1,64}, not "." or ".."); blank lines and lines starting with '#' are skipped;
// surrounding whitespace is trimmed. Throws posefuse::Error (field "--tokens-file") naming
// `path` and the line, never the token, for no tokens, a token that is too short or has
// characters not allowed in metadata, or a bad tenant name.
std::vector<AcceptedToken> parse_tokens_file(const std::string& text, const std::string& path);

}  // namespace posefuse::server
