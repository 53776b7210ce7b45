/* The gathering integrators (lane width 1): instant radiosity (`instant_radiosity`; Keller, "Instant
 * Radiosity", 1997) and stochastic radiosity (`radiosity`: light paths shot into per-triangle power sums,
 * the Monte-Carlo survey's §5 collision estimator). Both are per-sample techniques over pixel units: an
 * iteration is a sample index, and a unit's phases for iteration i first trace the iteration's
 * lt->light_paths light paths (BDPT's, light_path.cl, keyed (j, i) for path j: the sampler's sequence over
 * the iterations), then each pixel of the unit traces its camera path:
 *
 * camera path: from the lens through delta scattering (mirrors, glass) to its first non-delta vertex x,
 * adding what it sees of emitters on the way (no other strategy makes those paths here).
 *
 * instant_radiosity (phases ir_light, ir_gather): the light paths' non-delta vertices are the virtual point
 * lights. x takes next-event estimation (direct light, unweighted) and a shadow-tested connection to every
 * virtual point light of the iteration (indirect light), each f_x G f_y beta / M over the M light paths;
 * with lt->clamp > 0 the geometry term G = |cos_x| |cos_y| / d^2 is clamped to it (biased, dark corners;
 * 0: unbiased). What it cannot make: light reaching x through delta surfaces alone (caustics seen
 * directly), which no virtual point light lies on.
 *
 * radiosity (phases rad_clear, rad_shoot, rad_display): each light path adds the power it carries to the
 * sum of every non-delta triangle (or sphere) it reaches, in fixed point with integer atomics (bins, the
 * same bits in any order); triangle k's irradiance is then E_k = sum_k / (M A_k) and a diffuse surface's
 * radiance rho(x) E_k / pi (its texture at x; other non-delta materials are shown as diffuse of their
 * colour, which the host warns of). Without final gather the camera shows that at x; with it, x takes
 * next-event estimation and one BSDF-sampled ray to the next non-delta vertex y (through delta surfaces,
 * whose emitters it counts), which shows y's radiosity: the discretisation's error is then seen only
 * through one diffuse bounce. The light paths' sums keep paths of at most max_depth scattering events,
 * max_depth - 1 with final gather (x's own is the gather's); the camera's delta bounces are not counted. */
#define PC_BDPT 1
#include "light_path.cl"
#include "direct_light.cl"
#include "connect.cl"
#include "pixel_film.cl"
#include "splat_film.cl"

/* The unit's range (pixel units): pixels pixel_begin + i pixel_stride, i < pixel_count, of iteration
 * sample_begin (sample_count is 1: Technique::per_sample). */
#define PC_GATHER_UNIT uint pixel_begin, uint pixel_count, uint pixel_stride, uint sample_begin, uint sample_count

/* Cut-out ray numbers of instant radiosity's connections (light path j's vertex k), past BDPT's. */
#define PC_GATHER_CUTOUT_BASE 0x70000000u

/* A camera path's first non-delta vertex. */
typedef struct {
  Surface s;
  Hit hit;
  Material m;
  FrameLanes frame;
  float3 wo_local;
  float wo_ng;
  float3 throughput;
  uint depth; /* scattering events before it */
} GatherPoint;

/* Follows `ray` (throughput, `depth` scattering events before it) through delta scattering to the first
 * non-delta vertex, into *g; emitters it hits are added to *radiance, the first one only if count_first
 * (a gather from a vertex that took next-event estimation leaves it to that). False: none is reached. */
