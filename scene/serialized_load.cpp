// Mitsuba's .serialized meshes, format versions 3 and 4 (Mitsuba 0.6's documentation of the serialized
// shape; Mitsuba 3's src/shapes/serialized.cpp reads them the same way). A file is one or more shapes,
// each a 4-byte header (uint16 identifier 0x041C, uint16 version) and a zlib stream holding, little-endian:
// uint32 flags; version 4: the shape's name, NUL-terminated; uint64 vertex and triangle counts; positions,
// then normals (flag 0x0001), texture coordinates (0x0002) and colours (0x0008) per vertex, in float or
// double (0x2000); then uint32 index triples. After the last shape, a table of each shape's byte offset
// (uint64 in version 4, uint32 in version 3) and a uint32 count of shapes.
//
// The decompressed data is taken as it arrives, in growing chunks, and the counts are checked against
// it: a garbled count of 2^32 vertices over a few bytes of data fails when the data ends, having
// allocated no more than that data. The stream is inflated to its end so that zlib checks its checksum.
#include "scene/serialized_load.h"

#include <cctype>
#include <filesystem>
#include <algorithm>
#include <bit>
#include <climits>
#include <cmath>
#include <cstdio>
#include <new>

// zlib (Debian's zlib1g-dev, installed as a dependency of libpng-dev).
#include <zlib.h>

#include "scene/input_file.h"
#include "scene/scene_error.h"

namespace {

constexpr uint16_t kIdentifier = 0x041C;
constexpr uint32_t kHasNormals = 0x0001, kHasTexcoords = 0x0002, kHasColors = 0x0008, kFaceNormals = 0x0010,
                   kSinglePrecision = 0x1000, kDoublePrecision = 0x2000;
// Version 4's shape names: longer ones are garbled data without a NUL.
constexpr size_t kMaxNameBytes = size_t(1) << 16;
// Vertices and triangles of one shape: 32-bit indices (a file with more vertices stores 64-bit ones).
constexpr uint64_t kMaxCount = uint64_t(1) << 32;

template <class T>
T read_le(const char* bytes) {
  T value = 0;
  for (size_t i = 0; i < sizeof(T); ++i) value |= T(static_cast<unsigned char>(bytes[i])) << (8 * i);
  return value;
}

std::string hex(uint32_t value, int digits) {
  char text[16];
  std::snprintf(text, sizeof text, "0x%0*X", digits, unsigned(value));
  return text;
}

// A shape's zlib stream, inflated into `data` as far as asked.
class ShapeStream {
 public:
  ShapeStream(const std::string& where, const char* compressed, size_t size)
      : where_(where), next_(compressed), left_(size) {
    if (inflateInit(&z_) != Z_OK) throw SceneError(where_ + ": zlib cannot start inflating (out of memory?)");
  }
  ~ShapeStream() { inflateEnd(&z_); }
  ShapeStream(const ShapeStream&) = delete;
  ShapeStream& operator=(const ShapeStream&) = delete;

  // Inflates until `data` holds at least `bytes`, or the stream ends: whether it holds them. `data` grows
  // by at most what it holds already (64 KiB at first), never by more than asked.
  bool fill(uint64_t bytes) {
    while (data.size() < bytes && !ended_) {
      const size_t have = data.size();
      const size_t grow = size_t(std::min<uint64_t>(std::max<size_t>(have, size_t(1) << 16), bytes - have));
      data.resize(have + grow);
      data.resize(have + inflate_into(data.data() + have, grow));
    }
    return data.size() >= bytes;
  }

  // Inflates the rest of the stream (to its checksum) without keeping it: the bytes it held.
  uint64_t finish() {
    uint64_t rest = 0;
    char scratch[1 << 14];
    while (!ended_) rest += inflate_into(scratch, sizeof scratch);
    return rest;
  }

  std::string data;

