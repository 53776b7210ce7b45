// The scene as the JSON file describes it, after validation and transformation to world space and
// mesh cleaning: what scene/device_scene_build.cpp flattens for the device.
#pragma once
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include <glm/common.hpp>
#include <glm/exponential.hpp>
#include <glm/mat3x3.hpp>
#include <glm/vec3.hpp>
#include <glm/vec4.hpp>

#include "kernels/shared/types.h"
#include "kernels/shared/light_types.h"
#include "scene/mesh_clean.h"

// Positions are world coordinates in double until build_device_scene makes them camera-relative floats.
struct CameraDesc {
  glm::dvec3 position{0, 0, 0}, look_at{0, 0, -1}, up{0, 1, 0};
  float fov_y_degrees = 40;
  uint32_t width = 512, height = 512;
  float aperture_radius = 0;  // thin lens; 0 = pinhole
  float focus_distance = 1;   // thin lens: distance of the plane in focus along the view direction
  uint32_t filter = 0;        // PC_FILTER_*
  float filter_radius = 0.5f; // pixels
  float filter_sigma = 0.5f;  // pixels (Gaussian)
  bool aimed = true;          // look_at is what the camera looks at (false: a glTF camera, one unit ahead)
  bool left_handed = false;   // image x is cross(up, forward), as in pbrt's camera frame (camera.handedness)
};

// A material with its parameters as the kernels take them (kernels/shared/types.h, Material); which
// ones a type uses is written there.
struct MaterialDesc {
  std::string name;
  std::string type;               // "diffuse", "oren_nayar", ...
  uint32_t type_id = 0;           // PC_MAT_*
  glm::vec3 color{0.5f};          // reflectance, diffuse colour or transmittance
  uint32_t color_texture = 0xffffffffu;  // index into SceneDescription::textures; its value times color
                                         // is the colour (color is 1 for a texture from JSON)
  glm::vec3 specular{0}, k{0};    // phong specular; rough_conductor eta (in specular) and k
  float alpha = 0, sigma = 0, exponent = 1, ior = 1.5f;
  // Cut-outs: the fraction of rays the surface stops (kernels/cutout.cl), times the opacity texture's
  // value where there is one (index into SceneDescription::textures; its alpha channel when the 8-bit
  // image has one that is not all opaque, else its red channel, read linearly).
  float opacity = 1;
  uint32_t opacity_texture = 0xffffffffu;
};

// rough_conductor from a reflectance r at normal incidence: eta = 1 and k = 2 sqrt(r / (1 - r)) reflect
// exactly r there (r is capped just below 1, where k is infinite).
inline void set_conductor_reflectance(MaterialDesc& m, glm::vec3 reflectance) {
  glm::vec3 r = glm::min(reflectance, glm::vec3(0.9999f));
  m.specular = glm::vec3(1);
  m.k = 2.0f * glm::sqrt(r / (1.0f - r));
}

// An image texture, rows from the top, its texels stored as the device reads them, at the precision of
// the file (PC_TEXELS_* of kernels/shared/types.h): 8-bit sRGB, or linear half or float RGB.
// scene/texture_load.h decodes a texel to linear RGB as the device does.
struct TextureImage {
  std::string file;
  uint32_t width = 0, height = 0;
  uint32_t wrap = 0;               // PC_WRAP_*
  uint32_t format = 0;             // PC_TEXELS_*
  bool reflectance = false;        // a material colour: texels clamped to [0, 1] (an environment map is not)
  // The texel words (Texture.format); emptied by build_device_scene_taking_texels, which moves them
  // into the device scene.
  std::vector<uint32_t> words;
};

// A light that is not an emitting shape.
struct LightDesc {
  std::string label;              // "lights[2]" for messages
  uint32_t type = 0;              // PC_LIGHT_*
  glm::vec3 emission{0};          // intensity, irradiance or radiance (scale of the map)
  glm::dvec3 position{0};         // world coordinates, in double like all positions
  glm::vec3 direction{0, -1, 0};
  float cos_inner = 1, cos_outer = 0;
  uint32_t texture = 0xffffffffu; // environment map in SceneDescription::textures
  glm::dmat3 rotation{1.0};        // environment: takes the map's directions to the world's (its transform)
  uint32_t mapping = PC_ENV_LAT_LONG;  // environment map: its parameterisation and lookup, PC_ENV_*
};

struct RenderSettings {
  uint32_t spp = 16;
  uint32_t max_depth = 8;
  uint32_t seed = 1;
  uint32_t sampler = PC_SAMPLER_SOBOL;  // PC_SAMPLER_* of kernels/shared/types.h
  // The technique's name (runtime/technique.h checks it against the registry) and where the file gave
  // it, for messages ("scene.json: render.integrator"); empty place: the default.
  std::string integrator = "path", integrator_place;
  // render.integrator as an object ({"type": NAME, OPTION: VALUE, ...}): its options as a JSON object's text,
  // which the technique checks (runtime/technique.h); "{}" for none.
  std::string integrator_options = "{}";
  // AOVs to render (runtime/film_layout.h checks the names), each with its place ("render.aovs[1]").
  std::vector<std::string> aovs, aov_places;
};

