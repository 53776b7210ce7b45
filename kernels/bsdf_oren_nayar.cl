/* The qualitative Oren-Nayar model of rough diffuse reflection (pbrt-v3), sampled like Lambert.
 * sigma (radians) is the spread of facet slopes; sigma = 0 is Lambertian. Local frame, wo.z > 0. */
#ifndef PATHCL_BSDF_OREN_NAYAR_CL
#define PATHCL_BSDF_OREN_NAYAR_CL

/* Written once over lanes, as bsdf_diffuse.cl's lobes (sigma per lane); bsdf.cl dispatches to
 * them at every width (tests/bsdf_test.cpp, LobesGiveTheOneLaneBits). */
#define PC_LANE_W 1
#include "templates/bsdf_oren_nayar.cl"
#define PC_LANE_W 8
#include "templates/bsdf_oren_nayar.cl"
#define PC_LANE_W 16
#include "templates/bsdf_oren_nayar.cl"

#endif
