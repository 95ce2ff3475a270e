#pragma once
// Test support: run f and expect std::invalid_argument whose message names `field`.
#include <gtest/gtest.h>

#include <stdexcept>
#include <string>

namespace phaco::test {

template <class F>
void expect_invalid(F&& f, const std::string& field) {
  try {
    f();
    ADD_FAILURE() << "expected std::invalid_argument naming '" << field << "'";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find(field), std::string::npos)
        << "message '" << e.what() << "' does not name '" << field << "'";
  }
}

}  // namespace phaco::test
