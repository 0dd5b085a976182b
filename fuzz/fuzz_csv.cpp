// The directory form's CSV reader and number / hex fields (session/text_fields.*) on arbitrary
// file bytes, with an IMU file's columns: every row is read and every field parsed as the
// directory reader parses it (integers, floats, doubles, hex payloads).
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>

#include "common/error.hpp"
#include "seeds.hpp"
#include "session/recording_file.hpp"
#include "session/text_fields.hpp"

using namespace posefuse;

namespace {
const std::vector<std::string> kColumns = {"t_us", "gx", "gy", "gz", "payload"};
}

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  fuzz::init_harness([] {
    return fuzz::Seeds{{"imu.csv",
                        "t_us,gx,gy,gz,payload\n1000,0.5,-1e-3,nan,00ff\n"
                        "2000,inf,-inf,3.25,\r\n\n-9223372036854775808,1,2,3,AbCd\n"}};
  });
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  try {
    session::UniqueFd file(fuzz::memory_file(data, size));
    session::CsvReader csv(std::make_unique<session::FdInputStream>(std::move(file)), "imu/x.csv", kColumns);
    while (csv.next()) {
      try {
        const std::int64_t t = session::parse_int64(csv.at(0), csv.field(0));
        if (session::parse_int64(std::to_string(t), "t") != t) fuzz::invariant_failed("int64 round trip");
        (void)session::parse_uint64(csv.at(0), csv.field(0));
      } catch (const Error&) {
      }
      try {
        const double d = session::parse_double(csv.at(1), csv.field(1));
        const double back = session::parse_double(session::format_double(d), "d");
        if (!(back == d || (d != d && back != back))) fuzz::invariant_failed("double round trip");
        const float f = session::parse_float(csv.at(2), csv.field(2));
        const float fback = session::parse_float(session::format_float(f), "f");
        if (!(fback == f || (f != f && fback != fback))) fuzz::invariant_failed("float round trip");
      } catch (const Error&) {
      }
      try {
        const std::string bytes = session::from_hex(csv.at(4), csv.field(4));
        if (session::from_hex(session::to_hex(bytes), "hex") != bytes) fuzz::invariant_failed("hex round trip");
      } catch (const Error&) {
      }
    }
  } catch (const Error&) {
  }
  return 0;
}
