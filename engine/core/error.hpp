#pragma once
// Errors at the edges. InputError is bad input a person can fix (a malformed scenario, a missing
// mesh): the CLI prints its message and exits with code 2. Anything else is an internal error.
#include <stdexcept>
#include <string>

namespace phaco {

class InputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace phaco
