// bench_job_replicas: batch jobs per minute with 1, 2, 4 ... worker processes on one PostgreSQL
// job store, the lease takeover time after kill -9 of a worker, and the database's size per
// hour of recording.
//
//   bench_job_replicas [--workers 1,2,4] [--jobs N] [--session-s S] [--lease-s S]
//
// A private PostgreSQL cluster (tests/server/postgres_cluster.hpp), one `--role api`
// posefuse-server and W `--role worker` ones (--workers 1 --max-jobs 1 each: one job, one
// pipeline thread per process), all real processes (tests/server/server_process.hpp). N demo
// sessions of S seconds are submitted by reference at once; the time runs from the first
// submission until the last job has SUCCEEDED. Takeover: a long job on one of two workers, that
// worker killed once the job runs; the time until the other claims it (attempt 2) and until it
// has SUCCEEDED, with the lease and a heartbeat of a quarter of it.
#include <chrono>
#include <cstdio>
#include <iostream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "client/demo_session.hpp"
#include "client/fit_call.hpp"
#include "posefuse/v1/service.grpc.pb.h"
#include "server/job_transitions.hpp"
#include "server/pg_connection.hpp"
#include "tests/scratch_dir.hpp"
#include "tests/server/postgres_cluster.hpp"
#include "tests/server/server_process.hpp"

namespace {

namespace fs = std::filesystem;
using namespace posefuse;
using Clock = std::chrono::steady_clock;

struct Options {
  std::vector<int> workers{1, 2, 4};
  int jobs = 24;
  double session_s = 30.0;
  double lease_s = 2.0;
};

struct Process {
  std::unique_ptr<test::ServerProcess> process;
  std::unique_ptr<v1::PoseFuse::Stub> stub;
};

class Site {
 public:
  Site(test::PostgresCluster& cluster, fs::path dir, fs::path recordings, double lease_s)
      : conninfo_(cluster.conninfo(cluster.create_database())),
        dir_(std::move(dir)),
        recordings_(std::move(recordings)),
        lease_s_(lease_s) {
    fs::create_directories(dir_);
  }

  Process start(const std::string& role) {
    const std::string name = role + std::to_string(started_++);
    Process p;
    p.process = std::make_unique<test::ServerProcess>(
        POSEFUSE_SERVER_BINARY,
        std::vector<std::string>{"--listen", "127.0.0.1:0", "--workers", "1", "--max-jobs", "1", "--data-dir",
                                 (dir_ / name).string(), "--recordings-root", recordings_.string(), "--job-store",
                                 conninfo_, "--role", role, "--job-lease-s", std::to_string(lease_s_),
                                 "--job-heartbeat-s", std::to_string(lease_s_ / 4)},
        dir_ / (name + ".log"));
    p.stub = v1::PoseFuse::NewStub(client::make_channel("127.0.0.1:" + std::to_string(p.process->port())));
    return p;
  }
  const std::string& conninfo() const { return conninfo_; }

