// Input files (scenes, meshes, MTL files, images) as every reader opens them: the check each goes through
// before its reader sees it, so that a directory or a missing file is named as such rather than as what
// a library made of it ("basic_filebuf::underflow error", "no faces"); lines split as tinyobjloader splits
// them; and file names as exporters write them.
#pragma once
#include <cctype>
#include <cerrno>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "scene/scene_error.h"

// How messages about one kind of input file speak of it.
struct InputKind {
  const char* file;      // "cannot open the mesh file"
  const char* expected;  // "is a directory, expected a Wavefront OBJ file"
  const char* content;   // "looks like a Git LFS pointer, not a mesh"
};
inline constexpr InputKind kSceneInput{"scene file", "a JSON scene file", "a scene"};
inline constexpr InputKind kMeshInput{"mesh file", "an OBJ, PLY, STL or OFF mesh file", "a mesh"};
inline constexpr InputKind kMaterialInput{"material file", "an MTL material file", "a material file"};
inline constexpr InputKind kBufferInput{"buffer file", "a glTF buffer file", "a glTF buffer"};
inline constexpr InputKind kImageInput{"image file", "an image file (PNG, JPEG, BMP, TGA, Radiance HDR or OpenEXR)",
                                         "an image"};

// The file name's extension in lower case (".PLY" -> ".ply"; "" for none): readers are chosen by it.
inline std::string lower_extension(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
  return ext;
}

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

// nlohmann's "[json.exception.parse_error.101] parse error at line 5, column 1: syntax error ..." in our
// form, "FILE:5:1: malformed JSON: syntax error ...", keeping nlohmann's description of what is wrong.
inline std::string malformed_json_message(const std::string& path, const std::string& what) {
  size_t line = 0, column = 0, at = what.find("at line ");
  if (at != std::string::npos) std::sscanf(what.c_str() + at, "at line %zu, column %zu", &line, &column);
  size_t colon = what.find(": ", at == std::string::npos ? 0 : at);
  return path + (line > 0 ? ":" + std::to_string(line) + ":" + std::to_string(column) : "") +
         ": malformed JSON: " + (colon == std::string::npos ? "syntax error" : what.substr(colon + 2));
}

// Reads one line, ended by \n, \r\n or a lone \r (without it); false at the end of the input. This is
// how tinyobjloader splits lines (its safeGetline), so that our line numbers and face counts are its.
inline bool read_line(std::istream& in, std::string& line) {
  line.clear();
  std::streambuf& buffer = *in.rdbuf();
  int c = buffer.sbumpc();
  if (c == EOF) return false;
  for (; c != EOF && c != '\n'; c = buffer.sbumpc()) {
    if (c == '\r') {
      if (buffer.sgetc() == '\n') buffer.sbumpc();
      break;
    }
    line += char(c);
  }
  return true;
}

// The file that `name` (as an OBJ or MTL file writes it) names relative to `dir`. Exporters on Windows
// write "textures\wood.png": when the name as written is not found but is with each backslash read as a
// directory separator ("\ " as an escaped space), that file is taken, with a warning naming `where`.
inline std::string resolve_written_path(const std::filesystem::path& dir, const std::string& name,
                                        const std::string& where, std::vector<std::string>& warnings) {
  std::string written = (dir / name).string();
  if (name.find('\\') == std::string::npos || std::filesystem::exists(written)) return written;
  std::string slashed;
  for (size_t i = 0; i < name.size(); ++i) {
    if (name[i] != '\\')
      slashed += name[i];
    else if (i + 1 < name.size() && name[i + 1] == ' ')
      slashed += name[++i];
    else
      slashed += '/';
  }
  std::string alternative = (dir / slashed).string();
  if (!std::filesystem::exists(alternative)) return written;
  warnings.push_back(where + ": \"" + name + "\" not found, read as \"" + slashed +
                     "\" (backslashes taken as directory separators)");
  return alternative;
}
