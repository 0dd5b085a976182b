#pragma once
// JobStore in one SQLite database file (WAL mode). Jobs and results are stored as serialised
// protobuf messages beside the columns that queries need (state, create time). Thread-safe: one
// connection, one mutex.
#include <filesystem>
#include <mutex>

#include "server/job_store.hpp"

struct sqlite3;

namespace posefuse::server {

class SqliteJobStore : public JobStore {
 public:
  // Opens or creates the database. Throws kFailedPrecondition (field = the path) when it cannot.
  explicit SqliteJobStore(const std::filesystem::path& path);
  ~SqliteJobStore() override;
  SqliteJobStore(const SqliteJobStore&) = delete;
  SqliteJobStore& operator=(const SqliteJobStore&) = delete;

  v1::Job create(const v1::JobSpec& spec, const std::string& recording_path,
                 const std::string& owner, std::int64_t now_unix_us) override;
  std::optional<JobRecord> get(const std::string& job_id) override;
  std::vector<v1::Job> list(std::size_t limit, const std::string& after_job_id,
                            const std::vector<v1::Job::State>& states,
                            const std::string& owner) override;
  void update(const v1::Job& job) override;
  void append_results(const std::string& job_id,
                      const std::vector<v1::FitResult>& results) override;
  std::vector<v1::FitResult> results(const std::string& job_id) override;
  void clear_results(const std::string& job_id) override;
  std::vector<JobRecord> unfinished() override;

 private:
  void exec(const char* sql);
  bool has_column(const char* table, const char* column);

  std::filesystem::path path_;
  std::mutex mu_;
  sqlite3* db_ = nullptr;
};

}  // namespace posefuse::server
