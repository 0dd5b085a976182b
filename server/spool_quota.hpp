#pragma once
// The bytes that uploads in transit may hold in the spool folder together (--max-spool-mb), so
// that concurrent uploads cannot fill the disk however many there are: each upload reserves a
// chunk's bytes before it writes them and gives all back when it ends (its job now holds the
// file, or nothing is left of it). Thread-safe.
#include <atomic>
#include <cstdint>

namespace posefuse::server {

class SpoolQuota {
 public:
  explicit SpoolQuota(std::uint64_t max_bytes) : max_bytes_(max_bytes) {}

  // Reserves `bytes`; false, reserving nothing, when the uploads' bytes would pass the quota.
  bool try_reserve(std::uint64_t bytes) {
    std::uint64_t used = used_.load();
    do {
      if (bytes > max_bytes_ - used) return false;
    } while (!used_.compare_exchange_weak(used, used + bytes));
    return true;
  }
  void release(std::uint64_t bytes) { used_.fetch_sub(bytes); }

  std::uint64_t max_bytes() const { return max_bytes_; }
  std::uint64_t in_use() const { return used_.load(); }

 private:
  const std::uint64_t max_bytes_;
  std::atomic<std::uint64_t> used_{0};
};

}  // namespace posefuse::server
