// posefuse: the reference command-line client (docs/server.md).
//   posefuse fit RECORDING --server ADDR --out DIR
//   posefuse convert IN OUT
//   posefuse health --server ADDR
//   posefuse info --server ADDR
//   posefuse demo-session OUT
//   posefuse submit RECORDING_URI [--label TEXT] | jobs | watch JOB_ID | cancel JOB_ID
//   posefuse results JOB_ID --out DIR          (all with --server ADDR)
//   posefuse export RESULTS --format trc|mot|sto|gltf [--out FILE]
//   posefuse report RESULTS [--out FILE]
// Every failure ends with one readable line on stderr and a non-zero exit status.
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <string>
#include <vector>

#include "client/demo_session.hpp"
#include "client/fit_call.hpp"
#include "client/recording.hpp"
#include "common/error.hpp"
#include "grpc/health/v1/health.grpc.pb.h"
#include "opensim/export_results.hpp"
#include "posefuse/v1/service.grpc.pb.h"
#include "report/session_report.hpp"
#include "session/convert.hpp"

namespace {

using posefuse::Error;
namespace client = posefuse::client;

constexpr const char* kUsage =
    "usage:\n"
    "  posefuse fit RECORDING --server HOST:PORT --out DIR   stream a recording, write results\n"
    "      [--option KEY=VALUE ...]        set a stage option in the recording's header for this\n"
    "                                      call (e.g. --option fit.enabled=false; posefuse info\n"
    "                                      lists them); fit and upload take it\n"
    "      [--height M]                    the subject's standing height in metres (e.g. 1.72),\n"
    "                                      replacing the recording's: the body fit takes the shape\n"
    "                                      it implies when it cannot personalise; fit and upload\n"
    "                                      take it\n"
    "  posefuse convert IN OUT             recording directory <-> chunk file (.pfchunks)\n"
    "  posefuse health --server HOST:PORT  exit 0 when the server is SERVING\n"
    "  posefuse info --server HOST:PORT    versions, stages, options and limits\n"
    "  posefuse demo-session OUT           write the synthetic demo session (a directory, or a\n"
    "                                      chunk file when OUT ends in .pfchunks)\n"
    "  posefuse export RESULTS --format trc|mot|sto|gltf [--out FILE]\n"
    "                                      OpenSim files from a result directory: joint centres as\n"
    "                                      markers (.trc), joint angles (.mot), IMU orientations for\n"
    "                                      OpenSense (.sto); or the fitted body mesh with its\n"
    "                                      skeleton animation as binary glTF 2.0 (gltf); FILE\n"
    "                                      defaults to RESULTS/markers.trc, joint_angles.mot,\n"
    "                                      imu_orientations.sto, body.glb (docs/exports.md)\n"
    "  posefuse report RESULTS [--out FILE]  one self-contained HTML report: angles over time,\n"
    "                                      range of motion per repetition, warnings, calibration\n"
    "                                      (default FILE: RESULTS/report.html; docs/report.md)\n"
    "batch jobs (server started with --data-dir):\n"
    "  posefuse submit RECORDING_URI [--label TEXT]  a recording under the server's\n"
    "                                      --recordings-root; prints the job id\n"
    "  posefuse upload RECORDING [--label TEXT] [--option KEY=VALUE ...] [--height M]\n"
    "                                      stream a local recording into the server's\n"
    "                                      job store; prints the job id\n"
    "  posefuse jobs                       list jobs, newest first\n"
    "  posefuse watch JOB_ID               follow a job until it has finished\n"
    "  posefuse cancel JOB_ID              cancel a queued or running job\n"
    "  posefuse results JOB_ID --out DIR   write a finished job's results like fit does\n"
    "RECORDING is a recording directory or a chunk file. --server defaults to 127.0.0.1:50051.\n"
    "security (every command that talks to the server; docs/server.md \"Security\"):\n"
    "  --tls-ca FILE                       TLS, verifying the server against this CA (PEM)\n"
    "  --tls-cert FILE --tls-key FILE      client certificate and key for mutual TLS\n"
    "  --token-file FILE                   bearer token (else the POSEFUSE_TOKEN variable)\n";

constexpr int kExitUsage = 2;

// Positional arguments and --flag values of one command.
struct Arguments {
  std::vector<std::string> positional;
  std::map<std::string, std::string> flags;
  std::map<std::string, std::string> header_options;  // --option KEY=VALUE; a later same KEY wins

