// Mitsuba's .serialized meshes (scene/serialized_load.cpp): files this test writes itself with zlib, in
// format versions 4 (single precision, a shape name, a table of uint64 offsets) and 3 (double precision,
// uint32 offsets), read back exactly: positions, triangles, per-corner normals, texture coordinates and
// colours; shape_index picks the shape; face normals leave the corners without normals; each defect of a
// file is a SceneError naming the file and what is wrong.
#include <bit>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <limits>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <zlib.h>

#include "scene/scene_error.h"
#include "scene/serialized_load.h"
#include "test_support.h"

namespace {

constexpr uint32_t kNormals = 0x0001, kUvs = 0x0002, kColors = 0x0008, kFaceNormals = 0x0010, kSingle = 0x1000,
                   kDouble = 0x2000;

template <class T>
void put(std::string& out, T value) {
  for (size_t i = 0; i < sizeof(T); ++i) out += char(uint8_t(uint64_t(value) >> (8 * i)));
}

void put_real(std::string& out, double value, bool double_precision) {
  if (double_precision)
    put(out, std::bit_cast<uint64_t>(value));
  else
    put(out, std::bit_cast<uint32_t>(float(value)));
}

// One shape's data before compression. The counts default to the arrays' sizes.
struct Shape {
  uint32_t flags = kSingle;
  std::string name = "mesh";
  std::vector<double> positions, normals, uvs, colors;
  std::vector<uint32_t> indices;
  int64_t vertex_count = -1, triangle_count = -1;
};

std::string shape_data(const Shape& s, uint16_t version) {
  const bool dp = s.flags & kDouble;
  std::string out;
  put(out, s.flags);
  if (version == 4) out += s.name + '\0';
  put(out, uint64_t(s.vertex_count >= 0 ? s.vertex_count : int64_t(s.positions.size() / 3)));
  put(out, uint64_t(s.triangle_count >= 0 ? s.triangle_count : int64_t(s.indices.size() / 3)));
  for (const std::vector<double>* values : {&s.positions, &s.normals, &s.uvs, &s.colors})
    for (double v : *values) put_real(out, v, dp);
  for (uint32_t i : s.indices) put(out, i);
  return out;
}

std::string zlib_compress(const std::string& data) {
  uLongf size = compressBound(uLong(data.size()));
  std::string out(size, '\0');
  EXPECT_EQ(compress(reinterpret_cast<Bytef*>(out.data()), &size, reinterpret_cast<const Bytef*>(data.data()),
                     uLong(data.size())),
            Z_OK);
  out.resize(size);
  return out;
}

// A file of the shapes' data, each after its header, and the table of shapes at its end (unless `table`
// is false, as a one-shape file may be).
std::string serialized_file(uint16_t version, const std::vector<std::string>& data, bool table = true) {
  std::string file;
  std::vector<uint64_t> offsets;
  for (const std::string& d : data) {
    offsets.push_back(file.size());
    put(file, uint16_t(0x041C));
    put(file, version);
    file += zlib_compress(d);
  }
  if (table) {
    for (uint64_t offset : offsets) version == 4 ? put(file, offset) : put(file, uint32_t(offset));
    put(file, uint32_t(data.size()));
  }
  return file;
}

std::string write_binary(const std::string& name, const std::string& bytes) {
  const std::string path = temp_dir() + "/" + name;
  std::ofstream(path, std::ios::binary) << bytes;
  return path;
}

std::string load_error(const std::string& path, uint32_t shape_index = 0) {
  std::vector<std::string> warnings;
  try {
    load_serialized(path, shape_index, warnings);
  } catch (const SceneError& e) {
    return e.what();
  }
  return "";
}

// A unit quad (two triangles) with normals and texture coordinates, and a plain triangle.
Shape quad_shape(uint32_t precision) {
  Shape s;
  s.flags = precision | kNormals | kUvs;
  s.name = "Quad";
  s.positions = {0, 0, 0, 1.5, 0, 0, 1.5, -2.25, 0, 0, -2.25, 0.125};
  s.normals = {0, 0, 1, 0.5, 0, 1, 0, 0.25, 1, 0, 0, -1};
  s.uvs = {0, 0, 1, 0, 1, 0.75, 0.25, 1};
  s.indices = {0, 1, 2, 0, 2, 3};
  return s;
}

Shape triangle_shape(uint32_t precision) {
  Shape s;
  s.flags = precision;
  s.name = "Triangle";
  s.positions = {10, 20, 30, 11, 20, 30, 10, 21, 30};
  s.indices = {0, 2, 1};
  return s;
}

glm::dvec3 position(const Shape& s, uint32_t v) {
  return {s.positions[3 * v], s.positions[3 * v + 1], s.positions[3 * v + 2]};
}

// The soup holds the shape's vertices and triangles, and per corner the normals, (u, 1 - v) and colours
// the shape has, as floats.
void expect_shape(const PolygonSoup& soup, const Shape& s, bool normals_expected) {
  ASSERT_EQ(soup.positions.size(), s.positions.size() / 3);
  for (uint32_t v = 0; v < soup.positions.size(); ++v) EXPECT_EQ(soup.positions[v], position(s, v)) << "vertex " << v;
  ASSERT_EQ(soup.polygons.size(), s.indices.size() / 3);
  for (size_t t = 0; t < soup.polygons.size(); ++t)
    EXPECT_EQ(soup.polygons[t], (std::vector<uint32_t>{s.indices[3 * t], s.indices[3 * t + 1], s.indices[3 * t + 2]}));
  auto corners = [&](size_t t, auto make) {
    std::vector<decltype(make(0u))> out;
    for (int k = 0; k < 3; ++k) out.push_back(make(s.indices[3 * t + k]));
    return out;
  };
  EXPECT_EQ(soup.normals.size(), normals_expected ? soup.polygons.size() : 0);
  for (size_t t = 0; t < soup.normals.size(); ++t)
    EXPECT_EQ(soup.normals[t], corners(t, [&](uint32_t v) {
                return glm::vec3(float(s.normals[3 * v]), float(s.normals[3 * v + 1]), float(s.normals[3 * v + 2]));
              }));
  EXPECT_EQ(soup.uvs.size(), s.uvs.empty() ? 0 : soup.polygons.size());
  for (size_t t = 0; t < soup.uvs.size(); ++t)
    EXPECT_EQ(soup.uvs[t], corners(t, [&](uint32_t v) { return glm::vec2(float(s.uvs[2 * v]), float(1 - s.uvs[2 * v + 1])); }));
  EXPECT_EQ(soup.colors.size(), s.colors.empty() ? 0 : soup.polygons.size());
  for (size_t t = 0; t < soup.colors.size(); ++t)
    EXPECT_EQ(soup.colors[t], corners(t, [&](uint32_t v) {
                return glm::vec3(float(s.colors[3 * v]), float(s.colors[3 * v + 1]), float(s.colors[3 * v + 2]));
              }));
  EXPECT_TRUE(soup.materials.empty());
}

TEST(Serialized, Version4TwoShapesInSinglePrecision) {
  const Shape quad = quad_shape(kSingle), triangle = triangle_shape(kSingle);
  const std::string path =
      write_binary("two_v4.serialized", serialized_file(4, {shape_data(quad, 4), shape_data(triangle, 4)}));
  std::vector<std::string> warnings;
  expect_shape(load_serialized(path, 0, warnings), quad, true);
  expect_shape(load_serialized(path, 1, warnings), triangle, false);
  EXPECT_TRUE(warnings.empty());
}

TEST(Serialized, Version3TwoShapesInDoublePrecision) {
  // Values that float would round: read back as the doubles they are.
  Shape quad = quad_shape(kDouble);
  quad.positions = {0.1, 1 + 1e-9, -123456.789012345, 1e-300, 2.0 / 3, 0, 1, 1, 1, 0.3, 0.7, 1e30};
  quad.uvs = {0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8};
  Shape colored = triangle_shape(kDouble);
  colored.flags |= kColors;
  colored.colors = {0.25, 0.5, 1, 0, 0.1, 0.2, 1, 1, 1};
  const std::string path =
      write_binary("two_v3.serialized", serialized_file(3, {shape_data(colored, 3), shape_data(quad, 3)}));
  std::vector<std::string> warnings;
  expect_shape(load_serialized(path, 1, warnings), quad, true);
  expect_shape(load_serialized(path, 0, warnings), colored, false);
  EXPECT_TRUE(warnings.empty());
}

TEST(Serialized, FirstShapeNeedsNoTable) {
  const Shape triangle = triangle_shape(kSingle);
  const std::string path = write_binary("no_table.serialized", serialized_file(4, {shape_data(triangle, 4)}, false));
  std::vector<std::string> warnings;
  expect_shape(load_serialized(path, 0, warnings), triangle, false);
  EXPECT_TRUE(warnings.empty());
}

TEST(Serialized, FaceNormalsLeaveTheCornersWithoutNormals) {
  Shape quad = quad_shape(kSingle);
  quad.flags |= kFaceNormals;
  const std::string path = write_binary("face_normals.serialized", serialized_file(4, {shape_data(quad, 4)}));
  std::vector<std::string> warnings;
  expect_shape(load_serialized(path, 0, warnings), quad, false);
  EXPECT_TRUE(warnings.empty());
}

TEST(Serialized, ColoursOutsideTheUnitRangeAreClampedWithAWarning) {
  Shape s = triangle_shape(kSingle);
  s.flags |= kColors;
  s.colors = {1.5, 0.5, -0.25, 0, 0, 0, 1, 1, 1};
  const std::string path = write_binary("bright.serialized", serialized_file(4, {shape_data(s, 4)}));
  std::vector<std::string> warnings;
  const PolygonSoup soup = load_serialized(path, 0, warnings);
  ASSERT_EQ(soup.colors.size(), 1u);
  EXPECT_EQ(soup.colors[0][0], glm::vec3(1, 0.5f, 0));  // vertex 0, then 2, then 1
  EXPECT_EQ(soup.colors[0][1], glm::vec3(1, 1, 1));
  EXPECT_EQ(soup.colors[0][2], glm::vec3(0, 0, 0));
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_EQ(warnings[0], path + ": shape 0: 2 vertex colour values outside [0, 1] clamped");
}

TEST(Serialized, DataAfterTheTrianglesIsIgnoredWithAWarning) {
  const Shape s = triangle_shape(kSingle);
  const std::string path =
      write_binary("trailing.serialized", serialized_file(4, {shape_data(s, 4) + std::string(10, 'x')}));
  std::vector<std::string> warnings;
  expect_shape(load_serialized(path, 0, warnings), s, false);
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_EQ(warnings[0], path + ": shape 0: 10 bytes of data after its triangles ignored");
}

TEST(Serialized, BadIdentifierOrVersion) {
  std::string file = serialized_file(4, {shape_data(triangle_shape(kSingle), 4)});
  file[0] = 'P', file[1] = 'K';
  std::string path = write_binary("zip.serialized", file);
  EXPECT_EQ(load_error(path), path + ": not a Mitsuba serialized mesh: it begins with 0x4B50, not the format identifier 0x041C");
  path = write_binary("v5.serialized", serialized_file(5, {shape_data(triangle_shape(kSingle), 4)}));
  EXPECT_EQ(load_error(path), path + ": serialized format version 5, but pathcl reads versions 3 and 4");
  path = write_binary("short.serialized", std::string("\x1c\x04\x04", 3));
  EXPECT_EQ(load_error(path), path + ": truncated serialized file: 3 bytes, less than the 4 of its header");
  EXPECT_EQ(load_error(temp_dir() + "/missing.serialized"), temp_dir() + "/missing.serialized: cannot open the mesh file: no such file");
}

TEST(Serialized, ShapeIndexBeyondTheCount) {
  const std::string path = write_binary(
      "two.serialized", serialized_file(4, {shape_data(quad_shape(kSingle), 4), shape_data(triangle_shape(kSingle), 4)}));
  EXPECT_EQ(load_error(path, 3), path + ": shape_index 3, but the file holds 2 shapes (0 to 1)");
  EXPECT_EQ(load_error(path, 2), path + ": shape_index 2, but the file holds 2 shapes (0 to 1)");
  const std::string one = write_binary("one.serialized", serialized_file(3, {shape_data(triangle_shape(kDouble), 3)}));
  EXPECT_EQ(load_error(one, 1), one + ": shape_index 1, but the file holds 1 shape (0)");
}

TEST(Serialized, GarbledTableOfShapes) {
  std::string file = serialized_file(4, {shape_data(quad_shape(kSingle), 4), shape_data(triangle_shape(kSingle), 4)});
  const size_t entry = file.size() - 4 - 8;  // shape 1's offset
  std::string beyond = file;
  beyond[entry + 2] = 1;  // + 65536
  std::string path = write_binary("beyond.serialized", beyond);
  EXPECT_NE(load_error(path, 1).find(path + ": garbled table of shapes: shape 1 at byte offset "), std::string::npos);
  std::string off_header = file;
  off_header[entry] = char(off_header[entry] + 1);
  path = write_binary("off_header.serialized", off_header);
  EXPECT_NE(load_error(path, 1).find("does not begin with a serialized header (0x041C, version 4)"), std::string::npos);
  std::string many = file;
  many[file.size() - 1] = 0x10;  // 2^28 + 2 shapes
  path = write_binary("many.serialized", many);
  EXPECT_NE(load_error(path, 1).find(path + ": truncated or garbled serialized file: its table of shapes lists 268435458 shapes"),
            std::string::npos);
}

TEST(Serialized, TruncatedFile) {
  const std::string file = serialized_file(4, {shape_data(quad_shape(kSingle), 4)}, false);
  for (size_t cut : {size_t(1), size_t(20), file.size() - 6}) {
    const std::string path = write_binary("cut.serialized", file.substr(0, file.size() - cut));
    EXPECT_NE(load_error(path).find(path + ": shape 0: truncated serialized file: its zlib stream is cut short (after "),
              std::string::npos)
        << "cut " << cut << ": " << load_error(path);
  }
}

TEST(Serialized, CorruptZlibData) {
  const std::string file = serialized_file(4, {shape_data(quad_shape(kSingle), 4)}, false);
  std::string header = file;
  header[4] = 0x00;  // zlib's CMF byte
  std::string path = write_binary("corrupt_header.serialized", header);
  EXPECT_EQ(load_error(path), path + ": shape 0: corrupt zlib data (zlib: incorrect header check)");
  std::string checksum = file;
  checksum.back() = char(checksum.back() ^ 0x55);  // the stream's Adler-32
  path = write_binary("corrupt_checksum.serialized", checksum);
  EXPECT_EQ(load_error(path), path + ": shape 0: corrupt zlib data (zlib: incorrect data check)");
}

TEST(Serialized, CountsLargerThanTheData) {
  Shape s = triangle_shape(kSingle);
  s.vertex_count = 1000;
  std::string path = write_binary("many_vertices.serialized", serialized_file(4, {shape_data(s, 4)}));
  EXPECT_EQ(load_error(path), path + ": shape 0: truncated or garbled serialized data: its counts of 1000 vertices "
                                     "(positions in single precision) and 1 triangles take 12041 bytes, but its zlib "
                                     "stream holds 77");
  // Counts as large as pathcl reads over a few bytes: refused as the data ends, allocating nothing like them.
  s = triangle_shape(kDouble);
  s.flags |= kNormals | kUvs | kColors;
  s.vertex_count = int64_t(1) << 32;
  s.triangle_count = (int64_t(1) << 32) - 1;
  path = write_binary("huge_counts.serialized", serialized_file(3, {shape_data(s, 3)}));
  EXPECT_NE(load_error(path).find(": its counts of 4294967296 vertices (positions, normals, texture coordinates, "
                                  "colours in double precision) and 4294967295 triangles take "),
            std::string::npos);
  s.vertex_count = (int64_t(1) << 32) + 1;
  path = write_binary("too_many.serialized", serialized_file(3, {shape_data(s, 3)}));
  EXPECT_EQ(load_error(path), path + ": shape 0: 4294967297 vertices and 4294967295 triangles, more than pathcl reads "
                                     "in one shape (2^32 vertices, 2^32 - 1 triangles)");
  // Data that ends inside the name or before the counts.
  std::string data;
  put(data, kSingle);
  path = write_binary("no_name_end.serialized", serialized_file(4, {data + "name"}));
  EXPECT_EQ(load_error(path), path + ": shape 0: truncated or garbled serialized data: it ends inside the shape's name (8 bytes decompressed)");
  path = write_binary("no_counts.serialized", serialized_file(3, {data + "1234"}));
  EXPECT_EQ(load_error(path), path + ": shape 0: truncated or garbled serialized data: it ends before its vertex and "
                                     "triangle counts (8 bytes decompressed)");
}

TEST(Serialized, IndexOutOfRange) {
  Shape s = triangle_shape(kSingle);
  s.indices = {0, 1, 2, 2, 3, 0};
  const std::string path = write_binary("index.serialized", serialized_file(4, {shape_data(s, 4)}));
  EXPECT_EQ(load_error(path), path + ": shape 0: triangle 1: vertex index 3 out of range (3 vertices)");
}

TEST(Serialized, ValuesThatAreNotFinite) {
  Shape s = triangle_shape(kSingle);
  s.positions[4] = std::numeric_limits<double>::quiet_NaN();
  std::string path = write_binary("nan.serialized", serialized_file(4, {shape_data(s, 4)}));
  EXPECT_EQ(load_error(path), path + ": shape 0: vertex 1: coordinate is not finite or beyond float range");
  s = triangle_shape(kDouble);
  s.positions[6] = 1e300;
  path = write_binary("huge.serialized", serialized_file(3, {shape_data(s, 3)}));
  EXPECT_EQ(load_error(path), path + ": shape 0: vertex 2: coordinate is not finite or beyond float range");
  s = quad_shape(kSingle);
  s.normals[3] = std::numeric_limits<double>::infinity();
  path = write_binary("normal.serialized", serialized_file(4, {shape_data(s, 4)}));
  EXPECT_EQ(load_error(path), path + ": shape 0: vertex 1: normal is not finite or beyond float range");
  s = quad_shape(kSingle);
  s.uvs[7] = std::numeric_limits<double>::quiet_NaN();
  path = write_binary("uv.serialized", serialized_file(4, {shape_data(s, 4)}));
  EXPECT_EQ(load_error(path), path + ": shape 0: vertex 3: texture coordinate is not finite or beyond float range");
}

TEST(Serialized, OtherDefects) {
  Shape s = triangle_shape(kSingle);
  s.flags |= kDouble;
  std::string path = write_binary("both.serialized", serialized_file(4, {shape_data(s, 4)}));
  EXPECT_EQ(load_error(path), path + ": shape 0: garbled flags 0x00003000: both single (0x1000) and double (0x2000) precision");
  s = triangle_shape(kSingle);
  s.indices.clear();
  path = write_binary("empty.serialized", serialized_file(4, {shape_data(s, 4)}));
  EXPECT_EQ(load_error(path), path + ": shape 0: no faces (3 vertices)");
}

}  // namespace

