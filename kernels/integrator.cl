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

/* A path in flight, bounce by bounce (path_begin, path_shade, then its shadow ray's result): the same
 * steps for one path per work item (trace_path) and for a lane of the lane kernels (render_pass_lanes8,
 * render_pass_lanes16), so every path gets the same bits whichever kernel runs it. */
typedef struct {
  Ray ray;           /* the next ray to trace */
  float3 throughput, radiance;
  float3 nee;        /* the light sample's contribution, added when its shadow ray is not blocked */
  float3 prev_p;     /* the previous vertex */
  float eta_scale;   /* product of the (n_t / n_i)^2 that refraction divided the throughput by */
  float prev_bsdf_pdf;
  uint depth;
  bool prev_delta;   /* the camera ray counts as a delta: what it sees directly is not MIS-weighted */
} PathState;

inline void path_begin(const SceneData* sc, SampleKey key, uint px, uint py, PathState* st) {
  __constant const SceneHeader* h = sc->h;
  camera_ray(h, px, py, sample4(h, key, 0), &st->ray.o, &st->ray.d);
#ifdef PC_DEBUG_PERTURB
  /* Test builds only (DeviceFault::perturb): one operation rounded the other way, as a device of another
   * arithmetic class would, so that the start-up probe must tell the device apart. */
  st->ray.d.x = nextafter(st->ray.d.x, INFINITY);
#endif
  st->ray.tmin = 0.0f;
  st->ray.tmax = INFINITY;
  st->ray.skip_prim = PC_INVALID;
  st->ray.skip_instance = PC_INVALID;
  st->ray.cutout_seed = 0u;
#ifdef PC_HAS_CUTOUTS
  st->ray.cutout_seed = cutout_seed(key, 0u);
#endif
  st->throughput = (float3)(1.0f);
  st->radiance = (float3)(0.0f);
  st->nee = (float3)(0.0f);
  st->eta_scale = 1.0f;
  st->prev_bsdf_pdf = 0.0f;
  st->prev_delta = true;
  st->prev_p = st->ray.o;
  st->depth = 0u;
}

/* One bounce at the hit of st->ray (found) or where it escaped: adds the light seen there; when a light
 * sample wants a shadow ray, sets *shadow, st->nee and *has_shadow (the caller adds st->nee if the shadow
 * ray is not blocked, before the next bounce); samples the BSDF for st->ray's successor. Returns whether
 * the path goes on. */
