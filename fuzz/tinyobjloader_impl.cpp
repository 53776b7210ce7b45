// tinyobjloader compiled from its header with the fuzzers' instrumentation (instead of the
// uninstrumented shared library), so that ASan sees its memory accesses and libFuzzer its branches.
// Same configuration as tinyobjloader::tinyobjloader: float coordinates.
#define TINYOBJLOADER_IMPLEMENTATION
#include <tiny_obj_loader.h>
