// The environment map's sampling distribution (env_dist; layout and use in kernels/environment.cl).
#pragma once
#include <vector>

#include "scene/scene_description.h"

// Writes the map's distribution into dist: piecewise constant over texel cells in (u, v), each cell's
// weight the largest luminance the lookup reaches in the cell, times sin(theta at the row's centre) for a
// lat-long map (mapping PC_ENV_LAT_LONG); an equal-area map (PC_ENV_EQUAL_AREA, PC_ENV_EQUAL_AREA_NEAREST)
// preserves area and takes no such factor, and a nearest-texel one is sampled exactly in proportion to its
// texels' luminance. Sampling need not follow the bilinear radiance exactly, but its density must be > 0
// wherever that radiance is, and a bound keeps radiance / density bounded (no fireflies next to a sun).
// Returns the integral of the texels' luminance over the sphere (for the light's power).
double build_env_distribution(const TextureImage& map, std::vector<float>& dist, uint32_t mapping = PC_ENV_LAT_LONG);
