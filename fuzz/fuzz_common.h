// Shared by the libFuzzer targets: a per-process scratch directory for the files the loaders read.
#pragma once
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <system_error>

namespace fuzz {

// Inputs larger than this are skipped so that every iteration stays fast.
constexpr size_t kMaxInputBytes = 64 * 1024;

// A unit cube of quads, counter-clockwise seen from outside: what scenes name as "file": "m.obj".
constexpr const char kCubeObj[] =
    "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n"
    "f 1 4 3 2\nf 5 6 7 8\nf 1 2 6 5\nf 4 8 7 3\nf 1 5 8 4\nf 2 3 7 6\n";

// A fresh directory under /dev/shm (else the system temp directory), removed at normal exit.
class ScratchDir {
 public:
  ScratchDir() {
    std::error_code ec;
    std::filesystem::path base = std::filesystem::is_directory("/dev/shm", ec) ? std::filesystem::path("/dev/shm")
                                                                             : std::filesystem::temp_directory_path();
    std::string pattern = (base / "pathcl-fuzz-XXXXXX").string();
    if (!mkdtemp(pattern.data())) {
      std::perror("pathcl fuzz: mkdtemp");
      std::abort();
    }
    dir_ = pattern;
    write("m.obj", kCubeObj, sizeof kCubeObj - 1);
  }
  ~ScratchDir() {
    std::error_code ec;
    std::filesystem::remove_all(dir_, ec);
  }
  // Writes the bytes to dir/name (replacing it) and returns the path.
  std::string write(const char* name, const void* data, size_t size) const {
    std::string path = (dir_ / name).string();
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(static_cast<const char*>(data), static_cast<std::streamsize>(size));
    out.close();
    if (!out) {
      std::fprintf(stderr, "pathcl fuzz: cannot write %s\n", path.c_str());
      std::abort();
    }
    return path;
  }
  const std::filesystem::path& dir() const { return dir_; }

 private:
  std::filesystem::path dir_;
};

inline const ScratchDir& scratch() {
  static const ScratchDir dir;
  return dir;
}

// A broken invariant: report and crash so that libFuzzer keeps the input.
[[noreturn]] inline void invariant_failed(const char* what) {
  std::fprintf(stderr, "pathcl fuzz: invariant failed: %s\n", what);
  std::abort();
}

}  // namespace fuzz