// "independent", "stratified", "sobol", "halton" -> PC_SAMPLER_*; false for an unknown name.
bool sampler_from_name(const std::string& name, uint32_t* sampler);
const char* sampler_name(uint32_t sampler);

// The largest distance from the camera (in scene units, per axis) that geometry may reach, and so the
// largest sphere radius. The kernels work in camera-relative floats and square distances across the
// scene and multiply areas by 4 pi: with every coordinate within E of the camera a squared distance is
// at most 12 E^2, and 4 pi 12 E^2 stays below FLT_MAX for E = 1.5e18.
constexpr double kMaxSceneExtent = 1.5e18;

// A mesh that several shapes place becomes an instanced mesh when the shapes ask for it ("instance":
// true), or by default when its copies would hold at least this many triangles: below that, copies cost
// little memory, and tracing them directly saves each ray the instance level.
constexpr size_t kMinInstancedTriangles = 4096;

// A mesh that several shapes place (instances): loaded and cleaned once, in its own coordinates, and
// stored once on the device with a BVH of its own (kernels/intersect.cl, trace_instances).
struct InstancedMesh {
  std::string label;  // the first shape that places it, for messages and `pathcl info`
  TriangleMesh mesh;  // in the mesh's own coordinates (positions in double like a shape's)
  CleanReport clean;
  // Per triangle the material index ("material": "from_mtl"); empty when all have the shapes' material.
  std::vector<uint32_t> triangle_materials;
  glm::dvec3 lo{0}, hi{0};  // the box of mesh.positions (set_bounds), which each placement is checked by
};

// Sets m.lo and m.hi from its mesh's positions (both 0 for none).
void set_bounds(InstancedMesh& m);

// One shape after loading: a cleaned triangle mesh or an analytic sphere, in world space, or a
// placement of an InstancedMesh.
struct ShapeDesc {
  std::string label;  // "shapes[3] (meshes/box.obj)" for messages and `pathcl info`
  bool is_sphere = false;
  TriangleMesh mesh;  // when !is_sphere
  CleanReport clean;  // when !is_sphere
  glm::dvec3 center{0};  // world coordinates, like TriangleMesh::positions
  double radius = 0;
  bool flip_normals = false;  // sphere: normals point inwards (meshes are flipped by winding at load)
  glm::mat3 frame{1.0f};      // sphere: its own x, y, z axes in world space (unit columns), for its uvs
  uint32_t material = 0;      // index into SceneDescription::materials
  glm::vec3 emission{0};
  bool two_sided = false;
  // Meshes whose faces differ ("material": "from_mtl"): per triangle of mesh, the material index and
  // the emission; empty when every triangle has `material` and `emission`.
  std::vector<uint32_t> triangle_materials;
  std::vector<glm::vec3> triangle_emission;
  // An instance: index into SceneDescription::instanced_meshes, placed in the world by `transform`
  // (mesh, clean and the per-triangle vectors are then empty; an instance never emits). PC_INVALID for
  // a shape that holds its own geometry.
  uint32_t instance_of = 0xffffffffu;
  glm::dmat4 transform{1.0};
};

struct SceneDescription;
// A mesh's copy placed by a transform, in double: positions, normals (by the inverse transpose,
// normalized) and, for a mirroring transform, the winding, so that the front stays the front.
TriangleMesh placed_mesh(TriangleMesh mesh, const glm::dmat4& transform);
// An instance as a shape of its own: its mesh placed in the world (placed_mesh), its per-triangle
// materials; any other shape as it is.
ShapeDesc flattened_shape(const SceneDescription& scene, const ShapeDesc& s);
// The triangles a shape puts into the world (an instance's mesh's).
size_t shape_triangle_count(const SceneDescription& scene, const ShapeDesc& s);

inline uint32_t triangle_material(const ShapeDesc& s, size_t t) {
  return s.triangle_materials.empty() ? s.material : s.triangle_materials[t];
}
inline glm::vec3 triangle_emission(const ShapeDesc& s, size_t t) {
  return s.triangle_emission.empty() ? s.emission : s.triangle_emission[t];
}
// Whether any part of the shape emits.
inline bool shape_emits(const ShapeDesc& s) {
  for (const glm::vec3& e : s.triangle_emission)
    if (e != glm::vec3(0)) return true;
  return s.emission != glm::vec3(0);
}

struct SceneDescription {
  std::string path;  // the scene file, for messages
  CameraDesc camera;
  std::vector<MaterialDesc> materials;
  std::vector<ShapeDesc> shapes;
  std::vector<LightDesc> lights;
  std::vector<TextureImage> textures;
  std::vector<InstancedMesh> instanced_meshes;
  RenderSettings render;
  std::vector<std::string> warnings;  // things loading changed or ignored, each naming its place
};

// Reads and validates a scene file (JSON, or Mitsuba XML or pbrt translated, scene/scene_import.h); throws
// SceneError naming the file and JSON path (or source line) on bad input. `defines`: values for a Mitsuba
// file's <default>s (Mitsuba's -D NAME=VALUE).
SceneDescription load_scene(const std::string& path,
                            const std::vector<std::pair<std::string, std::string>>& defines = {});

// Loads an OBJ file into a polygon soup (all groups together), validating indices and coordinates;
// throws SceneError naming the file and line.
PolygonSoup load_obj(const std::string& path);