inline bool path_shade(const SceneData* sc, SampleKey key, PathState* st, bool found, const Hit* hit, Ray* shadow,
                       bool* has_shadow) {
  __constant const SceneHeader* h = sc->h;
  *has_shadow = false;
  if (!found) {
    st->radiance += st->throughput * escaped_radiance(sc, st->prev_p, st->ray.d, st->prev_bsdf_pdf, st->prev_delta);
    return false;
  }
  uint depth = st->depth;
  Surface s = scene_surface(sc, &st->ray, hit);
  PrimShading sh = sc->shading[s.prim];
  float3 wo = -st->ray.d;
#ifdef PC_HAS_AREA_LIGHTS
  if (sh.light != PC_INVALID) {
    float3 le = emitted_towards(sc->lights[sh.light].emission.xyz, sh.flags, s.ng, s.p, st->ray.o);
    float w = st->prev_delta ? 1.0f : power_heuristic(st->prev_bsdf_pdf, light_pdf(sc, sh.light, st->prev_p, s.p, s.ng));
    st->radiance += st->throughput * le * w;
  }
#endif
  if (depth >= h->max_depth) return false;

  Material m = material_at(sc, sh.material, &s, hit);
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
      if (ls.infinite) {
        *shadow = spawn_ray(&s, ls.wi);
      } else {
        *shadow = spawn_ray_to(s.p, s.p_err, s.ng, s.prim, s.instance, ls.p, ls.p_err, ls.n);
      }
#ifdef PC_HAS_CUTOUTS
      shadow->cutout_seed = cutout_seed(key, 2u * depth + 1u);
#endif
      float w = ls.delta ? 1.0f : power_heuristic(ls.pdf, bsdf_pdf(m, wo_local, wi_local));
      st->nee = st->throughput * f * ls.Le * (fabs(wi_local.z) * w / ls.pdf);
      *has_shadow = true;
    }
  }

  BsdfSample bs;
  if (!bsdf_sample(m, wo_local, u_bsdf.xyz, &bs)) return false;
  float3 wi = bs.wi.x * t + bs.wi.y * b + bs.wi.z * s.ns;
  /* Reflection must stay on wo's side of the geometric surface and transmission must cross it:
     with shading normals the two can disagree, and then the path stops rather than leak light. */
  bool transmitted = bs.wi.z * wo_local.z < 0.0f;
  if ((pc_dot(wi, s.ng) * wo_ng > 0.0f) == transmitted) return false;
  st->throughput *= bs.weight;
  st->eta_scale *= bs.eta2;
  st->prev_bsdf_pdf = bs.pdf;
  st->prev_delta = bs.delta;
  st->prev_p = s.p;
  if (depth + 1 > h->rr_depth) {
    /* Russian roulette: survive with probability min(1, max throughput), reweighted to stay unbiased.
     * The throughput is taken without the radiance scaling of refraction (pbrt-v4's etaScale): inside
     * glass it is (n_i / n_t)^2 = 0.44 times lower only until the path leaves again, and killing paths
     * for it there made glass scenes noisier (peer benchmark, glass-metal). */
    float q = fmin(1.0f, max_component(st->throughput) * st->eta_scale);
    if (u_light.w >= q) return false;
    st->throughput /= q;
  }
  st->ray = spawn_ray(&s, wi);
#ifdef PC_HAS_CUTOUTS
  st->ray.cutout_seed = cutout_seed(key, 2u * depth + 2u);
#endif
  st->depth = depth + 1u;
  return true;
}

inline float3 trace_path(const SceneData* sc, SampleKey key, uint px, uint py, uint* rays) {
  PathState st;
  path_begin(sc, key, px, py, &st);
  for (;;) {
    Hit hit;
    ++*rays;
    bool found = trace_scene(sc, sc, &st.ray, false, &hit);
    Ray shadow;
    bool has_shadow;
    bool more = path_shade(sc, key, &st, found, &hit, &shadow, &has_shadow);
    if (has_shadow) {
      Hit blocker;
      ++*rays;
      if (!trace_scene(sc, sc, &shadow, true, &blocker)) st.radiance += st.nee;
    }
    if (!more) return st.radiance;
  }
}

/* Adds sample s's radiance to a pixel's accumulators (even and odd half sums, squares). A sample that is
 * not a finite non-negative radiance is counted and dropped: it is a bug to find. */
inline void accumulate_sample(float3 L, uint s, float4* half_sum, float4* squares, uint* nan_samples,
                              uint* inf_samples, uint* negative_samples) {
#ifdef PC_DEBUG_INJECT_HAZARDS
  /* Test builds only (RenderOptions::debug_inject_hazards): proves that the hazard counters count. */
  if (s % 7u == 3u) L.x = NAN;
  if (s % 11u == 5u) L.y = INFINITY;
  if (s % 13u == 6u) L.z = -1.0f;
#endif
  if (isnan(L.x) || isnan(L.y) || isnan(L.z)) {
    ++*nan_samples;
    L = (float3)(0.0f);
  } else if (isinf(L.x) || isinf(L.y) || isinf(L.z)) {
    ++*inf_samples;
    L = (float3)(0.0f);
  } else if (L.x < 0.0f || L.y < 0.0f || L.z < 0.0f) {
    ++*negative_samples;
    L = (float3)(0.0f);
  }
  half_sum[s & 1u] += (float4)(L, 1.0f);
  squares->xyz += L * L;
}

