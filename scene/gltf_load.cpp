#include "scene/gltf_load.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <map>
#include <filesystem>
#include <set>

#include <glm/geometric.hpp>
#include <glm/gtc/quaternion.hpp>
#include <glm/gtc/type_ptr.hpp>
#include <glm/mat3x3.hpp>
#include <nlohmann/json.hpp>
#include <tiny_gltf.h>

#include "scene/input_file.h"
#include "scene/scene_error.h"
#include "scene/scene_limits.h"
#include "scene/texture_load.h"

namespace {

// What pathcl reads of the extensions a file may require; any other required one is refused, since a
// file that requires an extension renders wrongly without it (Draco and meshopt compression, quantized
// attributes, texture transforms, ...).
const std::set<std::string> kSupportedExtensions = {"KHR_lights_punctual", "KHR_materials_emissive_strength",
                                                    "KHR_materials_transmission", "KHR_materials_ior"};

struct Reader {
  const std::string& path;
  const tinygltf::Model& model;
  std::vector<std::string>& warnings;
  GltfScene scene;
  int default_material = -1;  // index into scene.materials of the glTF default material, once used
  std::map<std::pair<int, size_t>, uint32_t> first_placement;  // (mesh, primitive) -> its first GltfPrimitive

  [[noreturn]] void fail(const std::string& what) const { throw SceneError(path + ": " + what); }
  void warn(const std::string& what) { warnings.push_back(path + ": " + what); }
};

uint32_t read_u32(const std::string& bytes, size_t at) {
  uint32_t v;
  std::memcpy(&v, bytes.data() + at, 4);
  return v;  // GLB is little-endian, as every machine pathcl runs on
}

// tinygltf says "Invalid glTF binary." for every kind of broken GLB: these checks say what is broken.
void check_glb_header(const std::string& path, const std::string& bytes) {
  auto fail = [&](const std::string& what) { throw SceneError(path + ": " + what); };
  if (bytes.size() < 20)
    fail("truncated GLB file: " + std::to_string(bytes.size()) + " bytes, shorter than its 12-byte header and a chunk header");
  if (read_u32(bytes, 4) != 2) fail("GLB version " + std::to_string(read_u32(bytes, 4)) + " (expected 2, glTF 2.0)");
  uint64_t length = read_u32(bytes, 8);
  if (length > bytes.size())
    fail("truncated GLB file: its header says " + std::to_string(length) + " bytes, but the file has " +
         std::to_string(bytes.size()));
  uint64_t json_length = read_u32(bytes, 12);
  if (std::memcmp(bytes.data() + 16, "JSON", 4) != 0) fail("garbled GLB file: its first chunk is not JSON");
  if (20 + json_length > length)
    fail("truncated GLB file: its JSON chunk of " + std::to_string(json_length) + " bytes runs past the end (" +
         std::to_string(length) + " bytes)");
  uint64_t at = (20 + json_length + 3) / 4 * 4;
  if (at + 8 <= length) {
    uint64_t bin_length = read_u32(bytes, size_t(at));
    if (at + 8 + bin_length > length)
      fail("truncated GLB file: its binary chunk of " + std::to_string(bin_length) + " bytes runs past the end (" +
           std::to_string(length) + " bytes)");
  }
}

// tinygltf 2.7 hands an image's buffer view to the image callback without checking that the view lies
// inside its buffer (fuzz_gltf: a GLB image whose view ran past the BIN chunk was read out of bounds), and
// only checks the accessors' views later: the images' views are checked here first, on the JSON, taking
// tinygltf's default (0) where it would not read a number. tinygltf makes every buffer its byteLength long.
void check_image_buffer_views(const std::string& path, const nlohmann::json& doc) {
  using nlohmann::json;
  auto array = [&](const char* key) -> const json* {
    auto it = doc.find(key);
    return it != doc.end() && it->is_array() ? &*it : nullptr;
  };
  if (!doc.is_object()) return;
  const json *images = array("images"), *views = array("bufferViews"), *buffers = array("buffers");
  if (!images || !views || !buffers) return;
  // An index or size as tinygltf reads it, or -1 where it reports the file itself.
  auto index = [](const json& o, const char* key, size_t count) -> int64_t {
    if (!o.is_object() || !o.contains(key) || !o[key].is_number_integer()) return -1;
    int64_t i = o[key].get<int64_t>();
    return i >= 0 && uint64_t(i) < count ? i : -1;
  };
  auto number = [](const json& o, const char* key) -> uint64_t {
    return o.contains(key) && o[key].is_number_unsigned() ? o[key].get<uint64_t>() : 0;
  };
  for (size_t i = 0; i < images->size(); ++i) {
    const int64_t v = index((*images)[i], "bufferView", views->size());
    if (v < 0) continue;
    const json& view = (*views)[size_t(v)];
    const int64_t b = index(view, "buffer", buffers->size());
    if (b < 0 || !(*buffers)[size_t(b)].is_object() || !(*buffers)[size_t(b)].contains("byteLength") ||
        !(*buffers)[size_t(b)]["byteLength"].is_number_unsigned())
      continue;
    const uint64_t size = (*buffers)[size_t(b)]["byteLength"].get<uint64_t>();
    const uint64_t offset = number(view, "byteOffset"), length = number(view, "byteLength");
    const std::string where = path + ": images[" + std::to_string(i) + "]: bufferViews[" + std::to_string(v) + "]";
    if (length == 0) throw SceneError(where + ": the image's buffer view is empty");
    if (offset >= size || length > size - offset)
      throw SceneError(where + ": " + std::to_string(length) + " bytes from byte " + std::to_string(offset) +
                       " reach beyond the end of buffers[" + std::to_string(b) + "] (" + std::to_string(size) + " bytes)");
  }
}

// Keeps an embedded image's encoded bytes for pathcl's own decoder (scene/texture_load.h), which reads
// the formats pathcl reads with pathcl's messages; external images are read from their files there.
bool keep_image_bytes(tinygltf::Image* image, const int, std::string*, std::string*, int, int,
                      const unsigned char* bytes, int size, void*) {
  if (!image->uri.empty() && image->uri.rfind("data:", 0) != 0) return true;
  image->image.assign(bytes, bytes + size);
  image->as_is = true;
  return true;
}

// tinygltf's messages end in newlines and may hold several lines: one line of them.
std::string one_line(std::string text) {
  while (!text.empty() && (text.back() == '\n' || text.back() == ' ')) text.pop_back();
  std::replace(text.begin(), text.end(), '\n', ';');
  return text;
}

std::string percent_decoded(const std::string& uri) {
  std::string out;
  for (size_t i = 0; i < uri.size(); ++i) {
    if (uri[i] == '%' && i + 2 < uri.size() && std::isxdigit((unsigned char)uri[i + 1]) &&
        std::isxdigit((unsigned char)uri[i + 2])) {
      out += char(std::stoi(uri.substr(i + 1, 2), nullptr, 16));
      i += 2;
    } else {
      out += uri[i];
    }
  }
  return out;
}

// An accessor's elements, checked to lie inside its buffer view and buffer.
struct AccessorData {
  const unsigned char* data = nullptr;
  size_t stride = 0, count = 0;
  int components = 1, component_type = TINYGLTF_COMPONENT_TYPE_FLOAT;
  bool normalized = false;

