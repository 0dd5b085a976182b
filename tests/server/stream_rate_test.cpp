// The minimum stream rate rule on its own (server/stream_rate.hpp); the session that applies it
// is tested in server_test.cpp (ServerTest.SlowSender...).
#include "server/stream_rate.hpp"

#include <gtest/gtest.h>

#include <limits>

namespace posefuse::server {
namespace {

constexpr StreamRateRule kHalfRealTime{0.5, 1.0};

TEST(StreamRate, KeepingUpIsOk) {
  EXPECT_FALSE(stream_rate_shortfall(kHalfRealTime, 10.0, 10.0));   // real time
  EXPECT_FALSE(stream_rate_shortfall(kHalfRealTime, 10.0, 5.0));    // exactly the required rate
  EXPECT_FALSE(stream_rate_shortfall(kHalfRealTime, 10.0, 600.0));  // an upload, far faster
}

TEST(StreamRate, FallingBehindGivesTheShortfall) {
  const auto shortfall = stream_rate_shortfall(kHalfRealTime, 10.0, 4.0);
  ASSERT_TRUE(shortfall);
  EXPECT_DOUBLE_EQ(shortfall->wall_s, 10.0);
  EXPECT_DOUBLE_EQ(shortfall->stream_s, 4.0);
  EXPECT_DOUBLE_EQ(shortfall->rate, 0.4);
  EXPECT_DOUBLE_EQ(shortfall->required_rate, 0.5);
  // No data at all after the grace period is the slowest rate there is.
  const auto nothing = stream_rate_shortfall(kHalfRealTime, 1.5, 0.0);
  ASSERT_TRUE(nothing);
  EXPECT_DOUBLE_EQ(nothing->rate, 0.0);
}

TEST(StreamRate, NothingIsJudgedWithinTheGracePeriod) {
  EXPECT_FALSE(stream_rate_shortfall(kHalfRealTime, 0.0, 0.0));
  EXPECT_FALSE(stream_rate_shortfall(kHalfRealTime, 0.5, 0.0));
  EXPECT_FALSE(stream_rate_shortfall(kHalfRealTime, 1.0, 0.0));  // the grace period's last instant
  EXPECT_TRUE(stream_rate_shortfall(kHalfRealTime, 1.001, 0.0));
  // A grace of 0 judges from the start, but never at wall time 0 (no rate yet).
  EXPECT_FALSE(stream_rate_shortfall({0.5, 0.0}, 0.0, 0.0));
  EXPECT_TRUE(stream_rate_shortfall({0.5, 0.0}, 0.1, 0.0));
}

TEST(StreamRate, RateZeroDisablesTheRule) {
  EXPECT_FALSE(stream_rate_shortfall({0.0, 1.0}, 1e9, 0.0));
  EXPECT_FALSE(stream_rate_shortfall({0.0, 0.0}, 1e9, 0.0));
}

TEST(StreamRate, AbsurdStreamTimesFakeNoProgress) {
  // The session passes the validator's stream time, which only accepted timestamps advance
  // (SessionValidator.RejectedTimestampsAddNoStreamTime); whatever else reaches the rule counts
  // as no progress at all.
  for (const double stream_s : {-1.0, -1e300, std::numeric_limits<double>::quiet_NaN(),
                                std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity()}) {
    SCOPED_TRACE(stream_s);
    const auto shortfall = stream_rate_shortfall(kHalfRealTime, 10.0, stream_s);
    ASSERT_TRUE(shortfall);
    EXPECT_DOUBLE_EQ(shortfall->stream_s, 0.0);
    EXPECT_DOUBLE_EQ(shortfall->rate, 0.0);
  }
}

TEST(StreamRate, AbsurdWallTimesAreNotJudged) {
  for (const double wall_s :
       {-5.0, std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity()}) {
    SCOPED_TRACE(wall_s);
    EXPECT_FALSE(stream_rate_shortfall({0.5, 0.0}, wall_s, 0.0));
  }
}

TEST(StreamRate, DescriptionNamesBothRatesAndTheOptions) {
  const auto shortfall = stream_rate_shortfall(kHalfRealTime, 8.0, 1.0);
  ASSERT_TRUE(shortfall);
  const std::string text = describe(*shortfall, kHalfRealTime);
  EXPECT_NE(text.find("1.000 s of recording in 8.000 s"), std::string::npos) << text;
  EXPECT_NE(text.find("0.125x real time"), std::string::npos) << text;
  EXPECT_NE(text.find("required 0.5x"), std::string::npos) << text;
  EXPECT_NE(text.find("--min-stream-rate"), std::string::npos) << text;
  EXPECT_NE(text.find("--stream-rate-grace-s"), std::string::npos) << text;
}

}  // namespace
}  // namespace posefuse::server
