// PLY, STL and OFF files through CGAL's readers.
//
// CGAL 5.5's polygon-soup read_PLY keeps vertex and face colours and per-halfedge uvs but drops vertex
// normals and vertex uvs, and its point-set reader (read_PLY_with_properties) reads the vertices but not
// the faces. So PLY files are read here with the PLY_reader both of them are built on (CGAL/IO/PLY.h,
// namespace CGAL::IO::internal): one pass over the file, element by element, every property of every item
// read by CGAL and then taken by name. STL and OFF go through CGAL::IO::read_STL and read_OFF as they are.
// CGAL's readers report failure as false or a failed stream, never where: messages say what was being
// read (the vertices, the faces) when it failed.
#include "scene/ply_stl_off_load.h"

#include <cctype>
#include <cmath>
#include <cctype>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <new>
#include <sstream>
#include <stdexcept>
#include <utility>

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/IO/OFF.h>
#include <CGAL/IO/PLY.h>
#include <CGAL/IO/STL.h>

#include "scene/input_file.h"
#include "scene/scene_error.h"
#include "scene/texture_load.h"

namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = Kernel::Point_3;
using PlyElement = CGAL::IO::internal::PLY_element;

// The value of the numeric property `tag` of the item just read, of whichever PLY type the file gives it.
bool ply_number(PlyElement& element, const char* tag, double& value) {
  if (element.has_property<double>(tag)) {  // float or double (CGAL's overload for double takes both)
    element.assign(value, tag);
    return true;
  }
  auto try_type = [&](auto zero) {
    using T = decltype(zero);
    if (!element.has_property<T>(tag)) return false;
    T v;
    element.assign(v, tag);
    value = double(v);
    return true;
  };
  return try_type(int8_t()) || try_type(uint8_t()) || try_type(int16_t()) || try_type(uint16_t()) ||
         try_type(int32_t()) || try_type(uint32_t());
}

bool has_number(PlyElement& element, const char* tag) {
  return element.has_property<double>(tag) || element.has_property<int8_t>(tag) || element.has_property<uint8_t>(tag) ||
         element.has_property<int16_t>(tag) || element.has_property<uint16_t>(tag) ||
         element.has_property<int32_t>(tag) || element.has_property<uint32_t>(tag);
}

// The colour properties of a PLY element: red, green, blue (or r, g, b, or diffuse_red, ...); null when
// it has none.
const char* const* ply_color_tags(PlyElement& element) {
  static const char* const tags[][3] = {
      {"red", "green", "blue"}, {"r", "g", "b"}, {"diffuse_red", "diffuse_green", "diffuse_blue"}};
  for (const auto& t : tags)
    if (has_number(element, t[0]) && has_number(element, t[1]) && has_number(element, t[2])) return t;
  return nullptr;
}

// The colour of the item just read, linear: integers over their type's range (8-bit as 0 to 255, 16-bit
// as 0 to 65535), floats as they are; all taken as sRGB-encoded display values, the convention of
// scanners and MeshLab, as 8-bit images are.
glm::vec3 ply_color(PlyElement& element, const char* const* tags) {
  glm::vec3 color;
  for (int c = 0; c < 3; ++c) {
    double value = 0;
    ply_number(element, tags[c], value);
    const double range = element.has_property<double>(tags[c])                                             ? 1.0
                         : element.has_property<int16_t>(tags[c]) || element.has_property<uint16_t>(tags[c]) ? 65535.0
                                                                                                              : 255.0;
    color[c] = srgb_to_linear(value / range);
  }
  return color;
}

// Reads every property of the next item of `element` (CGAL buffers them for assign); false when the
// stream ends or a value cannot be read. A list whose length is garbled may ask for more memory than
// there is.
bool read_ply_item(std::istream& in, PlyElement& element) {
  try {
    for (std::size_t k = 0; k < element.number_of_properties(); ++k) {
      element.property(k)->get(in);
      if (in.fail()) return false;
    }
  } catch (const std::bad_alloc&) {
    return false;
  } catch (const std::length_error&) {
    return false;
  }
  return true;
}

bool finite(const glm::dvec3& p) { return std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z); }

