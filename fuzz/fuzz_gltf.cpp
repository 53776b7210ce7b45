// libFuzzer target: a glTF 2.0 file through load_gltf (scene/gltf_load.cpp: tinygltf, the node hierarchy,
// accessors, materials, KHR_lights_punctual, the camera), then every image a material uses decoded as
// scene_load decodes it (scene/texture_load.cpp), with the opacity map of a cut-out. The first input byte
// selects the file's name (bit 0: f.glb, else f.gltf; load_gltf tells the two apart by their content, so
// the name only shows in messages); the seeds begin with '0' (JSON) and '1' (GLB). The rest is the file.
// Beside it lie b.bin (the quad of fuzz/corpus/gltf/quad-external.gltf: 4 positions, 4 normals, 4 uvs, 6
// unsigned short indices) and t.png (1x1), for files with external buffers and images, and m.obj.
// Bad input must end in SceneError; any other exception, crash, sanitizer report or broken invariant
// below is a bug. fuzz_obj_clean cleans glTF primitives with CGAL as well. Run by scripts/fuzz.
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include <glm/geometric.hpp>

#include "fuzz/fuzz_common.h"
#include "kernels/shared/types.h"
#include "scene/gltf_load.h"
#include "scene/scene_description.h"
#include "scene/scene_error.h"
#include "scene/texture_load.h"

namespace {

// A 1x1 RGBA PNG.
const unsigned char kPng[] = {
    0x89, 0x50, 0x4e, 0x47, 0x0d, 0x0a, 0x1a, 0x0a, 0x00, 0x00, 0x00, 0x0d, 0x49, 0x48, 0x44, 0x52, 0x00, 0x00,
    0x00, 0x01, 0x00, 0x00, 0x00, 0x01, 0x08, 0x06, 0x00, 0x00, 0x00, 0x1f, 0x15, 0xc4, 0x89, 0x00, 0x00, 0x00,
    0x0d, 0x49, 0x44, 0x41, 0x54, 0x78, 0x9c, 0x63, 0xf8, 0xdf, 0xc0, 0x70, 0x00, 0x00, 0x06, 0x41, 0x02, 0x40,
    0x4c, 0xd1, 0x90, 0x17, 0x00, 0x00, 0x00, 0x00, 0x49, 0x45, 0x4e, 0x44, 0xae, 0x42, 0x60, 0x82};

// The unit quad: positions, normals (+z), uvs, then the indices 0 1 2 0 2 3 (140 bytes).
std::vector<unsigned char> quad_buffer() {
  const float floats[] = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0, 0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1,
                          0, 0, 1, 0, 1, 1, 0, 1};
  const uint16_t indices[] = {0, 1, 2, 0, 2, 3};
  std::vector<unsigned char> bytes(sizeof floats + sizeof indices);
  std::memcpy(bytes.data(), floats, sizeof floats);
  std::memcpy(bytes.data() + sizeof floats, indices, sizeof indices);
  return bytes;
}

const fuzz::ScratchDir& scratch_with_files() {
  static const fuzz::ScratchDir& dir = [] () -> const fuzz::ScratchDir& {
    const fuzz::ScratchDir& d = fuzz::scratch();
    const std::vector<unsigned char> buffer = quad_buffer();
    d.write("b.bin", buffer.data(), buffer.size());
    d.write("t.png", kPng, sizeof kPng);
    return d;
  }();
  return dir;
}

bool finite(glm::dvec3 p) { return std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z); }
bool finite(glm::vec3 p) { return std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z); }