TEST(Serialized, SceneMeshesNameTheirShapeIndex) {
  // A scene's mesh shape reads a .serialized file by its extension, the shape its shape_index names.
  const Shape quad = quad_shape(kSingle), triangle = triangle_shape(kSingle);
  write_binary("scene-two.serialized", serialized_file(4, {shape_data(quad, 4), shape_data(triangle, 4)}));
  auto scene = [](const std::string& shape) {
    return write_temp_file("serialized-scene.json", R"({"camera": {"position": [0, 0, 50], "look_at": [0, 0, 0],
      "width": 8, "height": 8}, "materials": {"m": {"type": "diffuse"}}, "shapes": [)" + shape + "]}");
  };
  const SceneDescription first = load_scene(scene(R"({"type": "mesh", "file": "scene-two.serialized", "material": "m"})"));
  ASSERT_EQ(first.shapes.size(), 1u);
  EXPECT_EQ(first.shapes[0].mesh.triangles.size(), 2u);
  const SceneDescription second = load_scene(
      scene(R"({"type": "mesh", "file": "scene-two.serialized", "shape_index": 1, "material": "m"})"));
  ASSERT_EQ(second.shapes[0].mesh.triangles.size(), 1u);
  EXPECT_EQ(second.shapes[0].mesh.positions[0].z, 30.0);
  EXPECT_NE(scene_load_error(scene(R"({"type": "mesh", "file": "scene-two.serialized", "shape_index": 2, "material": "m"})"))
                .find("shape_index 2, but the file holds 2 shapes (0 to 1)"),
            std::string::npos);
  EXPECT_NE(scene_load_error(scene(R"({"type": "mesh", "file": "m.obj", "shape_index": 1, "material": "m"})"))
                .find("shapes[0].shape_index: shape_index goes with a Mitsuba .serialized file"),
            std::string::npos);
}
