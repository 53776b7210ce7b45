// The scene as the JSON file describes it, after validation and transformation to world space and
// mesh cleaning: what scene/device_scene_build.cpp flattens for the device.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include <glm/vec3.hpp>

#include "scene/mesh_clean.h"

// Positions are world coordinates in double until build_device_scene makes them camera-relative floats.
struct CameraDesc {
  glm::dvec3 position{0, 0, 0}, look_at{0, 0, -1}, up{0, 1, 0};
  float fov_y_degrees = 40;
  uint32_t width = 512, height = 512;
};

struct MaterialDesc {
  std::string name;
  std::string type;  // "diffuse"
  glm::vec3 reflectance{0.5f};
};

struct RenderSettings {
  uint32_t spp = 16;
  uint32_t max_depth = 8;
  uint32_t seed = 1;
  uint32_t sampler = 0;  // PC_SAMPLER_* of kernels/shared/types.h
};

// "independent", "stratified", "sobol", "halton" -> PC_SAMPLER_*; false for an unknown name.
bool sampler_from_name(const std::string& name, uint32_t* sampler);
const char* sampler_name(uint32_t sampler);

// The largest distance from the camera (in scene units, per axis) that geometry may reach, and so the
// largest sphere radius. The kernels work in camera-relative floats and square distances across the
// scene and multiply areas by 4 pi: with every coordinate within E of the camera a squared distance is
// at most 12 E^2, and 4 pi 12 E^2 stays below FLT_MAX for E = 1.5e18.
constexpr double kMaxSceneExtent = 1.5e18;

// One shape after loading: a cleaned triangle mesh or an analytic sphere, in world space.
struct ShapeDesc {
  std::string label;  // "shapes[3] (meshes/box.obj)" for messages and `pathcl info`
  bool is_sphere = false;
  TriangleMesh mesh;  // when !is_sphere
  CleanReport clean;  // when !is_sphere
  glm::dvec3 center{0};  // world coordinates, like TriangleMesh::positions
  double radius = 0;
  bool flip_normals = false;  // sphere: normals point inwards (meshes are flipped by winding at load)
  uint32_t material = 0;      // index into SceneDescription::materials
  glm::vec3 emission{0};
  bool two_sided = false;
};

struct SceneDescription {
  std::string path;  // the scene file, for messages
  CameraDesc camera;
  std::vector<MaterialDesc> materials;
  std::vector<ShapeDesc> shapes;
  RenderSettings render;
};

// Reads and validates a scene file; throws SceneError naming the file and JSON path on bad input.
SceneDescription load_scene(const std::string& path);

// Loads an OBJ file into a polygon soup (all groups together), validating indices and coordinates;
// throws SceneError naming the file and line.
PolygonSoup load_obj(const std::string& path);
