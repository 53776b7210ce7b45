// glTF 2.0 files (.gltf, .glb) through tinygltf, as pathcl's own plain types: the triangles of every
// mesh a node of the default scene places, the metallic-roughness materials mapped onto pathcl's, the
// KHR_lights_punctual lights and the first camera, all in the glTF scene's space (the shape's transform
// is the caller's). docs/scene-format.md ("gltf") has the mapping and what it approximates.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include <glm/mat4x4.hpp>

#include "kernels/shared/types.h"
#include "scene/mesh_clean.h"
#include "scene/scene_description.h"

// An image a material uses: an external file (resolved against the glTF file's directory), or the bytes
// of one embedded in a data URI or a buffer view.
struct GltfImage {
  std::string name;   // "model.glb: images[0]" (embedded) or the file, for messages and to share it
  std::string file;   // external image, or "" when embedded
  std::string bytes;  // embedded image
};

// One material of the file, mapped. material.color_texture is unset: color_image names the image the
// colour (material.color times it) comes from, which the caller adds to the scene's textures.
struct GltfMaterial {
  std::string where;                   // "model.glb: materials[2]" for messages
  MaterialDesc material;
  uint32_t color_image = PC_INVALID;   // index into GltfScene::images
  uint32_t color_wrap = PC_WRAP_REPEAT;
  glm::vec3 emission{0};               // emissiveFactor times KHR_materials_emissive_strength
  uint32_t emission_image = PC_INVALID;  // emissiveTexture, multiplying emission
  uint32_t emission_wrap = PC_WRAP_REPEAT;
  bool two_sided = false;              // doubleSided: emits from both sides
  // alphaMode MASK or BLEND with a base colour texture: its alpha (times alpha_factor) is the opacity
  // map, thresholded at alpha_cutoff for MASK (alpha_cutoff < 0 for BLEND). Without a texture the
  // material's opacity holds it all.
  uint32_t opacity_image = PC_INVALID;
  float alpha_factor = 1, alpha_cutoff = -1;
};

// The opacity map of a glTF base colour image (GltfMaterial::opacity_image): its alpha times factor in
// every byte of each texel, thresholded to 0 or 1 at cutoff when cutoff >= 0 (alphaMode MASK).
TextureImage alpha_as_opacity(TextureImage image, float factor, float cutoff);

// The triangles of one primitive of one mesh as one node places it. Nodes that share a mesh share its
// geometry: the first placement holds it, the others refer to it (same_as).
struct GltfPrimitive {
  std::string where;   // "model.glb: nodes[3] meshes[1].primitives[0]"
  PolygonSoup soup;    // positions and normals in the mesh's coordinates, uvs with v up (pathcl's)
  glm::dmat4 transform{1.0};  // the node's: from the mesh's coordinates to the glTF scene's
  uint32_t same_as = PC_INVALID;  // another placement's index in GltfScene::primitives whose soup this is
  uint32_t material = 0;  // index into GltfScene::materials
};

struct GltfCamera {
  bool present = false;
  bool perspective = true;  // false: orthographic, which pathcl has not
  std::string where;        // "model.glb: nodes[4] (camera 0)"
  glm::dvec3 position{0}, forward{0, 0, -1}, up{0, 1, 0};  // the node's -z and +y
  double yfov_radians = 0.7;
  double aspect_ratio = 0;  // 0 when the file gives none
};

struct GltfScene {
  std::vector<GltfPrimitive> primitives;
  std::vector<GltfMaterial> materials;  // the file's, then the glTF default material where one is used
  std::vector<GltfImage> images;        // indexed like the file's images
  std::vector<LightDesc> lights;        // one per node with a light; label "model.glb: nodes[2] (light 0)"
  GltfCamera camera;                    // the first node with a camera, in depth-first order
};

// Reads a .gltf (JSON) or .glb (binary) file, told apart by its content ("glTF" magic), and its
// external buffers. Throws SceneError "FILE: what is wrong" on a file that cannot be read, is truncated,
// is not valid JSON, requires an extension pathcl does not support, or whose buffers, accessors or
// indices are missing or out of range; things approximated or ignored go into `warnings`.
GltfScene load_gltf(const std::string& path, std::vector<std::string>& warnings);

// Whether pathcl reads `path` with load_gltf: its extension is .gltf or .glb (any case).
bool is_gltf_file(const std::string& path);