 private:
  size_t inflate_into(char* out, size_t size) {
    size_t done = 0;
    while (done < size && !ended_) {
      if (z_.avail_in == 0 && left_ > 0) {  // avail_in is 32-bit: a larger stream in pieces
        z_.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(next_));
        z_.avail_in = uInt(std::min<size_t>(left_, UINT_MAX));
        next_ += z_.avail_in;
        left_ -= z_.avail_in;
      }
      const uInt chunk = uInt(std::min<size_t>(size - done, UINT_MAX));
      z_.next_out = reinterpret_cast<Bytef*>(out + done);
      z_.avail_out = chunk;
      const int rc = inflate(&z_, Z_NO_FLUSH);
      done += chunk - z_.avail_out;
      if (rc == Z_STREAM_END) {
        ended_ = true;
      } else if (rc == Z_DATA_ERROR || rc == Z_NEED_DICT || rc == Z_STREAM_ERROR) {
        throw SceneError(where_ + ": corrupt zlib data (zlib: " +
                         (z_.msg ? std::string(z_.msg) : rc == Z_NEED_DICT ? "needs a preset dictionary" : "stream error") + ")");
      } else if (rc == Z_MEM_ERROR) {
        throw std::bad_alloc();
      } else if (z_.avail_in == 0 && left_ == 0 && (rc == Z_BUF_ERROR || z_.avail_out > 0)) {
        // Everything given was read and the stream goes on: the file ends inside it.
        throw SceneError(where_ + ": truncated serialized file: its zlib stream is cut short (after " +
                         std::to_string(z_.total_in) + " compressed bytes, " + std::to_string(z_.total_out) +
                         " bytes of data)");
      }
    }
    return done;
  }

  std::string where_;
  const char* next_;
  size_t left_;
  z_stream z_{};
  bool ended_ = false;
};

// A position pathcl can hold: finite and within float range (as ply_stl_off_load.cpp asks).
bool position_in_range(const glm::dvec3& p) {
  const double m = 3.4028234663852886e38;
  return std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z) && std::abs(p.x) <= m &&
         std::abs(p.y) <= m && std::abs(p.z) <= m;
}

bool finite(const glm::vec2& v) { return std::isfinite(v.x) && std::isfinite(v.y); }
bool finite(const glm::vec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

// The byte offset of shape `shape_index` (> 0) from the table at the end of the file, and in *end where
// the shapes' data ends (where the table begins).
size_t shape_offset(const std::string& path, const std::string& file, uint16_t version, uint32_t shape_index,
                    size_t* end) {
  if (file.size() < 8)
    throw SceneError(path + ": shape_index " + std::to_string(shape_index) + ", but the file (" +
                     std::to_string(file.size()) + " bytes) has no table of shapes at its end");
  const uint32_t count = read_le<uint32_t>(file.data() + file.size() - 4);
  if (shape_index >= count)
    throw SceneError(path + ": shape_index " + std::to_string(shape_index) + ", but the file holds " +
                     (count == 0   ? std::string("no shapes (its table of shapes is empty)")
                      : count == 1 ? std::string("1 shape (0)")
                                   : std::to_string(count) + " shapes (0 to " + std::to_string(count - 1) + ")"));
  const uint64_t entry = version == 4 ? 8 : 4;
  const uint64_t table = uint64_t(count) * entry + 4;
  if (table > file.size() - 4)
    throw SceneError(path + ": truncated or garbled serialized file: its table of shapes lists " + std::to_string(count) +
                     " shapes, " + std::to_string(table) + " bytes, more than the file's " + std::to_string(file.size()) +
                     " after its header");
  *end = file.size() - size_t(table);
  const char* at = file.data() + *end + entry * shape_index;
  const uint64_t offset = entry == 8 ? read_le<uint64_t>(at) : read_le<uint32_t>(at);
  if (offset > *end || *end - offset < 4)
    throw SceneError(path + ": garbled table of shapes: shape " + std::to_string(shape_index) + " at byte offset " +
                     std::to_string(offset) + ", beyond the shapes' data (bytes 0 to " + std::to_string(*end) + ")");
  if (read_le<uint16_t>(file.data() + offset) != kIdentifier || read_le<uint16_t>(file.data() + offset + 2) != version)
    throw SceneError(path + ": garbled table of shapes: shape " + std::to_string(shape_index) + " at byte offset " +
                     std::to_string(offset) + " does not begin with a serialized header (" + hex(kIdentifier, 4) +
                     ", version " + std::to_string(version) + ")");
  return size_t(offset);
}

}  // namespace

