// The server's own files: the config file (server/server_config.*, read through a memfd's
// /proc path as from disk) and the tokens file's text (server/tokens_file.*). Each either
// applies or throws posefuse::Error; an accepted token is at least kMinTokenLength visible
// ASCII characters, and no error message holds a line of the tokens file that the parser took
// as a token (the messages name the line, never the token).
#include <cstddef>
#include <cstdint>
#include <string>

#include "common/error.hpp"
#include "seeds.hpp"
#include "server/server_config.hpp"
#include "server/tokens_file.hpp"
#include "session/recording_file.hpp"

using namespace posefuse;

namespace {
// The fixed words of the tokens file's messages: a line's first word that is part of them is
// not a token leaking into a message.
const std::string kMessageText =
    "--tokens-file: 'tokens' line : the tenant after the token must match [A-Za-z0-9_.-]{1,64} and not be '.' or "
    "'..' a token may hold only visible ASCII characters, no spaces token shorter than characters (make one with: "
    "openssl rand -hex 32) holds no tokens";
}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  fuzz::init_harness([] {
    return fuzz::Seeds{{"server.conf",
                        "# posefuse-server\nlisten = 127.0.0.1:50051\nworkers = 4\nmax-sessions = 8\n"
                        "tenant-max-sessions = 2\nmax-message-mb = 16.5\nidle-timeout-s = 30\nmin-stream-rate = 0.5\n"
                        "data-dir = /var/lib/posefuse data\ninsecure = false\njob-store = sqlite\n"},
                       {"tokens",
                        "# clinic tokens\n0123456789abcdef0123456789abcdef clinic-a\n\n"
                        "  fedcba9876543210fedcba9876543210\tclinic.b  \nzyxwvutsrqponmlkjihg\n"}};
  });
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    session::UniqueFd file(fuzz::memory_file(data, size));
    server::ServerOptions options;
    server::load_server_config("/proc/self/fd/" + std::to_string(file.get()), options);
  } catch (const Error&) {
  }
  try {
    for (const server::AcceptedToken& accepted : server::parse_tokens_file(text, "tokens")) {
      if (accepted.token.size() < server::kMinTokenLength) fuzz::invariant_failed("short token accepted");
      for (const unsigned char c : accepted.token) {
        if (c < 0x21 || c > 0x7e) fuzz::invariant_failed("token with a character metadata cannot carry");
      }
    }
  } catch (const Error& error) {
    // Every candidate token (a line's first word) long enough to be one must stay out of the message.
    std::size_t start = 0;
    while (start < text.size()) {
      std::size_t end = text.find('\n', start);
      if (end == std::string::npos) end = text.size();
      const std::string line = text.substr(start, end - start);
      const std::size_t first = line.find_first_not_of(" \t\r");
      if (first != std::string::npos && line[first] != '#') {
        const std::string word = line.substr(first, line.find_first_of(" \t\r", first) - first);
        if (word.size() >= server::kMinTokenLength && kMessageText.find(word) == std::string::npos &&
            std::string(error.what()).find(word) != std::string::npos) {
          fuzz::invariant_failed("a token in an error message");
        }
      }
      start = end + 1;
    }
  }
  return 0;
}
