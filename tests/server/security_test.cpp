// TLS, mutual TLS and bearer tokens (docs/server.md "Security"), against posefuse-server in
// process on 127.0.0.1:0. The certificates are made at run time with the openssl command line:
// a test CA, a server certificate for 127.0.0.1, a client certificate, and an unrelated CA.
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include <gtest/gtest.h>

#include "client/channel_security.hpp"
#include "client/demo_session.hpp"
#include "client/fit_call.hpp"
#include "posefuse/v1/service.grpc.pb.h"
#include "server/posefuse_server.hpp"
#include "server/security.hpp"
#include "session/file_bytes.hpp"
#include "tests/server/health_check.hpp"
#include "tests/server/reflection_call.hpp"
#include "tests/server/server_process.hpp"
#include "tests/server/test_support.hpp"

namespace posefuse::server {
namespace {

namespace fs = std::filesystem;
using test::set_test_deadline;

constexpr const char* kToken = "0123456789abcdef0123456789abcdef";
constexpr const char* kOtherToken = "fedcba9876543210fedcba9876543210";

// The certificate files, made once for the whole test binary and removed at exit.
class Certificates {
 public:
  Certificates() : dir_(fs::temp_directory_path() / ("posefuse_tls_" + std::to_string(::getpid()))) {
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    ok_ = make_ca("ca") && make_ca("other_ca") &&
          make_leaf("server", "ca",
                    "subjectAltName=IP:127.0.0.1,DNS:localhost\n"
                    "extendedKeyUsage=serverAuth\n") &&
          make_leaf("client", "ca", "extendedKeyUsage=clientAuth\n");
  }
  ~Certificates() { fs::remove_all(dir_); }

  bool ok() const { return ok_; }
  std::string file(const std::string& name) const { return (dir_ / name).string(); }
  std::string pem(const std::string& name) const { return session::read_file_bytes(file(name), name); }

 private:
  bool run(const std::string& command) const {
    return std::system((command + " >" + file("openssl.log") + " 2>&1").c_str()) == 0;
  }
  bool make_ca(const std::string& name) const {
    return run(
        "openssl req -x509 -newkey ec -pkeyopt ec_paramgen_curve:prime256v1 -nodes"
        " -days 2 -subj /CN=posefuse-test-" +
        name + " -keyout " + file(name + ".key") + " -out " + file(name + ".crt"));
  }
  bool make_leaf(const std::string& name, const std::string& ca, const std::string& ext) const {
    std::ofstream(file(name + ".ext")) << ext;
    return run("openssl req -new -newkey ec -pkeyopt ec_paramgen_curve:prime256v1 -nodes"
               " -subj /CN=posefuse-test-" +
               name + " -keyout " + file(name + ".key") + " -out " + file(name + ".csr")) &&
           run("openssl x509 -req -days 2 -in " + file(name + ".csr") + " -CA " + file(ca + ".crt") + " -CAkey " +
               file(ca + ".key") + " -CAcreateserial -out " + file(name + ".crt") + " -extfile " + file(name + ".ext"));
  }

  fs::path dir_;
  bool ok_ = false;
};

const Certificates& certificates() {
  static const Certificates made;
  return made;
}

class SecurityTest : public ::testing::Test {
 protected:
  void SetUp() override { ASSERT_TRUE(certificates().ok()) << "openssl failed to make the test certificates"; }

  void start(ServerOptions options) {
    options.listen = "127.0.0.1:0";
    options.workers = 2;
    server_ = std::make_unique<PoseFuseServer>(options);
    address_ = "127.0.0.1:" + std::to_string(server_->port());
  }
  ServerOptions tls_options() const {
    ServerOptions options;
    options.tls_cert = certificates().file("server.crt");
    options.tls_key = certificates().file("server.key");
    return options;
  }
  ServerOptions token_options() {
    std::ofstream(dir_.path() / "tokens") << "# clinic A\n" << kToken << "\n\n  # old\n";
    ServerOptions options;
    options.tokens_file = (dir_.path() / "tokens").string();
    return options;
  }
  client::ChannelSecurity trusting(const std::string& ca) const {
    client::ChannelSecurity security;
    security.ca_pem = certificates().pem(ca + ".crt");
    return security;
  }
  client::ChannelSecurity with_token(const std::string& token) const {
    client::ChannelSecurity security;
    security.bearer_token = token;
    return security;
  }