  // Component c of element i, normalized integers mapped to [0, 1] or [-1, 1] as glTF says (3.11).
  double get(size_t i, int c) const {
    const unsigned char* p = data + i * stride;
    switch (component_type) {
      case TINYGLTF_COMPONENT_TYPE_BYTE: {
        int8_t v;
        std::memcpy(&v, p + c, 1);
        return normalized ? std::max(v / 127.0, -1.0) : v;
      }
      case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: return normalized ? p[c] / 255.0 : p[c];
      case TINYGLTF_COMPONENT_TYPE_SHORT: {
        int16_t v;
        std::memcpy(&v, p + 2 * c, 2);
        return normalized ? std::max(v / 32767.0, -1.0) : v;
      }
      case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: {
        uint16_t v;
        std::memcpy(&v, p + 2 * c, 2);
        return normalized ? v / 65535.0 : v;
      }
      case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT: {
        uint32_t v;
        std::memcpy(&v, p + 4 * c, 4);
        return v;
      }
      default: {
        float v;
        std::memcpy(&v, p + 4 * c, 4);
        return v;
      }
    }
  }
};

int component_bytes(int type) {
  switch (type) {
    case TINYGLTF_COMPONENT_TYPE_BYTE:
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: return 1;
    case TINYGLTF_COMPONENT_TYPE_SHORT:
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: return 2;
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT:
    case TINYGLTF_COMPONENT_TYPE_FLOAT: return 4;
    default: return 0;
  }
}

// Accessor `index` for `use` ("POSITION of meshes[0].primitives[0]"), which needs `components` per
// element (1 for SCALAR, 2 for VEC2, 3 for VEC3).
AccessorData read_accessor(const Reader& r, int index, const std::string& use, int components) {
  const tinygltf::Model& m = r.model;
  if (index < 0 || size_t(index) >= m.accessors.size())
    r.fail(use + ": accessor " + std::to_string(index) + " out of range (" + std::to_string(m.accessors.size()) +
           " accessors)");
  const tinygltf::Accessor& a = m.accessors[size_t(index)];
  const std::string where = "accessors[" + std::to_string(index) + "] (" + use + ")";
  const int type_components = a.type == TINYGLTF_TYPE_SCALAR ? 1 : a.type == TINYGLTF_TYPE_VEC2 ? 2
                              : a.type == TINYGLTF_TYPE_VEC3 ? 3 : a.type == TINYGLTF_TYPE_VEC4 ? 4 : 0;
  if (type_components != components)
    r.fail(where + ": expected " + (components == 1 ? std::string("SCALAR") : "VEC" + std::to_string(components)) +
           " elements");
  if (component_bytes(a.componentType) == 0) r.fail(where + ": unsupported component type " + std::to_string(a.componentType));
  if (a.sparse.isSparse) r.fail(where + ": sparse accessors are not supported");
  AccessorData d;
  d.count = a.count;
  d.components = components;
  d.component_type = a.componentType;
  d.normalized = a.normalized;
  // glTF allows an accessor without a buffer view, all zeros, as the base of a sparse one (refused above):
  // alone it is no geometry, and its count would allocate without bound.
  if (a.bufferView < 0) r.fail(where + ": no bufferView (its elements would all be zero)");
  if (size_t(a.bufferView) >= m.bufferViews.size())
    r.fail(where + ": buffer view " + std::to_string(a.bufferView) + " out of range (" +
           std::to_string(m.bufferViews.size()) + " buffer views)");
  const tinygltf::BufferView& v = m.bufferViews[size_t(a.bufferView)];
  const std::string view_where = "bufferViews[" + std::to_string(a.bufferView) + "]";
  if (v.buffer < 0 || size_t(v.buffer) >= m.buffers.size())
    r.fail(view_where + ": buffer " + std::to_string(v.buffer) + " out of range (" + std::to_string(m.buffers.size()) +
           " buffers)");
  const tinygltf::Buffer& b = m.buffers[size_t(v.buffer)];
  // Each offset and length alone first: tinygltf takes them as any unsigned 64-bit number, and a sum of
  // two near 2^64 wraps around to a small one (fuzz_gltf: an offset of 2^64 - 16 read before the buffer).
  if (v.byteOffset > b.data.size() || v.byteLength > b.data.size() - v.byteOffset)
    r.fail(view_where + ": " + std::to_string(v.byteLength) + " bytes from byte " + std::to_string(v.byteOffset) +
           " reach beyond the end of buffers[" + std::to_string(v.buffer) + "] (" + std::to_string(b.data.size()) + " bytes)");
  const size_t element = size_t(component_bytes(a.componentType)) * size_t(components);
  d.stride = v.byteStride ? v.byteStride : element;
  if (d.stride < element) r.fail(view_where + ": byteStride " + std::to_string(v.byteStride) + " is smaller than an element");
  if (a.count > 0) {
    // No overflow: the offset is at most the view's length, the count at most 2^40 and the stride 252.
    if (a.count > (uint64_t(1) << 40) || a.byteOffset > v.byteLength ||
        uint64_t(a.byteOffset) + uint64_t(d.stride) * (a.count - 1) + element > v.byteLength)
      r.fail(where + ": " + std::to_string(a.count) + " elements from byte " + std::to_string(a.byteOffset) +
             " reach beyond the end of " + view_where + " (" + std::to_string(v.byteLength) + " bytes)");
  }
  d.data = b.data.data() + v.byteOffset + a.byteOffset;
  return d;
}

glm::dmat4 local_transform(const Reader& r, const tinygltf::Node& n, const std::string& where) {
  if (!n.matrix.empty()) {
    if (n.matrix.size() != 16) r.fail(where + ": matrix: expected 16 numbers");
    glm::dmat4 m = glm::make_mat4(n.matrix.data());  // glTF and glm are both column-major
    return m;
  }
  glm::dmat4 t(1.0);
  if (!n.translation.empty()) {
    if (n.translation.size() != 3) r.fail(where + ": translation: expected 3 numbers");
    t[3] = glm::dvec4(n.translation[0], n.translation[1], n.translation[2], 1.0);
  }
  glm::dmat4 rotation(1.0);
  if (!n.rotation.empty()) {
    if (n.rotation.size() != 4) r.fail(where + ": rotation: expected a quaternion of 4 numbers");
    glm::dquat q(n.rotation[3], n.rotation[0], n.rotation[1], n.rotation[2]);  // glTF writes x, y, z, w
    double length = glm::length(q);
    if (!(length > 0) || !std::isfinite(length)) r.fail(where + ": rotation: expected a non-zero quaternion");
    rotation = glm::mat4_cast(q / length);
  }
  glm::dmat4 scale(1.0);
  if (!n.scale.empty()) {
    if (n.scale.size() != 3) r.fail(where + ": scale: expected 3 numbers");
    scale = glm::scale(glm::dmat4(1.0), glm::dvec3(n.scale[0], n.scale[1], n.scale[2]));
  }
  return t * rotation * scale;  // glTF: T * R * S
}

// The triangles of one primitive's mode, as index triples into its vertices (glTF 2.0, 3.7.2.1).
std::vector<std::array<uint32_t, 3>> primitive_triangles(const Reader& r, int mode, const std::vector<uint32_t>& idx,
                                                         const std::string& where) {
  std::vector<std::array<uint32_t, 3>> tris;
  if (mode == -1 || mode == TINYGLTF_MODE_TRIANGLES) {
    for (size_t i = 0; i + 2 < idx.size(); i += 3) tris.push_back({idx[i], idx[i + 1], idx[i + 2]});
  } else if (mode == TINYGLTF_MODE_TRIANGLE_STRIP) {
    for (size_t i = 0; i + 2 < idx.size(); ++i)
      tris.push_back(i % 2 ? std::array<uint32_t, 3>{idx[i + 1], idx[i], idx[i + 2]}
                           : std::array<uint32_t, 3>{idx[i], idx[i + 1], idx[i + 2]});
  } else if (mode == TINYGLTF_MODE_TRIANGLE_FAN) {
    for (size_t i = 1; i + 1 < idx.size(); ++i) tris.push_back({idx[i], idx[i + 1], idx[0]});
  } else {
    const char* names[] = {"POINTS", "LINES", "LINE_LOOP", "LINE_STRIP"};
    r.fail(where + ": " + (mode >= 0 && mode < 4 ? std::string(names[mode]) : "mode " + std::to_string(mode)) +
           " is not supported (pathcl renders triangles: TRIANGLES, TRIANGLE_STRIP or TRIANGLE_FAN)");
  }
  return tris;
}

// The primitive in its mesh's coordinates (the caller places it by `global`, the node's transform).
void read_primitive(Reader& r, const tinygltf::Primitive& p, const glm::dmat4& global, const std::string& where) {
  auto attribute = [&](const char* name) {
    auto it = p.attributes.find(name);
    return it == p.attributes.end() ? -1 : it->second;
  };
  if (attribute("POSITION") < 0) r.fail(where + ": no POSITION attribute");
  AccessorData positions = read_accessor(r, attribute("POSITION"), "POSITION of " + where, 3);
  GltfPrimitive out;
  out.where = r.path + ": " + where;
  out.transform = global;
  PolygonSoup& soup = out.soup;
  for (size_t i = 0; i < positions.count; ++i) {
    glm::dvec3 pos(positions.get(i, 0), positions.get(i, 1), positions.get(i, 2));
    // Within float range, as the JSON loader asks of positions: a coordinate of 1e300 is finite in double,
    // and CGAL's clean-up overflowed on it (see ply_stl_off_load.cpp). The node's transform is checked
    // where the mesh is placed (scene_load.cpp).
    const double m = 3.4028234663852886e38;
    if (!std::isfinite(pos.x) || !std::isfinite(pos.y) || !std::isfinite(pos.z) || std::abs(pos.x) > m ||
        std::abs(pos.y) > m || std::abs(pos.z) > m)
      r.fail(where + ": POSITION " + std::to_string(i) + " is not finite or beyond float range");
    soup.positions.push_back(pos);
  }
  std::vector<uint32_t> indices;
  if (p.indices >= 0) {
    AccessorData d = read_accessor(r, p.indices, "indices of " + where, 1);
    if (d.component_type != TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE && d.component_type != TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT &&
        d.component_type != TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT)
      r.fail("accessors[" + std::to_string(p.indices) + "] (indices of " + where +
             "): expected unsigned integer indices");
    for (size_t i = 0; i < d.count; ++i) {
      double v = d.get(i, 0);
      if (v >= double(positions.count))
        r.fail(where + ": index " + std::to_string(uint64_t(v)) + " out of range (" + std::to_string(positions.count) +
               " vertices)");
      indices.push_back(uint32_t(v));
    }
  } else {
    if (positions.count > 0xffffffffu) r.fail(where + ": more than 2^32 vertices");
    for (size_t i = 0; i < positions.count; ++i) indices.push_back(uint32_t(i));
  }
  const int mode = p.mode;
  const std::vector<std::array<uint32_t, 3>> triangles = primitive_triangles(r, mode, indices, where);

  std::vector<glm::vec3> normals;
  if (attribute("NORMAL") >= 0) {
    AccessorData d = read_accessor(r, attribute("NORMAL"), "NORMAL of " + where, 3);
    if (d.count != positions.count) r.fail(where + ": NORMAL has " + std::to_string(d.count) + " elements, POSITION " + std::to_string(positions.count));
    // Normalized (and checked) by clean-up; placed with the mesh.
    for (size_t i = 0; i < d.count; ++i) {
      glm::dvec3 n(d.get(i, 0), d.get(i, 1), d.get(i, 2));
      if (!std::isfinite(n.x) || !std::isfinite(n.y) || !std::isfinite(n.z)) n = glm::dvec3(0);
      normals.push_back(glm::vec3(n));
    }
  }
  std::vector<glm::vec2> uvs;
  if (attribute("TEXCOORD_0") >= 0) {
    AccessorData d = read_accessor(r, attribute("TEXCOORD_0"), "TEXCOORD_0 of " + where, 2);
    if (d.count != positions.count) r.fail(where + ": TEXCOORD_0 has " + std::to_string(d.count) + " elements, POSITION " + std::to_string(positions.count));
    for (size_t i = 0; i < d.count; ++i) {
      double u = d.get(i, 0), v = d.get(i, 1);
      if (!std::isfinite(u) || !std::isfinite(v)) r.fail(where + ": TEXCOORD_0 " + std::to_string(i) + " is not finite");
      uvs.push_back(glm::vec2(float(u), float(1 - v)));  // glTF's v runs down the image, pathcl's up
    }
  }
  // COLOR_0 multiplies the base colour (glTF 2.0, 3.9.2), linear; VEC4's alpha is not read (pathcl's
  // cut-outs take alpha from the material).
  std::vector<glm::vec3> colors;
  if (attribute("COLOR_0") >= 0) {
    const int index = attribute("COLOR_0");
    const bool rgba = index < int(r.model.accessors.size()) && r.model.accessors[size_t(index)].type == TINYGLTF_TYPE_VEC4;
    AccessorData d = read_accessor(r, index, "COLOR_0 of " + where, rgba ? 4 : 3);
    if (d.count != positions.count) r.fail(where + ": COLOR_0 has " + std::to_string(d.count) + " elements, POSITION " + std::to_string(positions.count));
    for (size_t i = 0; i < d.count; ++i) {
      glm::vec3 c(float(d.get(i, 0)), float(d.get(i, 1)), float(d.get(i, 2)));
      for (int k = 0; k < 3; ++k)
        if (!(c[k] >= 0 && c[k] <= 1)) r.fail(where + ": COLOR_0 " + std::to_string(i) + " is not in [0, 1]");
      colors.push_back(c);
    }
  }
  // (A mirroring node transform turns counter-clockwise into clockwise, glTF 2.0, 3.7.2.1: placing the
  // mesh swaps the winding then, placed_mesh.)
  for (std::array<uint32_t, 3> t : triangles) {
    soup.polygons.push_back({t[0], t[1], t[2]});
    if (!normals.empty()) soup.normals.push_back({normals[t[0]], normals[t[1]], normals[t[2]]});
    if (!uvs.empty()) soup.uvs.push_back({uvs[t[0]], uvs[t[1]], uvs[t[2]]});
    if (!colors.empty()) soup.colors.push_back({colors[t[0]], colors[t[1]], colors[t[2]]});
  }
  if (!p.targets.empty()) r.warn(where + ": morph targets are not supported: the base shape is rendered");
  if (p.material < 0) {
    if (r.default_material < 0) {
      r.default_material = int(r.scene.materials.size());
      GltfMaterial m;
      m.where = r.path + ": the default material";
      // glTF's default material: white, metallic 1, roughness 1 (3.9.6).
      m.material.name = "gltf default material";
      m.material.type = "rough_conductor";
      m.material.type_id = PC_MAT_ROUGH_CONDUCTOR;
      m.material.alpha = 1;
      set_conductor_reflectance(m.material, glm::vec3(1));
      r.scene.materials.push_back(m);
    }
    out.material = uint32_t(r.default_material);
  } else {
    if (size_t(p.material) >= r.model.materials.size())
      r.fail(where + ": material " + std::to_string(p.material) + " out of range (" +
             std::to_string(r.model.materials.size()) + " materials)");
    out.material = uint32_t(p.material);
  }
  r.scene.primitives.push_back(std::move(out));
}

// A number of an extension object, or `fallback` when it is absent.
double extension_number(const tinygltf::ExtensionMap& extensions, const char* extension, const char* key, double fallback) {
  auto it = extensions.find(extension);
  if (it == extensions.end() || !it->second.Has(key) || !it->second.Get(key).IsNumber()) return fallback;
  return it->second.Get(key).GetNumberAsDouble();
}

uint32_t wrap_mode(Reader& r, const tinygltf::Texture& t, const std::string& where) {
  if (t.sampler < 0) return PC_WRAP_REPEAT;
  if (size_t(t.sampler) >= r.model.samplers.size()) r.fail(where + ": sampler " + std::to_string(t.sampler) + " out of range");
  const tinygltf::Sampler& s = r.model.samplers[size_t(t.sampler)];
  auto mode = [](int w) {
    return w == TINYGLTF_TEXTURE_WRAP_CLAMP_TO_EDGE ? PC_WRAP_CLAMP : w == TINYGLTF_TEXTURE_WRAP_MIRRORED_REPEAT ? PC_WRAP_MIRROR : PC_WRAP_REPEAT;
  };
  if (mode(s.wrapS) != mode(s.wrapT))
    r.warn(where + ": different wrap modes in s and t: pathcl has one per texture and uses wrapS's");
  return uint32_t(mode(s.wrapS));
}

// The image of a texture reference, or PC_INVALID; sets *wrap.
uint32_t texture_image(Reader& r, const tinygltf::TextureInfo& info, const std::string& where, uint32_t* wrap) {
  if (info.index < 0) return PC_INVALID;
  if (size_t(info.index) >= r.model.textures.size())
    r.fail(where + ": texture " + std::to_string(info.index) + " out of range (" + std::to_string(r.model.textures.size()) + " textures)");
  const tinygltf::Texture& t = r.model.textures[size_t(info.index)];
  if (info.texCoord != 0) r.warn(where + ": uses TEXCOORD_" + std::to_string(info.texCoord) + "; pathcl reads TEXCOORD_0 only");
  if (t.source < 0) {
    r.warn(where + ": texture " + std::to_string(info.index) + " has no image pathcl reads (PNG or JPEG): ignored");
    return PC_INVALID;
  }
  if (size_t(t.source) >= r.scene.images.size())
    r.fail(where + ": image " + std::to_string(t.source) + " out of range (" + std::to_string(r.scene.images.size()) + " images)");
  *wrap = wrap_mode(r, t, where);
  return uint32_t(t.source);
}

// The image decoded, for the values the loader reads from it itself (metallic and roughness).
TextureImage decode_image(const GltfImage& image) {
  return image.file.empty() ? decode_texture_image(image.name, image.bytes) : load_texture_image(image.file);
}

GltfMaterial read_material(Reader& r, size_t index) {
  const tinygltf::Material& src = r.model.materials[index];
  GltfMaterial out;
  const std::string where = "materials[" + std::to_string(index) + "]";
  out.where = r.path + ": " + where;
  MaterialDesc& m = out.material;
  m.name = src.name.empty() ? where : src.name;
  const tinygltf::PbrMetallicRoughness& pbr = src.pbrMetallicRoughness;
  glm::vec3 base(1);
  for (int c = 0; c < 3 && c < int(pbr.baseColorFactor.size()); ++c)
    base[c] = float(std::clamp(pbr.baseColorFactor[size_t(c)], 0.0, 1.0));
  double metallic = std::clamp(pbr.metallicFactor, 0.0, 1.0), roughness = std::clamp(pbr.roughnessFactor, 0.0, 1.0);
  uint32_t wrap = PC_WRAP_REPEAT;
  const uint32_t mr = texture_image(r, pbr.metallicRoughnessTexture, where + ".metallicRoughnessTexture", &wrap);
  if (mr != PC_INVALID) {
    // pathcl's materials have one metallic and one roughness value: the texture's means (blue is
    // metallic, green roughness; the values as stored, without sRGB decoding) times the factors.
    TextureImage image = decode_image(r.scene.images[mr]);
    double sum_g = 0, sum_b = 0;
    const size_t n = size_t(image.width) * image.height;
    for (size_t i = 0; i < n; ++i) {
      if (image.format == PC_TEXELS_SRGB8) {
        const unsigned char* b = reinterpret_cast<const unsigned char*>(image.words.data()) + 4 * i;
        sum_g += b[1] / 255.0;
        sum_b += b[2] / 255.0;
      } else {
        glm::vec3 t = texel_linear(image, i);
        sum_g += t.y;
        sum_b += t.z;
      }
    }
    metallic *= std::clamp(sum_b / double(n), 0.0, 1.0);
    roughness *= std::clamp(sum_g / double(n), 0.0, 1.0);
    r.warn(where + ": metallicRoughnessTexture replaced by its mean values (metallic " + std::to_string(metallic) +
           ", roughness " + std::to_string(roughness) + ")");
  }
  const double transmission = extension_number(src.extensions, "KHR_materials_transmission", "transmissionFactor", 0);
  double ior = extension_number(src.extensions, "KHR_materials_ior", "ior", 1.5);
  if (!(ior >= 1 && ior <= 10)) {
    r.warn(where + ": KHR_materials_ior " + std::to_string(ior) + " outside [1, 10]: 1.5 is used");
    ior = 1.5;
  }
  const uint32_t color_image = texture_image(r, pbr.baseColorTexture, where + ".baseColorTexture", &wrap);
  bool takes_texture = true;
  if (transmission >= 0.5 && metallic < 0.5) {
    m.type = "dielectric";
    m.type_id = PC_MAT_DIELECTRIC;
    m.ior = float(ior);
    m.color = base;
    if (roughness >= 0.01) r.warn(where + ": a transmissive material rendered as smooth glass (roughness ignored)");
  } else if (metallic >= 0.5) {
    if (roughness < 0.01) {
      m.type = "mirror";
      m.type_id = PC_MAT_MIRROR;
      m.color = base;
    } else {
      m.type = "rough_conductor";
      m.type_id = PC_MAT_ROUGH_CONDUCTOR;
      m.alpha = float(roughness * roughness);
      glm::vec3 specular = base;
      if (color_image != PC_INVALID) {
        // rough_conductor takes no texture: the texture's mean colour times the factor.
        TextureImage image = decode_image(r.scene.images[color_image]);
        glm::dvec3 sum(0);
        const size_t n = size_t(image.width) * image.height;
        for (size_t i = 0; i < n; ++i) sum += glm::dvec3(texel_linear(image, i));
        specular *= glm::clamp(glm::vec3(sum / double(n)), glm::vec3(0), glm::vec3(1));
        r.warn(where + ": a metal's baseColorTexture replaced by its mean colour (rough_conductor takes no texture)");
        takes_texture = false;
      }
      set_conductor_reflectance(m, specular);
    }
  } else {
    m.type = "plastic";
    m.type_id = PC_MAT_PLASTIC;
    m.color = base;
    m.ior = float(ior);
    m.alpha = roughness < 0.01 ? 0.0f : float(roughness * roughness);
  }
  if (takes_texture && color_image != PC_INVALID) {
    out.color_image = color_image;
    out.color_wrap = wrap;
  }
  for (int c = 0; c < 3 && c < int(src.emissiveFactor.size()); ++c) out.emission[c] = float(std::max(src.emissiveFactor[size_t(c)], 0.0));
  out.emission *= float(std::max(extension_number(src.extensions, "KHR_materials_emissive_strength", "emissiveStrength", 1.0), 0.0));
  if (out.emission.x > kMaxLightValue || out.emission.y > kMaxLightValue || out.emission.z > kMaxLightValue)
    r.fail(where + ": emission above 1e12");
  out.emission_image = texture_image(r, src.emissiveTexture, where + ".emissiveTexture", &out.emission_wrap);
  if (out.emission == glm::vec3(0)) out.emission_image = PC_INVALID;  // the factor's default is 0
  out.two_sided = src.doubleSided;
  // Alpha as a cut-out (docs/scene-format.md): BLEND is coverage, the probability that the surface is
  // there; MASK thresholds alpha at alphaCutoff.
  const float alpha = pbr.baseColorFactor.size() > 3 ? float(std::clamp(pbr.baseColorFactor[3], 0.0, 1.0)) : 1.0f;
  if (src.alphaMode == "BLEND" || src.alphaMode == "MASK") {
    const bool mask = src.alphaMode == "MASK";
    const float cutoff = float(std::max(src.alphaCutoff, 0.0));
    if (color_image != PC_INVALID) {
      out.opacity_image = color_image;
      out.alpha_factor = alpha;
      out.alpha_cutoff = mask ? cutoff : -1.0f;
    } else {
      m.opacity = mask ? (alpha >= cutoff ? 1.0f : 0.0f) : alpha;
    }
  } else if (!src.alphaMode.empty() && src.alphaMode != "OPAQUE") {
    r.fail(where + ": unknown alphaMode \"" + src.alphaMode + "\" (expected OPAQUE, MASK or BLEND)");
  }
  if (src.normalTexture.index >= 0) r.warn(where + ": normalTexture ignored (no normal maps)");
  return out;
}

std::string node_where(int index, const tinygltf::Node& n) {
  return "nodes[" + std::to_string(index) + "]" + (n.name.empty() ? "" : " \"" + n.name + "\"");
}

void read_light(Reader& r, int index, const glm::dmat4& global, const std::string& where) {
  if (index < 0 || size_t(index) >= r.model.lights.size())
    r.fail(where + ": light " + std::to_string(index) + " out of range (" + std::to_string(r.model.lights.size()) + " lights)");
  const tinygltf::Light& src = r.model.lights[size_t(index)];
  LightDesc l;
  l.label = r.path + ": " + where + " (light " + std::to_string(index) + ")";
  glm::dvec3 color(1);
  for (int c = 0; c < 3 && c < int(src.color.size()); ++c) color[c] = src.color[size_t(c)];
  if (!(color.x >= 0 && color.y >= 0 && color.z >= 0 && src.intensity >= 0))
    r.fail(where + ": light " + std::to_string(index) + ": expected a non-negative colour and intensity");
  // Candela for point and spot lights, lux for directional ones: pathcl's intensity and irradiance, one
  // to one (docs/scene-format.md).
  glm::dvec3 e = color * src.intensity;
  if (!(e.x <= kMaxLightValue && e.y <= kMaxLightValue && e.z <= kMaxLightValue))
    r.fail(where + ": light " + std::to_string(index) + ": intensity times colour above 1e12");
  l.emission = glm::vec3(e);
  l.position = glm::dvec3(global[3]);
  glm::dvec3 direction = glm::dmat3(global) * glm::dvec3(0, 0, -1);  // lights shine along their node's -z
  if (!(glm::length(direction) > 0) || !std::isfinite(glm::length(direction)))
    r.fail(where + ": the node's transform leaves its light no direction");
  l.direction = glm::vec3(glm::normalize(direction));
  if (src.type == "point") {
    l.type = PC_LIGHT_POINT;
  } else if (src.type == "spot") {
    l.type = PC_LIGHT_SPOT;
    double outer = src.spot.outerConeAngle, inner = src.spot.innerConeAngle;
    if (!(outer > 0 && outer <= M_PI / 2 && inner >= 0 && inner <= outer))
      r.fail(where + ": light " + std::to_string(index) + ": expected 0 <= innerConeAngle <= outerConeAngle <= pi/2, 0 < outerConeAngle");
    l.cos_outer = float(std::cos(outer));
    l.cos_inner = float(std::cos(inner));
  } else if (src.type == "directional") {
    l.type = PC_LIGHT_DIRECTIONAL;
  } else {
    r.fail(where + ": light " + std::to_string(index) + ": unknown type \"" + src.type + "\" (expected point, spot or directional)");
  }
  if (src.range > 0) r.warn(where + ": light " + std::to_string(index) + ": range ignored (pathcl's lights fall off with the inverse square only)");
  r.scene.lights.push_back(l);
}

void read_node(Reader& r, int index, const glm::dmat4& parent, std::vector<bool>& on_path) {
  const tinygltf::Model& m = r.model;
  if (index < 0 || size_t(index) >= m.nodes.size())
    r.fail("node " + std::to_string(index) + " out of range (" + std::to_string(m.nodes.size()) + " nodes)");
  if (on_path[size_t(index)]) r.fail("nodes[" + std::to_string(index) + "] is its own ancestor (the node hierarchy has a cycle)");
  on_path[size_t(index)] = true;
  const tinygltf::Node& n = m.nodes[size_t(index)];
  const std::string where = node_where(index, n);
  const glm::dmat4 global = parent * local_transform(r, n, where);
  if (n.mesh >= 0) {
    if (size_t(n.mesh) >= m.meshes.size())
      r.fail(where + ": mesh " + std::to_string(n.mesh) + " out of range (" + std::to_string(m.meshes.size()) + " meshes)");
    if (n.skin >= 0) r.warn(where + ": skins are not supported: the mesh is rendered in its bind pose");
    const tinygltf::Mesh& mesh = m.meshes[size_t(n.mesh)];
    for (size_t p = 0; p < mesh.primitives.size(); ++p) {
      const std::string primitive_where = where + " meshes[" + std::to_string(n.mesh) + "].primitives[" + std::to_string(p) + "]";
      auto [first, is_first] = r.first_placement.try_emplace({n.mesh, p}, uint32_t(r.scene.primitives.size()));
      if (is_first) {
        read_primitive(r, mesh.primitives[p], global, primitive_where);
        continue;
      }
      // Another node places the same mesh: its geometry is read once (GltfPrimitive::same_as).
      GltfPrimitive again;
      again.where = r.path + ": " + primitive_where;
      again.transform = global;
      again.same_as = first->second;
      again.material = r.scene.primitives[first->second].material;
      r.scene.primitives.push_back(std::move(again));
    }
  }
  auto light = n.extensions.find("KHR_lights_punctual");
  if (light != n.extensions.end() && light->second.Has("light")) {
    // An integer: tinygltf's GetNumberAsInt converts a real to int unchecked (fuzz_gltf: 1e30 is undefined
    // behaviour) and reads anything else as light 0.
    const tinygltf::Value& index = light->second.Get("light");
    if (!index.IsInt()) r.fail(where + ": KHR_lights_punctual: expected an integer light index");
    read_light(r, index.GetNumberAsInt(), global, where);
  }
  if (n.camera >= 0 && !r.scene.camera.present) {
    if (size_t(n.camera) >= m.cameras.size())
      r.fail(where + ": camera " + std::to_string(n.camera) + " out of range (" + std::to_string(m.cameras.size()) + " cameras)");
    const tinygltf::Camera& c = m.cameras[size_t(n.camera)];
    GltfCamera& camera = r.scene.camera;
    camera.present = true;
    camera.where = r.path + ": " + where + " (camera " + std::to_string(n.camera) + ")";
    camera.perspective = c.type == "perspective";
    camera.position = glm::dvec3(global[3]);
    camera.forward = glm::dmat3(global) * glm::dvec3(0, 0, -1);  // glTF cameras look along -z, +y up
    camera.up = glm::dmat3(global) * glm::dvec3(0, 1, 0);
    camera.yfov_radians = c.perspective.yfov;
    camera.aspect_ratio = c.perspective.aspectRatio;
  }
  for (int child : n.children) read_node(r, child, global, on_path);
  on_path[size_t(index)] = false;
}

}  // namespace