// A position pathcl can hold: finite and within float range, as the JSON loader asks of its positions
// (PLY doubles of 1e300 are finite, but CGAL's clean-up overflows on them to infinity and GMP raised
// SIGFPE converting it: fuzz_obj_clean).
bool position_in_range(const glm::dvec3& p) {
  const double m = 3.4028234663852886e38;
  return finite(p) && std::abs(p.x) <= m && std::abs(p.y) <= m && std::abs(p.z) <= m;
}

// CGAL's points as the soup's positions; throws for one that is not finite or beyond float range.
std::vector<glm::dvec3> finite_positions(const std::string& path, const std::vector<Point>& points) {
  std::vector<glm::dvec3> positions;
  positions.reserve(points.size());
  for (const Point& p : points) {
    positions.push_back({p.x(), p.y(), p.z()});
    if (!position_in_range(positions.back()))
      throw SceneError(path + ": vertex " + std::to_string(positions.size() - 1) +
                       ": coordinate is not finite or beyond float range");
  }
  return positions;
}

// CGAL 5.5's PLY_reader::init adds a property to the last element read, without checking that there is
// one: a property line before any element line is undefined behaviour there (fuzz_obj_clean found it).
void check_ply_properties_follow_an_element(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::string line, keyword;
  bool element = false;
  for (size_t number = 1; std::getline(in, line); ++number) {
    std::istringstream words(line);
    if (!(words >> keyword)) continue;
    if (keyword == "end_header") return;
    if (keyword == "element") element = true;
    if (keyword == "property" && !element)
      throw SceneError(path + ": line " + std::to_string(number) + ": a property before any element (a garbled PLY header)");
  }
}

