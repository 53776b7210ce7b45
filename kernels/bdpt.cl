/* Bidirectional path tracing (`bdpt`, lane width 1). Work item i of sample s traces light subpath
 * (i, s) (light_path.cl: the `light` integrator's path, its camera connections splatted, its non-delta
 * vertices kept in private memory, at most max_depth of them) and then the camera subpath of pixel i
 * with key (i, s) (the path integrator's sample dimensions, below the light path's), and at each camera
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

/* The camera subpath of key (pixel px, py) and its strategies s = 0, 1 and >= 2 with the light subpath's
 * vertices lv[0 .. lv_count) (in order of length), weighted with the merging factors *mis. Returns the
 * pixel's radiance estimate. VCM (vcm.cl): where `own` is false, the unit holds another unit's light
 * subpath of this key and the path takes only its merges (PC_VCM_MERGE: at each non-delta vertex, with
 * the grid's light vertices, into *merged); without connections (bpm, sppm) an emitter counts only where
 * the path to it is specular (merging makes the others), and SPPM stops at its first non-delta vertex,
 * after next-event estimation and merging there, unweighted. */
static inline float3 trace_camera_subpath(const SceneData* sc, __constant const LightTransportHeader* lt,
                                          __global const float* emission_cdf, SampleKey key, uint px, uint py,
                                          const MisFactors* mis, bool own, __global const LightVertex* lv, uint lv_count,
                                          uint* rays
#ifdef PC_VCM
                                   , const MergeGrid* grid, MergeSums* merged, SplatCounts* counts
#endif
) {
  __constant const SceneHeader* h = sc->h;
  Ray ray = camera_path_ray(h, key, px, py);
  float3 throughput = (float3)(1.0f), radiance = (float3)(0.0f);
  float eta_scale = 1.0f;
  /* Partial sums (light_path.cl): the first vertex's reverse strategy is the light path's camera
   * connection (t = 1), counted as PC_BDPT_LIGHT_TRACING_COUNT of its paths. */
  float dvcm = PC_BDPT_LIGHT_TRACING_COUNT / camera_direction_pdf(h, ray.d), dvc = 0.0f, dvm = 0.0f;
  bool specular = true; /* every scattering so far by a delta lobe */
  const bool sppm = (lt->vcm_mode & PC_VCM_SPPM) != 0u;
  float3 prev_p = ray.o;
  for (uint depth = 0;; ++depth) {
    Hit hit;
    ++*rays;
    uint t_count = depth + 2u; /* camera vertices of a path ending at this hit: the lens point and depth + 1 */
    if (!trace_scene(sc, sc, &ray, false, &hit)) {
#ifdef PC_HAS_ENVIRONMENT
      if (own && h->env_light != PC_INVALID && (mis->connect || specular)) { /* s = 0 by the environment */
        Light env = sc->lights[h->env_light];
        float3 le = env_radiance(env, sc->textures, sc->texels, ray.d);
        float others = 0.0f;
        if (depth > 0u && mis->connect) {
          float pos, dir;
          light_emission_pdf(sc, lt, h->env_light, prev_p, ray.d, -ray.d, &pos, &dir);
          float emit = emission_choice_pdf(emission_cdf, h->env_light) * pos * dir;
          others = environment_light_pdf(sc, prev_p, ray.d) * dvcm + emit * dvc;
        }
        radiance += throughput * le * strategy_weight(lt, mis, 0u, t_count, others);
      }
#endif
      break;
    }
    Surface s = scene_surface(sc, &ray, &hit);
    PrimShading sh = sc->shading[s.prim];
    float3 wo = -ray.d;
    float wo_ng = pc_dot(wo, s.ng);
    {
      float3 seg = s.p - prev_p;
      float dist2 = pc_dot(seg, seg), cos_in = fabs(wo_ng);
      dvcm *= dist2 / cos_in;
      dvc /= cos_in;
      dvm /= cos_in;
#ifdef PC_HAS_AREA_LIGHTS
      if (own && sh.light != PC_INVALID && (mis->connect || specular)) { /* s = 0 by an area light */
        float3 le = emitted_towards(sc->lights[sh.light].emission.xyz, sh.flags, s.ng, s.p, ray.o);
        float others = 0.0f;
        if (depth > 0u && mis->connect) {
          float pos, dir;
          light_emission_pdf(sc, lt, sh.light, s.p, s.ng, wo, &pos, &dir);
          float emit = emission_choice_pdf(emission_cdf, sh.light) * pos * dir;
          float direct_a = light_pdf(sc, sh.light, prev_p, s.p, s.ng) * cos_in / dist2;
          others = direct_a * dvcm + emit * dvc;
        }
        radiance += throughput * le * strategy_weight(lt, mis, 0u, t_count, others);
      }
#endif
    }
    if (depth >= h->max_depth) break;

    Material m = material_at(sc, sh.material, &s, &hit);
    MaterialLanes ml = material_lanes_of(m);
    FrameLanes frame;
    frame_about(s.ns, &frame);
    float3 wo_local = to_local(&frame, wo);
    float4 u_light = sample4(h, key, PC_DIM_LIGHT(depth));
    float4 u_bsdf = sample4(h, key, PC_DIM_BSDF(depth));

    if (!bsdf_is_delta(m) && own && (mis->connect || sppm)) {
      /* s = 1: next-event estimation, as the path integrator takes it, weighted against every strategy
       * (SPPM: its direct light, unweighted). */
      DirectLanes direct;
      if (direct_light_lanes(sc, &s, &frame, &ml, wo_local, wo_ng, u_light.x, u_light.y, u_light.z, 1, &direct)) {
        const LightSampleLanes* ls = &direct.ls;
        float w = 1.0f;
        if (!sppm) {
          float direct_pdf = ls->pdf, cos_at_light = 1.0f;
          if (!ls->infinite) {
            float3 to = ls->p - s.p;
            if (ls->delta) direct_pdf *= pc_dot(to, to); /* point, spot: nee_pdf_w's convention */
            else cos_at_light = fabs(pc_dot(ls->n, ls->wi));
          }
          float pos, dir;
          light_emission_pdf(sc, lt, ls->light, ls->p, ls->n, -ls->wi, &pos, &dir);
          float emit = emission_choice_pdf(emission_cdf, ls->light) * pos * dir;
          float bsdf_dir = ls->delta ? 0.0f : bsdf_pdf(m, wo_local, direct.wi_local);
          float bsdf_rev = bsdf_pdf(m, direct.wi_local, wo_local);
          float others = bsdf_dir / direct_pdf + emit * fabs(pc_dot(ls->wi, s.ng)) / (direct_pdf * cos_at_light) *
                                                     (mis->vm + dvcm + dvc * bsdf_rev);
          w = strategy_weight(lt, mis, 1u, t_count, others);
        }
#ifdef PC_HAS_CUTOUTS
        direct.shadow.cutout_seed = cutout_seed(key, PC_RAY_SHADOW(depth));
#endif
        Hit blocker;
        if (w != 0.0f) {
          ++*rays;
          if (!trace_scene(sc, sc, &direct.shadow, true, &blocker)) radiance += direct_contribution_lanes(throughput, &direct, w);
        }
      }
    }
    if (!bsdf_is_delta(m) && own && mis->connect) {
      /* s >= 2: a connection to each light vertex the depth limit allows. */
      for (uint k = 0; k < lv_count && lv[k].length + depth + 1u <= h->max_depth; ++k) {
        float others;
        float3 c = connect_vertices(sc, &s, m, &frame, wo_local, wo_ng, dvcm, dvc, mis->vm, lv + k, &others);
        if (!(c.x > 0.0f || c.y > 0.0f || c.z > 0.0f)) continue;
        float w = strategy_weight(lt, mis, lv[k].length + 1u, t_count, others);
        if (w == 0.0f) continue;
        float3 y_err = (float3)(lv[k].p.w);
        Ray shadow = spawn_ray_to(s.p, s.p_err, s.ng, s.prim, s.instance, lv[k].p.xyz, y_err, lv[k].ng.xyz);
#ifdef PC_HAS_CUTOUTS
        shadow.cutout_seed = cutout_seed(key, PC_BDPT_CUTOUT_BASE + depth * h->max_depth + k);
#endif
        Hit blocker;
        ++*rays;
        if (!trace_scene(sc, sc, &shadow, true, &blocker)) radiance += throughput * c * w;
      }
    }
#ifdef PC_VCM
    if (!bsdf_is_delta(m) && (lt->vcm_mode & PC_VCM_MERGE) != 0u) {
      merge_at(sc, grid, &s, m, &frame, wo_local, wo_ng, depth, throughput, dvcm, dvm, mis->vc, sppm, lt, merged, counts);
      if (sppm) break; /* SPPM's visible point */
    }
#endif

#ifdef PC_MLT
    if (t_count >= mlt_camera_stop(mis)) break; /* the strategies' last camera vertex was this one */
#endif
    BsdfSampleLanes bs;
    float3 wi;
    if (!scatter_lanes(&ml, &frame, s.ng, wo_local, wo_ng, u_bsdf.x, u_bsdf.y, u_bsdf.z, 1, &bs, &wi)) break;
    vcm_scatter_lanes(&ml, &bs, wo_local, wi, s.ng, 1, mis->vm, mis->vc, &dvcm, &dvc, &dvm);
    specular = specular && bs.delta;
    throughput *= bs.weight;
    eta_scale *= bs.eta2;
    prev_p = s.p;
    /* the path integrator's roulette */
    if (!roulette_lanes(max_component(throughput) * eta_scale, u_light.w, depth + 1u > h->rr_depth, 1, &throughput)) break;
    ray = spawn_ray(&s, wi);
#ifdef PC_HAS_CUTOUTS
    ray.cutout_seed = cutout_seed(key, PC_RAY_NEXT(depth));
#endif
  }
  return radiance;
}

