/* A connection between a camera vertex and a stored light vertex (bdpt.cl's strategies s >= 2, instant
 * radiosity's gathering in gather.cl): its unweighted contribution and, for BDPT's weights, the densities
 * of the strategies that make the same path. Needs light_path.cl (PC_BDPT: LightVertex). */
#ifndef PATHCL_CONNECT_CL
#define PATHCL_CONNECT_CL

/* Cut-out ray numbers of the connections (camera vertex depth d, light vertex k), past the light path's. */
#define PC_BDPT_CUTOUT_BASE 0x60000000u

/* The contribution of connecting camera vertex s (material m, shading frame f, wo_local towards the
 * previous camera vertex; dvcm, dvc its partial sums) to light vertex y, unweighted sums in *others. */
static inline float3 connect_vertices(const SceneData* sc, const Surface* s, Material m, const FrameLanes* f, float3 wo_local,
                                      float wo_ng, float dvcm, float dvc, float vm, __global const LightVertex* y, float* others) {
  float3 d = y->p.xyz - s->p;
  float dist2 = pc_dot(d, d);
  if (!(dist2 > 0.0f)) return (float3)(0.0f);
  float dist = sqrt(dist2);
  d /= dist;
  /* Reflection only at both ends (no non-delta material transmits), on each one's side of its surface. */
  float3 y_ng = y->ng.xyz, y_ns = y->ns.xyz, wl = y->wl.xyz;
  if (!(pc_dot(d, s->ng) * wo_ng > 0.0f) || !(pc_dot(-d, y_ng) * pc_dot(wl, y_ng) > 0.0f)) return (float3)(0.0f);
  float3 wi_local = to_local(f, d);
  float3 f_camera = bsdf_eval(m, wo_local, wi_local);
  Material my = sc->materials[y->material];
  my.color.xyz = y->color.xyz;
  FrameLanes yf;
  frame_about(y_ns, &yf);
  float3 wc_local = to_local(&yf, -d), wl_local = to_local(&yf, wl);
  float3 f_light = bsdf_eval(my, wc_local, wl_local);
  /* Each end's density of making the other (per area there), and the reverse densities. */
  float camera_dir_a = bsdf_pdf(m, wo_local, wi_local) * fabs(pc_dot(d, y_ng)) / dist2;
  float camera_rev = bsdf_pdf(m, wi_local, wo_local);
  float light_dir_a = bsdf_pdf(my, wl_local, wc_local) * fabs(pc_dot(d, s->ng)) / dist2;
  float light_rev = bsdf_pdf(my, wc_local, wl_local);
  *others = camera_dir_a * (vm + y->ng.w + y->ns.w * light_rev) + light_dir_a * (vm + dvcm + dvc * camera_rev);
  /* The camera end's cosine (shading normal), the light end's adjoint factor (light_path.cl). */
  float g = fabs(wi_local.z) * fabs(pc_dot(wl, y_ns)) * fabs(pc_dot(d, y_ng)) / (fabs(pc_dot(wl, y_ng)) * dist2);
  return f_camera * f_light * y->beta.xyz * g;
}

#endif
