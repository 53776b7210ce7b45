// The limits of the render settings that both the scene file ("render", "camera") and the command line
// (--spp, --max-depth, ...) set: one set of limits, so a value the file refuses is refused as an option too.
// Below them, the limits of what a scene may ask for that only the scene file sets.
#pragma once
#include <cstdint>

constexpr uint32_t kMaxSpp = 1u << 24;        // samples per pixel: the film counts them in floats, exact to 2^24
constexpr uint32_t kMaxDepth = 1024;          // scattering events of a path
constexpr uint32_t kMaxFilmSide = 16384;      // camera.width and camera.height, in pixels

// A pixel filter wider than the largest film makes no sense, and pixel positions plus filter offsets
// stay exact to 1/256 pixel in float below 2 kMaxFilmSide.
constexpr double kMaxFilterRadius = kMaxFilmSide;  // pixels, for "radius", and 3 "sigma" (its default radius)
// Texels of one image (3 GiB as float texels), and the 4-byte words of all textures' texels together
// (16 GiB): word indices on the device are 32-bit (kernels/texture.cl, Texture::offset).
constexpr uint64_t kMaxTextureTexels = uint64_t(1) << 28;
constexpr uint64_t kMaxSceneTexelWords = uint64_t(1) << 32;
// The largest value of a light's colour channel (emission, MTL Ke, intensity, irradiance, radiance, an
// environment map's scale). The film sums each sample's square over up to kMaxSpp samples in float: a
// radiance of 1e12 seen directly sums to 1.7e31 there, which leaves a factor of 1e7 below FLT_MAX for
// the light that reflections gather from lights close by. 1e12 is still 600 times the sun's luminance.
constexpr float kMaxLightValue = 1e12f;
// A mesh shape's "subdivide": parts per edge (each triangle into their square).
constexpr uint32_t kMaxSubdivide = 64;
