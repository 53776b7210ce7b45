/* Bidirectional path tracing (`bdpt`, W = PC_LANES samples at once, a lane each: kernels/lanes.cl). Work
 * item i of sample s traces light subpath (i, s) (light_path.cl: the `light` integrator's path, its camera
 * connections splatted, its non-delta vertices kept in device memory, at most max_depth of them) and then
 * the camera subpath of pixel i with key (i, s) (the path integrator's sample dimensions, below the light path's), and at each camera
 * vertex takes every strategy: the emitter it hits (s = 0), next-event estimation (s = 1) and a
 * connection to each light vertex (s >= 2); the light path's own camera connections are t = 1. A path
 * with k scattering events is made by all k + 2 strategies (t = 0, a light path hitting the lens, is not
 * taken), each weighted by the balance heuristic. The weights come from partial sums carried along each
 * subpath, dVCM and dVC (Georgiev, "Implementing Vertex Connection and Merging", 2012, with vertex
 * merging off; SmallVCM's BPT), so a connection costs two BSDF evaluations and their reverse densities,
 * whatever the path length. What differs from SmallVCM:
 *  - next-event estimation chooses lights through the light tree, from the receiving point: its density
 *    of the light vertex is evaluated where the receiver is known (light_path.cl, first vertex);
 *  - the camera's directional density is per whole image (camera_direction_pdf), so the light paths per
 *    sample (the pixel count) cancel;
 *  - Russian roulette is left out of the densities (any weights that sum to one over the strategies that
 *    can make a path keep the estimate unbiased; roulette never makes a strategy impossible);
 *  - area conversions take the geometric normal's cosine, throughputs the shading normal's.
 * The camera subpath's contributions (s = 0, 1, >= 2) go to its own pixel of the splat film, once per
 * sample, so that the squares estimate the pixel's variance; t = 1 splats land anywhere. */
#define PC_BDPT 1
#include "light_path.cl"
#include "direct_light.cl"
#include "connect.cl"

/* The camera subpaths of the lanes in m, lane j's of key (pixel[j], key.sample) (one lane: key) through image
 * pixel (px[j], py[j]), and their strategies s = 0, 1 and >= 2 with lane j's light subpath vertices
 * lv[lv_first[j] .. lv_first[j] + lv_count[j]) (in order of length), weighted with the merging factors *mis.
 * Returns each lane's radiance estimate. The lanes go bounce by bounce together, each doing the one-lane
 * operations, its connections lane by lane in order. VCM (vcm.cl): in the lanes outside `own`, the unit
 * holds another unit's light subpath of this key and the path takes only its merges (PC_VCM_MERGE: at each
 * non-delta vertex but vcm's first (below), with the grid's light vertices, lane j's into merged[j]); without
 * connections (bpm, sppm) an emitter counts only where the path to it is specular (merging makes the others),
 * and SPPM stops at its first non-delta vertex, after next-event estimation and merging there, unweighted. */
