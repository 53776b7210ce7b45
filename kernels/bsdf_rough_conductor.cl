/* Rough metal: GGX microfacet reflection with the conductor Fresnel term (complex index eta + i k per
 * channel; a "specular" colour is turned into eta = 1 and the k that reflects it at normal incidence),
 * sampled by visible normals. Local frame, wo.z > 0. */
#ifndef PATHCL_BSDF_ROUGH_CONDUCTOR_CL
#define PATHCL_BSDF_ROUGH_CONDUCTOR_CL

/* Written once over lanes, as bsdf_diffuse.cl's lobes (eta, k and alpha per lane); bsdf.cl dispatches
 * to them at every width (tests/bsdf_test.cpp, LobesGiveTheOneLaneBits). */
#define PC_LANE_W 1
#include "templates/bsdf_rough_conductor.cl"
#define PC_LANE_W 8
#include "templates/bsdf_rough_conductor.cl"
#define PC_LANE_W 16
#include "templates/bsdf_rough_conductor.cl"

#endif