static inline bool walk_to_non_delta(const SceneData* sc, SampleKey key, Ray ray, float3 throughput, uint depth,
                                     bool count_first, float3* radiance, uint* rays, GatherPoint* g) {
  __constant const SceneHeader* h = sc->h;
  float eta_scale = 1.0f;
  for (bool first = true;; first = false) {
    Hit hit;
    ++*rays;
    const bool count = count_first || !first;
    if (!trace_scene(sc, sc, &ray, false, &hit)) {
#ifdef PC_HAS_ENVIRONMENT
      if (count && h->env_light != PC_INVALID)
        *radiance += throughput * env_radiance(sc->lights[h->env_light], sc->textures, sc->texels, ray.d);
#endif
      return false;
    }
    Surface s = scene_surface(sc, &ray, &hit);
    PrimShading sh = sc->shading[s.prim];
#ifdef PC_HAS_AREA_LIGHTS
    if (count && sh.light != PC_INVALID)
      *radiance += throughput * emitted_towards(sc->lights[sh.light].emission.xyz, sh.flags, s.ng, s.p, ray.o);
#endif
    if (depth >= h->max_depth) return false;
    Material m = material_at(sc, sh.material, &s, &hit);
    FrameLanes frame;
    frame_about(s.ns, &frame);
    float3 wo = -ray.d;
    float3 wo_local = to_local(&frame, wo);
    float wo_ng = pc_dot(wo, s.ng);
    if (!bsdf_is_delta(m)) {
      g->s = s;
      g->hit = hit;
      g->m = m;
      g->frame = frame;
      g->wo_local = wo_local;
      g->wo_ng = wo_ng;
      g->throughput = throughput;
      g->depth = depth;
      return true;
    }
    float4 u = sample4(h, key, PC_DIM_BSDF(depth));
    MaterialLanes ml = material_lanes_of(m);
    BsdfSampleLanes bs;
    float3 wi;
    if (!scatter_lanes(&ml, &frame, s.ng, wo_local, wo_ng, u.x, u.y, u.z, 1, &bs, &wi)) return false;
    throughput *= bs.weight;
    eta_scale *= bs.eta2;
    if (!roulette_lanes(max_component(throughput) * eta_scale, u.w, depth + 1u > h->rr_depth, 1, &throughput)) return false;
    ray = spawn_ray(&s, wi);
#ifdef PC_HAS_CUTOUTS
    ray.cutout_seed = cutout_seed(key, PC_RAY_NEXT(depth));
#endif
    ++depth;
  }
}

/* The camera path of `key` (at its pixel) to its first non-delta vertex (walk_to_non_delta). */
static inline bool camera_to_non_delta(const SceneData* sc, SampleKey key, float3* radiance, uint* rays, GatherPoint* g) {
  Ray ray;
  camera_path_rays(sc->h, key, key.pixel, key.pixel % sc->h->width, key.pixel / sc->h->width, &ray);
  return walk_to_non_delta(sc, key, ray, (float3)(1.0f), 0u, true, radiance, rays, g);
}

/* Next-event estimation at g (unweighted: the gathering integrators make direct light no other way). */
static inline float3 gather_direct(const SceneData* sc, SampleKey key, const GatherPoint* g, uint* rays) {
  if (g->depth >= sc->h->max_depth) return (float3)(0.0f);
  float4 u = sample4(sc->h, key, PC_DIM_LIGHT(g->depth));
  MaterialLanes ml = material_lanes_of(g->m);
  DirectLanes direct;
  if (!direct_light_lanes(sc, &g->s, &g->frame, &ml, g->wo_local, g->wo_ng, u.x, u.y, u.z, 1, &direct)) return (float3)(0.0f);
#ifdef PC_HAS_CUTOUTS
  direct.shadow.cutout_seed = cutout_seed(key, PC_RAY_SHADOW(g->depth));
#endif
  Hit blocker;
  ++*rays;
  if (trace_scene(sc, sc, &direct.shadow, true, &blocker)) return (float3)(0.0f);
  return direct_contribution_lanes(g->throughput, &direct, 1.0f);
}

/* Adds sample `sample`'s radiance L to pixel `pixel` of the pixel film (pixel_film.cl), counting hazards. */
static inline void add_to_pixel(__global float4* film, uint pixel, uint sample, float3 L, SplatCounts* n) {
  uint at = 3u * pixel;
  float4 half_sum[2] = {film[at], film[at + 1u]}, squares = film[at + 2u];
  accumulate_sample(L, sample, half_sum, &squares, &n->nan_splats, &n->inf_splats, &n->negative_splats);
  film[at] = half_sum[0];
  film[at + 1u] = half_sum[1];
  film[at + 2u] = squares;
}