  std::string flag(const std::string& name, const std::string& fallback) const {
    const auto it = flags.find(name);
    return it == flags.end() ? fallback : it->second;
  }
};

Arguments parse_arguments(int argc, char** argv, int first) {
  Arguments args;
  for (int i = first; i < argc; ++i) {
    std::string text = argv[i];
    if (text.rfind("--", 0) != 0) {
      args.positional.push_back(text);
      continue;
    }
    if (text == "--option" || text.rfind("--option=", 0) == 0) {  // repeatable: one stage option each
      if (text == "--option" && i + 1 >= argc)
        throw posefuse::Error(posefuse::ErrorCode::kInvalidArgument, text, "needs KEY=VALUE");
      const auto [key, value] = client::parse_header_option(text == "--option" ? argv[++i] : text.substr(9));
      args.header_options[key] = value;
    } else if (const auto eq = text.find('='); eq != std::string::npos) {
      args.flags[text.substr(0, eq)] = text.substr(eq + 1);
    } else if (i + 1 < argc) {
      args.flags[text] = argv[++i];
    } else {
      throw posefuse::Error(posefuse::ErrorCode::kInvalidArgument, text, "needs a value");
    }
  }
  return args;
}

void require(bool ok, const std::string& what) {
  if (!ok) throw Error(posefuse::ErrorCode::kInvalidArgument, "usage", what);
}

// What --option and --height set in the recording's header.
client::HeaderEdits header_edits(const Arguments& args) {
  client::HeaderEdits edits;
  edits.options = args.header_options;
  if (args.flags.count("--height") == 1) edits.height_m = client::parse_height_m(args.flags.at("--height"));
  return edits;
}

void check_flags(const Arguments& args, const std::vector<std::string>& known) {
  if (!args.header_options.empty()) {
    bool takes_options = false;
    for (const auto& k : known) takes_options = takes_options || k == "--option";
    require(takes_options, "unknown option --option (only fit and upload set stage options)");
  }
  if (args.flags.count("--height") == 1) {
    bool takes_height = false;
    for (const auto& k : known) takes_height = takes_height || k == "--height";
    require(takes_height, "unknown option --height (only fit and upload set the subject's height)");
  }
  for (const auto& [name, value] : args.flags) {
    bool found = false;
    for (const auto& k : known) found = found || k == name;
    require(found, "unknown option " + name);
  }
}

// check_flags for a command that calls the server: --server and the security options too.
void check_server_flags(const Arguments& args, std::vector<std::string> known) {
  for (const char* flag : {"--server", "--tls-ca", "--tls-cert", "--tls-key", "--token-file"}) {
    known.emplace_back(flag);
  }
  check_flags(args, known);
}

std::shared_ptr<grpc::Channel> connect(const Arguments& args) {
  return client::make_channel(
      args.flag("--server", "127.0.0.1:50051"),
      client::load_channel_security(args.flag("--tls-ca", ""), args.flag("--tls-cert", ""), args.flag("--tls-key", ""),
                                    args.flag("--token-file", ""), std::getenv("POSEFUSE_TOKEN")));
}

std::string format_eta(double seconds) {
  if (seconds < 0 || !std::isfinite(seconds)) return "--";
  char text[32];
  if (seconds < 60) {
    std::snprintf(text, sizeof text, "%.0f s", seconds);
  } else {
    std::snprintf(text, sizeof text, "%d min %02d s", static_cast<int>(seconds) / 60, static_cast<int>(seconds) % 60);
  }
  return text;
}

// The progress line: rewritten in place on a terminal, a line every few seconds otherwise.
class ProgressLine {
 public:
  ProgressLine() : tty_(isatty(STDERR_FILENO) == 1) {}

