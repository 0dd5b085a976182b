// The option-table mechanism on a table of its own: defaults, values out of range, values of the
// wrong type and unknown choices, each refused with an error naming the option and the value.
#include "session/option_reader.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <map>
#include <string>

#include "common/error.hpp"
#include "session/mag_calibration_option.hpp"

namespace posefuse::session {
namespace {

const OptionTable& test_table() {
  static const OptionTable table{
      {.key = "t.flag", .type = OptionType::kBool, .default_value = "true", .description = "a switch"},
      {.key = "t.count",
       .type = OptionType::kInteger,
       .default_value = "3",
       .min = at_least(1),
       .max = at_most(9),
       .description = "a count"},
      {.key = "t.id",
       .type = OptionType::kInteger,
       .min = at_least(0),
       .max = at_most(4294967295.0),
       .description = "an id"},
      {.key = "t.duration_s",
       .type = OptionType::kReal,
       .default_value = "5",
       .min = above(0),
       .max = at_most(120),
       .unit = "s",
       .description = "a duration"},
      {.key = "t.tone_hz",
       .type = OptionType::kReal,
       .default_value = "2700",
       .min = above(0),
       .words = {"auto"},
       .unit = "Hz",
       .description = "a frequency or auto"},
      {.key = "t.mode",
       .type = OptionType::kChoice,
       .default_value = "depth",
       .words = {"depth", "sdk"},
       .description = "a mode"},
      {.key = "t.rotation", .type = OptionType::kQuaternion, .description = "a rotation"},
      {.key = "t.mag.<device_id>", .type = OptionType::kMagCalibration, .description = "per device"},
  };
  return table;
}

v1::SessionHeader header_with(const std::map<std::string, std::string>& options) {
  v1::SessionHeader header;
  for (const auto& [key, value] : options) (*header.mutable_options())[key] = value;
  return header;
}

// `read` on a header setting key = value throws kInvalidArgument naming the option, with the value
// and `rule` in the message.
void expect_refused(const std::string& key, const std::string& value, const std::string& rule,
                    const std::function<void(const OptionReader&)>& read) {
  SCOPED_TRACE(key + " = '" + value + "'");
  const v1::SessionHeader header = header_with({{key, value}});
  const OptionReader options(test_table(), header);
  try {
    read(options);
    ADD_FAILURE() << "accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kInvalidArgument);
    EXPECT_EQ(e.field(), "header.options[" + key + "]");
    EXPECT_NE(std::string(e.what()).find("'" + value + "'"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find(rule), std::string::npos) << e.what();
  }
}

void expect_bug(const std::function<void()>& read) {
  try {
    read();
    ADD_FAILURE() << "accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kInternal) << e.what();
  }
}

TEST(OptionReader, UnsetOptionsTakeTheTablesDefaults) {
  const v1::SessionHeader header;
  const OptionReader options(test_table(), header);
  EXPECT_TRUE(options.boolean("t.flag"));
  EXPECT_EQ(options.integer("t.count"), 3);
  EXPECT_EQ(options.optional_integer("t.id"), std::nullopt);
  EXPECT_EQ(options.real("t.duration_s"), 5.0);
  EXPECT_EQ(options.word("t.tone_hz"), std::nullopt);
  EXPECT_EQ(options.real("t.tone_hz"), 2700.0);
  EXPECT_TRUE(options.choice_is("t.mode", "depth"));
  EXPECT_FALSE(options.choice_is("t.mode", "sdk"));
  EXPECT_EQ(options.quaternion("t.rotation"), std::nullopt);
  EXPECT_EQ(options.mag_calibration("t.mag.left"), std::nullopt);
  EXPECT_FALSE(options.given("t.count"));
}

TEST(OptionReader, SetOptionsAreParsedAsTheirType) {
  imu::MagCalibration calibration;
  calibration.center_uT = imu::Vec3(1, 2, 3);
  const v1::SessionHeader header = header_with({{"t.flag", "0"},
                                                {"t.count", "9"},
                                                {"t.id", "4294967295"},
                                                {"t.duration_s", "120"},
                                                {"t.tone_hz", "auto"},
                                                {"t.mode", "sdk"},
                                                {"t.rotation", "0, 0, 0, 1.0004"},
                                                {"t.mag.left", format_mag_calibration(calibration)}});
  const OptionReader options(test_table(), header);
  EXPECT_FALSE(options.boolean("t.flag"));
  EXPECT_EQ(options.integer("t.count"), 9);  // the bounds are inclusive
  EXPECT_EQ(options.optional_integer("t.id"), 4294967295);
  EXPECT_EQ(options.real("t.duration_s"), 120.0);
  EXPECT_EQ(options.word("t.tone_hz"), "auto");
  EXPECT_TRUE(options.choice_is("t.mode", "sdk"));
  const auto rotation = options.quaternion("t.rotation");
  ASSERT_TRUE(rotation);
  EXPECT_DOUBLE_EQ(rotation->norm(), 1.0);  // normalised
  EXPECT_DOUBLE_EQ(rotation->z(), 1.0);
  const auto mag = options.mag_calibration("t.mag.left");
  ASSERT_TRUE(mag);
  EXPECT_EQ(mag->center_uT, calibration.center_uT);
  EXPECT_EQ(options.mag_calibration("t.mag.right"), std::nullopt);
  EXPECT_TRUE(options.given("t.count"));
}

TEST(OptionReader, ValuesOutOfRangeAreRefused) {
  const auto duration = [](const OptionReader& o) { o.real("t.duration_s"); };
  for (const char* value : {"0", "-1", "120.5", "1e300", "inf", "-inf", "nan"}) {
    expect_refused("t.duration_s", value, "must be a number in (0, 120] s", duration);
  }
  const auto count = [](const OptionReader& o) { o.integer("t.count"); };
  for (const char* value : {"0", "10", "-3"}) expect_refused("t.count", value, "must be an integer in [1, 9]", count);
  const auto id = [](const OptionReader& o) { o.optional_integer("t.id"); };
  for (const char* value : {"-1", "4294967296"})
    expect_refused("t.id", value, "must be an integer in [0, 4294967295]", id);
  expect_refused("t.tone_hz", "0", "must be a number > 0 Hz or 'auto'",
                 [](const OptionReader& o) { o.real("t.tone_hz"); });
}

TEST(OptionReader, ValuesOfTheWrongTypeAreRefused) {
  const auto flag = [](const OptionReader& o) { o.boolean("t.flag"); };
  for (const char* value : {"yes", "on", "2", "TRUE", ""})
    expect_refused("t.flag", value, "must be true or false", flag);
  const auto count = [](const OptionReader& o) { o.integer("t.count"); };
  for (const char* value : {"2.5", "three", "+3", " 3", ""}) {
    expect_refused("t.count", value, "must be an integer in [1, 9]", count);
  }
  const auto duration = [](const OptionReader& o) { o.real("t.duration_s"); };
  for (const char* value : {"soon", "5s", ""}) expect_refused("t.duration_s", value, "must be a number", duration);
  const auto tone = [](const OptionReader& o) {
    if (!o.word("t.tone_hz")) o.real("t.tone_hz");
  };
  expect_refused("t.tone_hz", "loud", "must be a number > 0 Hz or 'auto'", tone);
  const auto rotation = [](const OptionReader& o) { o.quaternion("t.rotation"); };
  expect_refused("t.rotation", "1 0 0", "expected four numbers 'w x y z'", rotation);
  expect_refused("t.rotation", "2 0 0 0", "not a unit quaternion", rotation);
  expect_refused("t.rotation", "1 0 0 x", "expected four numbers 'w x y z'", rotation);
  expect_refused("t.mag.left", "1 2 3", "expected 12 numbers",
                 [](const OptionReader& o) { o.mag_calibration("t.mag.left"); });
}

TEST(OptionReader, UnknownChoicesAreRefused) {
  const auto mode = [](const OptionReader& o) { o.choice_is("t.mode", "depth"); };
  for (const char* value : {"laser", "Depth", ""}) expect_refused("t.mode", value, "must be 'depth' or 'sdk'", mode);
}

TEST(OptionReader, ReadingAKeyNotInTheTableOrAsAnotherTypeIsABug) {
  const v1::SessionHeader header = header_with({{"t.tone_hz", "auto"}});
  const OptionReader options(test_table(), header);
  expect_bug([&] { options.real("t.missing"); });
  expect_bug([&] { options.given("t.missing"); });
  expect_bug([&] { options.real("t.flag"); });
  expect_bug([&] { options.boolean("t.count"); });
  expect_bug([&] { options.integer("t.id"); });               // no default: read as optional
  expect_bug([&] { options.real("t.tone_hz"); });             // holds its word: ask word() first
  expect_bug([&] { options.choice_is("t.mode", "laser"); });  // not one of its choices
}

TEST(OptionTable, FamiliesMatchTheirMembers) {
  EXPECT_EQ(find_option(test_table(), "t.mag.left"), &test_table().back());
  EXPECT_EQ(find_option(test_table(), "t.mag."), nullptr);
  EXPECT_EQ(find_option(test_table(), "t.count"), &test_table()[1]);
  EXPECT_EQ(find_option(test_table(), "t.counts"), nullptr);
}

TEST(OptionTable, ValuesAreDescribedForPeople) {
  const OptionTable& t = test_table();
  EXPECT_EQ(describe_values(t[0]), "true or false");
  EXPECT_EQ(describe_values(t[1]), "an integer in [1, 9]");
  EXPECT_EQ(describe_values_and_unit(t[3]), "a number in (0, 120] s");
  EXPECT_EQ(describe_values_and_unit(t[4]), "a number > 0 Hz or 'auto'");
  EXPECT_EQ(describe_values(t[4]), "a number > 0 or 'auto'");
  EXPECT_EQ(describe_values(t[5]), "'depth' or 'sdk'");
  EXPECT_EQ(describe_values(t[6]), "a unit quaternion 'w x y z'");
  EXPECT_EQ(option_field("t.count"), "header.options[t.count]");
}

}  // namespace
}  // namespace posefuse::session