PolygonSoup load_ply(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw SceneError(path + ": cannot open the mesh file");
  check_ply_properties_follow_an_element(path);
  CGAL::IO::internal::PLY_reader reader(false);
  if (!reader.init(in)) throw SceneError(path + ": not a PLY file (its header cannot be read)");

  // A file whose header has no faces is a point cloud (a scan's raw points, as most scan collections also
  // ship): say so before reading its body, whatever the body holds.
  std::size_t header_vertices = 0, header_faces = 0;
  for (std::size_t e = 0; e < reader.number_of_elements(); ++e) {
    const std::string& name = reader.element(e).name();
    if (name == "vertex" || name == "vertices") header_vertices += reader.element(e).number_of_items();
    if (name == "face" || name == "faces") header_faces += reader.element(e).number_of_items();
  }
  if (header_faces == 0)
    throw SceneError(path + ": no faces (" + std::to_string(header_vertices) +
                     " vertices: a point cloud? pathcl renders surfaces)");

  PolygonSoup soup;
  std::vector<glm::vec3> vertex_normals;
  std::vector<glm::vec2> vertex_uvs;
  std::vector<glm::vec3> vertex_colors;
  bool have_faces = false;
  for (std::size_t e = 0; e < reader.number_of_elements(); ++e) {
    PlyElement& element = reader.element(e);
    const std::string& name = element.name();
    const std::string items = std::to_string(element.number_of_items());
    if (name == "vertex" || name == "vertices") {
      if (element.number_of_items() > 0 &&
          (!has_number(element, "x") || !has_number(element, "y") || !has_number(element, "z")))
        throw SceneError(path + ": the PLY vertices have no x, y and z properties");
      const bool normals = has_number(element, "nx") && has_number(element, "ny") && has_number(element, "nz");
      const char* uv_tags[][2] = {{"u", "v"}, {"s", "t"}, {"texture_u", "texture_v"}, {"texture_s", "texture_t"}};
      const char** uv = nullptr;
      for (auto& tags : uv_tags)
        if (!uv && has_number(element, tags[0]) && has_number(element, tags[1])) uv = tags;
      const char* const* color = ply_color_tags(element);
      for (std::size_t j = 0; j < element.number_of_items(); ++j) {
        if (!read_ply_item(in, element))
          throw SceneError(path + ": truncated or garbled PLY file: cannot read vertex " + std::to_string(j) +
                           " of " + items);
        glm::dvec3 p;
        ply_number(element, "x", p.x), ply_number(element, "y", p.y), ply_number(element, "z", p.z);
        if (!position_in_range(p))
          throw SceneError(path + ": vertex " + std::to_string(j) + ": coordinate is not finite or beyond float range");
        soup.positions.push_back(p);
        if (normals) {
          glm::dvec3 n;
          ply_number(element, "nx", n.x), ply_number(element, "ny", n.y), ply_number(element, "nz", n.z);
          if (!finite(n)) throw SceneError(path + ": vertex " + std::to_string(j) + ": normal is not finite");
          vertex_normals.push_back(glm::vec3(n));
        }
        if (uv) {
          double u, v;
          ply_number(element, uv[0], u), ply_number(element, uv[1], v);
          if (!std::isfinite(u) || !std::isfinite(v))
            throw SceneError(path + ": vertex " + std::to_string(j) + ": texture coordinate is not finite");
          vertex_uvs.push_back({float(u), float(v)});
        }
        if (color) vertex_colors.push_back(ply_color(element, color));
      }
    } else if (name == "face" || name == "faces") {
      have_faces = true;
      const char* tag = element.has_property<std::vector<int32_t>>("vertex_indices") ||
                                element.has_property<std::vector<uint32_t>>("vertex_indices")
                            ? "vertex_indices" : "vertex_index";
      const bool signed_indices = element.has_property<std::vector<int32_t>>(tag);
      if (!signed_indices && !element.has_property<std::vector<uint32_t>>(tag))
        throw SceneError(path + ": the PLY faces have no vertex_indices list of int or uint");
      const bool corner_uvs = element.has_property<std::vector<float>>("texcoord");
      const char* const* color = ply_color_tags(element);
      for (std::size_t j = 0; j < element.number_of_items(); ++j) {
        const std::string where = path + ": face " + std::to_string(j);
        if (!read_ply_item(in, element))
          throw SceneError(path + ": truncated or garbled PLY file: cannot read face " + std::to_string(j) + " of " + items);
        std::vector<uint32_t> polygon;
        auto take = [&](const auto& indices) {
          for (auto i : indices) {
            if (i < 0 || uint64_t(i) >= soup.positions.size())
              throw SceneError(where + ": vertex index " + std::to_string(i) + " out of range (" +
                               std::to_string(soup.positions.size()) + " vertices before the faces)");
            polygon.push_back(uint32_t(i));
          }
        };
        if (signed_indices) {
          std::vector<int32_t> indices;
          element.assign(indices, tag);
          take(indices);
        } else {
          std::vector<uint32_t> indices;
          element.assign(indices, tag);
          take(indices);
        }
        if (corner_uvs) {
          std::vector<float> uvs;
          element.assign(uvs, "texcoord");
          if (uvs.size() != 2 * polygon.size())
            throw SceneError(where + ": " + std::to_string(uvs.size()) + " texcoord values for " +
                             std::to_string(polygon.size()) + " corners (expected 2 per corner)");
          std::vector<glm::vec2> corners;
          for (std::size_t k = 0; k < polygon.size(); ++k) {
            if (!std::isfinite(uvs[2 * k]) || !std::isfinite(uvs[2 * k + 1]))
              throw SceneError(where + ": texture coordinate is not finite");
            corners.push_back({uvs[2 * k], uvs[2 * k + 1]});
          }
          soup.uvs.resize(soup.polygons.size());
          soup.uvs.push_back(std::move(corners));
        }
        if (color) soup.colors.push_back(std::vector<glm::vec3>(polygon.size(), ply_color(element, color)));
        soup.polygons.push_back(std::move(polygon));
      }
    } else {
      // Other elements (edges, materials, a scanner's own) are read past. One without properties takes no
      // bytes, whatever its count says (fuzz_obj_clean: "element e -1" looped over 2^64 - 1 empty items).
      if (element.number_of_properties() == 0) continue;
      for (std::size_t j = 0; j < element.number_of_items(); ++j)
        if (!read_ply_item(in, element))
          throw SceneError(path + ": truncated or garbled PLY file: cannot read " + name + " " + std::to_string(j) +
                           " of " + items);
    }
  }
  if (!soup.uvs.empty()) soup.uvs.resize(soup.polygons.size());  // faces before the first with texcoord
  if (!have_faces || soup.polygons.empty())
    throw SceneError(path + ": no faces (" + std::to_string(soup.positions.size()) +
                     " vertices: a point cloud? pathcl renders surfaces)");
  // Per-vertex attributes become the corners' of every face (texcoord of the faces wins over vertex uvs).
  if (!vertex_normals.empty())
    for (const std::vector<uint32_t>& polygon : soup.polygons) {
      std::vector<glm::vec3>& corners = soup.normals.emplace_back();
      for (uint32_t v : polygon) corners.push_back(vertex_normals[v]);
    }
  if (!vertex_uvs.empty() && soup.uvs.empty())
    for (const std::vector<uint32_t>& polygon : soup.polygons) {
      std::vector<glm::vec2>& corners = soup.uvs.emplace_back();
      for (uint32_t v : polygon) corners.push_back(vertex_uvs[v]);
    }
  // Vertex colours win over face colours where a file has both (they are the finer of the two).
  if (!vertex_colors.empty()) {
    soup.colors.clear();
    for (const std::vector<uint32_t>& polygon : soup.polygons) {
      std::vector<glm::vec3>& corners = soup.colors.emplace_back();
      for (uint32_t v : polygon) corners.push_back(vertex_colors[v]);
    }
  }
  return soup;
}

