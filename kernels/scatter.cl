/* The scattering stage the integrators share, written once over this program's lanes (kernels/lanes.cl):
 * the shading frame and the change to and from it; the BSDF's sample, its direction in the scene and the
 * side test (scatter_lanes); Russian roulette (roulette_lanes); BDPT's partial MIS sums after scattering
 * (vcm_scatter_lanes). Direct lighting is direct_light.cl's. The path integrator, light tracing, BDPT, the
 * merging integrators and the AOV pass run them at their W (1, 8 or 16 lanes); the Metropolis and gathering
 * integrators, whose programs are one lane wide, at W = 1, where LaneF is float, Lane3 float3 and a mask 0
 * or 1 (a Material becomes one lane with material_lanes_of).
 * Each does the operations the integrators did before it, in the same order: the same bits. */
#ifndef PATHCL_SCATTER_CL
#define PATHCL_SCATTER_CL

#include "math.cl"
#include "lanes.cl"
#include "bsdf.cl"

/* A local shading frame: tangent t, bitangent b and normal n (make_frame about the shading normal). */
typedef struct {
  Lane3 t, b, n;
} FrameLanes;

PC_LANE_INLINE void frame_about(Lane3 n, FrameLanes* f) {
  make_frame(n, &f->t, &f->b);
  f->n = n;
}

static inline Lane3 to_local(const FrameLanes* f, Lane3 w) { return lane3(pc_dot(w, f->t), pc_dot(w, f->b), pc_dot(w, f->n)); }

static inline Lane3 to_world(const FrameLanes* f, Lane3 w) {
  return lane3_add(lane3_add(lane3_scale(f->t, w.x), lane3_scale(f->b, w.y)), lane3_scale(f->n, w.z));
}

/* Scattering at a surface vertex of the lanes in m: the BSDF's sample *bs for wo_local (towards the previous
 * vertex: the camera side on camera paths, back along the light path on light paths; wo_ng its cosine with
 * the geometric normal ng) from u0, u1 (direction) and u2 (lobe), and *wi, its direction in the scene.
 * Returns the lanes that go on: those with a sample whose reflection stays on wo's side of the geometric
 * surface and whose transmission crosses it (with shading normals the two can disagree, and then the path
 * stops rather than leak light). */
PC_LANE_INLINE LaneI scatter_lanes(const MaterialLanes* mat, const FrameLanes* f, Lane3 ng, Lane3 wo_local, LaneF wo_ng,
                           LaneF u0, LaneF u1, LaneF u2, LaneI m, BsdfSampleLanes* bs, Lane3* wi) {
  m &= bsdf_sample_lanes(mat, wo_local, u0, u1, u2, m, bs);
  *wi = to_world(f, bs->wi);
  LaneI transmitted = bs->wi.z * wo_local.z < 0.0f;
  return m & ((pc_dot(*wi, ng) * wo_ng > 0.0f) != transmitted);
}

/* Russian roulette of the lanes in `roulette` (of live): each survives with probability q = min(1, weight)
 * (u its roulette number), its throughput divided by q to stay unbiased. Returns live without the lanes
 * that ended. weight is the throughput's largest component scaled to where paths start (camera paths: times
 * the refraction scaling divided out, pbrt-v4's etaScale; light paths: over the emitted weight). */
PC_LANE_INLINE LaneI roulette_lanes(LaneF weight, LaneF u, LaneI roulette, LaneI live, Lane3* throughput) {
  roulette &= live;
  if (!pc_any_(roulette)) return live;
  LaneF q = fmin(1.0f, weight);
  live &= !(roulette & (u >= q));
  roulette &= live;
  *throughput = lane3_select(*throughput, lane3_div(*throughput, q), roulette);
  return live;
}

/* The partial MIS sums dVCM, dVC and dVM of BDPT and VCM (bdpt.cl, vcm.cl, light_path.cl) after the
 * scattering *bs of the lanes in m, from wo_local to wi (Georgiev's eq. 34-36, SmallVCM's; the cosine is
 * the geometric normal ng's), with the merging factors vm and vc (0 for BDPT, whose dVC is then the same
 * bits) and merge 1 where the vertex merges, else 0 (with vm 0: vcm's first camera vertex, bdpt.cl): a delta
 * lobe keeps dVC and dVM (its reverse density equals the forward one) and leaves no strategy connecting or
 * merging there (dVCM = 0). */
PC_LANE_INLINE void vcm_scatter_lanes(const MaterialLanes* mat, const BsdfSampleLanes* bs, Lane3 wo_local, Lane3 wi, Lane3 ng,
                              LaneI m, LaneF vm, LaneF vc, float merge, LaneF* dvcm, LaneF* dvc, LaneF* dvm) {
  LaneF cos_out = fabs(pc_dot(wi, ng));
  LaneI rough = m & !bs->delta;
  LaneF reverse = bsdf_pdf_lanes(mat, bs->wi, wo_local, rough);
  *dvc = select(*dvc * cos_out, cos_out / bs->pdf * (*dvc * reverse + *dvcm + vm), rough);
  *dvm = select(*dvm * cos_out, cos_out / bs->pdf * (*dvm * reverse + *dvcm * vc + merge), rough);
  *dvcm = select((LaneF)(0.0f), 1.0f / bs->pdf, rough);
}

#endif
