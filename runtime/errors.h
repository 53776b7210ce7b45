// Failures and how the command line maps them to exit codes: bad usage and bad input exit with 2
// (SceneError in scene/ and UsageError), failures of the device, the kernel build or I/O with 1.
#pragma once
#include <stdexcept>
#include <string>

struct UsageError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

struct RuntimeFailure : std::runtime_error {
  using std::runtime_error::runtime_error;
};
