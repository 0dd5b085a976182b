// body::parse_npy / parse_npz on archives that lie about their sizes (found by fuzz/fuzz_npz):
// what they claim is checked before it is allocated or multiplied.
#include "body/npz_reader.hpp"

#include <gtest/gtest.h>
#include <sys/resource.h>

#include <string>

#include "../imu/expect_error.hpp"
#include "common/error.hpp"
#include "npz_writer.hpp"

namespace posefuse::body {
namespace {

using posefuse::testing::expect_error;

// `archive` with the uncompressed size of its first central directory entry set to `size`.
std::string with_claimed_size(std::string archive, std::uint32_t size) {
  const std::size_t entry = archive.find("PK\x01\x02");
  EXPECT_NE(entry, std::string::npos);
  std::string field;
  testing::put(field, size, 4);
  archive.replace(entry + 24, 4, field);
  return archive;
}

long peak_rss_kb() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return usage.ru_maxrss;
}

TEST(NpzReader, DeflatedMemberClaimingAGigabyteIsDataLossWithoutAllocatingIt) {
  const std::string archive = testing::zip({{"a.npy", testing::npy({3}, {1, 2, 3})}}, true);
  const std::string lying = with_claimed_size(archive, 1u << 30);
  const long before_kb = peak_rss_kb();
  expect_error([&] { parse_npz(lying, "x.npz"); }, ErrorCode::kDataLoss, "x.npz/a.npy", "1073741824 claimed");
  EXPECT_LT(peak_rss_kb() - before_kb, 64 * 1024) << "the claimed size was allocated";
}

TEST(NpzReader, DeflatedMemberInflatingToMoreThanItClaimsIsDataLoss) {
  const std::string npy = testing::npy({3}, {1, 2, 3});
  const std::string archive = testing::zip({{"a.npy", npy}}, true);
  expect_error([&] { parse_npz(with_claimed_size(archive, static_cast<std::uint32_t>(npy.size() - 1)), "x.npz"); },
               ErrorCode::kDataLoss, "x.npz/a.npy", "longer than claimed");
  EXPECT_EQ(parse_npz(archive, "x.npz").at("a").values.size(), 3u);
}

TEST(NpzReader, ShapeWhoseProductOverflowsIsResourceExhausted) {
  // 2^32 * 2^32 wraps to 0 in 64 bits: an array of "no" elements with an absurd shape.
  expect_error(
      [&] {
        parse_npy(testing::npy({4294967296, 4294967296}, {}), "big.npy");
      },
      ErrorCode::kResourceExhausted, "big.npy");
  expect_error(
      [&] {
        parse_npy(testing::npy({999999999999, 999999999999, 3}, {}), "big.npy");
      },
      ErrorCode::kResourceExhausted, "big.npy");
  EXPECT_EQ(parse_npy(testing::npy({4294967296, 0}, {}), "empty.npy").values.size(), 0u);
}

}  // namespace
}  // namespace posefuse::body
