#pragma once
// Runs numbered jobs on worker threads and hands their results to the calling thread in job
// order, so that a consumer (the session writer) works while the workers render the next frames.
//
// Job i always runs on worker i % workers: a worker keeps state between its jobs (a refitted
// BVH, buffers), so a fixed assignment keeps the output independent of thread timing. A worker
// runs at most `lookahead` jobs ahead of the consumer (bounded memory). The first exception, in
// job order, from a job or from the consumer stops every worker and is rethrown here after all
// threads have been joined.
#include <condition_variable>
#include <cstdint>
#include <exception>
#include <functional>
#include <mutex>
#include <optional>
#include <thread>
#include <vector>

namespace posefuse::sim {

template <typename Result>
void run_ordered(int workers, std::int64_t jobs, int lookahead,
                 const std::function<Result(int worker, std::int64_t job)>& produce,
                 const std::function<void(std::int64_t job, Result& result)>& consume) {
  struct Slot {
    std::optional<Result> result;
    std::exception_ptr error;
    bool ready = false;
  };
  const auto ring = static_cast<std::int64_t>(workers) * lookahead;
  std::vector<Slot> slots(static_cast<std::size_t>(ring));
  std::mutex mutex;
  std::condition_variable changed;
  std::int64_t consumed = 0;  // jobs [0, consumed) are done with
  bool stop = false;

  const auto work = [&](int worker) {
    for (std::int64_t job = worker; job < jobs; job += workers) {
      {
        // Slot job % ring is free once job - ring has been consumed.
        std::unique_lock<std::mutex> lock(mutex);
        changed.wait(lock, [&] { return stop || consumed > job - ring; });
        if (stop) return;
      }
      Slot filled;
      try {
        filled.result.emplace(produce(worker, job));
      } catch (...) {
        filled.error = std::current_exception();
      }
      filled.ready = true;
      const bool failed = filled.error != nullptr;
      {
        std::lock_guard<std::mutex> lock(mutex);
        slots[static_cast<std::size_t>(job % ring)] = std::move(filled);
      }
      changed.notify_all();
      if (failed) return;
    }
  };

  std::vector<std::thread> threads;
  std::exception_ptr error;
  try {
    for (int w = 0; w < workers; ++w) threads.emplace_back(work, w);
    for (std::int64_t job = 0; job < jobs; ++job) {
      Slot taken;
      {
        std::unique_lock<std::mutex> lock(mutex);
        Slot& slot = slots[static_cast<std::size_t>(job % ring)];
        changed.wait(lock, [&] { return slot.ready; });
        taken = std::move(slot);
        slot = Slot{};
      }
      if (taken.error) std::rethrow_exception(taken.error);
      consume(job, *taken.result);
      {
        std::lock_guard<std::mutex> lock(mutex);
        consumed = job + 1;
      }
      changed.notify_all();
    }
  } catch (...) {
    error = std::current_exception();
  }
  {
    std::lock_guard<std::mutex> lock(mutex);
    stop = true;
  }
  changed.notify_all();
  for (std::thread& thread : threads) thread.join();
  if (error) std::rethrow_exception(error);
}

}  // namespace posefuse::sim
