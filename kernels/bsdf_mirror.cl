/* A perfect mirror of the given reflectance: one delta lobe. Local frame, wo.z > 0. */
#ifndef PATHCL_BSDF_MIRROR_CL
#define PATHCL_BSDF_MIRROR_CL

/* Written once over lanes, as bsdf_diffuse.cl's lobes; the mask: where the sample is valid. */
#define PC_LANE_W 1
#include "templates/bsdf_mirror.cl"
#define PC_LANE_W 8
#include "templates/bsdf_mirror.cl"
#define PC_LANE_W 16
#include "templates/bsdf_mirror.cl"

#endif