  void show(const client::FitProgress& p, bool last) {
    if (!tty_ && !last && p.elapsed_s - last_line_s_ < 2.0) return;
    last_line_s_ = p.elapsed_s;
    shown_ = true;
    const double fps = p.elapsed_s > 0 ? p.depth_frames_sent / p.elapsed_s : 0.0;
    std::string eta = "--";
    char percent[16] = "";
    if (p.fraction_read > 0) {
      std::snprintf(percent, sizeof percent, " (%3.0f%%)", 100.0 * p.fraction_read);
      eta = format_eta(p.elapsed_s * (1.0 - p.fraction_read) / p.fraction_read);
    }
    std::fprintf(stderr, "%sfit: %llu chunks%s, %llu frames, %.1f frames/s, ETA %s%s", tty_ ? "\r" : "",
                 static_cast<unsigned long long>(p.chunks_sent), percent,
                 static_cast<unsigned long long>(p.depth_frames_sent), fps, last ? "0 s" : eta.c_str(),
                 tty_ ? "   " : "\n");
    if (tty_ && last) std::fputc('\n', stderr);
  }
  // Ends a line left open on a terminal, so that an error starts on its own line.
  void interrupt() {
    if (tty_ && shown_) std::fputc('\n', stderr);
  }

 private:
  bool tty_;
  bool shown_ = false;
  double last_line_s_ = -1e9;
};

int command_fit(const Arguments& args) {
  check_server_flags(args, {"--out", "--option", "--height"});
  require(args.positional.size() == 1, "fit takes one RECORDING (see posefuse --help)");
  require(args.flags.count("--out") == 1, "fit needs --out DIR");
  const client::HeaderEdits edits = header_edits(args);
  const std::string server = args.flag("--server", "127.0.0.1:50051");
  client::ResultWriter writer(args.flag("--out", ""));
  ProgressLine progress;
  const client::FitOutcome outcome = client::run_fit(
      connect(args), args.positional[0], writer, [&](const client::FitProgress& p) { progress.show(p, false); }, edits);
  if (outcome.local_error) {
    progress.interrupt();
    throw *outcome.local_error;
  }
  if (!outcome.status.ok()) {
    progress.interrupt();
    std::fprintf(stderr, "posefuse: fit: %s\n", client::status_line(outcome.status, server).c_str());
    if (outcome.results_received > 0) {
      std::fprintf(stderr, "posefuse: fit: partial results are in %s\n", writer.directory().string().c_str());
    }
    return 1;
  }
  progress.show(outcome.progress, true);
  const posefuse::v1::Summary* summary = writer.summary();
  std::printf("results: %s\n", writer.directory().string().c_str());
  std::printf("  %llu IMU orientations in imu_orientations/, calibration.json, summary.json\n",
              static_cast<unsigned long long>(writer.orientation_samples()));
  if (writer.forearm_samples() + writer.imu_positions() + writer.recovered_segments() > 0) {
    std::printf("  %llu forearm orientations in forearm_orientations/, %llu IMU positions, %llu recovered segments\n",
                static_cast<unsigned long long>(writer.forearm_samples()),
                static_cast<unsigned long long>(writer.imu_positions()),
                static_cast<unsigned long long>(writer.recovered_segments()));
  }
  if (writer.offline_forearm_samples() > 0) {
    std::printf("  %llu forearm orientations re-solved with the final mounting in forearm_orientations_offline/\n",
                static_cast<unsigned long long>(writer.offline_forearm_samples()));
  }
  if (summary != nullptr) {
    std::printf("  %llu chunks, %llu depth frames, %.1f s of recording processed in %.2f s\n",
                static_cast<unsigned long long>(summary->chunks()),
                static_cast<unsigned long long>(summary->depth_frames()), summary->stream_duration_s(),
                summary->processing_duration_s());
  }
  std::printf("  %llu warnings, %llu item errors (warnings.txt)\n", static_cast<unsigned long long>(writer.warnings()),
              static_cast<unsigned long long>(writer.item_errors()));
  return 0;
}

int command_convert(const Arguments& args) {
  check_flags(args, {});
  require(args.positional.size() == 2, "convert takes IN and OUT");
  const std::filesystem::path in = args.positional[0], out = args.positional[1];
  const std::uint64_t chunks = std::filesystem::is_directory(in) ? posefuse::session::directory_to_chunk_file(in, out)
                                                                 : posefuse::session::chunk_file_to_directory(in, out);
  std::printf("converted %llu chunks: %s -> %s\n", static_cast<unsigned long long>(chunks), in.string().c_str(),
              out.string().c_str());
  return 0;
}

void set_deadline(grpc::ClientContext& context) {
  context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(5));
}

