// The limits of the render settings that both the scene file ("render", "camera") and the command line
// (--spp, --max-depth, ...) set: one set of limits, so a value the file refuses is refused as an option too.
#pragma once
#include <cstdint>

constexpr uint32_t kMaxSpp = 1u << 24;        // samples per pixel: the film counts them in floats, exact to 2^24
constexpr uint32_t kMaxDepth = 1024;          // scattering events of a path
constexpr uint32_t kMaxFilmSide = 16384;      // camera.width and camera.height, in pixels