  grpc::Status server_info(const client::ChannelSecurity& security) {
    auto stub = v1::PoseFuse::NewStub(client::make_channel(address_, security));
    grpc::ClientContext context;
    set_test_deadline(context);
    v1::ServerInfo info;
    return stub->GetServerInfo(&context, {}, &info);
  }

  test::TempDir dir_;
  std::unique_ptr<PoseFuseServer> server_;
  std::string address_;
};

TEST_F(SecurityTest, TlsFitWithTheServersCaWritesEveryResult) {
  start(tls_options());
  const fs::path recording = dir_.path() / "demo.pfchunks";
  demo::write_demo_session(recording);
  client::ResultWriter writer(dir_.path() / "out");
  const client::FitOutcome outcome = client::run_fit(client::make_channel(address_, trusting("ca")), recording, writer);
  ASSERT_FALSE(outcome.local_error) << outcome.local_error->what();
  ASSERT_TRUE(outcome.status.ok()) << outcome.status.error_message();
  EXPECT_EQ(writer.orientation_samples(), 1600u);  // 800 per IMU in the demo session
  ASSERT_NE(writer.summary(), nullptr);
  EXPECT_EQ(writer.summary()->depth_frames(), 300u);
}

TEST_F(SecurityTest, ClientTrustingAnotherCaFailsTheHandshake) {
  start(tls_options());
  const grpc::Status status = server_info(trusting("other_ca"));
  EXPECT_EQ(status.error_code(), grpc::StatusCode::UNAVAILABLE) << status.error_message();
  EXPECT_EQ(client::status_line(status, address_).rfind("TLS handshake with the server at", 0), 0u)
      << client::status_line(status, address_);
}

TEST_F(SecurityTest, PlaintextClientCannotCallATlsServer) {
  start(tls_options());
  const grpc::Status status = server_info({});
  EXPECT_EQ(status.error_code(), grpc::StatusCode::UNAVAILABLE) << status.error_message();
}

TEST_F(SecurityTest, MutualTlsRejectsAClientWithoutCertificate) {
  ServerOptions options = tls_options();
  options.tls_client_ca = certificates().file("ca.crt");
  start(options);
  const grpc::Status status = server_info(trusting("ca"));
  EXPECT_EQ(status.error_code(), grpc::StatusCode::UNAVAILABLE) << status.error_message();
}

TEST_F(SecurityTest, MutualTlsAcceptsAClientWithCertificate) {
  ServerOptions options = tls_options();
  options.tls_client_ca = certificates().file("ca.crt");
  start(options);
  client::ChannelSecurity security = trusting("ca");
  security.cert_chain_pem = certificates().pem("client.crt");
  security.private_key_pem = certificates().pem("client.key");
  const grpc::Status status = server_info(security);
  EXPECT_TRUE(status.ok()) << status.error_message();
}

TEST_F(SecurityTest, CallWithoutTokenIsUnauthenticated) {
  start(token_options());
  const grpc::Status status = server_info({});
  EXPECT_EQ(status.error_code(), grpc::StatusCode::UNAUTHENTICATED);
  EXPECT_NE(status.error_message().find("no bearer token"), std::string::npos) << status.error_message();
  EXPECT_NE(client::status_line(status, address_).find("--token-file"), std::string::npos);
}

TEST_F(SecurityTest, CallWithWrongTokenIsUnauthenticated) {
  start(token_options());
  const grpc::Status status = server_info(with_token(kOtherToken));
  EXPECT_EQ(status.error_code(), grpc::StatusCode::UNAUTHENTICATED);
  EXPECT_EQ(status.error_message().find(kOtherToken), std::string::npos);  // never echoed
}

TEST_F(SecurityTest, CallWithRightTokenIsOk) {
  start(token_options());
  const grpc::Status status = server_info(with_token(kToken));
  EXPECT_TRUE(status.ok()) << status.error_message();
}

TEST_F(SecurityTest, FitAndJobCallsWithoutTokenAreUnauthenticated) {
  start(token_options());
  auto stub = v1::PoseFuse::NewStub(client::make_channel(address_));
  {
    grpc::ClientContext context;
    set_test_deadline(context);
    auto stream = stub->Fit(&context);
    stream->WritesDone();
    v1::FitResult result;
    EXPECT_FALSE(stream->Read(&result));
    EXPECT_EQ(stream->Finish().error_code(), grpc::StatusCode::UNAUTHENTICATED);
  }
  {
    grpc::ClientContext context;
    set_test_deadline(context);
    v1::ListJobsResponse response;
    EXPECT_EQ(stub->ListJobs(&context, {}, &response).error_code(), grpc::StatusCode::UNAUTHENTICATED);
  }
  {
    grpc::ClientContext context;
    set_test_deadline(context);
    v1::WatchJobRequest request;
    request.set_job_id("1");
    auto reader = stub->WatchJob(&context, request);
    v1::Job job;
    EXPECT_FALSE(reader->Read(&job));
    EXPECT_EQ(reader->Finish().error_code(), grpc::StatusCode::UNAUTHENTICATED);
  }
}

TEST_F(SecurityTest, HealthNeedsNoToken) {
  ServerOptions options = token_options();
  options.tls_cert = certificates().file("server.crt");
  options.tls_key = certificates().file("server.key");
  start(options);
  grpc::health::v1::HealthCheckResponse response;
  const grpc::Status status = test::check_health(client::make_channel(address_, trusting("ca")), &response);
  ASSERT_TRUE(status.ok()) << status.error_message();
  EXPECT_EQ(response.status(), grpc::health::v1::HealthCheckResponse::SERVING);
}

TEST_F(SecurityTest, ReflectionNeedsTheToken) {
  start(token_options());
  grpc::reflection::v1alpha::ServerReflectionRequest request;
  request.set_list_services("*");
  grpc::reflection::v1alpha::ServerReflectionResponse response;
  grpc::Status status = test::ask_reflection(client::make_channel(address_), request, &response);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::UNAUTHENTICATED) << status.error_message();
  status = test::ask_reflection(client::make_channel(address_, with_token(kToken)), request, &response);
  ASSERT_TRUE(status.ok()) << status.error_message();
  EXPECT_EQ(response.list_services_response().service_size(), 3);
}

// The field of the posefuse::Error that starting a server with `options` throws.
std::string start_error_field(const ServerOptions& options) {
  try {
    PoseFuseServer server(options);
  } catch (const Error& error) {
    return error.field();
  }
  return "no error";
}

TEST_F(SecurityTest, BadSecurityFilesNameTheFlag) {
  const std::string missing = (dir_.path() / "missing.pem").string();
  ServerOptions options = tls_options();
  options.tls_cert = missing;
  EXPECT_EQ(start_error_field(options), "--tls-cert");
  options = tls_options();
  options.tls_key = certificates().file("server.crt");  // a certificate is not a key
  EXPECT_EQ(start_error_field(options), "--tls-key");
  options = tls_options();
  options.tls_key.clear();
  EXPECT_EQ(start_error_field(options), "--tls-key");
  options = tls_options();
  options.tls_client_ca = certificates().file("server.ext");  // not PEM
  EXPECT_EQ(start_error_field(options), "--tls-client-ca");
  options = {};
  options.tls_client_ca = certificates().file("ca.crt");  // mutual TLS needs TLS
  EXPECT_EQ(start_error_field(options), "--tls-client-ca");
  options = {};
  options.tokens_file = missing;
  EXPECT_EQ(start_error_field(options), "--tokens-file");
}

TEST_F(SecurityTest, TokensFileRejectsShortTokensAndCommentOnlyFiles) {
  const fs::path path = dir_.path() / "tokens";
  std::ofstream(path) << "# only a comment\n\n";
  EXPECT_THROW(BearerTokens::load(path.string()), Error);
  std::ofstream(path) << "short\n";
  try {
    BearerTokens::load(path.string());
    FAIL() << "no error";
  } catch (const Error& error) {
    EXPECT_EQ(error.field(), "--tokens-file");
    EXPECT_EQ(std::string(error.what()).find("short\n"), std::string::npos);
  }
  std::ofstream(path) << "# two clinics\n" << kToken << "\n  " << kOtherToken << "  \n";
  const BearerTokens tokens = BearerTokens::load(path.string());
  EXPECT_EQ(tokens.size(), 2u);
  EXPECT_TRUE(tokens.accepts(kToken));
  EXPECT_TRUE(tokens.accepts(kOtherToken));
  EXPECT_FALSE(tokens.accepts(std::string(kToken).substr(0, 31)));  // a prefix is not the token
  EXPECT_FALSE(tokens.accepts(std::string(kToken) + "0"));
  EXPECT_FALSE(tokens.accepts(""));
}

TEST_F(SecurityTest, TokensFileMapsTokensToTenants) {
  const fs::path path = dir_.path() / "tokens";
  std::ofstream(path) << kToken << "   clinic-a \n" << kOtherToken << "\n";
  const BearerTokens tokens = BearerTokens::load(path.string());
  EXPECT_EQ(tokens.tenant_of(kToken), "clinic-a");
  EXPECT_EQ(tokens.tenant_of(kOtherToken), "");  // listed without a tenant: the shared one
  EXPECT_EQ(tokens.tenant_of(std::string(kToken) + " clinic-a"), std::nullopt);
  EXPECT_TRUE(tokens.names_tenants());
  EXPECT_EQ(tokens.tenants(), (std::vector<std::string>{"clinic-a", ""}));
  // A tenant is also a folder name of the recordings root: "." and ".." are not names.
  for (const char* tenant : {"clinic a", "../clinic", "cl!nic", ".", ".."}) {
    std::ofstream(path) << kToken << " " << tenant << "\n";
    try {
      BearerTokens::load(path.string());
      ADD_FAILURE() << "accepted tenant " << tenant;
    } catch (const Error& error) {
      EXPECT_EQ(error.field(), "--tokens-file");
      EXPECT_NE(std::string(error.what()).find("line 1: the tenant"), std::string::npos) << error.what();
      EXPECT_EQ(std::string(error.what()).find(kToken), std::string::npos);  // never echoed
    }
  }
}

TEST(ListenAddress, OnlyLoopbackAddressesAndUnixSocketsStayOnThisMachine) {
  for (const char* local : {"127.0.0.1:50051", "127.1.2.3:0", "localhost:50051", "[::1]:50051", "[::ffff:127.0.0.1]:1",
                            "unix:/run/posefuse.sock", "unix-abstract:posefuse"}) {
    EXPECT_TRUE(listens_on_loopback_only(local)) << local;
  }
  for (const char* beyond : {"0.0.0.0:50051", "[::]:50051", ":50051", "10.0.0.5:50051", "128.0.0.1:1",
                             "posefuse.hospital.example:50051", "[::ffff:10.0.0.1]:1", "localhost.evil:1"}) {
    EXPECT_FALSE(listens_on_loopback_only(beyond)) << beyond;
  }
}

// The real posefuse-server executable started with --listen 0.0.0.0:0 and `flags`.
class ListenBeyondLoopback : public SecurityTest {
 protected:
  std::unique_ptr<test::ServerProcess> run_server(std::vector<std::string> flags) {
    flags.insert(flags.begin(), {"--listen", "0.0.0.0:0", "--workers", "1"});
    return std::make_unique<test::ServerProcess>(POSEFUSE_SERVER_BINARY, flags, dir_.path() / "server.log");
  }
  // Exit status 2 and one line naming the missing flags.
  void expect_refused(const std::vector<std::string>& flags, const std::string& missing) {
    const auto server = run_server(flags);
    EXPECT_EQ(server->wait_exit(), 2);
    const std::string log = server->log();
    EXPECT_EQ(log,
              "posefuse-server: --listen: '0.0.0.0:0' is not a loopback address, and serving beyond this machine "
              "needs TLS (--tls-cert, --tls-key) and tokens (--tokens-file); missing: " +
                  missing + ". Give them, or --insecure to serve without\n");
  }
  std::vector<std::string> tls_flags() const {
    return {"--tls-cert", certificates().file("server.crt"), "--tls-key", certificates().file("server.key")};
  }
  std::vector<std::string> token_flags() { return {"--tokens-file", token_options().tokens_file}; }
};

TEST_F(ListenBeyondLoopback, WithoutTlsOrTokensTheServerRefusesToStartNamingWhatIsMissing) {
  expect_refused({}, "--tls-cert/--tls-key and --tokens-file");
  expect_refused(token_flags(), "--tls-cert/--tls-key");
  expect_refused(tls_flags(), "--tokens-file");
  // The same from a config file.
  std::ofstream(dir_.path() / "server.conf") << "listen = 0.0.0.0:0\n";
  const auto server = std::make_unique<test::ServerProcess>(
      POSEFUSE_SERVER_BINARY, std::vector<std::string>{"--config", (dir_.path() / "server.conf").string()},
      dir_.path() / "server.log");
  EXPECT_EQ(server->wait_exit(), 2);
  // After the config file's own log line.
  EXPECT_NE(server->log().find(" event=config file=", 0), std::string::npos) << server->log();
  EXPECT_NE(server->log().find("\nposefuse-server: --listen: '0.0.0.0:0' is not a loopback address"), std::string::npos)
      << server->log();
}

TEST_F(ListenBeyondLoopback, WithTlsAndTokensItServes) {
  std::vector<std::string> flags = tls_flags();
  const std::vector<std::string> tokens = token_flags();
  flags.insert(flags.end(), tokens.begin(), tokens.end());
  const auto server = run_server(flags);
  address_ = "127.0.0.1:" + std::to_string(server->port());
  client::ChannelSecurity security = trusting("ca");
  security.bearer_token = kToken;
  EXPECT_TRUE(server_info(security).ok());
  EXPECT_EQ(server_info(trusting("ca")).error_code(), grpc::StatusCode::UNAUTHENTICATED);
  EXPECT_EQ(server->terminate(), 0);
}

TEST_F(ListenBeyondLoopback, InsecureServesPlaintextWithoutTokensAndSaysSo) {
  const auto server = run_server({"--insecure"});
  address_ = "127.0.0.1:" + std::to_string(server->port());
  EXPECT_TRUE(server_info({}).ok());
  EXPECT_EQ(server->terminate(), 0);
  EXPECT_NE(server->log().find(" level=warning event=insecure_listen listen=0.0.0.0:0"), std::string::npos)
      << server->log();
}

TEST(ClientSecurity, TokenComesFromTheFileElseTheEnvironment) {
  const fs::path path = fs::temp_directory_path() / ("posefuse_token_" + std::to_string(::getpid()));
  std::ofstream(path) << "# my clinic\n  " << kToken << " \n";
  EXPECT_EQ(client::load_channel_security("", "", "", path.string(), "from-env").bearer_token, kToken);
  EXPECT_EQ(client::load_channel_security("", "", "", "", "from-env").bearer_token, "from-env");
  EXPECT_EQ(client::load_channel_security("", "", "", "", nullptr).bearer_token, "");
  fs::remove(path);
  try {
    client::load_channel_security("", "cert.pem", "", "", nullptr);
    FAIL() << "no error";
  } catch (const Error& error) {
    EXPECT_EQ(error.field(), "--tls-key");
  }
}

}  // namespace
}  // namespace posefuse::server