int command_health(const Arguments& args) {
  check_server_flags(args, {});
  require(args.positional.empty(), "health takes no positional arguments");
  const std::string server = args.flag("--server", "127.0.0.1:50051");
  auto stub = grpc::health::v1::Health::NewStub(connect(args));
  grpc::ClientContext context;
  set_deadline(context);
  grpc::health::v1::HealthCheckRequest request;
  grpc::health::v1::HealthCheckResponse response;
  const grpc::Status status = stub->Check(&context, request, &response);
  if (!status.ok()) {
    std::fprintf(stderr, "posefuse: health: %s\n", client::status_line(status, server).c_str());
    return 1;
  }
  const std::string name = grpc::health::v1::HealthCheckResponse::ServingStatus_Name(response.status());
  std::printf("%s\n", name.c_str());
  return response.status() == grpc::health::v1::HealthCheckResponse::SERVING ? 0 : 1;
}

int command_info(const Arguments& args) {
  check_server_flags(args, {});
  require(args.positional.empty(), "info takes no positional arguments");
  const std::string server = args.flag("--server", "127.0.0.1:50051");
  auto stub = posefuse::v1::PoseFuse::NewStub(connect(args));
  grpc::ClientContext context;
  set_deadline(context);
  posefuse::v1::ServerInfo info;
  const grpc::Status status = stub->GetServerInfo(&context, {}, &info);
  if (!status.ok()) {
    std::fprintf(stderr, "posefuse: info: %s\n", client::status_line(status, server).c_str());
    return 1;
  }
  std::printf("posefuse-server %s (%s; gRPC %s, protobuf %s)\n", info.server_version().c_str(),
              info.api_version().c_str(), info.grpc_version().c_str(), info.protobuf_version().c_str());
  std::printf("session format versions:");
  for (const auto v : info.session_format_versions()) std::printf(" %u", v);
  std::printf("\nstages:\n");
  for (const auto& stage : info.stages()) {
    std::printf("  %-18s %s\n", stage.name().c_str(), stage.description().c_str());
  }
  std::printf("options (SessionHeader.options):\n");
  for (const auto& option : info.options()) {
    std::printf("  %-18s default %-6s %s\n", option.key().c_str(), option.default_value().c_str(),
                option.description().c_str());
  }
  std::printf("models: %s\n", info.models().empty() ? "none loaded" : "");
  for (const auto& model : info.models()) {
    std::printf("  %s %s: %s\n", model.name().c_str(), model.version().c_str(), model.description().c_str());
  }
  const auto& limits = info.limits();
  std::printf(
      "limits: max message %.1f MiB, %u sessions, %u queued chunks and %.0f MiB of memory per session, "
      "idle timeout %.0f s, %u workers\n",
      static_cast<double>(limits.max_message_bytes()) / (1024.0 * 1024.0), limits.max_sessions(),
      limits.max_queued_chunks(), static_cast<double>(limits.max_session_memory_bytes()) / (1024.0 * 1024.0),
      limits.idle_timeout_s(), limits.workers());
  if (info.jobs_supported()) {
    std::printf("batch jobs: on, uploads up to %.0f MiB\n",
                static_cast<double>(limits.max_upload_bytes()) / (1024.0 * 1024.0));
  } else {
    std::printf("batch jobs: off (server started without --data-dir)\n");
  }
  return 0;
}

std::string job_line(const posefuse::v1::Job& job) {
  std::string line = job.job_id() + "  " + posefuse::v1::Job::State_Name(job.state());
  if (job.has_progress()) {
    line += "  " + std::to_string(job.progress().chunks_processed()) + " chunks";
  }
  if (!job.label().empty()) line += "  label=" + job.label();
  if (!job.recording_uri().empty()) line += "  " + job.recording_uri();
  if (job.state() == posefuse::v1::Job::FAILED) line += "  error: " + job.error_message();
  return line;
}