bool is_gltf_file(const std::string& path) {
  const std::string ext = lower_extension(path);
  return ext == ".gltf" || ext == ".glb";
}

// Refuses a file whose extensionsRequired names an extension pathcl does not read, before tinygltf reads
// the rest: such files may be invalid without the extension (KHR_draco_mesh_compression's accessors have no
// buffer view, which tinygltf reports as "accessor[0] invalid bufferView"; assimp-testmodels' draco/).
void check_required_extensions(const std::string& path, const nlohmann::json& doc) {
  if (!doc.is_object() || !doc.contains("extensionsRequired") || !doc["extensionsRequired"].is_array()) return;
  for (const nlohmann::json& e : doc["extensionsRequired"])
    if (e.is_string() && !kSupportedExtensions.count(e.get<std::string>()))
      throw SceneError(path + ": requires the extension " + e.get<std::string>() +
                       ", which pathcl does not support (it reads KHR_lights_punctual, "
                       "KHR_materials_emissive_strength, KHR_materials_transmission and KHR_materials_ior)");
}

GltfScene load_gltf(const std::string& path, std::vector<std::string>& warnings) {
  const std::string bytes = read_input_file(path, kMeshInput);
  const std::string dir = std::filesystem::path(path).parent_path().string();
  tinygltf::Model model;
  tinygltf::TinyGLTF loader;
  loader.SetImageLoader(keep_image_bytes, nullptr);
  std::string err, warn;
  bool ok;
  if (bytes.rfind("glTF", 0) == 0) {
    check_glb_header(path, bytes);
    const nlohmann::json doc = nlohmann::json::parse(bytes.substr(20, read_u32(bytes, 12)), nullptr, false);
    if (!doc.is_discarded()) {  // malformed: tinygltf says why
      check_required_extensions(path, doc);
      check_image_buffer_views(path, doc);
    }
    ok = loader.LoadBinaryFromMemory(&model, &err, &warn, reinterpret_cast<const unsigned char*>(bytes.data()),
                                     unsigned(bytes.size()), dir);
  } else {
    if (bytes.find_first_not_of(" \t\r\n") == std::string::npos) throw SceneError(path + ": the file is empty, expected glTF");
    if (bytes.find_first_not_of(" \t\r\n\xef\xbb\xbf") != std::string::npos && bytes[bytes.find_first_not_of(" \t\r\n\xef\xbb\xbf")] != '{')
      throw SceneError(path + ": neither glTF JSON nor a GLB file (it starts with neither { nor the GLB magic \"glTF\")");
    // tinygltf passes on nlohmann's message as it is, and says only "File not found" of a buffer: the
    // JSON and the external buffers are checked here first, to be named in pathcl's words.
    nlohmann::json doc;
    try {
      doc = nlohmann::json::parse(bytes);
    } catch (const nlohmann::json::exception& e) {
      throw SceneError(malformed_json_message(path, e.what()));
    }
    check_required_extensions(path, doc);
    if (doc.is_object() && doc.contains("buffers") && doc["buffers"].is_array())
      for (size_t i = 0; i < doc["buffers"].size(); ++i) {
        const nlohmann::json& b = doc["buffers"][i];
        if (!b.is_object() || !b.contains("uri") || !b["uri"].is_string()) continue;
        const std::string uri = b["uri"].get<std::string>();
        if (uri.rfind("data:", 0) == 0) continue;
        const std::string file = (std::filesystem::path(dir) / percent_decoded(uri)).string();
        try {
          read_input_file(file, kBufferInput, 64);
        } catch (const SceneError& e) {
          throw SceneError(path + ": buffers[" + std::to_string(i) + "]: " + e.what());
        }
      }
    check_image_buffer_views(path, doc);
    ok = loader.LoadASCIIFromString(&model, &err, &warn, bytes.data(), unsigned(bytes.size()), dir);
  }
  if (!ok) throw SceneError(path + ": " + (err.empty() ? "tinygltf cannot read the file" : one_line(err)));
  Reader r{path, model, warnings, {}, -1, {}};
  std::string ignored;
  for (const std::string& e : model.extensionsUsed)
    if (!kSupportedExtensions.count(e)) ignored += (ignored.empty() ? "" : ", ") + e;
  if (!ignored.empty()) r.warn("extensions not used by pathcl (optional in this file): " + ignored);

  for (size_t i = 0; i < model.images.size(); ++i) {
    const tinygltf::Image& src = model.images[i];
    GltfImage image;
    if (!src.uri.empty() && src.uri.rfind("data:", 0) != 0) {
      image.file = (std::filesystem::path(dir) / percent_decoded(src.uri)).string();
      image.name = image.file;
    } else {
      image.name = path + ": images[" + std::to_string(i) + "]";
      image.bytes.assign(src.image.begin(), src.image.end());
    }
    r.scene.images.push_back(std::move(image));
  }
  for (size_t i = 0; i < model.materials.size(); ++i) r.scene.materials.push_back(read_material(r, i));

  if (model.scenes.empty()) r.fail("no scenes: nothing to place");
  const int scene = model.defaultScene >= 0 ? model.defaultScene : 0;
  if (size_t(scene) >= model.scenes.size())
    r.fail("scene " + std::to_string(scene) + " out of range (" + std::to_string(model.scenes.size()) + " scenes)");
  std::vector<bool> on_path(model.nodes.size(), false);
  for (int node : model.scenes[size_t(scene)].nodes) read_node(r, node, glm::dmat4(1.0), on_path);
  return std::move(r.scene);
}

TextureImage alpha_as_opacity(TextureImage image, float factor, float cutoff) {
  if (image.format != PC_TEXELS_SRGB8) return image;  // glTF images are PNG or JPEG: not reached
  for (uint32_t& word : image.words) {
    float a = float(word >> 24) / 255.0f * factor;
    uint32_t byte = cutoff >= 0 ? (a >= cutoff ? 255u : 0u) : uint32_t(std::lround(a * 255.0f));
    word = byte | byte << 8 | byte << 16 | byte << 24;
  }
  return image;
}
