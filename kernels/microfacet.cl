/* The GGX (Trowbridge-Reitz) microfacet distribution in the local frame (normal +z), isotropic, with
 * Smith masking and sampling of the visible normals (Heitz 2018). Written once over lanes (V3, F, I as in
 * fresnel.cl): alpha per lane, branches as per-lane selects. */
#ifndef PATHCL_MICROFACET_CL
#define PATHCL_MICROFACET_CL

#define PC_LANE_W 1
#include "templates/microfacet.cl"
#define PC_LANE_W 8
#include "templates/microfacet.cl"
#define PC_LANE_W 16
#include "templates/microfacet.cl"

#endif
