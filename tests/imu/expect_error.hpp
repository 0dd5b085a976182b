#pragma once
// Asserts that `call` throws posefuse::Error with the given code and field, and (if given) a
// message containing `message_part`.
#include <gtest/gtest.h>

#include <string>

#include "common/error.hpp"

namespace posefuse::testing {

template <typename Call>
void expect_error(Call&& call, ErrorCode code, const std::string& field, const std::string& message_part = "") {
  try {
    call();
    ADD_FAILURE() << "expected posefuse::Error on " << field;
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), code) << e.what();
    EXPECT_EQ(e.field(), field) << e.what();
    EXPECT_NE(std::string(e.what()).find(message_part), std::string::npos) << e.what();
  }
}

}  // namespace posefuse::testing
