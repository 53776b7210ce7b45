/* Fresnel reflectance of smooth interfaces, unpolarised light, and mirror reflection and refraction in
 * the local frame (normal +z). Written once over lanes (V3 lane3f/lane3f8/lane3f16, F, I their float and
 * int types; issue 15): branches are per-lane selects, so every lane gets the one-lane bits. */
#ifndef PATHCL_FRESNEL_CL
#define PATHCL_FRESNEL_CL

/* fresnel_conductor's per channel part (pbrt-v3 FrConductor), with cos2 = cos_i^2 and sin2 = 1 - cos2. */
#define PC_LANE_W 1
#include "templates/fresnel.cl"
#define PC_LANE_W 8
#include "templates/fresnel.cl"
#define PC_LANE_W 16
#include "templates/fresnel.cl"


#endif
