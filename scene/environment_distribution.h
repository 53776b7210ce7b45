// The environment map's sampling distribution (env_dist; layout and use in kernels/environment.cl).
#pragma once
#include <vector>

#include "scene/scene_description.h"

// Writes the map's distribution into dist: piecewise constant over texel cells in (u, v), each cell's
// weight sin(theta at the row's centre) times the largest luminance the bilinear lookup reaches in the
// cell. Sampling need not follow the bilinear radiance exactly, but its density must be > 0 wherever that
// radiance is, and a bound keeps radiance / density bounded (no fireflies next to a sun). Returns the
// integral of the texels' luminance over the sphere (for the light's power).
double build_env_distribution(const TextureImage& map, std::vector<float>& dist);
