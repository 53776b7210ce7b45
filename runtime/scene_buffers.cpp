#include "runtime/scene_buffers.h"

#include <cstring>
#include <stdexcept>
#include <string>

bool is_bvh_layout_array(const char* name) {
  return std::strcmp(name, "nodes") == 0 || std::strcmp(name, "bvh8") == 0 || std::strcmp(name, "bvh16") == 0;
}

bool scene_array_used(const char* name, uint32_t bvh_width) {
  return !is_bvh_layout_array(name) || std::strcmp(name, bvh_width == 4 ? "nodes" : bvh_width == 8 ? "bvh8" : "bvh16") == 0;
}

size_t scene_bytes(const DeviceScene& scene, uint32_t width) {
  size_t bytes = sizeof(SceneHeader);
#define PC_ADD_BYTES(T, name) \
  if (scene_array_used(#name, width)) bytes += scene.name.size() * sizeof(T);
  PC_SCENE_ARRAYS(PC_ADD_BYTES)
#undef PC_ADD_BYTES
  return bytes;
}

namespace {

// The device's BVH width, which the scene must have been built with (DeviceScene::bvh_layouts).
uint32_t built_bvh_width(const ClContext& cl, const DeviceScene& scene) {
  uint32_t width = bvh_width(cl.info);
  if (!(scene.bvh_layouts & bvh_layout(width)))
    throw std::logic_error("the device scene holds no " + std::to_string(width) + "-wide BVH for " + cl.info.name +
                           " (build it with its devices' bvh_layouts)");
  return width;
}

}  // namespace

BvhBuffers upload_bvh(ClContext& cl, const DeviceScene& scene) {
  uint32_t width = built_bvh_width(cl, scene);
  if (width == 8) return {upload(cl, scene.bvh8)};
  if (width == 16) return {upload(cl, scene.bvh16)};
  return {upload(cl, scene.nodes)};
}

// The 8- and 16-wide layouts' nodes and leaf blocks are one buffer, bound as both.
cl_uint BvhBuffers::bind(ClKernel& kernel, cl_uint first) const {
  kernel.arg(first, tree.mem);
  kernel.arg(first + 1, tree.mem);
  return first + 2;
}

// An array the device does not read gets the one-element buffer of an empty vector.
SceneBuffers::SceneBuffers(ClContext& cl, const DeviceScene& scene, const SceneHeader& h)
    : header(cl, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, sizeof h, &h) {
  uint32_t width = built_bvh_width(cl, scene);
#define PC_UPLOAD(T, name) \
  arrays.push_back(scene_array_used(#name, width) ? upload(cl, scene.name) : upload(cl, std::vector<T>()));
  PC_SCENE_ARRAYS(PC_UPLOAD)
#undef PC_UPLOAD
}

cl_uint SceneBuffers::bind(ClKernel& kernel) const {
  kernel.arg(0, header.mem);
  cl_uint index = 1;
  for (const ClBuffer& b : arrays) kernel.arg(index++, b.mem);
  return index;
}
