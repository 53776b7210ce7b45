// The flattened, device-ready scene: plain arrays of the shared structs, no pointers. This is all that
// runtime/ sees of a scene.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

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
  kFeatureAll = (1u << 5) - 1,
};

struct DeviceScene {
  SceneHeader header{};              // camera, film size and counts; settings are filled in per render
  std::vector<BvhNode> nodes;
  std::vector<Primitive> prims;      // BVH leaf order
  std::vector<uint32_t> leaf_slot;    // scene-order primitive index -> index into prims
  std::vector<PrimShading> shading;  // scene order (the primitive index of hits and ray files)
  std::vector<pc_float4> normals;    // 3 per primitive in scene order, only for smooth shapes
  std::vector<Material> materials;
  std::vector<Light> lights;
  std::vector<float> light_cdf;      // light_count + 1 entries, light_cdf[0] = 0, last = 1
  uint32_t features = 0;
  uint32_t triangle_count = 0, sphere_count = 0;
  uint32_t skipped_zero_area_emitters = 0;
  Bvh bvh;                           // statistics; bvh.nodes is moved into nodes
};

// Flattens the scene: primitives in scene order (shapes in file order, triangles of a mesh in mesh
// order), the BVH over them, the light distribution (proportional to power), the camera basis.
DeviceScene build_device_scene(const SceneDescription& scene);

// Geometry of a scene-order primitive as the host sees it (for tests and ray generation).
Primitive scene_primitive(const DeviceScene& scene, uint32_t prim_index);
