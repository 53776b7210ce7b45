/* A connection between a camera vertex and a stored light vertex (bdpt.cl's strategies s >= 2, instant
 * radiosity's gathering in gather.cl): its unweighted contribution and, for BDPT's weights, the densities
 * of the strategies that make the same path. Needs light_path.cl (PC_BDPT: LightVertex). */
#ifndef PATHCL_CONNECT_CL
#define PATHCL_CONNECT_CL

/* Cut-out ray numbers of the connections (camera vertex depth d, light vertex k), past the light path's. */
#define PC_BDPT_CUTOUT_BASE 0x60000000u

/* The contribution of connecting camera vertex s of the lanes in m (material mat, shading frame f, wo_local
 * towards the previous camera vertex; dvcm, dvc its partial sums; vm_light and vm_camera the merging factor
 * at the light vertex and at the camera vertex, light_path.cl's MisFactors.vm or 0) to light vertex lv[slot]
 * of each lane, unweighted, and the sums of the densities of the other strategies in *others (0 where nothing
 * connects); the light vertex's point, its error bound and geometric normal in *y_p, *y_err, *y_ng (the shadow ray's). */
static inline Lane3 connect_vertices(const SceneData* sc, const SurfaceLanes* s, const MaterialLanes* mat, const FrameLanes* f,
                                     Lane3 wo_local, LaneF wo_ng, LaneF dvcm, LaneF dvc, float vm_light, float vm_camera,
                                     __global const LightVertex* lv, LaneU slot, LaneI m, LaneF* others, Lane3* y_p,
                                     LaneF* y_err, Lane3* y_ng) {
  const uint stride = (uint)(sizeof(LightVertex) / sizeof(float4));
  slot = lane_safe_index(slot, m);
  Lane3 y_ns, wl, beta, color;
  LaneF y_dvcm, y_dvc, unused;
  lane_gather4(&lv->p, stride, slot, y_p, y_err);
  lane_gather4(&lv->ng, stride, slot, y_ng, &y_dvcm);
  lane_gather4(&lv->ns, stride, slot, &y_ns, &y_dvc);
  lane_gather4(&lv->wl, stride, slot, &wl, &unused);
  lane_gather4(&lv->beta, stride, slot, &beta, &unused);
  lane_gather4(&lv->color, stride, slot, &color, &unused);
  Lane3 d = lane3_sub(*y_p, s->p);
  LaneF dist2 = pc_dot(d, d);
  m &= dist2 > 0.0f;
  LaneF dist = sqrt(dist2);
  d = lane3_div(d, dist);
  /* Reflection only at both ends (no non-delta material transmits), on each one's side of its surface. */
  m &= (pc_dot(d, s->ng) * wo_ng > 0.0f) & (pc_dot(lane3_neg(d), *y_ng) * pc_dot(wl, *y_ng) > 0.0f);
  *others = (LaneF)(0.0f);
  if (!pc_any_(m)) return lane3_splat((float3)(0.0f));
  Lane3 wi_local = to_local(f, d);
  Lane3 f_camera = bsdf_eval_lanes(mat, wo_local, wi_local, m);
  LaneGroups at;
  MaterialLanes my;
  material_lanes_gather(sc, lane_gather_uint(PC_FIELD_U(lv, material), slot), m, &at, &my);
  my.color = color;
  FrameLanes yf;
  frame_about(y_ns, &yf);
  Lane3 wc_local = to_local(&yf, lane3_neg(d)), wl_local = to_local(&yf, wl);
  Lane3 f_light = bsdf_eval_lanes(&my, wc_local, wl_local, m);
  /* Each end's density of making the other (per area there), and the reverse densities. */
  LaneF camera_dir_a = bsdf_pdf_lanes(mat, wo_local, wi_local, m) * fabs(pc_dot(d, *y_ng)) / dist2;
  LaneF camera_rev = bsdf_pdf_lanes(mat, wi_local, wo_local, m);
  LaneF light_dir_a = bsdf_pdf_lanes(&my, wl_local, wc_local, m) * fabs(pc_dot(d, s->ng)) / dist2;
  LaneF light_rev = bsdf_pdf_lanes(&my, wc_local, wl_local, m);
  *others = camera_dir_a * (vm_light + y_dvcm + y_dvc * light_rev) + light_dir_a * (vm_camera + dvcm + dvc * camera_rev);
  /* The camera end's cosine (shading normal), the light end's adjoint factor (light_path.cl). */
  LaneF g = fabs(wi_local.z) * fabs(pc_dot(wl, y_ns)) * fabs(pc_dot(d, *y_ng)) / (fabs(pc_dot(wl, *y_ng)) * dist2);
  return lane3_select(lane3_splat((float3)(0.0f)), lane3_scale(lane3_mul(lane3_mul(f_camera, f_light), beta), g), m);
}

#endif
