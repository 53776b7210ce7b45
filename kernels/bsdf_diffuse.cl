/* Lambertian reflection. Local frame (normal +z), wo.z > 0 (bsdf.cl mirrors back-side hits). */
#ifndef PATHCL_BSDF_DIFFUSE_CL
#define PATHCL_BSDF_DIFFUSE_CL

/* Test builds only (RenderOptions::debug_bias_diffuse): a 1 % error that `pathcl bench`'s gate must catch. */
#ifdef PC_DEBUG_BIAS_DIFFUSE
#define PC_DIFFUSE_SCALE 1.01f
#else
#define PC_DIFFUSE_SCALE 1.0f
#endif

/* Written once over lanes (V3 lane3f/lane3f8/lane3f16, F, I their float and int types; issue 15): c is the
 * reflectance per lane and branches are per-lane selects, so every lane gets the one-lane bits
 * (tests/bsdf_test.cpp, LobesGiveTheOneLaneBits); bsdf.cl dispatches to these at every width, one included. */
#define PC_LANE_W 1
#include "templates/bsdf_diffuse.cl"
#define PC_LANE_W 8
#include "templates/bsdf_diffuse.cl"
#define PC_LANE_W 16
#include "templates/bsdf_diffuse.cl"

#endif
