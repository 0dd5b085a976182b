#include "client/channel_security.hpp"

#include <sstream>

#include "common/error.hpp"
#include "session/file_bytes.hpp"

namespace posefuse::client {

namespace {

std::string read_option_file(const std::string& path, const std::string& option) {
  if (path.empty()) return {};
  std::string text = session::read_file_bytes(path, option);
  if (text.empty()) throw_invalid(option, "'" + path + "' is empty");
  return text;
}

std::string first_token(const std::string& text, const std::string& path) {
  std::istringstream lines(text);
  std::string line;
  while (std::getline(lines, line)) {
    const auto first = line.find_first_not_of(" \t\r");
    if (first == std::string::npos || line[first] == '#') continue;
    const auto last = line.find_last_not_of(" \t\r");
    return line.substr(first, last - first + 1);
  }
  throw_invalid("--token-file", "'" + path + "' holds no token");
}

}  // namespace

ChannelSecurity load_channel_security(const std::string& ca_file, const std::string& cert_file,
                                      const std::string& key_file, const std::string& token_file,
                                      const char* token_env) {
  if (cert_file.empty() != key_file.empty()) {
    throw_invalid(cert_file.empty() ? "--tls-cert" : "--tls-key", "is missing: --tls-cert and --tls-key go together");
  }
  ChannelSecurity security;
  security.ca_pem = read_option_file(ca_file, "--tls-ca");
  security.cert_chain_pem = read_option_file(cert_file, "--tls-cert");
  security.private_key_pem = read_option_file(key_file, "--tls-key");
  if (!token_file.empty()) {
    security.bearer_token = first_token(read_option_file(token_file, "--token-file"), token_file);
  } else if (token_env != nullptr) {
    security.bearer_token = token_env;
  }
  return security;
}

}  // namespace posefuse::client
