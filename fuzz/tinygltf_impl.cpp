// tinygltf compiled from its header with the fuzzers' instrumentation (instead of the uninstrumented
// shared library of libtinygltf-dev), so that ASan sees its memory accesses and libFuzzer its branches.
// pathcl decodes images itself (scene/gltf_load.cpp sets its own image callback) and writes none.
#define TINYGLTF_IMPLEMENTATION
#define TINYGLTF_NO_STB_IMAGE
#define TINYGLTF_NO_STB_IMAGE_WRITE
#include <tiny_gltf.h>
