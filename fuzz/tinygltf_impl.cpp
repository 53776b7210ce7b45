// tinygltf compiled from its header with the fuzzers' instrumentation (instead of the uninstrumented
// shared library of libtinygltf-dev), so that ASan sees its memory accesses and libFuzzer its branches.
// pathcl decodes images itself (scene/gltf_load.cpp sets its own image callback) and writes none.
// TINYGLTF_NO_STB_IMAGE and TINYGLTF_NO_STB_IMAGE_WRITE come from fuzz/CMakeLists.txt, for every file of
// the library that includes tiny_gltf.h.
#define TINYGLTF_IMPLEMENTATION
#include <tiny_gltf.h>
