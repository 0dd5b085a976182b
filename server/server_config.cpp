#include "server/server_config.hpp"

#include <map>

#include "common/error.hpp"
#include "server/text_lines.hpp"
#include "session/file_bytes.hpp"
#include "session/text_fields.hpp"

namespace posefuse::server {

namespace {

unsigned parse_count(const std::string& text, const std::string& field) {
  const std::uint64_t value = session::parse_uint64(text, field);
  if (value > 1'000'000) throw_invalid(field, "is too large");
  return static_cast<unsigned>(value);
}

bool parse_switch(const std::string& text, const std::string& field) {
  if (text == "true") return true;
  if (text == "false") return false;
  throw_invalid(field, "is '" + text + "'; expected true or false");
}

}  // namespace

void set_server_option(ServerOptions& o, const std::string& key, const std::string& value, const std::string& field) {
  auto number = [&] { return session::parse_double(value, field); };
  auto count = [&] { return parse_count(value, field); };
  if (key == "listen") o.listen = value;
  else if (key == "workers") o.workers = count();
  else if (key == "max-sessions") o.max_sessions = count();
  else if (key == "tenant-max-sessions") o.tenant_max_sessions = count();
  else if (key == "max-message-mb") o.max_message_mb = number();
  else if (key == "idle-timeout-s") o.idle_timeout_s = number();
  else if (key == "min-stream-rate") o.min_stream_rate = number();
  else if (key == "stream-rate-grace-s") o.stream_rate_grace_s = number();
  else if (key == "max-queued-chunks") o.max_queued_chunks = count();
  else if (key == "max-session-memory-mb") o.max_session_memory_mb = number();
  else if (key == "shutdown-grace-s") o.shutdown_grace_s = number();
  else if (key == "data-dir") o.data_dir = value;
  else if (key == "recordings-root") o.recordings_root = value;
  else if (key == "max-jobs") o.max_jobs = count();
  else if (key == "job-store") o.job_store = value;
  else if (key == "role") o.role = value;
  else if (key == "job-lease-s") o.job_lease_s = number();
  else if (key == "job-heartbeat-s") o.job_heartbeat_s = number();
  else if (key == "job-max-attempts") o.job_max_attempts = count();
  else if (key == "job-deadline-s") o.job_deadline_s = number();
  else if (key == "job-stall-s") o.job_stall_s = number();
  else if (key == "max-upload-mb") o.max_upload_mb = number();
  else if (key == "max-spool-mb") o.max_spool_mb = number();
  else if (key == "metrics-listen") o.metrics_listen = value;
  else if (key == "tls-cert") o.tls_cert = value;
  else if (key == "tls-key") o.tls_key = value;
  else if (key == "tls-client-ca") o.tls_client_ca = value;
  else if (key == "tokens-file") o.tokens_file = value;
  else if (key == "insecure") o.insecure = parse_switch(value, field);
  else
    throw_invalid(
        field, "unknown " + std::string(field.rfind("--", 0) == 0 ? "flag" : "key") + " (see posefuse-server --help)");
}

void load_server_config(const std::filesystem::path& path, ServerOptions& options) {
  const std::string text = session::read_file_bytes(path, "--config");
  std::map<std::string, int> first_line;  // key -> line it was set on
  for (const TextLine& line : meaningful_lines(text)) {
    const std::string where = "'" + path.string() + "' line " + std::to_string(line.number);
    const auto eq = line.text.find('=');
    if (eq == std::string::npos) {
      throw_invalid("--config", where + ": expected 'key = value'");
    }
    const std::string key = trim_whitespace(line.text.substr(0, eq));
    const std::string value = trim_whitespace(line.text.substr(eq + 1));
    if (key.empty()) throw_invalid("--config", where + ": no key before '='");
    if (key.rfind("--", 0) == 0) {
      throw_invalid("--config", where + ": write the key without '--' ('" + key.substr(2) + "')");
    }
    if (key == "config") throw_invalid("--config", where + ": a config file cannot name another");
    if (const auto [it, inserted] = first_line.emplace(key, line.number); !inserted) {
      throw_invalid("--config",
                    where + ": '" + key + "' is set again (first on line " + std::to_string(it->second) + ")");
    }
    try {
      set_server_option(options, key, value, key);
    } catch (const Error& error) {
      // The key's own error (unknown key, bad value), with the place it came from.
      throw_invalid("--config", where + ": " + error.what());
    }
  }
}

CommandLine parse_server_command_line(const std::vector<std::string>& arguments) {
  // (flag, value) in command-line order; --config is taken out and applied first.
  std::vector<std::pair<std::string, std::string>> flags;
  CommandLine line;
  for (std::size_t i = 0; i < arguments.size(); ++i) {
    std::string flag = arguments[i];
    std::string value;
    if (flag == "--help" || flag == "-h") {
      line.help = true;
      return line;
    }
    if (flag.rfind("--", 0) != 0) throw_invalid(flag, "unexpected argument (flags start with --)");
    if (const auto eq = flag.find('='); eq != std::string::npos) {
      value = flag.substr(eq + 1);
      flag.resize(eq);
    } else if (flag == "--insecure") {
      value = "true";  // a switch: the next argument is another flag
    } else if (i + 1 < arguments.size()) {
      value = arguments[++i];
    } else {
      throw_invalid(flag, "needs a value");
    }
    if (flag == "--config") {
      if (!line.config_file.empty()) throw_invalid(flag, "given twice");
      line.config_file = value;
    } else {
      flags.emplace_back(std::move(flag), std::move(value));
    }
  }
  if (!line.config_file.empty()) load_server_config(line.config_file, line.options);
  for (const auto& [flag, value] : flags) set_server_option(line.options, flag.substr(2), value, flag);
  return line;
}

}  // namespace posefuse::server