/* ---- instant radiosity ------------------------------------------------------------------------------ */

/* The iteration's light paths j < M: work item i traces j = i, i + pixel_count, ..., each into its slots
 * j max_depth of light_vertices (never an atomic counter), their count into vertex_counts[j]. */
PC_KERNEL_BODY void ir_light_item(const SceneData* scene, __constant const LightTransportHeader* lt,
                                  __global const float* emission_cdf, __global SplatStats* stats,
                                  __global LightVertex* light_vertices, __global uint* vertex_counts, PC_GATHER_UNIT,
                                  uint item) {
  SceneData sc = *scene;
  __constant const SceneHeader* h = sc.h;
  if (item >= pixel_count) return;
  SplatCounts n = {0u, 0u, 0u, 0u, 0u, 0u};
  const MisFactors mis = {0.0f, 0.0f, false, 1u};
  uint slots = light_vertex_slots(h);
  for (uint j = item; j < lt->light_paths; j += pixel_count) {
    uint count = 0u;
    trace_light_paths_lanes(&sc, lt, emission_cdf, (__global uint*)0, light_path_key(h, j, sample_begin), j, 1, &n, &mis,
                            light_vertices + j * slots, &count);
    vertex_counts[j] = count;
  }
  add_splat_counts(stats, &n);
}
__kernel void ir_light(PC_SCENE_PARAMS, __constant const LightTransportHeader* lt, __global const float* emission_cdf,
                       __global SplatStats* stats, __global LightVertex* light_vertices, __global uint* vertex_counts,
                       PC_GATHER_UNIT) {
  SceneData sc = PC_SCENE_DATA;
  ir_light_item(&sc, lt, emission_cdf, stats, light_vertices, vertex_counts, pixel_begin, pixel_count, pixel_stride,
                sample_begin, sample_count, get_global_id(0));
}

/* Each pixel of the unit: its camera path, next-event estimation and a connection to every virtual point
 * light at its first non-delta vertex. */
PC_KERNEL_BODY void ir_gather_item(const SceneData* scene, __constant const LightTransportHeader* lt,
                                   __global float4* film, __global SplatStats* stats,
                                   __global const LightVertex* light_vertices, __global const uint* vertex_counts,
                                   PC_GATHER_UNIT, uint item) {
  SceneData sc = *scene;
  __constant const SceneHeader* h = sc.h;
  if (item >= pixel_count) return;
  uint pixel = pixel_begin + item * pixel_stride;
  SampleKey key = light_path_key(h, pixel, sample_begin);
  SplatCounts n = {0u, 0u, 0u, 0u, 0u, 0u};
  float3 L = (float3)(0.0f);
  GatherPoint g;
  if (camera_to_non_delta(&sc, key, &L, &n.rays, &g)) {
    L += gather_direct(&sc, key, &g, &n.rays);
    float3 indirect = (float3)(0.0f);
    uint slots = light_vertex_slots(h), paths = lt->light_paths;
    MaterialLanes m = material_lanes_of(g.m);
    for (uint j = 0; j < paths; ++j)
      for (uint k = 0; k < vertex_counts[j]; ++k) {
        __global const LightVertex* y = light_vertices + j * slots + k;
        if (y->length + g.depth + 1u > h->max_depth) break; /* in order of length */
        float others;
        float3 y_p, y_ng;
        float y_err;
        float3 c = connect_vertices(&sc, &g.s, &m, &g.frame, g.wo_local, g.wo_ng, 0.0f, 0.0f, 0.0f, 0.0f, light_vertices,
                                    j * slots + k, 1, &others, &y_p, &y_err, &y_ng);
        if (!(c.x > 0.0f || c.y > 0.0f || c.z > 0.0f)) continue;
        if (lt->clamp > 0.0f) {
          float3 d = y->p.xyz - g.s.p;
          float dist2 = pc_dot(d, d);
          float geometry = fabs(pc_dot(d, g.s.ns)) * fabs(pc_dot(d, y->ns.xyz)) / (dist2 * dist2);
          if (geometry > lt->clamp) c *= lt->clamp / geometry;
        }
        Ray shadow = spawn_ray_to(g.s.p, g.s.p_err, g.s.ng, g.s.prim, g.s.instance, y->p.xyz, (float3)(y->p.w), y->ng.xyz);
#ifdef PC_HAS_CUTOUTS
        shadow.cutout_seed = cutout_seed(key, PC_GATHER_CUTOUT_BASE + j * slots + k);
#endif
        Hit blocker;
        ++n.rays;
        if (!trace_scene(&sc, &sc, &shadow, true, &blocker)) indirect += c;
      }
    L += g.throughput * indirect / (float)paths;
  }
  add_to_pixel(film, pixel, sample_begin, L, &n);
  add_splat_counts(stats, &n);
}
__kernel void ir_gather(PC_SCENE_PARAMS, __constant const LightTransportHeader* lt, __global float4* film,
                        __global SplatStats* stats, __global const LightVertex* light_vertices,
                        __global const uint* vertex_counts, PC_GATHER_UNIT) {
  SceneData sc = PC_SCENE_DATA;
  ir_gather_item(&sc, lt, film, stats, light_vertices, vertex_counts, pixel_begin, pixel_count, pixel_stride,
                 sample_begin, sample_count, get_global_id(0));
}