// A binary STL file is an 80-byte header, a triangle count and 50 bytes per triangle: a file of another
// length that does not begin as ASCII STL does ("solid" and white space: a blank, a tab as in
// assimp-testmodels' sphereWithHole.stl, or the line's end) is truncated (CGAL would try it as ASCII and
// report only that it failed).
void check_binary_stl_size(const std::string& path, const std::string& head) {
  const std::uintmax_t size = std::filesystem::file_size(path);
  if (head.rfind("solid", 0) == 0 && head.size() > 5 && std::isspace(static_cast<unsigned char>(head[5]))) return;
  if (size < 84)
    throw SceneError(path + ": truncated STL file (" + std::to_string(size) +
                     " bytes, less than the 84 of a binary STL header)");
  uint32_t count = 0;
  for (int i = 0; i < 4; ++i) count |= uint32_t(static_cast<unsigned char>(head[80 + i])) << (8 * i);
  const std::uintmax_t expected = 84 + 50 * std::uintmax_t(count);
  if (size != expected)
    throw SceneError(path + ": truncated or garbled binary STL file: its header says " + std::to_string(count) +
                     " triangles, " + std::to_string(expected) + " bytes, but the file has " + std::to_string(size));
}

PolygonSoup load_stl(const std::string& path, const std::string& head) {
  check_binary_stl_size(path, head);
  std::ifstream file(path, std::ios::binary);
  if (!file) throw SceneError(path + ": cannot open the mesh file");
  // CGAL 5.5 takes a file for ASCII only when "solid" is followed by a blank or a line end, and reads any
  // other as binary without checking its size: "solid\tname" (assimp-testmodels' sphereWithHole.stl)
  // gave a garbage mesh. The same text with a blank there is what the file means.
  std::istringstream retyped;
  std::istream* stream = &file;
  if (head.rfind("solid", 0) == 0 && head.size() > 5 && head[5] != ' ' && head[5] != '\n' && head[5] != '\r') {
    std::string text((std::istreambuf_iterator<char>(file)), std::istreambuf_iterator<char>());
    text[5] = ' ';
    retyped.str(std::move(text));
    stream = &retyped;
  }
  std::istream& in = *stream;
  std::vector<Point> points;
  std::vector<std::vector<std::size_t>> triangles;
  if (!CGAL::IO::read_STL(in, points, triangles, CGAL::parameters::verbose(false)))
    throw SceneError(path + ": truncated or garbled STL file (CGAL's reader cannot read it)");
  PolygonSoup soup;
  soup.positions = finite_positions(path, points);
  for (const auto& t : triangles) soup.polygons.push_back({uint32_t(t[0]), uint32_t(t[1]), uint32_t(t[2])});
  // CGAL's reader takes an ASCII file it cannot parse for an empty binary one.
  if (soup.polygons.empty() && head.find("facet") != std::string::npos)
    throw SceneError(path + ": truncated or garbled ASCII STL file: no facet could be read");
  if (soup.polygons.empty()) throw SceneError(path + ": no faces");
  return soup;
}

