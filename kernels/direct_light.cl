/* The direct-lighting stage the path integrator (at its W) and BDPT's camera subpath (W = 1) share:
 * next-event estimation's light sample, the BSDF towards it and the shadow ray (direct_light_lanes), and
 * what it adds once weighted by each integrator's MIS (direct_contribution_lanes). Light tracing's
 * counterpart, the connection to the camera, is light_path.cl's. */
#ifndef PATHCL_DIRECT_LIGHT_CL
#define PATHCL_DIRECT_LIGHT_CL

#include "scatter.cl"
#include "lights.cl"
#include "surface.cl"

/* Next-event estimation's light sample at surface vertex s of the lanes in m (their materials not delta):
 * a light chosen from the light tree and a point on it (u0 chooses, u1 u2 the point), the BSDF f towards
 * it, in the frame, and the shadow ray (cut-out seed 0, the caller's). */
typedef struct {
  LightSampleLanes ls;
  Lane3 wi_local, f;
  RayLanes shadow;
} DirectLanes;

/* Returns the lanes whose sample can contribute: f above zero, and reflection only (no transmissive material
 * takes light samples): the light on wo's side of the geometric surface (wo_ng: wo's cosine with it), so
 * that shading normals cannot leak light through it. */
PC_LANE_INLINE LaneI direct_light_lanes(const SceneData* sc, const SurfaceLanes* s, const FrameLanes* f, const MaterialLanes* mat,
                                Lane3 wo_local, LaneF wo_ng, LaneF u0, LaneF u1, LaneF u2, LaneI m, DirectLanes* d) {
  if (sc->h->light_count == 0u || !pc_any_(m)) return (LaneI)(0);
  m &= sample_light_lanes(sc, s->p, u0, u1, u2, m, &d->ls);
  if (!pc_any_(m)) return m;
  d->wi_local = to_local(f, d->ls.wi);
  d->f = bsdf_eval_lanes(mat, wo_local, d->wi_local, m);
  m &= (pc_dot(d->ls.wi, s->ng) * wo_ng > 0.0f) & lane3_any_positive(d->f);
  if (!pc_any_(m)) return m;
  spawn_ray_lanes(s->p, s->p_err, s->ng, s->prim, s->instance, d->ls.wi, &d->shadow);
  LaneI finite = m & !d->ls.infinite;
  if (pc_any_(finite)) {
    RayLanes to_point;
    spawn_ray_to_lanes(s->p, s->p_err, s->ng, s->prim, s->instance, d->ls.p, d->ls.p_err, d->ls.n, &to_point);
    d->shadow.o = lane3_select(d->shadow.o, to_point.o, finite);
    d->shadow.d = lane3_select(d->shadow.d, to_point.d, finite);
    d->shadow.tmax = select(d->shadow.tmax, to_point.tmax, finite);
  }
  d->shadow.cutout_seed = (LaneU)(0u);
  return m;
}

/* What the light sample adds where its shadow ray is not blocked, with MIS weight w: throughput f Le |cos| w
 * over the sample's density. */
static inline Lane3 direct_contribution_lanes(Lane3 throughput, const DirectLanes* d, LaneF w) {
  return lane3_scale(lane3_mul(lane3_mul(throughput, d->f), d->ls.Le), fabs(d->wi_local.z) * w / d->ls.pdf);
}

#endif
