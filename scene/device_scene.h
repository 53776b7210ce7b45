// The flattened, device-ready scene: plain arrays of the shared structs, no pointers. This is all that
// runtime/ sees of a scene: neither the scene description nor the binary BVH comes with it (they are
// scene/device_scene_build.h's and scene/bvh_build.h's).
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include <glm/vec3.hpp>

#include "kernels/shared/types.h"

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
  kFeatureCutouts = 1u << 16,  // a material with opacity below 1 or an opacity texture
  kFeatureInstances = 1u << 17,  // a mesh placed more than once, stored once (two-level BVH)
  kFeatureVertexColors = 1u << 18,  // a mesh with vertex colours
  kFeatureAll = (1u << 19) - 1,
};

// Whether meshes that several shapes place stay instances (stored once, with a BVH of their own under the
// instance BVH) or become copies in world coordinates (ray files, which other tracers read as triangles,
// and tests that compare the two).
enum class Instancing { keep, flatten };


// Which of the BVH layouts a device scene holds (DeviceScene::bvh_layouts): the arrays nodes (4-wide),
// bvh8 and bvh16. Each device reads one (runtime/device.h, bvh_width), so a render builds only its devices'
// layouts; the others stay empty. On the 549k-triangle benchmark terrain the two that an 8-wide CPU device
// does not read cost 0.12 s of building and 38 MB of peak memory (docs/benchmarks-notes.md).
constexpr uint32_t kBvhLayout4 = 1, kBvhLayout8 = 2, kBvhLayout16 = 4;
constexpr uint32_t kBvhLayoutsAll = kBvhLayout4 | kBvhLayout8 | kBvhLayout16;

// Where the device's float coordinates have their origin. Rendering puts it at the camera (the kernel's
// camera then sits at 0): floats are finest where the image needs them, and a scene 1e6 away from the
// world origin renders like one at it, because world positions stay in double until the camera position
// is subtracted. Ray files (`pathcl rays`, bench/make_rays) hold world coordinates and other tracers
// read the same files, so their scenes keep the world origin and the rays are traced as written.
enum class DeviceOrigin { camera, world };

// Figures of the binary SAH tree the device's 4-wide BVH was collapsed from (scene/bvh_build.h).
struct BvhStats {
  uint32_t node_count = 0;  // binary nodes
  double sah_cost = 0;      // expected traversal + intersection cost (C_trav = C_isect = 1)
  uint32_t depth = 0, leaf_count = 0, max_leaf_size = 0;
  double build_ms = 0;      // binary build and collapse
};

// The arrays (PC_SCENE_ARRAYS of kernels/shared/types.h):
//   nodes      the 4-wide BVH (collapse_to_bvh4 of the binary tree)
//   bvh8       the 8-wide BVH (collapse_to_bvh8 of the same tree) and its leaves, four primitives a
//              block, in one array (append_wide_bvh)
//   bvh16      the 16-wide BVH (collapse_to_bvh16) and its leaves, laid out as bvh8; a device gets one
//              of nodes, bvh8 and bvh16 (runtime/device.h, bvh_width), and only those of bvh_layouts
//              are built
//   prims      geometry in BVH leaf order
//   shading    per primitive in scene order (the primitive index of hits and ray files)
//   normals    3 per primitive in scene order, only for smooth shapes
//   uvs        2 per primitive in scene order (kernels/scene.cl), only with textures
//   colors     3 per primitive in scene order (its corners' linear vertex colours; white for primitives
//              without), only when some mesh has vertex colours
//   materials
//   lights     area lights first (in primitive order), then point and spot lights (these are the light
//              BVH's, [0, header.tree_light_count)), then directional and environment lights
//   light_cdf  over the lights at infinity: their count + 1 entries, light_cdf[0] = 0, last = 1
//   light_bvh  the light BVH over the finite lights (scene/light_bvh_build.h), depth-first
//   textures, texels
//   env_dist   the environment map's sampling distribution (kernels/environment.cl)
//   instances  the rest of the scene (identity) and each placement of an instanced mesh, in the order of
//              instance_bvh's leaves; nodes, bvh8, bvh16 and prims hold the rest of the scene's
//              BVH first (root 0), then each instanced mesh's
//   instance_bvh  the binary BVH over the instances' boxes
struct DeviceScene {
  SceneHeader header{};              // camera, film size and counts; settings are filled in per render
  glm::dvec3 origin{0};              // world position of the device coordinates' origin (DeviceOrigin)
  double view_distance = 0;          // from the camera to what it looks at (its look_at); 0: not given (glTF)
#define PC_DEVICE_SCENE_VECTOR(T, name) std::vector<T> name;
  PC_SCENE_ARRAYS(PC_DEVICE_SCENE_VECTOR)
#undef PC_DEVICE_SCENE_VECTOR
  std::vector<uint32_t> leaf_slot;    // scene-order primitive index -> index into prims (host only)
  // The shape-id AOV's tables (uploaded for the AOV pass alone, kernels/aov.cl): per scene-order primitive
  // the index of its shape in SceneDescription::shapes (PC_INVALID for an instanced mesh's own triangles,
  // whose placements give the shape), and per instance (in instances' order) the shape that places it
  // (PC_INVALID for the rest of the scene).
  std::vector<uint32_t> prim_shapes, instance_shapes;
  uint32_t features = 0;
  uint32_t triangle_count = 0, sphere_count = 0;  // as stored (an instanced mesh's triangles once)
  uint32_t instance_count = 0;            // placements of instanced meshes
  uint64_t instanced_triangle_count = 0;  // the triangles they place, counted per placement
  uint32_t skipped_zero_area_emitters = 0;  // triangles and spheres whose float area is 0
  BvhStats bvh;
  uint32_t bvh_layouts = kBvhLayoutsAll;  // the layouts built (kBvhLayout4, 8, 16); the others' arrays are empty
  uint32_t wide_depth = 0;           // depth of the 4-wide tree
  uint32_t wide8_depth = 0;          // depth of the 8-wide tree
  uint32_t wide8_nodes = 0;          // its nodes (in bvh8, among the leaf blocks)
  uint32_t wide16_depth = 0;         // depth of the 16-wide tree
  uint32_t wide16_nodes = 0;         // its nodes (in bvh16, among the leaf blocks)
};
