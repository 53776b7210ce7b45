/* Normalised modified Phong (Lafortune and Willems 1994): a Lambertian lobe plus
 * specular (n + 2) / (2 pi) cos^n(angle between wi and the mirror direction of wo). The host keeps
 * diffuse + specular <= 1 per channel; the specular lobe's albedo is at most `specular` (equal at
 * normal incidence), so energy never exceeds 1. Sampling picks a lobe in proportion to luminance, then
 * cosine-weighted or cos^n about the mirror direction. Local frame, wo.z > 0. */
#ifndef PATHCL_BSDF_PHONG_CL
#define PATHCL_BSDF_PHONG_CL

/* Written once over lanes, as bsdf_diffuse.cl's lobes (colour, specular colour and exponent per lane; the
 * lobe choice a per-lane select between both directions); bsdf.cl dispatches to them at every width
 * (tests/bsdf_test.cpp, LobesGiveTheOneLaneBits). */
#define PC_LANE_W 1
#include "templates/bsdf_phong.cl"
#define PC_LANE_W 8
#include "templates/bsdf_phong.cl"
#define PC_LANE_W 16
#include "templates/bsdf_phong.cl"

#endif