#if !defined(PC_VCM) && !defined(PC_MLT)
/* One work unit, as light_integrator.cl's light_pass: the BDPT samples of pixels [path_begin, path_begin +
 * path_count) (a light subpath and a camera subpath each) for samples [sample_begin, sample_begin +
 * sample_count), into the splat film (cleared by the host per unit); work item i keeps its light subpath's
 * vertices in light_vertices[i max_depth ..). */
PC_KERNEL_BODY void bdpt_pass_item(const SceneData* scene, __constant const LightTransportHeader* lt,
                                   __global const float* emission_cdf, __global uint* film, __global SplatStats* stats,
                                   __global LightVertex* light_vertices, uint path_begin, uint path_count,
                                   uint sample_begin, uint sample_count, uint item) {
  SceneData sc = *scene;
  __constant const SceneHeader* h = sc.h;
  if (item >= path_count) return;
  uint pixel = path_begin + item;
  SampleKey key = light_path_key(h, pixel, sample_begin);
  SplatCounts n = {0u, 0u, 0u, 0u, 0u, 0u};
  const MisFactors mis = {0.0f, 0.0f, true, 1u};
  __global LightVertex* vertices = light_vertices + item * light_vertex_slots(h);
  for (uint s = sample_begin; s < sample_begin + sample_count; ++s) {
    key.sample = s;
    uint count = 0u;
    trace_light_paths_lanes(&sc, lt, emission_cdf, film, key, key.pixel, 1, &n, &mis, vertices, &count);
    float3 L = trace_camera_subpath(&sc, lt, emission_cdf, key, pixel % h->width, pixel / h->width, &mis, true,
                                    vertices, count, &n.rays);
    if (splat_is_valid(L, &n)) n.overflows += splat_camera(film, lt, pixel, s & 1u, L);
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
