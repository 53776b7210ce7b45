/* A light path (lane width 1): emitted from a light chosen by power (emission.cl), connected to the camera
 * at every non-delta vertex (camera_importance.cl), shadow-tested and splatted into the pixels its image
 * position lands in (splat_film.cl), weighted by the pixel filter. The `light` integrator traces these
 * alone; BDPT (bdpt.cl, which defines PC_BDPT) traces the same paths as its light subpaths: then each
 * camera connection is weighted by multiple importance sampling against BDPT's other strategies, and the
 * non-delta vertices are kept for the camera subpath to connect to.
 *
 * Importance transport (Veach's thesis, ch. 5; pbrt-v4): the BSDF is evaluated with wo the direction to
 * the camera (or the next vertex) and wi the direction back along the light path; refraction does not
 * scale by (n_t / n_i)^2 (the radiance scaling the BSDF applies is undone: BsdfSample.eta2), and with
 * shading normals each vertex takes the adjoint BSDF's factor |w_l . n_s| |w_o . n_g| / (|w_l . n_g| |w_o . n_s|)
 * (w_l towards the light, w_o outgoing), at connections too, so that light and path tracing estimate the
 * same pixel values.
 *
 * What a light path alone cannot see: light reaching the camera directly from an emitter (the emitter's
 * own vertex is not connected), and anything seen through a specular (delta) surface, since a connection
 * to a pinhole through a mirror or glass has probability zero (docs/light-transport.md). */
#ifndef PATHCL_LIGHT_PATH_CL
#define PATHCL_LIGHT_PATH_CL

#include "shared/types.h"
#include "shared/light_types.h"
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
#include "emission.cl"
#include "camera_importance.cl"
#include "splat_film.cl"
#include "scatter.cl"

/* Sample dimensions (groups of four, sampler.cl). Light paths take groups from light_group_base on, above
 * every group a camera path of the same key takes (PC_DIM_* of sampler.cl: BDPT's camera subpath, the path
 * integrator's), so that the two subpaths of a BDPT sample are independent. */
#define PC_LT_EMIT_POS(h) (light_group_base(h) + 0u)          /* x: light choice, yz: point, w: side */
#define PC_LT_EMIT_DIR(h) (light_group_base(h) + 1u)          /* xy: direction */
#define PC_LT_CONNECT(h, v) (light_group_base(h) + 2u + 2u * (v)) /* xy: lens point, z: roulette, at vertex v */
#define PC_LT_BSDF(h, v) (light_group_base(h) + 3u + 2u * (v))    /* xyz: BSDF sample at vertex v */

/* Cut-out ray numbers of a light path: 0 the first ray, then 2 v + 1 the camera connection of vertex v and
 * 2 v + 2 the ray leaving it; offset from the path integrator's by this (their keys coincide). */
#define PC_LT_CUTOUT_BASE 0x40000000u

typedef struct {
  uint rays, nan_splats, inf_splats, negative_splats, overflows, light_vertices;
} SplatCounts;

/* The key of light path `path` in sample `sample` (numbered like the pixels: a sample holds width x height
 * light paths), the key of the camera path of the same pixel too. */
static inline SampleKey light_path_key(__constant const SceneHeader* h, uint path, uint sample) {
  SampleKey key;
  key.pixel = path;
  key.seed = h->seed;
  key.sample = sample;
  return key;
}

/* The camera ray of key's camera path at pixel (px, py) (BDPT's camera subpath, the gathering integrators'). */
static inline Ray camera_path_ray(__constant const SceneHeader* h, SampleKey key, uint px, uint py) {
  Ray ray;
  camera_ray(h, px, py, sample4(h, key, PC_DIM_CAMERA), &ray.o, &ray.d);
  ray.tmin = 0.0f;
  ray.tmax = INFINITY;
  ray.skip_prim = PC_INVALID;
  ray.skip_instance = PC_INVALID;
#ifdef PC_HAS_CUTOUTS
  ray.cutout_seed = cutout_seed(key, PC_RAY_CAMERA);
#endif
  return ray;
}

