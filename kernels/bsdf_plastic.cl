/* Plastic: a Lambertian base under a dielectric coat (index ior), smooth (alpha = 0: a delta reflection)
 * or rough (GGX). Light reaching the base passes the coat twice: the base lobe is scaled by
 * (1 - F(cos_o)) (1 - F(cos_i)); light reflected inside the coat is not returned, so energy never
 * exceeds 1. The coat lobe is chosen with probability F(cos_o) against (1 - F(cos_o)) times the base's
 * largest reflectance. Local frame, wo.z > 0. */
#ifndef PATHCL_BSDF_PLASTIC_CL
#define PATHCL_BSDF_PLASTIC_CL

/* Written once over lanes, as bsdf_diffuse.cl's lobes (colour, ior and alpha per lane; smooth or rough
 * coat and the lobe choice per-lane selects); bsdf.cl dispatches to them at every
 * width (tests/bsdf_test.cpp, LobesGiveTheOneLaneBits). */
#define PC_LANE_W 1
#include "templates/bsdf_plastic.cl"
#define PC_LANE_W 8
#include "templates/bsdf_plastic.cl"
#define PC_LANE_W 16
#include "templates/bsdf_plastic.cl"

#endif
