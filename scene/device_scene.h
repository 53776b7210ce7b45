// The flattened, device-ready scene: plain arrays of the shared structs, no pointers. This is all that
// runtime/ sees of a scene.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include <glm/vec3.hpp>

#include "kernels/shared/types.h"
#include "scene/bvh_build.h"
#include "scene/scene_description.h"

// Scene features that select kernel code (-D flags); per-render settings never appear here.
enum : uint32_t {
  kFeatureTriangles = 1u << 0,
  kFeatureSpheres = 1u << 1,
  kFeatureSmoothNormals = 1u << 2,
  kFeatureAreaLights = 1u << 3,
  kFeatureDiffuse = 1u << 4,
  kFeatureOrenNayar = 1u << 5,
  kFeaturePhong = 1u << 6,
  kFeatureMirror = 1u << 7,
  kFeatureDielectric = 1u << 8,
  kFeatureRoughConductor = 1u << 9,
  kFeaturePlastic = 1u << 10,
  kFeatureTextures = 1u << 11,
  kFeaturePointLights = 1u << 12,  // point and spot
  kFeatureDirectionalLights = 1u << 13,
  kFeatureEnvironment = 1u << 14,
  kFeatureEnvironmentMap = 1u << 15,
  kFeatureAll = (1u << 16) - 1,
};


// Where the device's float coordinates have their origin. Rendering puts it at the camera (the kernel's
// camera then sits at 0): floats are finest where the image needs them, and a scene 1e6 away from the
// world origin renders like one at it, because world positions stay in double until the camera position
// is subtracted. Ray files (`pathcl rays`, bench/make_rays) hold world coordinates and other tracers
// read the same files, so their scenes keep the world origin and the rays are traced as written.
enum class DeviceOrigin { camera, world };

struct DeviceScene {
  SceneHeader header{};              // camera, film size and counts; settings are filled in per render
  glm::dvec3 origin{0};              // world position of the device coordinates' origin (DeviceOrigin)
  std::vector<Bvh4Node> nodes;      // the 4-wide BVH (collapse_to_bvh4 of bvh)
  std::vector<Primitive> prims;      // BVH leaf order
  std::vector<uint32_t> leaf_slot;    // scene-order primitive index -> index into prims
  std::vector<PrimShading> shading;  // scene order (the primitive index of hits and ray files)
  std::vector<pc_float4> normals;    // 3 per primitive in scene order, only for smooth shapes
  std::vector<pc_float4> uvs;        // 2 per primitive in scene order (kernels/scene.cl), only with textures
  std::vector<Material> materials;
  std::vector<Light> lights;         // area lights first (in primitive order), then the others
  std::vector<float> light_cdf;      // light_count + 1 entries, light_cdf[0] = 0, last = 1
  std::vector<Texture> textures;
  std::vector<pc_float4> texels;
  std::vector<float> env_dist;       // the environment map's sampling distribution (kernels/environment.cl)
  uint32_t features = 0;
  uint32_t triangle_count = 0, sphere_count = 0;
  uint32_t skipped_zero_area_emitters = 0;  // triangles and spheres whose float area is 0
  Bvh bvh;                           // the binary tree's statistics; its nodes are dropped once collapsed
  uint32_t wide_depth = 0;           // depth of the 4-wide tree
};

// Flattens the scene: primitives in scene order (shapes in file order, triangles of a mesh in mesh
// order), the BVH over them, the light distribution (proportional to power), the camera basis; every
// position relative to `origin`, converted to float only after that subtraction. Throws SceneError when
// geometry lies farther than kMaxSceneExtent from the origin.
DeviceScene build_device_scene(const SceneDescription& scene, DeviceOrigin origin = DeviceOrigin::camera);

// Geometry of a scene-order primitive as the device sees it (world minus DeviceScene::origin), for tests
// and ray generation.
Primitive scene_primitive(const DeviceScene& scene, uint32_t prim_index);
