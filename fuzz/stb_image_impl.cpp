// stb_image compiled from its header with the fuzzers' instrumentation (instead of the uninstrumented
// shared library of libstb-dev, which pathcl_scene links), so that ASan sees its memory accesses and
// libFuzzer its branches. scene/texture_load.cpp is its only user.
#define STB_IMAGE_IMPLEMENTATION
#include <stb_image.h>
