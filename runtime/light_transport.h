// What the light-transport integrators (`light`; later BDPT and photon merging) need on the device beside
// the scene: the scene's bounding sphere, the distribution that chooses a light to emit from (by power),
// and the fixed-point scales of the splat film (kernels/shared/light_types.h).
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "kernels/shared/types.h"
#include "kernels/shared/light_types.h"
#include "scene/device_scene.h"

struct LightTransportSetup {
  LightTransportHeader header{};
  std::vector<float> emission_cdf;  // light_count + 1 entries, [0] = 0, last = 1
  std::vector<double> power;        // per light, the luminance power the choice is proportional to (W)
};

// The power of each light (luminance): area pi A L (twice for two-sided emitters), point 4 pi I, spot
// 2 pi I (1 - (cos_inner + cos_outer) / 2) (pbrt-v4's), directional pi R^2 E and environment
// pi R^2 4 E_env (E_env its irradiance estimate of scene/device_scene_build.cpp), R the scene's bounding
// radius. The splat scale is the power of two that puts a pixel 2^20 times brighter than the scene's
// typical radiance, Phi / (4 pi^2 R^2), summed over `spp` samples, at 2^62 units; the squares' scale the
// same for its square.
LightTransportSetup light_transport_setup(const DeviceScene& scene, uint32_t spp);

// The `splats` layer (PC_SPLAT_WORDS 64-bit sums per pixel; or the splat layer of that name) as the film's
// means, variances and half images at film.spp: mean = (even + odd) / (scale spp); variance of the mean from
// the squares (kernels/light_integrator.cl). overflows: sums at or above 2^63 (a hazard) are counted there.
// With first_share > 0 the two halves hold two sets of independent estimates of the image instead of the even
// and odd samples (mlt's first and second half of its chains), first_share of them in the first: each half
// image is its set's own image (its sum over spp first_share, or spp (1 - first_share)), and the variance of
// the mean first_share (1 - first_share) times their squared difference.
struct Film;
void develop_splats(Film& film, const LightTransportHeader& lt, uint64_t* overflows);
void develop_splat_layer(Film& film, const LightTransportHeader& lt, uint64_t* overflows, const char* layer,
                         double first_share = 0);

// The splat film's -D flags on a device: 64-bit atomics where it has them (cl_khr_int64_base_atomics),
// unless the build asks for word pairs.
struct TechniqueBuild;
std::string splat_build_options(const TechniqueBuild& build);

// The merging integrators' first radius where the scene gives none: the footprint of a pixel (its height)
// at the distance the camera looks at (its look_at; a camera without one, glTF's: the distance to the
// scene's centre, or the scene's radius from near it).
double default_merging_radius(const DeviceScene& scene, const LightTransportHeader& lt);

// BDPT and the merging integrators keep each light subpath of a unit in max_depth slots of LightVertex
// (kernels/shared/light_types.h) on the device: the bytes for sizes.unit_items paths, and the most paths a
// unit may hold on sizes.device when each path also takes extra_bytes (its grid entries): the vertex
// buffer within the device's largest allocation, all of them within a quarter of its memory.
struct TechniqueSizes;
size_t light_vertex_slots(const TechniqueSizes& sizes);  // per path: max_depth, at least 1 (kernels' too)
size_t light_vertex_bytes(const TechniqueSizes& sizes);
uint32_t light_vertex_unit_paths(const TechniqueSizes& sizes, size_t extra_bytes);
