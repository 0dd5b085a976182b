#pragma once
// A fixed set of threads running submitted tasks in FIFO order. The server runs session
// pipelines here, never on gRPC's reactor threads (a pipeline step can take milliseconds; a
// blocked reactor thread would stall every other call).
#include <condition_variable>
#include <cstddef>
#include <deque>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

namespace posefuse::server {

class WorkerPool {
 public:
  explicit WorkerPool(std::size_t threads);
  ~WorkerPool();  // runs what is queued, then joins
  WorkerPool(const WorkerPool&) = delete;
  WorkerPool& operator=(const WorkerPool&) = delete;

  // Tasks must not throw (the server's tasks catch everything themselves).
  void submit(std::function<void()> task);
  // Tasks waiting for a thread (a gauge for logs and metrics).
  std::size_t queued() const;
  std::size_t threads() const;
  // One more thread, for a task that will not return soon (a job blocked inside a read).
  void add_thread();

 private:
  void run();

  mutable std::mutex mu_;
  std::condition_variable ready_;
  std::deque<std::function<void()>> tasks_;
  bool stopping_ = false;
  std::vector<std::thread> threads_;
};

}  // namespace posefuse::server