PolygonSoup load_serialized(const std::string& path, uint32_t shape_index, std::vector<std::string>& warnings) {
  // The same checks as every input: a directory, a missing file, a Git LFS pointer.
  const std::string file = read_input_file(path, kMeshInput);
  if (file.size() < 4)
    throw SceneError(path + ": truncated serialized file: " + std::to_string(file.size()) +
                     " bytes, less than the 4 of its header");
  const uint16_t identifier = read_le<uint16_t>(file.data()), version = read_le<uint16_t>(file.data() + 2);
  if (identifier != kIdentifier)
    throw SceneError(path + ": not a Mitsuba serialized mesh: it begins with " + hex(identifier, 4) +
                     ", not the format identifier " + hex(kIdentifier, 4));
  if (version != 3 && version != 4)
    throw SceneError(path + ": serialized format version " + std::to_string(version) +
                     ", but pathcl reads versions 3 and 4");

  size_t begin = 0, end = file.size();
  if (shape_index > 0) begin = shape_offset(path, file, version, shape_index, &end);
  const std::string where = path + ": shape " + std::to_string(shape_index);
  ShapeStream z(where, file.data() + begin + 4, end - begin - 4);
  auto cut_short = [&](const std::string& what) {
    return SceneError(where + ": truncated or garbled serialized data: it ends " + what + " (" +
                      std::to_string(z.data.size()) + " bytes decompressed)");
  };

  if (!z.fill(4)) throw cut_short("before its flags");
  const uint32_t flags = read_le<uint32_t>(z.data.data());
  size_t at = 4;
  if ((flags & kSinglePrecision) && (flags & kDoublePrecision))
    throw SceneError(where + ": garbled flags " + hex(flags, 8) +
                     ": both single (0x1000) and double (0x2000) precision");
  if (version == 4) {  // the name, read past
    size_t nul;
    while ((nul = z.data.find('\0', at)) == std::string::npos) {
      if (z.data.size() - at > kMaxNameBytes)
        throw SceneError(where + ": garbled serialized data: no NUL ends the shape's name within its first " +
                         std::to_string(kMaxNameBytes) + " bytes");
      const size_t before = z.data.size();
      z.fill(before + 4096);
      if (z.data.size() == before) throw cut_short("inside the shape's name");
    }
    at = nul + 1;
  }
  if (!z.fill(at + 16)) throw cut_short("before its vertex and triangle counts");
  const uint64_t vertex_count = read_le<uint64_t>(z.data.data() + at);
  const uint64_t triangle_count = read_le<uint64_t>(z.data.data() + at + 8);
  at += 16;
  if (vertex_count > kMaxCount || triangle_count > kMaxCount - 1)
    throw SceneError(where + ": " + std::to_string(vertex_count) + " vertices and " + std::to_string(triangle_count) +
                     " triangles, more than pathcl reads in one shape (2^32 vertices, 2^32 - 1 triangles)");

  // Mitsuba reads single precision unless the double precision flag is set (either may be set).
  const bool double_precision = flags & kDoublePrecision;
  const bool normals = flags & kHasNormals, uvs = flags & kHasTexcoords, colors = flags & kHasColors;
  const bool keep_normals = normals && !(flags & kFaceNormals);  // face normals: rendered flat
  const uint64_t scalar = double_precision ? 8 : 4;
  const uint64_t vertex_bytes = scalar * (3 + 3 * normals + 2 * uvs + 3 * colors);
  const uint64_t expected = at + vertex_count * vertex_bytes + triangle_count * 12;
  if (!z.fill(expected)) {
    std::string layout = "positions";
    if (normals) layout += ", normals";
    if (uvs) layout += ", texture coordinates";
    if (colors) layout += ", colours";
    throw SceneError(where + ": truncated or garbled serialized data: its counts of " + std::to_string(vertex_count) +
                     " vertices (" + layout + " in " + (double_precision ? "double" : "single") + " precision) and " +
                     std::to_string(triangle_count) + " triangles take " + std::to_string(expected) +
                     " bytes, but its zlib stream holds " + std::to_string(z.data.size()));
  }
  const uint64_t extra = z.data.size() - expected + z.finish();
  if (extra > 0)
    warnings.push_back(where + ": " + std::to_string(extra) + " bytes of data after its triangles ignored");
  if (triangle_count == 0) throw SceneError(where + ": no faces (" + std::to_string(vertex_count) + " vertices)");

  const char* bytes = z.data.data();
  auto real = [&](uint64_t i) -> double {  // value i of the arrays after the counts
    const char* p = bytes + at + i * scalar;
    return double_precision ? std::bit_cast<double>(read_le<uint64_t>(p)) : double(std::bit_cast<float>(read_le<uint32_t>(p)));
  };
  const size_t vertices = size_t(vertex_count), triangles = size_t(triangle_count);
  uint64_t next = 0;  // the next value of `real`

  PolygonSoup soup;
  soup.positions.resize(vertices);
  for (size_t j = 0; j < vertices; ++j, next += 3) {
    glm::dvec3& p = soup.positions[j];
    p = {real(next), real(next + 1), real(next + 2)};
    if (!position_in_range(p))
      throw SceneError(where + ": vertex " + std::to_string(j) + ": coordinate is not finite or beyond float range");
  }
  std::vector<glm::vec3> vertex_normals;
  if (keep_normals) {
    vertex_normals.resize(vertices);
    for (size_t j = 0; j < vertices; ++j) {
      vertex_normals[j] = glm::vec3(float(real(next + 3 * j)), float(real(next + 3 * j + 1)), float(real(next + 3 * j + 2)));
      if (!finite(vertex_normals[j]))
        throw SceneError(where + ": vertex " + std::to_string(j) + ": normal is not finite or beyond float range");
    }
  }
  if (normals) next += 3 * vertex_count;
  std::vector<glm::vec2> vertex_uvs;
  if (uvs) {
    vertex_uvs.resize(vertices);
    for (size_t j = 0; j < vertices; ++j, next += 2) {
      vertex_uvs[j] = glm::vec2(float(real(next)), float(1.0 - real(next + 1)));
      if (!finite(vertex_uvs[j]))
        throw SceneError(where + ": vertex " + std::to_string(j) + ": texture coordinate is not finite or beyond float range");
    }
  }
  std::vector<glm::vec3> vertex_colors;
  if (colors) {
    vertex_colors.resize(vertices);
    size_t clamped = 0;
    for (size_t j = 0; j < vertices; ++j, next += 3) {
      glm::vec3& c = vertex_colors[j];
      c = glm::vec3(float(real(next)), float(real(next + 1)), float(real(next + 2)));
      if (!finite(c)) throw SceneError(where + ": vertex " + std::to_string(j) + ": colour is not finite");
      for (int k = 0; k < 3; ++k)
        if (c[k] < 0 || c[k] > 1) c[k] = std::clamp(c[k], 0.0f, 1.0f), ++clamped;
    }
    if (clamped > 0)
      warnings.push_back(where + ": " + std::to_string(clamped) + " vertex colour values outside [0, 1] clamped");
  }

  const char* indices = bytes + at + next * scalar;
  soup.polygons.resize(triangles);
  if (keep_normals) soup.normals.resize(triangles);
  if (uvs) soup.uvs.resize(triangles);
  if (colors) soup.colors.resize(triangles);
  for (size_t t = 0; t < triangles; ++t) {
    std::vector<uint32_t>& polygon = soup.polygons[t];
    polygon.resize(3);
    for (int k = 0; k < 3; ++k) {
      polygon[k] = read_le<uint32_t>(indices + 12 * t + 4 * k);
      if (polygon[k] >= vertex_count)
        throw SceneError(where + ": triangle " + std::to_string(t) + ": vertex index " + std::to_string(polygon[k]) +
                         " out of range (" + std::to_string(vertex_count) + " vertices)");
    }
    if (keep_normals) soup.normals[t] = {vertex_normals[polygon[0]], vertex_normals[polygon[1]], vertex_normals[polygon[2]]};
    if (uvs) soup.uvs[t] = {vertex_uvs[polygon[0]], vertex_uvs[polygon[1]], vertex_uvs[polygon[2]]};
    if (colors) soup.colors[t] = {vertex_colors[polygon[0]], vertex_colors[polygon[1]], vertex_colors[polygon[2]]};
  }
  return soup;
}

bool is_serialized_file(const std::string& path) { return lower_extension(path) == ".serialized"; }