/* The unit's counters into stats (UnitStats) with integer atomics. */
inline void add_unit_stats(__global UnitStats* stats, uint rays, uint nan_samples, uint inf_samples,
                           uint negative_samples) {
  volatile __global uint* counters = (volatile __global uint*)&stats->rays_lo;
  add_counter64(counters, rays);
  if (nan_samples) atomic_add(counters + 2, nan_samples);
  if (inf_samples) atomic_add(counters + 3, inf_samples);
  if (negative_samples) atomic_add(counters + 4, negative_samples);
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
    accumulate_sample(trace_path(&sc, key, px, py, &rays), s, half_sum, &squares, &nan_samples, &inf_samples,
                      &negative_samples);
  }
  film[3 * pixel] = half_sum[0];
  film[3 * pixel + 1] = half_sum[1];
  film[3 * pixel + 2] = squares;
  add_unit_stats(stats, rays, nan_samples, inf_samples, negative_samples);
}

/* ---- The lane kernels (issue 15): W = PC_LANES = 8 or 16 paths per work item ----
 * Built only where the render asks for them (-DPC_LANES, runtime/device_worker.cpp): the one-path
 * program does not pay for them.
 * Lane j of work item i renders pixel pixel_begin + (N i + j) pixel_stride, its samples one after the
 * other as render_pass does, and starts its next sample as soon as its path ends (per-lane
 * regeneration), so the lanes stay busy until every lane's pixel is done. The rays of all lanes are
 * traced together, as one packet (kernels/packet.cl), and each lane's bounce runs path_shade: every pixel
 * gets render_pass's bits. */
#ifdef PC_LANES
/* M(PC_LANES) with PC_LANES's value, for macros that paste it into names. */
#define PC_FOR_LANES_(M, N) M(N)
#define PC_FOR_LANES(M) PC_FOR_LANES_(M, PC_LANES)
#if defined(PC_BVH8) && !defined(PC_HAS_INSTANCES)
#include "packet.cl"
#define PC_LANES_PACKETS
#endif

/* The rays of the lanes set in bits (hits[j], found[j] for each), as one packet where the device's layout
 * has packets, else each alone. */
#ifdef PC_LANES_PACKETS
#define PC_TRACE_LANES(N)                                                                                 \
  inline void trace_lanes##N(const SceneData* sc, const Ray* rays, uint bits, bool any_hit, Hit* hits, bool* found) { \
    trace_rays_as_packet##N(sc, PC_SCENE_BVH(sc), sc->prims, rays, bits, any_hit, hits, found);           \
  }
#else
#define PC_TRACE_LANES(N)                                                                                 \
  inline void trace_lanes##N(const SceneData* sc, const Ray* rays, uint bits, bool any_hit, Hit* hits, bool* found) { \
    for (uint j = 0u; j < N; ++j)                                                                         \
      if ((bits >> j) & 1u) found[j] = trace_scene(sc, sc, rays + j, any_hit, hits + j);                  \
  }
#endif
PC_FOR_LANES(PC_TRACE_LANES)
#undef PC_TRACE_LANES