// Each face's vertex count of a binary OFF file, which CGAL 5.5 resizes the face to before reading it, as it
// does in ASCII files: a count of 10^9 (a float's bits read as the count) asked for 8.5 GB (fuzz_obj_clean,
// out of memory). The file is walked as CGAL's read_OFF reads it: after the line with BINARY, big-endian
// int32 counts (a dimension first for nOFF), then per vertex 3 float32 coordinates (4 for 4OFF) and as many
// for the normal (NOFF), then per face its vertex count and indices (CGAL reads no colour count after
// them). Colours and texture coordinates are refused as in ASCII files. `in` stands after BINARY's line.
void check_binary_off_faces(const std::string& path, const std::string& keyword, std::istream& in) {
  const std::string prefix = keyword.substr(0, keyword.size() - 3);
  if (prefix.find("ST") != std::string::npos || prefix.find('C') != std::string::npos)
    throw SceneError(path + ": " + keyword + " BINARY: texture coordinates and colours in OFF files are not "
                     "supported (CGAL's OFF reader misreads them); write the mesh as PLY or OBJ");
  const std::string data(std::istreambuf_iterator<char>(in), {});
  size_t at = 0;
  auto int32 = [&](int64_t& v) {
    if (at + 4 > data.size()) return false;
    uint32_t u = 0;
    for (int i = 0; i < 4; ++i) u = u << 8 | static_cast<unsigned char>(data[at + i]);
    at += 4;
    v = int32_t(u);
    return true;
  };
  int64_t vertices = 0, faces = 0, edges = 0, dimension = 0;
  if (prefix.find('n') != std::string::npos && !int32(dimension)) return;
  if (!int32(vertices) || !int32(faces) || !int32(edges)) return;  // CGAL refuses a header cut short
  // As in ASCII files: CGAL doubles the count of edges and adds the others times 2.1, as ints, unchecked
  // (fuzz_obj_clean: UBSan, 2 * 1851878912, the bytes of "nan" read as the count of edges).
  const char* names[] = {"vertices", "faces", "edges"};
  const int64_t counts[] = {vertices, faces, edges};
  const uint64_t size = data.size();
  for (int i = 0; i < 3; ++i)
    if (counts[i] < 0 || uint64_t(counts[i]) > (i < 2 ? size / 2 : size))
      throw SceneError(path + ": truncated or garbled OFF file: its header's count of " + names[i] + " is " +
                       std::to_string(counts[i]) + ", not a number up to what the " + std::to_string(size) +
                       " bytes after its binary header hold");
  const bool homogeneous = prefix.find('4') != std::string::npos, normals = prefix.find('N') != std::string::npos;
  const uint64_t vertex_bytes = 4 * (3 + homogeneous) * (1 + normals);
  if (uint64_t(vertices) > data.size() / vertex_bytes) return;  // truncated: CGAL fails reading the vertices
  at += size_t(vertices) * vertex_bytes;
  for (int64_t f = 0, count = 0; f < faces; ++f) {
    // CGAL takes a count cut short by the end of the file as a count (fuzz_obj_clean: 3 bytes of text read
    // as 1886547712 vertices), and reads no further once the stream has failed only if it is not at its end.
    auto truncated = [&] {
      return SceneError(path + ": truncated binary OFF file: face " + std::to_string(f) + " of " +
                        std::to_string(faces) + " is cut short");
    };
    if (!int32(count)) throw truncated();
    if (count < 0 || count > 255)
      throw SceneError(path + ": face " + std::to_string(f) + " has " + std::to_string(count) +
                       " vertices, more than the 255 pathcl reads (or a garbled binary OFF file)");
    at += size_t(4 * count);
    if (at > data.size()) throw truncated();
  }
}