/* ---- radiosity -------------------------------------------------------------------------------------- */

/* A primitive's power sums: three 64-bit fixed-point words (R G B, each two uints, low first). */
#define PC_BIN_WORDS 6u

/* Work items of a unit's shooting: each traces light paths i, i + items, ... into its own vertex slots,
 * so that the slots take at most 2^17 vertices (14.7 MB) whatever the unit. */
static inline uint shoot_items(__constant const SceneHeader* h, uint pixel_count) {
  return min(pixel_count, max(1u, (1u << 17) / light_vertex_slots(h)));
}

__kernel void rad_clear(PC_SCENE_PARAMS, __global uint* bins, PC_GATHER_UNIT) {
  uint item = get_global_id(0);
  if (item >= pixel_count) return;
  for (uint w = item; w < h->prim_count * PC_BIN_WORDS; w += pixel_count) bins[w] = 0u;
}

/* The iteration's light paths, each vertex's arriving power added to its primitive's sums. */
PC_KERNEL_BODY void rad_shoot_item(const SceneData* scene, __constant const LightTransportHeader* lt,
                                   __global const float* emission_cdf, __global SplatStats* stats,
                                   __global LightVertex* light_vertices, __global uint* bins, PC_GATHER_UNIT,
                                   uint global_id) {
  SceneData sc = *scene;
  __constant const SceneHeader* h = sc.h;
  uint item = global_id, items = shoot_items(h, pixel_count);
  if (item >= items) return;
  SplatCounts n = {0u, 0u, 0u, 0u, 0u, 0u};
  const MisFactors mis = {0.0f, 0.0f, false, 1u};
  __global LightVertex* vertices = light_vertices + item * light_vertex_slots(h);
  /* The longest light path the display uses: with final gather x's own scattering event is the gather's. */
  uint longest = lt->final_gather ? h->max_depth - 1u : h->max_depth;
  for (uint j = item; j < lt->light_paths; j += items) {
    uint count = 0u;
    trace_light_paths_lanes(&sc, lt, emission_cdf, (__global uint*)0, light_path_key(h, j, sample_begin), j, 1, &n, &mis,
                            vertices, &count);
    for (uint k = 0; k < count && vertices[k].length <= longest; ++k) {
      float3 beta = vertices[k].beta.xyz;
      if (!splat_is_valid(beta, &n)) continue;
      volatile __global uint* bin = (volatile __global uint*)bins + PC_BIN_WORDS * vertices[k].prim;
      n.overflows += !splat_add(bin, beta.x, lt->bin_scale) + !splat_add(bin + 2, beta.y, lt->bin_scale) +
                     !splat_add(bin + 4, beta.z, lt->bin_scale);
    }
  }
  add_splat_counts(stats, &n);
}
__kernel void rad_shoot(PC_SCENE_PARAMS, __constant const LightTransportHeader* lt, __global const float* emission_cdf,
                        __global SplatStats* stats, __global LightVertex* light_vertices, __global uint* bins,
                        PC_GATHER_UNIT) {
  SceneData sc = PC_SCENE_DATA;
  rad_shoot_item(&sc, lt, emission_cdf, stats, light_vertices, bins, pixel_begin, pixel_count, pixel_stride,
                 sample_begin, sample_count, get_global_id(0));
}