std::unique_ptr<posefuse::v1::PoseFuse::Stub> job_stub(const Arguments& args, std::size_t positional,
                                                       bool takes_header_options = false) {
  std::vector<std::string> known{"--label", "--out"};
  if (takes_header_options) known.insert(known.end(), {"--option", "--height"});
  check_server_flags(args, known);
  require(args.positional.size() == positional, "wrong number of arguments (see --help)");
  return posefuse::v1::PoseFuse::NewStub(connect(args));
}

int call_failed(const char* command, const Arguments& args, const grpc::Status& status) {
  std::fprintf(stderr, "posefuse: %s: %s\n", command,
               client::status_line(status, args.flag("--server", "127.0.0.1:50051")).c_str());
  return 1;
}

int command_submit(const Arguments& args) {
  auto stub = job_stub(args, 1);
  grpc::ClientContext context;
  set_deadline(context);
  posefuse::v1::Job job;
  auto writer = stub->SubmitJob(&context, &job);
  posefuse::v1::SubmitJobRequest request;
  request.mutable_spec()->set_recording_uri(args.positional[0]);
  request.mutable_spec()->set_label(args.flag("--label", ""));
  writer->Write(request);
  writer->WritesDone();
  const grpc::Status status = writer->Finish();
  if (!status.ok()) return call_failed("submit", args, status);
  std::printf("%s\n", job_line(job).c_str());
  return 0;
}

// Streams a local recording into the server's job store (SubmitJob by upload): the server
// spools it to disk and runs it like a job by reference.
int command_upload(const Arguments& args) {
  auto stub = job_stub(args, 1, true);
  client::Recording recording(args.positional[0], header_edits(args));
  grpc::ClientContext context;  // no deadline: a long recording takes as long as it takes
  posefuse::v1::Job job;
  auto writer = stub->SubmitJob(&context, &job);
  posefuse::v1::SubmitJobRequest request;
  request.mutable_spec()->set_upload(true);
  request.mutable_spec()->set_label(args.flag("--label", ""));
  bool open = writer->Write(request);
  std::uint64_t chunks = 0;
  while (open && recording.next(*request.mutable_chunk())) {
    open = writer->Write(request);  // false: the server ended the call; Finish says why
    ++chunks;
  }
  if (open) writer->WritesDone();
  const grpc::Status status = writer->Finish();
  if (!status.ok()) return call_failed("upload", args, status);
  std::fprintf(stderr, "posefuse: uploaded %llu chunks\n", static_cast<unsigned long long>(chunks));
  std::printf("%s\n", job_line(job).c_str());
  return 0;
}

int command_jobs(const Arguments& args) {
  auto stub = job_stub(args, 0);
  std::string page_token;
  do {
    grpc::ClientContext context;
    set_deadline(context);
    posefuse::v1::ListJobsRequest request;
    request.set_page_token(page_token);
    posefuse::v1::ListJobsResponse response;
    const grpc::Status status = stub->ListJobs(&context, request, &response);
    if (!status.ok()) return call_failed("jobs", args, status);
    for (const auto& job : response.jobs()) std::printf("%s\n", job_line(job).c_str());
    page_token = response.next_page_token();
  } while (!page_token.empty());
  return 0;
}

int command_watch(const Arguments& args) {
  auto stub = job_stub(args, 1);
  grpc::ClientContext context;  // no deadline: a job may run for long
  posefuse::v1::WatchJobRequest request;
  request.set_job_id(args.positional[0]);
  auto reader = stub->WatchJob(&context, request);
  posefuse::v1::Job job;
  while (reader->Read(&job)) std::printf("%s\n", job_line(job).c_str());
  const grpc::Status status = reader->Finish();
  if (!status.ok()) return call_failed("watch", args, status);
  return job.state() == posefuse::v1::Job::SUCCEEDED ? 0 : 1;
}

int command_cancel(const Arguments& args) {
  auto stub = job_stub(args, 1);
  grpc::ClientContext context;
  set_deadline(context);
  posefuse::v1::CancelJobRequest request;
  request.set_job_id(args.positional[0]);
  posefuse::v1::Job job;
  const grpc::Status status = stub->CancelJob(&context, request, &job);
  if (!status.ok()) return call_failed("cancel", args, status);
  std::printf("%s\n", job_line(job).c_str());
  return 0;
}