/* The adjoint BSDF's shading-normal factor at a vertex (see the top of the file). */
static inline float shading_normal_factor(float3 w_light, float3 w_out, float3 ns, float3 ng) {
  float num = fabs(pc_dot(w_light, ns)) * fabs(pc_dot(w_out, ng));
  float den = fabs(pc_dot(w_light, ng)) * fabs(pc_dot(w_out, ns));
  return den > 0.0f ? num / den : 0.0f;
}

/* False (and counted) for a colour that is not finite and non-negative: such a splat is dropped. */
static inline bool splat_is_valid(float3 c, SplatCounts* n) {
  if (isnan(c.x) || isnan(c.y) || isnan(c.z)) {
    ++n->nan_splats;
    return false;
  }
  if (isinf(c.x) || isinf(c.y) || isinf(c.z)) {
    ++n->inf_splats;
    return false;
  }
  if (c.x < 0.0f || c.y < 0.0f || c.z < 0.0f) {
    ++n->negative_splats;
    return false;
  }
  return true;
}

/* Splats colour c landing at image position `raster` into every pixel the filter reaches, weighted by it. */
static inline void splat_filtered(__global uint* film, __constant const SceneHeader* h, __constant const LightTransportHeader* lt,
                                  float2 raster, uint parity, float3 c, SplatCounts* n) {
  if (!splat_is_valid(c, n)) return;
  float r = h->filter_radius;
  int x0 = max(0, (int)floor(raster.x - r)), x1 = min((int)h->width - 1, (int)floor(raster.x + r));
  int y0 = max(0, (int)floor(raster.y - r)), y1 = min((int)h->height - 1, (int)floor(raster.y + r));
  for (int y = y0; y <= y1; ++y) {
    float wy = filter_density_1d(h, raster.y - ((float)y + 0.5f));
    if (!(wy > 0.0f)) continue;
    for (int x = x0; x <= x1; ++x) {
      float w = wy * filter_density_1d(h, raster.x - ((float)x + 0.5f));
      if (w > 0.0f) n->overflows += splat_pixel(film, lt, (uint)y * h->width + (uint)x, parity, c * w);
    }
  }
}

#ifdef PC_BDPT
/* The factors of the merging strategies in an iteration's MIS weights (SmallVCM's mMisVmWeightFactor and
 * mMisVcWeightFactor; vcm.cl): vm = eta = pi r^2 N with merging on (N light paths an iteration), vc = 1 / eta
 * with connections on too, else 0. BDPT's are 0: its sums then take the same bits (x + 0 is x).
 * connect: whether this iteration takes the connection strategies (s >= 1 with t >= 1); the light paths
 * then splat their camera connections. first_length: the shortest light vertex kept (SPPM keeps those
 * after one scattering event at least: direct light is next-event estimation's).
 * Metropolis (mlt.cl, PC_MLT): a sample takes one strategy, only_s light and only_t camera vertices, weighted
 * by the balance heuristic against the others; or (only_s PC_INVALID) every strategy of the depths (scattering
 * events) depth_lo .. depth_hi, weighted. Its subpaths stop where those strategies need no more vertices
 * (mlt_light_stop, mlt_camera_stop), and its light tracing connections (t = 1) are kept in *splat instead of
 * splatted. */
typedef struct {
  float vm, vc;
  bool connect;
  uint first_length;
#ifdef PC_MLT
  uint only_s, only_t, depth_lo, depth_hi;
#endif
} MisFactors;

#ifdef PC_MLT
/* The light subpath stops after vertex v where v + 2 reaches this; the camera subpath before scattering at a
 * vertex of t_count camera vertices where t_count reaches this. */
static inline uint mlt_light_stop(const MisFactors* m) { return m->only_s == PC_INVALID ? m->depth_hi + 1u : m->only_s; }
static inline uint mlt_camera_stop(const MisFactors* m) { return m->only_s == PC_INVALID ? m->depth_hi + 2u : m->only_t; }
#endif

#ifdef PC_MLT
/* A Metropolis sample's light tracing contribution: its raster position and value (mlt.cl); with several
 * strategies taken (only_s PC_INVALID) the last one, and the luminance of them all. */
typedef struct {
  float2 raster;
  float3 value;
  float luminance;
} MltSplat;
#endif

/* Light vertex slots per light path of a unit (runtime/light_transport.h's light_vertex_slots). */
static inline uint light_vertex_slots(__constant const SceneHeader* h) { return max(h->max_depth, 1u); }

