/* The megakernel: one work item renders sample_count samples of one pixel, whole paths each, and adds
 * them to the film one by one (so any split into passes sums in the same order). */
#include "shared/types.h"
#include "math.cl"
#include "rng.cl"
#include "sampler.cl"
#include "sampling.cl"
#include "scene.cl"
#include "camera.cl"
#include "intersect.cl"
#include "surface.cl"
#include "texture.cl"
#include "bsdf.cl"
#include "environment.cl"
#include "lights.cl"
#include "material.cl"
#include "counters.cl"

/* Light along a ray that escaped: the environment, weighted against light sampling by MIS. */
inline float3 escaped_radiance(const SceneData* sc, float3 x, float3 d, float prev_bsdf_pdf, bool prev_delta) {
#ifdef PC_HAS_ENVIRONMENT
  if (sc->h->env_light != PC_INVALID) {
    Light env = sc->lights[sc->h->env_light];
    float3 le = env_radiance(env, sc->textures, sc->texels, d);
    if (prev_delta) return le;
    return le * power_heuristic(prev_bsdf_pdf, environment_light_pdf(sc, x, d));
  }
#endif
  return (float3)(0.0f);
}

inline float3 trace_path(const SceneData* sc, SampleKey key, uint px, uint py, uint* rays) {
  __constant const SceneHeader* h = sc->h;
  Ray ray;
  camera_ray(h, px, py, sample4(h, key, 0), &ray.o, &ray.d);
#ifdef PC_DEBUG_PERTURB
  /* Test builds only (DeviceFault::perturb): one operation rounded the other way, as a device of another
   * arithmetic class would, so that the start-up probe must tell the device apart. */
  ray.d.x = nextafter(ray.d.x, INFINITY);
#endif
  ray.tmin = 0.0f;
  ray.tmax = INFINITY;
  ray.skip_prim = PC_INVALID;
  ray.skip_instance = PC_INVALID;
#ifdef PC_HAS_CUTOUTS
  ray.cutout_seed = cutout_seed(key, 0u);
#endif
  float3 throughput = (float3)(1.0f), radiance = (float3)(0.0f);
  float eta_scale = 1.0f; /* product of the (n_t / n_i)^2 that refraction divided the throughput by */
  float prev_bsdf_pdf = 0.0f;
  bool prev_delta = true; /* the camera ray counts as a delta: what it sees directly is not MIS-weighted */
  float3 prev_p = ray.o;
  for (uint depth = 0;; ++depth) {
    Hit hit;
    ++*rays;
    if (!trace_scene(sc, sc, &ray, false, &hit)) {
      radiance += throughput * escaped_radiance(sc, prev_p, ray.d, prev_bsdf_pdf, prev_delta);
      break;
    }
    Surface s = scene_surface(sc, &ray, &hit);
    PrimShading sh = sc->shading[s.prim];
    float3 wo = -ray.d;
#ifdef PC_HAS_AREA_LIGHTS
    if (sh.light != PC_INVALID) {
      float3 le = emitted_towards(sc->lights[sh.light].emission.xyz, sh.flags, s.ng, s.p, ray.o);
      float w = prev_delta ? 1.0f : power_heuristic(prev_bsdf_pdf, light_pdf(sc, sh.light, prev_p, s.p, s.ng));
      radiance += throughput * le * w;
    }
#endif
    if (depth >= h->max_depth) break;

    Material m = material_at(sc, sh.material, &s, &hit);
    /* Local shading frame about the front-side shading normal. */
    float3 t, b;
    make_frame(s.ns, &t, &b);
    float3 wo_local = (float3)(pc_dot(wo, t), pc_dot(wo, b), pc_dot(wo, s.ns));
    float wo_ng = pc_dot(wo, s.ng);
    float4 u_light = sample4(h, key, 1 + 2 * depth);
    float4 u_bsdf = sample4(h, key, 2 + 2 * depth);

    /* Next-event estimation, weighted against BSDF sampling by the power heuristic. */
    LightSample ls;
    if (h->light_count > 0 && !bsdf_is_delta(m) && sample_light(sc, s.p, u_light.xyz, &ls)) {
      float3 wi_local = (float3)(pc_dot(ls.wi, t), pc_dot(ls.wi, b), pc_dot(ls.wi, s.ns));
      float3 f = bsdf_eval(m, wo_local, wi_local);
      /* Only reflection here (no transmissive material takes light samples): the light must be on
         wo's side of the geometric surface, so shading normals cannot leak light through it. */
      if (pc_dot(ls.wi, s.ng) * wo_ng > 0.0f && (f.x > 0.0f || f.y > 0.0f || f.z > 0.0f)) {
        Ray shadow;
        if (ls.infinite) {
          shadow = spawn_ray(&s, ls.wi);
        } else {
          shadow = spawn_ray_to(s.p, s.p_err, s.ng, s.prim, s.instance, ls.p, ls.p_err, ls.n);
        }
        Hit blocker;
        ++*rays;
#ifdef PC_HAS_CUTOUTS
        shadow.cutout_seed = cutout_seed(key, 2u * depth + 1u);
#endif
        if (!trace_scene(sc, sc, &shadow, true, &blocker)) {
          float w = ls.delta ? 1.0f : power_heuristic(ls.pdf, bsdf_pdf(m, wo_local, wi_local));
          radiance += throughput * f * ls.Le * (fabs(wi_local.z) * w / ls.pdf);
        }
      }
    }

    BsdfSample bs;
    if (!bsdf_sample(m, wo_local, u_bsdf.xyz, &bs)) break;
    float3 wi = bs.wi.x * t + bs.wi.y * b + bs.wi.z * s.ns;
    /* Reflection must stay on wo's side of the geometric surface and transmission must cross it:
       with shading normals the two can disagree, and then the path stops rather than leak light. */
    bool transmitted = bs.wi.z * wo_local.z < 0.0f;
    if ((pc_dot(wi, s.ng) * wo_ng > 0.0f) == transmitted) break;
    throughput *= bs.weight;
    eta_scale *= bs.eta2;
    prev_bsdf_pdf = bs.pdf;
    prev_delta = bs.delta;
    prev_p = s.p;
    if (depth + 1 > h->rr_depth) {
      /* Russian roulette: survive with probability min(1, max throughput), reweighted to stay unbiased.
       * The throughput is taken without the radiance scaling of refraction (pbrt-v4's etaScale): inside
       * glass it is (n_i / n_t)^2 = 0.44 times lower only until the path leaves again, and killing paths
       * for it there made glass scenes noisier (peer benchmark, glass-metal). */
      float q = fmin(1.0f, max_component(throughput) * eta_scale);
      if (u_light.w >= q) break;
      throughput /= q;
    }
    ray = spawn_ray(&s, wi);
#ifdef PC_HAS_CUTOUTS
    ray.cutout_seed = cutout_seed(key, 2u * depth + 2u);
#endif
  }
  return radiance;
}