// The counts of an ASCII OFF header, checked before CGAL reads them; true when some face has a colour
// after its indices, which CGAL 5.5 reads past without returning it: its header reader converts
// (vertices + faces) * 2.1 to int with no range check (UBSan in File_header_OFF_impl.h, found by
// fuzz_obj_clean with a count of -2147483). Every vertex and face takes at least 2 bytes ("0\n"), every
// edge at least one. Binary headers are left to CGAL.
bool check_ascii_off_counts(const std::string& path, std::uintmax_t size) {
  std::ifstream in(path, std::ios::binary);
  auto next = [&](std::string& token) {
    while (in >> token) {
      if (token[0] != '#') return true;
      std::string comment;
      std::getline(in, comment);
    }
    return false;
  };
  // The keyword as CGAL's File_header_OFF reads it: after blank space and '#' comment lines, letters and
  // digits, the character after them taken with them ("OFF." is OFF: fuzz_obj_clean found binary files so
  // named past these checks); then a count, or BINARY and the rest of its line.
  const auto line_end = [&] { in.ignore(std::numeric_limits<std::streamsize>::max(), '\n'); };
  auto word = [&](char c) {
    std::string w(1, c);
    while (in.get(c) && std::isalnum(static_cast<unsigned char>(c))) w += c;
    return std::make_pair(w, c);
  };
  char c = 0;
  while (in >> c && c == '#') line_end();
  if (!in) return false;
  const std::string keyword = word(c).first;
  if (keyword.size() < 3 || keyword.compare(keyword.size() - 3, 3, "OFF") != 0) return false;
  while (in >> c && c == '#') line_end();
  if (!in) return false;
  if (!std::isdigit(static_cast<unsigned char>(c))) {
    const auto [binary, after] = word(c);
    if (binary != "BINARY") return false;  // CGAL refuses it
    if (after != '\n') line_end();
    check_binary_off_faces(path, keyword, in);
    return false;
  }
  in.putback(c);
  std::string token;
  if (!next(token)) return false;
  // CGAL 5.5's ASCII scanner reads texture coordinates and colours by indices it computes from each line
  // without checking them: for "ST" it uses uninitialised colour bookkeeping (ASan: SEGV in scan_texture),
  // and with "C" a short line reads out of bounds (fuzz_obj_clean, scan_color). Until a reader that
  // checks them, such files are refused rather than misread.
  std::string prefix = keyword.substr(0, keyword.size() - 3);
  if (prefix.find("ST") != std::string::npos || prefix.find('C') != std::string::npos)
    throw SceneError(path + ": " + keyword + ": texture coordinates and colours in ASCII OFF files are not "
                     "supported (CGAL's OFF reader misreads them); write the mesh as PLY or OBJ");
  if (keyword.size() > 3 && keyword[keyword.size() - 4] == 'n' && !next(token)) return false;  // nOFF: the dimension first
  const char* names[] = {"vertices", "faces", "edges"};
  unsigned long long counts[3] = {};
  for (int i = 0; i < 3; ++i) {
    if (i > 0 && !next(token)) return false;
    bool digits = !token.empty() && token.size() <= 12 && token.find_first_not_of("0123456789") == std::string::npos;
    if (!digits || std::stoull(token) > (i < 2 ? size / 2 : size))
      throw SceneError(path + ": truncated or garbled OFF file: its header's count of " + names[i] + " is " + token +
                       ", not a number up to what a file of " + std::to_string(size) + " bytes holds");
    counts[i] = std::stoull(token);
  }
  // Each face's vertex count, which CGAL sizes the face by before reading it (a count of 10^15 asked for
  // petabytes; fuzz_obj_clean): at most 255, as for OBJ faces.
  std::string line;
  bool colored = false;
  std::getline(in, line);  // the rest of the counts' line
  for (unsigned long long v = 0; v < counts[0] && std::getline(in, line);)
    if (line.find_first_not_of(" \t\r") != std::string::npos && line[line.find_first_not_of(" \t\r")] != '#') ++v;
  for (unsigned long long f = 0; f < counts[1] && next(token); ++f) {
    bool digits = !token.empty() && token.size() <= 3 && token.find_first_not_of("0123456789") == std::string::npos;
    if (!digits || std::stoul(token) > 255)
      throw SceneError(path + ": face " + std::to_string(f) + " has " + token +
                       " vertices, more than the 255 pathcl reads (or a garbled OFF file)");
    std::getline(in, line);  // the face's indices and colour
    std::istringstream words(line);
    unsigned long entries = 0;
    for (std::string word; words >> word && word[0] != '#';) ++entries;
    colored = colored || entries > std::stoul(token);
  }
  return colored;
}