/* The density with which next-event estimation from x (lights.cl's sample_light) picks light `index` at y
 * (normal ny), or in direction d for a light at infinity: per solid angle at x, light choice included;
 * for a point or spot light the choice times the squared distance (its solid-angle density at the light
 * being a delta of area density 1; SmallVCM's convention). */
static inline float nee_pdf_w(const SceneData* sc, uint index, float3 x, float3 y, float3 ny, float3 d) {
  Light light = sc->lights[index];
  switch (light.type) {
#ifdef PC_HAS_AREA_LIGHTS
    case PC_LIGHT_AREA:
      return light_pdf(sc, index, x, y, ny);
#endif
#ifdef PC_HAS_POINT_LIGHTS
    case PC_LIGHT_POINT:
    case PC_LIGHT_SPOT: {
      float3 to = y - x;
      return light_choice_pdf(sc, x, index) * pc_dot(to, to);
    }
#endif
#ifdef PC_HAS_DIRECTIONAL_LIGHTS
    case PC_LIGHT_DIRECTIONAL:
      return light_choice_pdf(sc, x, index);
#endif
#ifdef PC_HAS_ENVIRONMENT
    case PC_LIGHT_ENVIRONMENT:
      return light_choice_pdf(sc, x, index) * env_pdf(light, sc->textures, sc->env_dist, d);
#endif
    default:
      return 0.0f;
  }
}

/* The balance heuristic counts light tracing (t = 1) as this fraction of its light paths: the balance
 * heuristic with sample counts, which keeps the weights of every path's strategies summing to one (any
 * positive counts do) and so the estimate unbiased; the count enters as the camera subpath's first dVCM
 * (bdpt.cl), which only the t = 1 terms contain, and divides t = 1's own sum. Why less than one: the other
 * strategies' samples are stratified per pixel by the sampler, while the splats reaching a pixel come from
 * unstratified light paths, a noise their densities do not show (on a diffuse floor lit by a small lamp,
 * light tracing's density is of the order of next-event estimation's, so it gets a like share). Measured
 * (docs/benchmarks.md, relMSE at 8 spp, sobol): 0.25 best of 1, 0.5, 0.25, 0.1, 0.03 on the Cornell box
 * (25 % below 1), as good as 1 on glass-metal and the lamp turned up, better on the terrain. Caustics from
 * delta lights keep weight 1: no other strategy makes them. */
#define PC_BDPT_LIGHT_TRACING_COUNT 0.25f

/* The balance heuristic's weight of strategy (s light vertices, t camera vertices) from the sum of the
 * other strategies' densities relative to its own; with lt->only_strategy (tests) that strategy alone,
 * unweighted, and no other; for a Metropolis sample (mis->only) that strategy alone, weighted. */
static inline float strategy_weight(__constant const LightTransportHeader* lt, const MisFactors* mis, uint s, uint t, float others) {
#ifdef PC_MLT
  if (mis->only_s == PC_INVALID ? s + t < mis->depth_lo + 2u || s + t > mis->depth_hi + 2u : s != mis->only_s || t != mis->only_t)
    return 0.0f;
#endif
  if (lt->only_strategy != PC_INVALID) return lt->only_strategy == (s | (t << 16)) ? 1.0f : 0.0f;
  return 1.0f / (1.0f + others);
}
#endif

/* Traces light path (key) and splats its camera connections. BDPT: with MIS weights (and the merging
 * factors *mis), and its non-delta vertices in vertices[0 .. *count) (room for max_depth). */
