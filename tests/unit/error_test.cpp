#include "renderer/base/error.hpp"

#include <gtest/gtest.h>

#include <string>

namespace bounce {
namespace {

TEST(Error, CheckNamesTheConditionTheValuesAndWhere) {
    const int value = 3;
    const unsigned line = __LINE__ + 2;
    try {
        BOUNCE_CHECK(value == 4, "value is {}", value);
        FAIL() << "BOUNCE_CHECK did not throw";
    } catch (const Error& error) {
        EXPECT_EQ(std::string(error.what()),
                  "check failed: value == 4: value is 3 (error_test.cpp:" + std::to_string(line) + ")");
    }
}

TEST(Error, FailNamesWhere) {
    const unsigned line = __LINE__ + 2;
    try {
        BOUNCE_FAIL("no {} here", "luck");
        FAIL() << "BOUNCE_FAIL did not throw";
    } catch (const Error& error) {
        EXPECT_EQ(std::string(error.what()), "no luck here (error_test.cpp:" + std::to_string(line) + ")");
    }
}

}  // namespace
}  // namespace bounce