PolygonSoup load_off(const std::string& path, std::vector<std::string>& warnings) {
  const std::uintmax_t size = std::filesystem::file_size(path);
  if (check_ascii_off_counts(path, size))
    warnings.push_back(path + ": face colours ignored (CGAL's OFF reader does not return them; a PLY file keeps them)");
  {
    // CGAL sizes its arrays by the header's counts before reading them: a garbled count would ask for
    // any amount of memory. Every vertex and face takes at least 2 bytes (ASCII "0\n"; binary, 4 or more).
    std::ifstream in(path, std::ios::binary);
    CGAL::File_scanner_OFF scanner(in, false);
    if (in.fail()) throw SceneError(path + ": not an OFF file (its header cannot be read)");
    if (scanner.size_of_vertices() > size / 2 || scanner.size_of_facets() > size / 2)
      throw SceneError(path + ": truncated or garbled OFF file: its header says " +
                       std::to_string(scanner.size_of_vertices()) + " vertices and " +
                       std::to_string(scanner.size_of_facets()) + " faces, more than a file of " +
                       std::to_string(size) + " bytes holds");
  }
  std::ifstream in(path, std::ios::binary);
  std::vector<Point> points;
  std::vector<std::vector<std::size_t>> polygons;
  std::vector<Kernel::Vector_3> normals;
  std::vector<Kernel::Point_2> uvs;
  bool read = false;
  try {
    read = CGAL::IO::read_OFF(in, points, polygons,
                              CGAL::parameters::vertex_normal_output_iterator(std::back_inserter(normals))
                                  .vertex_texture_output_iterator(std::back_inserter(uvs))
                                  .verbose(false));
  } catch (const std::length_error&) {  // a face's vertex count of 10^40: CGAL resizes the face to it
  } catch (const std::bad_alloc&) {
  }
  if (!read) throw SceneError(path + ": truncated or garbled OFF file (CGAL's reader cannot read it)");
  PolygonSoup soup;
  soup.positions = finite_positions(path, points);
  for (const auto& polygon : polygons) {
    std::vector<uint32_t>& p = soup.polygons.emplace_back();
    for (std::size_t v : polygon) p.push_back(uint32_t(v));  // read_OFF checked the range
    if (normals.size() == points.size()) {
      std::vector<glm::vec3>& corners = soup.normals.emplace_back();
      for (std::size_t v : polygon) {
        const Kernel::Vector_3& n = normals[v];
        corners.push_back(glm::vec3(float(n.x()), float(n.y()), float(n.z())));
        if (!finite(glm::dvec3(corners.back())))
          throw SceneError(path + ": vertex " + std::to_string(v) + ": normal is not finite");
      }
    }
    if (uvs.size() == points.size()) {
      std::vector<glm::vec2>& corners = soup.uvs.emplace_back();
      for (std::size_t v : polygon) {
        corners.push_back({float(uvs[v].x()), float(uvs[v].y())});
        if (!std::isfinite(corners.back().x) || !std::isfinite(corners.back().y))
          throw SceneError(path + ": vertex " + std::to_string(v) + ": texture coordinate is not finite");
      }
    }
  }
  if (soup.polygons.empty()) throw SceneError(path + ": no faces");
  return soup;
}

}  // namespace

bool is_ply_stl_off_file(const std::string& path) {
  const std::string ext = lower_extension(path);
  return ext == ".ply" || ext == ".stl" || ext == ".off";
}

PolygonSoup load_ply_stl_off(const std::string& path, std::vector<std::string>& warnings) {
  // The same checks as every input: a directory, a missing file, a Git LFS pointer.
  const std::string head = read_input_file(path, kMeshInput, 512);
  const std::string ext = lower_extension(path);
  try {
    if (ext == ".ply") return load_ply(path);
    if (ext == ".stl") return load_stl(path, head);
    return load_off(path, warnings);
  } catch (const CGAL::Failure_exception& e) {
    // Only where CGAL's checks are compiled in (debug and fuzz builds).
    throw SceneError(path + ": CGAL cannot read this file: " + e.expression());
  }
}