#define PC_RENDER_PASS_LANES(N)                                                                           \
  __kernel void render_pass_lanes##N(PC_SCENE_PARAMS, __global float4* film, __global UnitStats* stats,    \
                                     uint pixel_begin, uint pixel_count, uint pixel_stride, uint sample_begin, \
                                     uint sample_count) {                                                 \
    SceneData sc = PC_SCENE_DATA;                                                                         \
    uint first = get_global_id(0) * N;                                                                    \
    if (first >= pixel_count) return;                                                                     \
    uint rays = 0u, nan_samples = 0u, inf_samples = 0u, negative_samples = 0u;                            \
    PathState st[N];                                                                                      \
    SampleKey key[N];                                                                                     \
    uint pixel[N];                                                                                        \
    float4 half_sum[N][2], squares[N];                                                                    \
    uint active = 0u; /* bit j: lane j has a path in flight */                                           \
    for (uint j = 0u; j < N; ++j) {                                                                       \
      if (first + j >= pixel_count || sample_count == 0u) continue;                                      \
      pixel[j] = pixel_begin + (first + j) * pixel_stride;                                                \
      key[j].pixel = pixel[j];                                                                            \
      key[j].seed = h->seed;                                                                              \
      key[j].sample = sample_begin;                                                                       \
      half_sum[j][0] = film[3 * pixel[j]];                                                                \
      half_sum[j][1] = film[3 * pixel[j] + 1];                                                            \
      squares[j] = film[3 * pixel[j] + 2];                                                                \
      path_begin(&sc, key[j], pixel[j] % h->width, pixel[j] / h->width, st + j);                          \
      active |= 1u << j;                                                                                  \
    }                                                                                                     \
    uint used = active;                                                                                   \
    while (active != 0u) {                                                                                \
      Ray r[N], shadow[N];                                                                                \
      Hit hit[N];                                                                                         \
      bool found[N], has_shadow[N], more[N];                                                              \
      for (uint j = 0u; j < N; ++j) r[j] = st[j].ray;                                                     \
      trace_lanes##N(&sc, r, active, false, hit, found);                                                  \
      uint shadows = 0u;                                                                                  \
      for (uint j = 0u; j < N; ++j) {                                                                     \
        if (!((active >> j) & 1u)) continue;                                                              \
        ++rays;                                                                                           \
        more[j] = path_shade(&sc, key[j], st + j, found[j], hit + j, shadow + j, has_shadow + j);         \
        if (has_shadow[j]) shadows |= 1u << j;                                                            \
      }                                                                                                   \
      if (shadows != 0u) {                                                                                \
        bool blocked[N];                                                                                  \
        for (uint j = 0u; j < N; ++j)                                                                     \
          if (!((shadows >> j) & 1u)) shadow[j] = r[j]; /* any ray: the lane is not traced */             \
        trace_lanes##N(&sc, shadow, shadows, true, hit, blocked);                                         \
        for (uint j = 0u; j < N; ++j) {                                                                   \
          if (!((shadows >> j) & 1u)) continue;                                                           \
          ++rays;                                                                                         \
          if (!blocked[j]) st[j].radiance += st[j].nee;                                                   \
        }                                                                                                 \
      }                                                                                                   \
      for (uint j = 0u; j < N; ++j) {                                                                     \
        if (!((active >> j) & 1u) || more[j]) continue;                                                   \
        uint s = key[j].sample;                                                                           \
        accumulate_sample(st[j].radiance, s, half_sum[j], squares + j, &nan_samples, &inf_samples,       \
                          &negative_samples);                                                             \
        if (s + 1u < sample_begin + sample_count) {                                                       \
          key[j].sample = s + 1u;                                                                         \
          path_begin(&sc, key[j], pixel[j] % h->width, pixel[j] / h->width, st + j);                      \
        } else {                                                                                          \
          active &= ~(1u << j);                                                                           \
        }                                                                                                 \
      }                                                                                                   \
    }                                                                                                     \
    for (uint j = 0u; j < N; ++j) {                                                                       \
      if (!((used >> j) & 1u)) continue;                                                                  \
      film[3 * pixel[j]] = half_sum[j][0];                                                                \
      film[3 * pixel[j] + 1] = half_sum[j][1];                                                            \
      film[3 * pixel[j] + 2] = squares[j];                                                                \
    }                                                                                                     \
    add_unit_stats(stats, rays, nan_samples, inf_samples, negative_samples);                              \
  }
PC_FOR_LANES(PC_RENDER_PASS_LANES)
#undef PC_RENDER_PASS_LANES
#undef PC_FOR_LANES
#undef PC_FOR_LANES_
#endif /* PC_LANES */
