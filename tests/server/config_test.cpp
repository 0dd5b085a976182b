// posefuse-server's command line and config file (server_config.hpp), and the structured log
// line format (log.hpp).
#include <cctype>
#include <fstream>

#include <gtest/gtest.h>

#include "common/error.hpp"
#include "server/log.hpp"
#include "server/server_config.hpp"
#include "tests/server/test_support.hpp"

namespace posefuse::server {
namespace {

class ConfigTest : public ::testing::Test {
 protected:
  std::string write_config(const std::string& text) {
    const auto path = temp_.path() / "server.conf";
    std::ofstream(path) << text;
    return path.string();
  }
  // The message of the posefuse::Error that parsing `arguments` throws ("" if none).
  static std::string error_of(const std::vector<std::string>& arguments) {
    try {
      parse_server_command_line(arguments);
    } catch (const Error& error) {
      return error.what();
    }
    return "";
  }
  test::TempDir temp_;
};

TEST_F(ConfigTest, FileSetsEveryKindOfOptionAndFlagsOverrideItWhereverConfigStands) {
  const std::string path = write_config(
      "# posefuse-server settings\n"
      "\n"
      "listen = 0.0.0.0:6000\n"
      "  workers=3  \n"
      "max-message-mb = 2.5\n"
      "data-dir = /var/lib/posefuse data # not a comment\n"
      "max-upload-mb = 100\n"
      "max-spool-mb = 300\n"
      "tenant-max-sessions = 3\n"
      "insecure = true\n");
  const CommandLine line = parse_server_command_line({"--workers", "5", "--config", path, "--listen=127.0.0.1:7000"});
  EXPECT_FALSE(line.help);
  EXPECT_EQ(line.config_file, path);
  EXPECT_EQ(line.options.listen, "127.0.0.1:7000");  // flag after --config
  EXPECT_EQ(line.options.workers, 5u);               // flag before --config
  EXPECT_DOUBLE_EQ(line.options.max_message_mb, 2.5);
  EXPECT_EQ(line.options.data_dir, "/var/lib/posefuse data # not a comment");
  EXPECT_DOUBLE_EQ(line.options.max_upload_mb, 100.0);
  EXPECT_DOUBLE_EQ(line.options.max_spool_mb, 300.0);
  EXPECT_EQ(line.options.tenant_max_sessions, 3u);
  EXPECT_TRUE(line.options.insecure);
  EXPECT_EQ(line.options.max_sessions, ServerOptions{}.max_sessions);  // untouched default
}

TEST_F(ConfigTest, JobStoreRoleAndLeaseKeys) {
  const std::string path = write_config(
      "job-store = host=/run/postgresql dbname=posefuse\n"
      "role = worker\n"
      "job-lease-s = 12.5\n"
      "job-stall-s = 60\n");
  const CommandLine line = parse_server_command_line(
      {"--config", path, "--job-heartbeat-s", "2", "--job-max-attempts=5", "--job-deadline-s", "7200"});
  EXPECT_EQ(line.options.job_store, "host=/run/postgresql dbname=posefuse");
  EXPECT_EQ(line.options.role, "worker");
  EXPECT_DOUBLE_EQ(line.options.job_lease_s, 12.5);
  EXPECT_DOUBLE_EQ(line.options.job_heartbeat_s, 2.0);
  EXPECT_EQ(line.options.job_max_attempts, 5u);
  EXPECT_DOUBLE_EQ(line.options.job_deadline_s, 7200.0);
  EXPECT_DOUBLE_EQ(line.options.job_stall_s, 60.0);
}

TEST_F(ConfigTest, StreamRateKeys) {
  const std::string path = write_config("min-stream-rate = 0\n");
  const CommandLine line = parse_server_command_line({"--config", path, "--stream-rate-grace-s=5"});
  EXPECT_DOUBLE_EQ(line.options.min_stream_rate, 0.0);
  EXPECT_DOUBLE_EQ(line.options.stream_rate_grace_s, 5.0);
}

TEST_F(ConfigTest, UnknownKeyIsAnErrorNamingTheFileAndLine) {
  const std::string path = write_config("workers = 2\n\nmax_sessions = 4\n");
  const std::string message = error_of({"--config", path});
  EXPECT_EQ(message.rfind("--config: '" + path + "' line 3: max_sessions: unknown key", 0), 0u) << message;
}

TEST_F(ConfigTest, BadLinesAreErrorsNamingTheLine) {
  EXPECT_NE(error_of({"--config", write_config("workers = many\n")}).find("line 1: workers: "), std::string::npos);
  EXPECT_NE(error_of({"--config", write_config("workers 2\n")}).find("line 1: expected 'key = value'"),
            std::string::npos);
  EXPECT_NE(error_of({"--config", write_config("workers = 1\nworkers = 2\n")})
                .find("line 2: 'workers' is set again (first on line 1)"),
            std::string::npos);
  EXPECT_NE(error_of({"--config", write_config("--workers = 2\n")}).find("without '--'"), std::string::npos);
  EXPECT_NE(error_of({"--config", write_config("config = other.conf\n")}).find("cannot name another"),
            std::string::npos);
  EXPECT_EQ(error_of({"--config", (temp_.path() / "missing.conf").string()}).rfind("--config", 0), 0u);
}

TEST_F(ConfigTest, FlagErrorsNameTheFlag) {
  EXPECT_EQ(error_of({"--max-sessions", "x"}).rfind("--max-sessions: ", 0), 0u);
  EXPECT_EQ(error_of({"--nope", "1"}).rfind("--nope: unknown flag", 0), 0u);
  EXPECT_EQ(error_of({"--workers"}).rfind("--workers: needs a value", 0), 0u);
  EXPECT_EQ(error_of({"stray"}).rfind("stray: unexpected argument", 0), 0u);
  EXPECT_TRUE(parse_server_command_line({"--help"}).help);
  // --insecure is a switch: the next flag stays a flag.
  const CommandLine line = parse_server_command_line({"--insecure", "--workers", "2"});
  EXPECT_TRUE(line.options.insecure);
  EXPECT_EQ(line.options.workers, 2u);
  EXPECT_FALSE(parse_server_command_line({"--insecure=false"}).options.insecure);
  EXPECT_EQ(error_of({"--insecure=yes"}).rfind("--insecure: is 'yes'; expected true or false", 0), 0u);
}

TEST(StructuredLog, OneLinePerEventWithQuotedValues) {
  ::testing::internal::CaptureStderr();
  log_event("info", "upload_end", {{"job", "abc"}, {"note", "two words \"quoted\"\nnext"}});
  const std::string text = ::testing::internal::GetCapturedStderr();
  // time=<UTC, milliseconds> then the fields in order; the value with spaces, quotes and a
  // newline quoted and escaped, still one line.
  const std::string pattern = "dddd-dd-ddTdd:dd:dd.dddZ";
  ASSERT_GT(text.size(), 5 + pattern.size()) << text;
  EXPECT_EQ(text.substr(0, 5), "time=");
  for (std::size_t i = 0; i < pattern.size(); ++i) {
    const char c = text[5 + i];
    EXPECT_TRUE(pattern[i] == 'd' ? std::isdigit(static_cast<unsigned char>(c)) != 0 : c == pattern[i]) << text;
  }
  EXPECT_EQ(text.substr(5 + pattern.size()),
            " level=info event=upload_end job=abc note=\"two words \\\"quoted\\\" next\"\n");
}

}  // namespace
}  // namespace posefuse::server