 private:
  std::string conninfo_;
  fs::path dir_;
  fs::path recordings_;
  double lease_s_;
  int started_ = 0;
};

std::string submit(Process& api, const std::string& uri) {
  grpc::ClientContext context;
  v1::Job job;
  auto writer = api.stub->SubmitJob(&context, &job);
  v1::SubmitJobRequest request;
  request.mutable_spec()->set_recording_uri(uri);
  writer->Write(request);
  writer->WritesDone();
  const grpc::Status status = writer->Finish();
  if (!status.ok()) throw std::runtime_error("SubmitJob: " + status.error_message());
  return job.job_id();
}

v1::Job get(Process& api, const std::string& id) {
  grpc::ClientContext context;
  v1::GetJobRequest request;
  request.set_job_id(id);
  v1::Job job;
  const grpc::Status status = api.stub->GetJob(&context, request, &job);
  if (!status.ok()) throw std::runtime_error("GetJob: " + status.error_message());
  return job;
}

void wait_all(Process& api, const std::vector<std::string>& ids) {
  for (const std::string& id : ids) {
    while (true) {
      const v1::Job job = get(api, id);
      if (server::is_terminal(job.state())) {
        if (job.state() != v1::Job::SUCCEEDED)
          throw std::runtime_error("job " + id + " " + v1::Job::State_Name(job.state()));
        break;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
  }
}

double seconds_since(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

std::int64_t relation_bytes(const std::string& conninfo, const std::string& table) {
  server::PgConnection connection(conninfo);
  server::PgResult row = connection.exec("SELECT pg_total_relation_size($1::regclass)", {server::pg_text(table)});
  return server::pg_int64(row.get(), 0, 0);
}

std::vector<int> parse_list(const std::string& text) {
  std::vector<int> out;
  std::stringstream in(text);
  for (std::string item; std::getline(in, item, ',');) out.push_back(std::stoi(item));
  return out;
}

}  // namespace

int run_bench(int argc, char** argv) {
  Options options;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string flag = argv[i], value = argv[i + 1];
    if (flag == "--workers") options.workers = parse_list(value);
    else if (flag == "--jobs") options.jobs = std::stoi(value);
    else if (flag == "--session-s") options.session_s = std::stod(value);
    else if (flag == "--lease-s") options.lease_s = std::stod(value);
    else {
      std::cerr << "usage: bench_job_replicas [--workers 1,2,4] [--jobs N] [--session-s S] [--lease-s S]\n";
      return 2;
    }
  }
  const fs::path bin = test::PostgresCluster::find_bin_dir();
  if (bin.empty()) {
    std::cerr << "bench_job_replicas: PostgreSQL is not installed (/usr/lib/postgresql/*/bin)\n";
    return 1;
  }
  const fs::path dir = posefuse::testing::fresh_scratch_dir("bench_job_replicas", "run");
  fs::create_directories(dir / "recordings");
  demo::DemoSessionOptions session;
  session.duration_s = options.session_s;
  demo::write_demo_session(dir / "recordings" / "session.pfchunks", session);
  const double recording_bytes = static_cast<double>(fs::file_size(dir / "recordings" / "session.pfchunks"));
  test::PostgresCluster cluster(bin);

  std::printf("jobs of a %.0f s demo session, %d jobs, %u cores\n", options.session_s, options.jobs,
              std::thread::hardware_concurrency());
  std::printf("| worker processes | wall s | jobs/min | jobs/min per worker |\n|---|---|---|---|\n");
  double results_bytes_per_job = 0;
  for (const int workers : options.workers) {
    Site site(cluster, dir / ("w" + std::to_string(workers)), dir / "recordings", options.lease_s);
    Process api = site.start("api");
    std::vector<Process> pool;
    for (int w = 0; w < workers; ++w) pool.push_back(site.start("worker"));
    const Clock::time_point start = Clock::now();
    std::vector<std::string> ids;
    for (int j = 0; j < options.jobs; ++j) ids.push_back(submit(api, "session.pfchunks"));
    wait_all(api, ids);
    const double wall = seconds_since(start);
    const double per_minute = options.jobs / wall * 60.0;
    std::printf("| %d | %.2f | %.1f | %.1f |\n", workers, wall, per_minute, per_minute / workers);
    results_bytes_per_job = static_cast<double>(relation_bytes(site.conninfo(), "results")) / options.jobs;
    for (Process& p : pool) p.process->terminate();
    api.process->terminate();
  }
  const double hours = options.session_s / 3600.0;
  std::printf(
      "\ndatabase size per hour of recording: results %.1f MiB (kept), upload %.1f MiB "
      "(the chunk file, while its job is queued or running)\n",
      results_bytes_per_job / hours / (1 << 20), recording_bytes / hours / (1 << 20));

  // Takeover: a job three times as long, its worker killed once it runs.
  demo::DemoSessionOptions long_session;
  long_session.duration_s = options.session_s * 3;
  demo::write_demo_session(dir / "recordings" / "long.pfchunks", long_session);
  std::printf("\n| lease s | kill -> claimed again s | kill -> SUCCEEDED s |\n|---|---|---|\n");
  for (int repeat = 0; repeat < 3; ++repeat) {
    Site site(cluster, dir / ("takeover" + std::to_string(repeat)), dir / "recordings", options.lease_s);
    Process api = site.start("api");
    std::vector<Process> pool;
    for (int w = 0; w < 2; ++w) pool.push_back(site.start("worker"));
    const std::string id = submit(api, "long.pfchunks");
    while (get(api, id).progress().chunks_processed() == 0) std::this_thread::sleep_for(std::chrono::milliseconds(5));
    const std::string claimed = "event=job_claimed job=" + id;
    const int victim = pool[0].process->log().find(claimed) != std::string::npos ? 0 : 1;
    pool[static_cast<std::size_t>(victim)].process->kill9();
    const Clock::time_point killed = Clock::now();
    Process& survivor = pool[static_cast<std::size_t>(1 - victim)];
    while (survivor.process->log().find(claimed + " attempt=2") == std::string::npos) {
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    const double reclaimed = seconds_since(killed);
    wait_all(api, {id});
    std::printf("| %.1f | %.2f | %.2f |\n", options.lease_s, reclaimed, seconds_since(killed));
    survivor.process->terminate();
    api.process->terminate();
  }
  return 0;
}

int main(int argc, char** argv) {
  // Caught here, so that the cluster and the server processes are stopped on the way out.
  try {
    return run_bench(argc, argv);
  } catch (const std::exception& error) {
    std::cerr << "bench_job_replicas: " << error.what() << "\n";
    return 1;
  }
}