void check_image_index(uint32_t i, const GltfScene& scene) {
  if (i != PC_INVALID && i >= scene.images.size()) fuzz::invariant_failed("material image out of range");
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1 || size > fuzz::kMaxInputBytes) return 0;
  const fuzz::ScratchDir& dir = scratch_with_files();
  const std::string path = dir.write(data[0] & 1 ? "f.glb" : "f.gltf", data + 1, size - 1);
  try {
    std::vector<std::string> warnings;
    const GltfScene scene = load_gltf(path, warnings);

    // What read_gltf_shape (scene/scene_load.cpp) relies on.
    for (const GltfPrimitive& p : scene.primitives) {
      if (p.material >= scene.materials.size()) fuzz::invariant_failed("primitive material out of range");
      const size_t index = size_t(&p - scene.primitives.data());
      if (p.same_as != PC_INVALID && (p.same_as >= index || scene.primitives[p.same_as].same_as != PC_INVALID ||
                                      !p.soup.positions.empty()))
        fuzz::invariant_failed("a repeated placement not referring to an earlier primitive's geometry");
      const PolygonSoup& soup = p.soup;
      for (const glm::dvec3& x : soup.positions)
        if (!finite(x)) fuzz::invariant_failed("a position not finite");
      for (const auto& polygon : soup.polygons) {
        if (polygon.size() != 3) fuzz::invariant_failed("a glTF polygon that is not a triangle");
        for (uint32_t v : polygon)
          if (v >= soup.positions.size()) fuzz::invariant_failed("a vertex index out of range");
      }
      if (!soup.normals.empty() && soup.normals.size() != soup.polygons.size())
        fuzz::invariant_failed("normals not one triple per triangle");
      if (!soup.uvs.empty() && soup.uvs.size() != soup.polygons.size())
        fuzz::invariant_failed("uvs not one triple per triangle");
      for (size_t i = 0; i < soup.normals.size(); ++i)
        if (soup.normals[i].size() != soup.polygons[i].size()) fuzz::invariant_failed("normals not one per corner");
      for (size_t i = 0; i < soup.uvs.size(); ++i) {
        if (soup.uvs[i].size() != soup.polygons[i].size()) fuzz::invariant_failed("uvs not one per corner");
        for (const glm::vec2& uv : soup.uvs[i])
          if (!std::isfinite(uv.x) || !std::isfinite(uv.y)) fuzz::invariant_failed("a uv not finite");
      }
    }
    for (const GltfMaterial& m : scene.materials) {
      check_image_index(m.color_image, scene);
      check_image_index(m.emission_image, scene);
      check_image_index(m.opacity_image, scene);
      if (!finite(m.emission) || m.emission.x < 0 || m.emission.y < 0 || m.emission.z < 0)
        fuzz::invariant_failed("emission negative or not finite");
    }
    for (const LightDesc& l : scene.lights) {
      if (!finite(l.emission) || l.emission.x < 0 || l.emission.y < 0 || l.emission.z < 0)
        fuzz::invariant_failed("light emission negative or not finite");
      if (!finite(l.direction) || std::abs(glm::length(l.direction) - 1) > 1e-4f)
        fuzz::invariant_failed("light direction not a unit vector");
      if (!(l.cos_inner >= l.cos_outer)) fuzz::invariant_failed("spot light cones out of order");
    }

    // Every image a material uses, decoded as scene_load decodes it: embedded ones from their bytes,
    // external ones from their files (only those beside the glTF file: a fuzzed uri may name any file).
    for (const GltfMaterial& m : scene.materials)
      for (uint32_t i : {m.color_image, m.emission_image, m.opacity_image}) {
        if (i == PC_INVALID) continue;
        const GltfImage& image = scene.images[i];
        try {
          TextureImage t;
          if (image.file.empty()) {
            t = decode_texture_image(image.name, image.bytes);
          } else {
            if (std::filesystem::path(image.file).lexically_normal().parent_path() != dir.dir()) continue;
            t = load_texture_image(image.file);
          }
          if (i == m.opacity_image) t = alpha_as_opacity(std::move(t), m.alpha_factor, m.alpha_cutoff);
          if (t.width == 0 || t.height == 0 || t.words.empty()) fuzz::invariant_failed("an image without texels");
        } catch (const SceneError&) {
          // A bad image: scene_load reports it for the material.
        }
      }
  } catch (const SceneError&) {
    // Rejected input: expected.
  }
  return 0;
}