static inline Lane3 trace_camera_subpaths(const SceneData* sc, __constant const LightTransportHeader* lt,
                                          __global const float* emission_cdf, SampleKey key, LaneU pixel, LaneU px,
                                          LaneU py, LaneI m, const MisFactors* mis, LaneI own,
                                          __global const LightVertex* lv, const uint* lv_first, const uint* lv_count,
                                          uint* rays
#ifdef PC_VCM
                                   , const MergeGrid* grid, MergeSums* merged, SplatCounts* counts
#endif
) {
  __constant const SceneHeader* h = sc->h;
  RayLanes ray;
  camera_path_rays(h, key, pixel, px, py, &ray);
  Lane3 throughput = lane3_splat((float3)(1.0f)), radiance = lane3_splat((float3)(0.0f));
  LaneF eta_scale = (LaneF)(1.0f);
  /* Partial sums (light_path.cl): the first vertex's reverse strategy is the light path's camera
   * connection (t = 1), counted as light_tracing_count of its paths (0: not a strategy). */
  LaneF dvcm = light_tracing_count(mis) / camera_direction_pdf(h, ray.d), dvc = (LaneF)(0.0f), dvm = (LaneF)(0.0f);
  LaneI specular = m; /* every scattering so far by a delta lobe */
  const bool sppm = (lt->vcm_mode & PC_VCM_SPPM) != 0u;
  Lane3 prev_p = ray.o;
  LaneI live = m;
  for (uint depth = 0;; ++depth) {
    HitLanes hit;
    *rays += lane_count(live);
    uint t_count = depth + 2u; /* camera vertices of a path ending at this hit: the lens point and depth + 1 */
    LaneI found = trace_lanes(sc, &ray, live, false, &hit);
#ifdef PC_HAS_ENVIRONMENT
    /* s = 0 by the environment */
    LaneI escaped = h->env_light != PC_INVALID ? own & live & !found & (mis->connect ? live : specular) : (LaneI)(0);
    if (pc_any_(escaped)) {
      Light env = sc->lights[h->env_light];
      Lane3 le = env_radiance_lanes(env, sc->textures, sc->texels, ray.d, escaped);
      LaneF others = (LaneF)(0.0f);
      if (depth > 0u && mis->connect) {
        LaneF pos, dir;
        LaneU index = (LaneU)(h->env_light);
        light_emission_pdf_lanes(sc, lt, index, prev_p, ray.d, lane3_neg(ray.d), escaped, &pos, &dir);
        LaneF emit = emission_choice_pdf_lanes(emission_cdf, index, escaped) * pos * dir;
        others = environment_light_pdf_lanes(sc, prev_p, ray.d, escaped) * dvcm + emit * dvc;
      }
      LaneF w = strategy_weight(lt, mis, (LaneU)(0u), (LaneU)(t_count), others);
      radiance = lane3_select(radiance, lane3_add(radiance, lane3_scale(lane3_mul(throughput, le), w)), escaped);
    }
#endif
    live &= found;
    if (!pc_any_(live)) break;
    ShadingLanes sh;
    SurfaceLanes s = scene_surface_lanes(sc, &ray, &hit, live, &sh);
    Lane3 wo = lane3_neg(ray.d);
    LaneF wo_ng = pc_dot(wo, s.ng);
    {
      Lane3 seg = lane3_sub(s.p, prev_p);
      LaneF dist2 = pc_dot(seg, seg), cos_in = fabs(wo_ng);
      dvcm *= dist2 / cos_in;
      dvc /= cos_in;
      dvm /= cos_in;
#ifdef PC_HAS_AREA_LIGHTS
      /* s = 0 by an area light */
      LaneI lit = own & live & (sh.light != PC_INVALID) & (mis->connect ? live : specular);
      if (pc_any_(lit)) {
        Lane3 emission;
        LaneF unused;
        lane_gather4(&sc->lights->emission, (uint)(sizeof(Light) / sizeof(float4)), lane_safe_index(sh.light, lit), &emission,
                     &unused);
        Lane3 le = emitted_towards_lanes(emission, sh.flags, s.ng, s.p, ray.o);
        LaneF others = (LaneF)(0.0f);
        if (depth > 0u && mis->connect) {
          LaneF pos, dir;
          light_emission_pdf_lanes(sc, lt, sh.light, s.p, s.ng, wo, lit, &pos, &dir);
          LaneF emit = emission_choice_pdf_lanes(emission_cdf, sh.light, lit) * pos * dir;
          LaneF direct_a = light_pdf_lanes(sc, sh.light, prev_p, s.p, s.ng, lit) * cos_in / dist2;
          others = direct_a * dvcm + emit * dvc;
        }
        LaneF w = strategy_weight(lt, mis, (LaneU)(0u), (LaneU)(t_count), others);
        radiance = lane3_select(radiance, lane3_add(radiance, lane3_scale(lane3_mul(throughput, le), w)), lit);
      }
#endif
    }
    if (depth >= h->max_depth) break;

    MaterialLanes mat = material_at_lanes(sc, sh.material, &s, &sh, &hit, live);
    FrameLanes frame;
    frame_about(s.ns, &frame);
    Lane3 wo_local = to_local(&frame, wo);
    LaneF ul0, ul1, ul2, ul3, ub0, ub1, ub2, ub3;
    key_sample4_lanes(h, key, pixel, PC_DIM_LIGHT(depth), &ul0, &ul1, &ul2, &ul3);
    key_sample4_lanes(h, key, pixel, PC_DIM_BSDF(depth), &ub0, &ub1, &ub2, &ub3);
    LaneI nondelta = live & !bsdf_is_delta_lanes(mat.type);
    /* vcm (merging and connections) takes no merges at the camera's first vertex: light tracing (t = 1) makes
     * the same paths there, and a merge within half a pixel's footprint is light tracing through a blurred
     * pixel, which cost a third of the merges' time. That strategy is left out of every weight: vm_here and
     * merge_here (vcm_scatter_lanes) are 0 at depth 0, and light_path.cl's t = 1 weight has no merge. */
    const bool merges_here = depth > 0u || !(mis->vc > 0.0f);
    const float vm_here = merges_here ? mis->vm : 0.0f;

    /* s = 1: next-event estimation, as the path integrator takes it, weighted against every strategy
     * (SPPM: its direct light, unweighted). */
    LaneI nee = mis->connect || sppm ? own & nondelta : (LaneI)(0);
    if (pc_any_(nee)) {
      DirectLanes direct;
      nee = direct_light_lanes(sc, &s, &frame, &mat, wo_local, wo_ng, ul0, ul1, ul2, nee, &direct);
      if (pc_any_(nee)) {
        const LightSampleLanes* ls = &direct.ls;
        LaneF w = (LaneF)(1.0f);
        if (!sppm) {
          LaneI finite = !ls->infinite;
          Lane3 to = lane3_sub(ls->p, s.p);
          /* point, spot: nee_pdf_w's convention */
          LaneF direct_pdf = select(ls->pdf, ls->pdf * pc_dot(to, to), finite & ls->delta);
          LaneF cos_at_light = select((LaneF)(1.0f), fabs(pc_dot(ls->n, ls->wi)), finite & !ls->delta);
          LaneF pos, dir;
          light_emission_pdf_lanes(sc, lt, ls->light, ls->p, ls->n, lane3_neg(ls->wi), nee, &pos, &dir);
          LaneF emit = emission_choice_pdf_lanes(emission_cdf, ls->light, nee) * pos * dir;
          LaneF bsdf_dir = select(bsdf_pdf_lanes(&mat, wo_local, direct.wi_local, nee), (LaneF)(0.0f), ls->delta);
          LaneF bsdf_rev = bsdf_pdf_lanes(&mat, direct.wi_local, wo_local, nee);
          LaneF others = bsdf_dir / direct_pdf + emit * fabs(pc_dot(ls->wi, s.ng)) / (direct_pdf * cos_at_light) *
                                                     (vm_here + dvcm + dvc * bsdf_rev);
          w = strategy_weight(lt, mis, (LaneU)(1u), (LaneU)(t_count), others);
        }
#ifdef PC_HAS_CUTOUTS
        direct.shadow.cutout_seed = key_cutout_seed_lanes(h, key, pixel, PC_RAY_SHADOW(depth));
#endif
        LaneI shoot = nee & (w != 0.0f);
        if (pc_any_(shoot)) {
          *rays += lane_count(shoot);
          HitLanes blocker;
          LaneI reach = shoot & !trace_lanes(sc, &direct.shadow, shoot, true, &blocker);
          radiance = lane3_select(radiance, lane3_add(radiance, direct_contribution_lanes(throughput, &direct, w)), reach);
        }
      }
    }
    /* s >= 2: a connection to each light vertex the depth limit allows, lane j's k-th with the others' k-th. */
    LaneI connecting = mis->connect ? own & nondelta : (LaneI)(0);
    uint most = 0u;
    PC_EACH_LANE(j, pc_lane_bits(connecting)) most = max(most, lv_count[j]);
    for (uint k = 0; k < most; ++k) {
      uint slot_of[PC_LANES], length_of[PC_LANES], valid = 0u;
      for (uint j = 0u; j < PC_LANES; ++j) slot_of[j] = length_of[j] = 0u;
      PC_EACH_LANE(j, pc_lane_bits(connecting)) {
        if (k >= lv_count[j]) continue;
        slot_of[j] = lv_first[j] + k;
        length_of[j] = lv[slot_of[j]].length;
        if (length_of[j] + depth + 1u <= h->max_depth) valid |= 1u << j;
      }
      /* a lane's vertices are in order of length: past the limit at k, past it after k */
      connecting = pc_lanes_of_bits(valid, connecting);
      if (!pc_any_(connecting)) break;
      LaneU slot = lane_load(slot_of), length = lane_load(length_of);
      LaneF others, y_err;
      Lane3 y_p, y_ng;
      Lane3 c = connect_vertices(sc, &s, &mat, &frame, wo_local, wo_ng, dvcm, dvc, mis->vm, vm_here, lv, slot, connecting, &others, &y_p,
                                 &y_err, &y_ng);
      LaneI shoot = connecting & lane3_any_positive(c);
      if (!pc_any_(shoot)) continue;
      LaneF w = strategy_weight(lt, mis, length + 1u, (LaneU)(t_count), others);
      shoot &= w != 0.0f;
      if (!pc_any_(shoot)) continue;
      RayLanes shadow;
      spawn_ray_to_lanes(s.p, s.p_err, s.ng, s.prim, s.instance, y_p, lane3(y_err, y_err, y_err), y_ng, &shadow);
      shadow.cutout_seed = (LaneU)(0u);
#ifdef PC_HAS_CUTOUTS
      shadow.cutout_seed = key_cutout_seed_lanes(h, key, pixel, PC_BDPT_CUTOUT_BASE + depth * h->max_depth + k);
#endif
      *rays += lane_count(shoot);
      HitLanes blocker;
      LaneI reach = shoot & !trace_lanes(sc, &shadow, shoot, true, &blocker);
      radiance = lane3_select(radiance, lane3_add(radiance, lane3_scale(lane3_mul(throughput, c), w)), reach);
    }
#ifdef PC_VCM
    if (pc_any_(nondelta) && vcm_merges(lt) && merges_here) {
      merge_at(sc, grid, &s, &mat, &frame, wo_local, wo_ng, depth, throughput, dvcm, dvm, mis->vc, sppm, nondelta, lt, merged,
               counts);
      if (sppm) { /* SPPM's visible points */
        live &= !nondelta;
        if (!pc_any_(live)) break;
      }
    }
#endif

#ifdef PC_MLT
    if (t_count >= mlt_camera_stop(mis)) break; /* the strategies' last camera vertex was this one */
#endif
    BsdfSampleLanes bs;
    Lane3 wi;
    live = scatter_lanes(&mat, &frame, s.ng, wo_local, wo_ng, ub0, ub1, ub2, live, &bs, &wi);
    if (!pc_any_(live)) break;
    vcm_scatter_lanes(&mat, &bs, wo_local, wi, s.ng, live, vm_here, mis->vc, merges_here ? 1.0f : 0.0f, &dvcm, &dvc, &dvm);
    specular &= bs.delta;
    throughput = lane3_select(throughput, lane3_mul(throughput, bs.weight), live);
    eta_scale = select(eta_scale, eta_scale * bs.eta2, live);
    prev_p = s.p;
    /* the path integrator's roulette */
    live = roulette_lanes(lane3_max_component(throughput) * eta_scale, ul3, pc_lanes_of_bits(depth + 1u > h->rr_depth ? ~0u : 0u, live),
                          live, &throughput);
    if (!pc_any_(live)) break;
    spawn_ray_lanes(s.p, s.p_err, s.ng, s.prim, s.instance, wi, &ray);
    ray.cutout_seed = (LaneU)(0u);
#ifdef PC_HAS_CUTOUTS
    ray.cutout_seed = key_cutout_seed_lanes(h, key, pixel, PC_RAY_NEXT(depth));
#endif
  }
  return radiance;
}