static inline void trace_light_path(const SceneData* sc, __constant const LightTransportHeader* lt,
                                    __global const float* emission_cdf, __global uint* film, SampleKey key, SplatCounts* n
#ifdef PC_BDPT
                             , const MisFactors* mis, __global LightVertex* vertices, uint* count
#endif
#ifdef PC_MLT
                             , MltSplat* splat
#endif
) {
  __constant const SceneHeader* h = sc->h;
  if (h->max_depth == 0u) return; /* no scattering: only directly seen lights, which light paths cannot see */
  float4 u_pos = sample4(h, key, PC_LT_EMIT_POS(h)), u_dir = sample4(h, key, PC_LT_EMIT_DIR(h));
  EmissionSample e;
  if (!sample_emission(sc, lt, emission_cdf, u_pos.x, u_pos.yzw, u_dir.xy, &e)) return;
  float3 beta = emission_weight(&e);
  float beta0 = max_component(beta);
  uint parity = key.sample & 1u;
  Ray ray;
  ray.o = e.prim != PC_INVALID ? offset_ray_origin(e.p, e.p_err, e.n, e.d) : e.p;
  ray.d = e.d;
  ray.tmin = 0.0f;
  ray.tmax = INFINITY;
  ray.skip_prim = e.prim;
  ray.skip_instance = 0u;
#ifdef PC_HAS_CUTOUTS
  ray.cutout_seed = cutout_seed(key, PC_LT_CUTOUT_BASE);
#endif
#ifdef PC_BDPT
  /* dVC starts as the emission's cosine over its density (0 for a delta light: no strategy but this one
   * reaches its paths' first vertex); dVCM needs next-event estimation's density, which the light tree
   * makes depend on the receiver, and is set at the first vertex. */
  float emit_pdf = e.pdf_choice * e.pdf_pos * e.pdf_dir;
  bool area = e.prim != PC_INVALID;
  float cos_light = area ? fabs(pc_dot(e.n, e.d)) : 1.0f;
  float dvc = e.delta_pos || e.delta_dir ? 0.0f : cos_light / emit_pdf, dvcm = 0.0f;
  float dvm = dvc * mis->vc;
  float3 prev_p = e.p;
#endif
  for (uint v = 0;; ++v) { /* v + 1 scattering events at the vertex found now */
    Hit hit;
    ++n->rays;
    if (!trace_scene(sc, sc, &ray, false, &hit)) break;
    Surface s = scene_surface(sc, &ray, &hit);
    PrimShading sh = sc->shading[s.prim];
    Material m = material_at(sc, sh.material, &s, &hit);
    FrameLanes frame;
    frame_about(s.ns, &frame);
    float3 w_light = -ray.d; /* back along the light path */
    float3 wl_local = to_local(&frame, w_light);
    float wl_ng = pc_dot(w_light, s.ng);
    float4 u_connect = sample4(h, key, PC_LT_CONNECT(h, v));
#ifdef PC_BDPT
    /* The densities of reaching this vertex, per area: dVCM /= p(light path reaches it), in solid angle
     * times cos / dist^2 (Georgiev's eq. 31-33; the cosines are the geometric normal's throughout). */
    float cos_in = fabs(wl_ng);
    if (v == 0u) {
      float direct = nee_pdf_w(sc, e.light, s.p, e.p, e.n, -e.d);
      dvcm = direct * cos_light / emit_pdf;
    } else {
      float3 seg = s.p - prev_p;
      dvcm *= pc_dot(seg, seg);
    }
    dvcm /= cos_in;
    dvc /= cos_in;
    dvm /= cos_in;
    prev_p = s.p;
#endif

    /* Connection to the camera. */
    CameraWiSample cs;
#ifdef PC_BDPT
    bool connect = mis->connect;
#else
    bool connect = true;
#endif
    if (connect && !bsdf_is_delta(m) && camera_sample_wi(h, s.p, u_connect.xy, &cs)) {
      float3 wc_local = to_local(&frame, cs.wi);
      float3 f = bsdf_eval(m, wc_local, wl_local);
      /* Reflection only (no non-delta material transmits): the camera on the light's side of the surface. */
      if (pc_dot(cs.wi, s.ng) * wl_ng > 0.0f && (f.x > 0.0f || f.y > 0.0f || f.z > 0.0f)) {
        Ray shadow = spawn_ray(&s, cs.wi);
        shadow.d = cs.p - shadow.o;
        shadow.tmax = 1.0f - PC_SHADOW_EPSILON;
#ifdef PC_HAS_CUTOUTS
        shadow.cutout_seed = cutout_seed(key, PC_LT_CUTOUT_BASE + 2u * v + 1u);
#endif
        float g = fabs(wc_local.z) * shading_normal_factor(w_light, cs.wi, s.ns, s.ng);
        /* over the width x height paths of a sample: the film sums to the pixel mean times spp */
        float per_path = g * cs.We / (cs.pdf * (float)(h->width * h->height));
#ifdef PC_BDPT
        /* Against the camera subpath reaching this vertex (t >= 2): its density per area here, with the
         * image position uniform over the image, over the light subpath's (times the light paths per
         * sample, which is the pixel count: camera_direction_pdf is per whole image, so they cancel). */
        float cam_pdf_a = camera_direction_pdf(h, -cs.wi) * fabs(pc_dot(cs.wi, s.ng)) / (cs.dist * cs.dist);
        float rev = bsdf_pdf(m, wc_local, wl_local);
        per_path *= strategy_weight(lt, mis, v + 2u, 1u, cam_pdf_a * (mis->vm + dvcm + dvc * rev) / PC_BDPT_LIGHT_TRACING_COUNT);
#endif
        Hit blocker;
        if (per_path != 0.0f) { /* a NaN goes on, to be counted */
          ++n->rays;
          if (!trace_scene(sc, sc, &shadow, true, &blocker)) {
#ifdef PC_MLT
            splat->raster = cs.raster;
            splat->value = beta * f * per_path;
            if (splat_is_valid(splat->value, n)) splat->luminance += luminance(splat->value);
#else
            splat_filtered(film, h, lt, cs.raster, parity, beta * f * per_path, n);
#endif
          }
        }
      }
    }
#ifdef PC_BDPT
    if (!bsdf_is_delta(m) && v + 1u >= mis->first_length) {
      __global LightVertex* lv = vertices + (*count)++;
      ++n->light_vertices;
      lv->p = (float4)(s.p, max_component(s.p_err));
      lv->ng = (float4)(s.ng, dvcm);
      lv->ns = (float4)(s.ns, dvc);
      lv->wl = (float4)(w_light, dvm);
      lv->beta = (float4)(beta, 0.0f);
      lv->color = (float4)(m.color.xyz, 0.0f);
      lv->material = sh.material;
      lv->prim = s.prim;
      lv->instance = s.instance;
      lv->length = v + 1u;
    }
#endif
    if (v + 1u >= h->max_depth) break;
#ifdef PC_MLT
    if (v + 2u >= mlt_light_stop(mis)) break; /* the strategies' last light vertex was this one */
#endif

    /* The next vertex. */
    float4 u_bsdf = sample4(h, key, PC_LT_BSDF(h, v));
    MaterialLanes ml = material_lanes_of(m);
    BsdfSampleLanes bs;
    float3 wi;
    if (!scatter_lanes(&ml, &frame, s.ng, wl_local, wl_ng, u_bsdf.x, u_bsdf.y, u_bsdf.z, 1, &bs, &wi)) break;
#ifdef PC_BDPT
    vcm_scatter_lanes(&ml, &bs, wl_local, wi, s.ng, 1, mis->vm, mis->vc, &dvcm, &dvc, &dvm);
#endif
    /* Importance is not scaled by refraction: undo the radiance scaling (bs.eta2) the sample applied. */
    beta *= bs.weight * (bs.eta2 * shading_normal_factor(w_light, wi, s.ns, s.ng));
    /* Russian roulette on the throughput relative to the emitted one (light paths start at power scale). */
    if (!roulette_lanes(max_component(beta) / beta0, u_connect.z, v + 1u > h->rr_depth, 1, &beta)) break;
    ray = spawn_ray(&s, wi);
#ifdef PC_HAS_CUTOUTS
    ray.cutout_seed = cutout_seed(key, PC_LT_CUTOUT_BASE + 2u * v + 2u);
#endif
  }
}

/* Adds a work unit's counts to its SplatStats (integer atomics). */
static inline void add_splat_counts(__global SplatStats* stats, const SplatCounts* n) {
  volatile __global uint* counters = (volatile __global uint*)&stats->rays_lo;
  add_counter64(counters, n->rays);
  if (n->nan_splats) atomic_add(counters + 2, n->nan_splats);
  if (n->inf_splats) atomic_add(counters + 3, n->inf_splats);
  if (n->negative_splats) atomic_add(counters + 4, n->negative_splats);
  if (n->overflows) atomic_add(counters + 5, n->overflows);
  if (n->light_vertices) atomic_add(counters + 6, n->light_vertices);
}

#endif
