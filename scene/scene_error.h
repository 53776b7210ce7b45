// Bad scene or mesh input: the message names the file and the place (JSON path or line) and what was
// expected. The command line maps it to exit code 2. Also the check that every input file goes through
// before its reader sees it, so that a directory or a missing file is named as such rather than as what
// a library made of it ("basic_filebuf::underflow error", "no faces").
#pragma once
#include <cerrno>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <stdexcept>
#include <string>

struct SceneError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// How messages about one kind of input file speak of it.
struct InputKind {
  const char* file;      // "cannot open the mesh file"
  const char* expected;  // "is a directory, expected a Wavefront OBJ file"
  const char* content;   // "looks like a Git LFS pointer, not a mesh"
};
inline constexpr InputKind kSceneInput{"scene file", "a JSON scene file", "a scene"};
inline constexpr InputKind kMeshInput{"mesh file", "a Wavefront OBJ file", "a mesh"};
inline constexpr InputKind kMaterialInput{"material file", "an MTL material file", "a material file"};
inline constexpr InputKind kImageInput{"image file", "an image file (PNG, JPEG or OpenEXR)", "an image"};

// Reads up to `limit` bytes from the start of the file, or throws SceneError naming it: a directory, a
// file that cannot be opened (and why), or a Git LFS pointer (what a clone without git lfs has in place of
// its large files).
inline std::string read_input_file(const std::string& path, const InputKind& kind, size_t limit = SIZE_MAX) {
  std::error_code ignored;
  if (std::filesystem::is_directory(path, ignored)) throw SceneError(path + ": is a directory, expected " + kind.expected);
  errno = 0;
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    std::string why = errno == ENOENT ? "no such file" : errno == EACCES ? "permission denied"
                      : errno != 0    ? std::strerror(errno) : "";
    throw SceneError(path + ": cannot open the " + kind.file + (why.empty() ? "" : ": " + why));
  }
  std::string text;
  if (limit == SIZE_MAX) {
    text.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  } else {
    text.resize(limit);
    in.read(text.data(), std::streamsize(limit));
    text.resize(size_t(in.gcount()));
  }
  if (text.rfind("version https://git-lfs.github.com/spec/", 0) == 0)
    throw SceneError(path + ": looks like a Git LFS pointer, not " + kind.content + " (run git lfs pull)");
  return text;
}