/* The area of the primitive a hit found (leaf-ordered prims: triangles in device coordinates; the
 * radiosity technique takes no instanced meshes). */
static inline float hit_area(const SceneData* sc, const Hit* hit) {
  Primitive p = sc->prims[hit->slot];
  if (as_uint(p.b.w) == PC_PRIM_SPHERE) return 4.0f * PC_PI * p.b.x * p.b.x;
  return 0.5f * length(cross(p.b.xyz - p.a.xyz, p.c.xyz - p.a.xyz));
}

/* Radiance leaving non-delta vertex g towards its camera side by the iteration's radiosity: rho E / pi,
 * E the irradiance of its primitive (rho: the material's colour there). */
static inline float3 radiosity_at(const SceneData* sc, __constant const LightTransportHeader* lt, __global const uint* bins,
                                  const GatherPoint* g) {
  __global const uint* bin = bins + PC_BIN_WORDS * g->s.prim;
  float3 power = (float3)((float)splat_word_pair(bin), (float)splat_word_pair(bin + 2), (float)splat_word_pair(bin + 4));
  float area = hit_area(sc, &g->hit);
  if (!(area > 0.0f)) return (float3)(0.0f);
  return g->m.color.xyz * power / (lt->bin_scale * (float)lt->light_paths * area * PC_PI);
}

PC_KERNEL_BODY void rad_display_item(const SceneData* scene, __constant const LightTransportHeader* lt,
                                     __global float4* film, __global SplatStats* stats, __global const uint* bins,
                                     PC_GATHER_UNIT, uint item) {
  SceneData sc = *scene;
  __constant const SceneHeader* h = sc.h;
  if (item >= pixel_count) return;
  uint pixel = pixel_begin + item * pixel_stride;
  SampleKey key = light_path_key(h, pixel, sample_begin);
  SplatCounts n = {0u, 0u, 0u, 0u, 0u, 0u};
  float3 L = (float3)(0.0f);
  GatherPoint x;
  if (camera_to_non_delta(&sc, key, &L, &n.rays, &x)) {
    if (!lt->final_gather) {
      L += x.throughput * radiosity_at(&sc, lt, bins, &x);
    } else if (x.depth < h->max_depth) {
      L += gather_direct(&sc, key, &x, &n.rays);
      float4 u = sample4(h, key, PC_DIM_BSDF(x.depth));
      MaterialLanes ml = material_lanes_of(x.m);
      BsdfSampleLanes bs;
      float3 wi;
      if (scatter_lanes(&ml, &x.frame, x.s.ng, x.wo_local, x.wo_ng, u.x, u.y, u.z, 1, &bs, &wi)) {
        Ray ray = spawn_ray(&x.s, wi);
#ifdef PC_HAS_CUTOUTS
        ray.cutout_seed = cutout_seed(key, PC_RAY_NEXT(x.depth));
#endif
        GatherPoint y;
        if (walk_to_non_delta(&sc, key, ray, x.throughput * bs.weight, x.depth + 1u, false, &L, &n.rays, &y))
          L += y.throughput * radiosity_at(&sc, lt, bins, &y);
      }
    }
  }
  add_to_pixel(film, pixel, sample_begin, L, &n);
  add_splat_counts(stats, &n);
}
__kernel void rad_display(PC_SCENE_PARAMS, __constant const LightTransportHeader* lt, __global float4* film,
                          __global SplatStats* stats, __global const uint* bins, PC_GATHER_UNIT) {
  SceneData sc = PC_SCENE_DATA;
  rad_display_item(&sc, lt, film, stats, bins, pixel_begin, pixel_count, pixel_stride, sample_begin, sample_count,
                   get_global_id(0));
}