int command_results(const Arguments& args) {
  auto stub = job_stub(args, 1);
  require(args.flags.count("--out") == 1, "results needs --out DIR");
  client::ResultWriter writer(args.flag("--out", ""));
  grpc::ClientContext context;
  posefuse::v1::GetJobResultsRequest request;
  request.set_job_id(args.positional[0]);
  auto reader = stub->GetJobResults(&context, request);
  posefuse::v1::FitResult result;
  while (reader->Read(&result)) writer.write(result);
  const grpc::Status status = reader->Finish();
  if (!status.ok()) return call_failed("results", args, status);
  writer.finish();
  std::printf("results: %s (%llu IMU orientations, %llu warnings, %llu item errors)\n",
              writer.directory().string().c_str(), static_cast<unsigned long long>(writer.orientation_samples()),
              static_cast<unsigned long long>(writer.warnings()),
              static_cast<unsigned long long>(writer.item_errors()));
  return 0;
}

int command_export(const Arguments& args) {
  check_flags(args, {"--format", "--out"});
  require(args.positional.size() == 1, "export takes one RESULTS directory");
  const auto format = posefuse::opensim::export_format(args.flag("--format", ""));
  require(format.has_value(), "export needs --format trc, mot, sto or gltf");
  const posefuse::opensim::ExportReport report =
      posefuse::opensim::export_results(args.positional[0], *format, args.flag("--out", ""));
  for (const std::string& warning : report.warnings)
    std::fprintf(stderr, "posefuse: export: warning: %s\n", warning.c_str());
  std::printf("%s: %s\n", report.file.string().c_str(), report.summary.c_str());
  return 0;
}

int command_report(const Arguments& args) {
  check_flags(args, {"--out"});
  require(args.positional.size() == 1, "report takes one RESULTS directory");
  const std::filesystem::path results = args.positional[0];
  const std::filesystem::path out = args.flag("--out", (results / "report.html").string());
  const posefuse::report::ReportContents contents = posefuse::report::write_session_report(results, out);
  std::printf("%s: %zu plots, %zu repetitions, %zu warnings\n", out.string().c_str(), contents.plots,
              contents.repetitions, contents.warnings);
  return 0;
}

int command_demo_session(const Arguments& args) {
  check_flags(args, {});
  require(args.positional.size() == 1, "demo-session takes OUT");
  const std::uint64_t chunks = posefuse::demo::write_demo_session(args.positional[0]);
  std::printf("demo session (small and synthetic, for tests; realistic sessions: posefuse-sim): %llu chunks in %s\n",
              static_cast<unsigned long long>(chunks), args.positional[0].c_str());
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2 || std::string(argv[1]) == "--help" || std::string(argv[1]) == "-h") {
    std::fputs(kUsage, argc < 2 ? stderr : stdout);
    return argc < 2 ? kExitUsage : 0;
  }
  const std::string command = argv[1];
  try {
    const Arguments args = parse_arguments(argc, argv, 2);
    if (command == "fit") return command_fit(args);
    if (command == "convert") return command_convert(args);
    if (command == "health") return command_health(args);
    if (command == "info") return command_info(args);
    if (command == "demo-session") return command_demo_session(args);
    if (command == "submit") return command_submit(args);
    if (command == "upload") return command_upload(args);
    if (command == "jobs") return command_jobs(args);
    if (command == "watch") return command_watch(args);
    if (command == "cancel") return command_cancel(args);
    if (command == "results") return command_results(args);
    if (command == "export") return command_export(args);
    if (command == "report") return command_report(args);
    std::fprintf(stderr, "posefuse: unknown command '%s'\n%s", command.c_str(), kUsage);
    return kExitUsage;
  } catch (const Error& error) {
    std::fprintf(stderr, "posefuse: %s: %s\n", command.c_str(), error.what());
    return error.field() == "usage" ? kExitUsage : 1;
  } catch (const std::exception& error) {
    std::fprintf(stderr, "posefuse: %s: %s\n", command.c_str(), error.what());
    return 1;
  }
}
