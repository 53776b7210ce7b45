// Bad scene or mesh input: the message names the file and the place (JSON path or line) and what was
// expected. The command line maps it to exit code 2.
#pragma once
#include <stdexcept>
#include <string>

struct SceneError : std::runtime_error {
  using std::runtime_error::runtime_error;
};
