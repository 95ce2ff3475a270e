#pragma once
// Test support: run f and expect std::invalid_argument whose message names `field`; or get the
// message of the phaco::InputError f throws, to check it names the file and the field.
#include <gtest/gtest.h>

#include <stdexcept>
#include <string>

#include "engine/core/error.hpp"

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

// The message of the InputError `f` throws; a test failure (and "") when it throws none.
template <class F>
std::string input_error_of(F&& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  ADD_FAILURE() << "expected an InputError";
  return {};
}

}  // namespace phaco::test
