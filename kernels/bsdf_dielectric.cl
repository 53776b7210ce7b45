/* Smooth glass: exact Fresnel reflectance chooses between mirror reflection and refraction; total
 * internal reflection past the critical angle. The front side (normal +z) faces the outside medium
 * (index 1), the back the inside (index ior). Radiance crossing into a denser medium is concentrated
 * by (n_i / n_t)^2 (pbrt's radiance transport mode); `color` tints transmission. */
#ifndef PATHCL_BSDF_DIELECTRIC_CL
#define PATHCL_BSDF_DIELECTRIC_CL

/* Written once over lanes, as bsdf_diffuse.cl's lobes (colour and ior per lane; reflection or refraction
 * a per-lane select); *eta2 is (n_t / n_i)^2 where the weight was divided by it, else 1. The mask: where
 * the sample is valid. */
#define PC_LANE_W 1
#include "templates/bsdf_dielectric.cl"
#define PC_LANE_W 8
#include "templates/bsdf_dielectric.cl"
#define PC_LANE_W 16
#include "templates/bsdf_dielectric.cl"

#endif