/* One work unit: samples [sample_begin, sample_begin + sample_count) of pixels pixel_begin + i * pixel_stride,
 * i < pixel_count (stride 1 for the render's units, larger for the start-up probe). Each work item carries
 * its pixel's accumulators from the film and adds the samples one by one, so any split into units, on any
 * device, sums in the same order.
 * The film holds three float4 per pixel: the sums of the even-numbered and of the odd-numbered samples
 * (w counts them) and the sum of squares. The two half sums give a noise estimate from the image itself.
 * stats (UnitStats): rays (64 bits) and hazard counts, added with integer atomics. */
__kernel void render_pass(PC_SCENE_PARAMS, __global float4* film, __global UnitStats* stats, uint pixel_begin,
                          uint pixel_count, uint pixel_stride, uint sample_begin, uint sample_count) {
  SceneData sc = PC_SCENE_DATA;
  uint item = get_global_id(0);
  if (item >= pixel_count) return;
  uint pixel = pixel_begin + item * pixel_stride;
  uint px = pixel % h->width, py = pixel / h->width;
  SampleKey key;
  key.pixel = pixel;
  key.seed = h->seed;
  uint rays = 0u, nan_samples = 0u, inf_samples = 0u, negative_samples = 0u;
  float4 half_sum[2] = {film[3 * pixel], film[3 * pixel + 1]};
  float4 squares = film[3 * pixel + 2];
  for (uint s = sample_begin; s < sample_begin + sample_count; ++s) {
    key.sample = s;
    float3 L = trace_path(&sc, key, px, py, &rays);
#ifdef PC_DEBUG_INJECT_HAZARDS
    /* Test builds only (RenderOptions::debug_inject_hazards): proves that the hazard counters count. */
    if (s % 7u == 3u) L.x = NAN;
    if (s % 11u == 5u) L.y = INFINITY;
    if (s % 13u == 6u) L.z = -1.0f;
#endif
    /* A sample that is not a finite non-negative radiance is counted and dropped: it is a bug to find. */
    if (isnan(L.x) || isnan(L.y) || isnan(L.z)) {
      ++nan_samples;
      L = (float3)(0.0f);
    } else if (isinf(L.x) || isinf(L.y) || isinf(L.z)) {
      ++inf_samples;
      L = (float3)(0.0f);
    } else if (L.x < 0.0f || L.y < 0.0f || L.z < 0.0f) {
      ++negative_samples;
      L = (float3)(0.0f);
    }
    half_sum[s & 1u] += (float4)(L, 1.0f);
    squares.xyz += L * L;
  }
  film[3 * pixel] = half_sum[0];
  film[3 * pixel + 1] = half_sum[1];
  film[3 * pixel + 2] = squares;
  volatile __global uint* counters = (volatile __global uint*)&stats->rays_lo;
  add_counter64(counters, rays);
  if (nan_samples) atomic_add(counters + 2, nan_samples);
  if (inf_samples) atomic_add(counters + 3, inf_samples);
  if (negative_samples) atomic_add(counters + 4, negative_samples);
}
