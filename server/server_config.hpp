#pragma once
// posefuse-server's configuration from its command line and an optional config file
// (docs/server.md "Config file").
//
// The config file holds `key = value` lines with the same keys as the flags, without the
// leading "--" (`max-sessions = 4`); blank lines and lines starting with '#' are ignored;
// whitespace around key and value is trimmed; the value is the rest of the line (no quoting, no
// inline comments, so paths may hold '#' and spaces). A key may appear once. The file is read
// first and flags override it, wherever --config stands on the command line.
#include <filesystem>
#include <string>
#include <vector>

#include "server/server_options.hpp"

namespace posefuse::server {

// Sets the option called `key` (a flag name without "--", e.g. "max-sessions") from `value`.
// Throws posefuse::Error (kInvalidArgument) with `field` for a value that does not parse, and
// for an unknown key.
void set_server_option(ServerOptions& options, const std::string& key, const std::string& value,
                       const std::string& field);

// Applies a config file to `options`. Errors name the file and line: "'FILE' line 7: ...".
void load_server_config(const std::filesystem::path& path, ServerOptions& options);

struct CommandLine {
  ServerOptions options;
  bool help = false;        // --help or -h: print the usage and exit
  std::string config_file;  // empty without --config
};

// `arguments` without the program name. "--flag value" and "--flag=value" both work.
CommandLine parse_server_command_line(const std::vector<std::string>& arguments);

}  // namespace posefuse::server