#if !defined(PC_VCM) && !defined(PC_MLT)
/* One work unit, as light_integrator.cl's light_pass: the BDPT samples of pixels [path_begin, path_begin +
 * path_count) (a light subpath and a camera subpath each) for samples [sample_begin, sample_begin +
 * sample_count), into the splat film (cleared by the host per unit). Work item i takes pixels i G .. i G + G
 * - 1 (G = PC_ITEM_PIXELS: W x PC_LANE_PIXELS, 1 for one lane), W at a time, pixel p's light subpath's
 * vertices in light_vertices[(p - path_begin) max_depth ..). */
PC_KERNEL_BODY void bdpt_pass_item(const SceneData* scene, __constant const LightTransportHeader* lt,
                                   __global const float* emission_cdf, __global uint* film, __global SplatStats* stats,
                                   __global LightVertex* light_vertices, uint path_begin, uint path_count,
                                   uint sample_begin, uint sample_count, uint item) {
  SceneData sc = *scene;
  __constant const SceneHeader* h = sc.h;
  uint first = item * PC_ITEM_PIXELS;
  if (first >= path_count) return;
  LaneU lane = lane_indices();
  SampleKey key = light_path_key(h, path_begin + first, sample_begin);
  SplatCounts n = {0u, 0u, 0u, 0u, 0u, 0u};
  const MisFactors mis = {0.0f, 0.0f, true, 1u};
  for (uint s = sample_begin; s < sample_begin + sample_count; ++s) {
    key.sample = s;
    for (uint b = first; b < min(first + PC_ITEM_PIXELS, path_count); b += PC_LANES) {
      LaneU index = (LaneU)(b) + lane, pixel = (LaneU)(path_begin) + index;
      LaneI m = index < path_count;
      key.pixel = path_begin + b;
      __global LightVertex* vertices = light_vertices + b * light_vertex_slots(h);
      uint count[PC_LANES], first_slot[PC_LANES];
      for (uint j = 0u; j < PC_LANES; ++j) count[j] = 0u, first_slot[j] = j * light_vertex_slots(h);
      trace_light_paths_lanes(&sc, lt, emission_cdf, film, key, pixel, m, &n, &mis, vertices, count);
      Lane3 L = trace_camera_subpaths(&sc, lt, emission_cdf, key, pixel, pixel % h->width, pixel / h->width, m, &mis, m,
                                      vertices, first_slot, count, &n.rays);
      PC_EACH_LANE(j, pc_lane_bits(m)) {
        float3 value = lane3_at(L, j);
        if (splat_is_valid(value, &n)) n.overflows += splat_camera(film, lt, path_begin + b + j, s & 1u, value);
      }
    }
  }
  add_splat_counts(stats, &n);
}
__kernel void bdpt_pass(PC_SCENE_PARAMS, __constant const LightTransportHeader* lt, __global const float* emission_cdf,
                        __global uint* film, __global SplatStats* stats, __global LightVertex* light_vertices,
                        uint path_begin, uint path_count, uint sample_begin, uint sample_count) {
  SceneData sc = PC_SCENE_DATA;
  bdpt_pass_item(&sc, lt, emission_cdf, film, stats, light_vertices, path_begin, path_count, sample_begin, sample_count,
                 get_global_id(0));
}
#endif
