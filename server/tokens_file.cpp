#include "server/tokens_file.hpp"

#include "common/error.hpp"
#include "server/text_lines.hpp"

namespace posefuse::server {

namespace {

// Visible ASCII only: what a metadata value may carry and a file editor shows plainly.
bool valid_token_characters(const std::string& token) {
  for (const unsigned char c : token) {
    if (c < 0x21 || c > 0x7e) return false;
  }
  return true;
}

// A tenant names who owns jobs and its folder of the recordings root: a plain name that is safe
// in logs and as one path component.
bool valid_tenant(const std::string& tenant) {
  if (tenant.empty() || tenant.size() > 64 || tenant == "." || tenant == "..") return false;
  for (const char c : tenant) {
    const bool ok =
        (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' || c == '.' || c == '-';
    if (!ok) return false;
  }
  return true;
}

}  // namespace

std::vector<AcceptedToken> parse_tokens_file(const std::string& text, const std::string& path) {
  const std::string flag = "--tokens-file";
  std::vector<AcceptedToken> tokens;
  for (const TextLine& line : meaningful_lines(text)) {
    // "<token>" or "<token> <tenant>".
    const std::size_t gap = line.text.find_first_of(" \t");
    const std::string token = line.text.substr(0, gap);
    const std::string tenant = gap == std::string::npos ? std::string() : trim_whitespace(line.text.substr(gap));
    // The messages name the line, never the token.
    const std::string where = "'" + path + "' line " + std::to_string(line.number);
    if (gap != std::string::npos && !valid_tenant(tenant)) {
      throw_invalid(flag,
                    where + ": the tenant after the token must match [A-Za-z0-9_.-]{1,64} and not be '.' or '..'");
    }
    if (!valid_token_characters(token)) {
      throw_invalid(flag, where + ": a token may hold only visible ASCII characters, no spaces");
    }
    if (token.size() < kMinTokenLength) {
      throw_invalid(flag, where + ": token shorter than " + std::to_string(kMinTokenLength) +
                              " characters (make one with: openssl rand -hex 32)");
    }
    tokens.push_back({token, tenant});
  }
  if (tokens.empty()) throw_invalid(flag, "'" + path + "' holds no tokens");
  return tokens;
}

}  // namespace posefuse::server
