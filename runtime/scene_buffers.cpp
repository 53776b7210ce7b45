#include "runtime/scene_buffers.h"

size_t scene_bytes(const DeviceScene& scene) {
  size_t bytes = sizeof(SceneHeader);
#define PC_ADD_BYTES(T, name) bytes += scene.name.size() * sizeof(T);
  PC_SCENE_ARRAYS(PC_ADD_BYTES)
#undef PC_ADD_BYTES
  return bytes;
}

SceneBuffers::SceneBuffers(ClContext& cl, const DeviceScene& scene, const SceneHeader& h)
    : header(cl, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, sizeof h, &h) {
#define PC_UPLOAD(T, name) arrays.push_back(upload(cl, scene.name));
  PC_SCENE_ARRAYS(PC_UPLOAD)
#undef PC_UPLOAD
}

cl_uint SceneBuffers::bind(ClKernel& kernel) const {
  kernel.arg(0, header.mem);
  cl_uint index = 1;
  for (const ClBuffer& b : arrays) kernel.arg(index++, b.mem);
  return index;
}
