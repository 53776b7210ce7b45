// A device scene's header and arrays (PC_SCENE_ARRAYS of kernels/shared/types.h) uploaded to one device,
// and bound as the first arguments of a kernel that takes PC_SCENE_PARAMS (kernels/scene.cl).
#pragma once
#include <cstddef>
#include <vector>

#include "runtime/device.h"
#include "runtime/kernel_program.h"
#include "scene/device_scene.h"

// Whether the array is one of the BVH layouts (nodes, bvh8, bvh16), and whether a device with this BVH width
// (runtime/device.h) reads it: it gets only one of the layouts.
bool is_bvh_layout_array(const char* name);
bool scene_array_used(const char* name, uint32_t bvh_width);
// Bytes of device memory the header and the arrays take on a device with this BVH width.
size_t scene_bytes(const DeviceScene& scene, uint32_t bvh_width);
// The scene's BVH in the device's layout, for kernels that take its nodes and leaf blocks as two arguments
// (kernels/trace.cl): the 8-wide tree's one array as both, or the 4-wide tree's nodes as both (it has no
// blocks).
struct BvhBuffers {
  ClBuffer tree;  // nodes (4-wide) or bvh8 (8-wide)
  // Sets arguments first and first + 1 (both tree); returns first + 2.
  cl_uint bind(ClKernel& kernel, cl_uint first) const;
};
BvhBuffers upload_bvh(ClContext& cl, const DeviceScene& scene);

struct SceneBuffers {
  ClBuffer header;
  std::vector<ClBuffer> arrays;  // in PC_SCENE_ARRAYS order
  // header: the scene's header with this render's settings filled in.
  SceneBuffers(ClContext& cl, const DeviceScene& scene, const SceneHeader& header);
  // Sets the kernel's arguments 0 .. arrays.size(); returns the index of the next argument.
  cl_uint bind(ClKernel& kernel) const;
};
