/* Light paths, one per lane of the program's width (kernels/lanes.cl; mlt's programs are one wide):
 * emitted from a light chosen by power (emission.cl), connected to the camera at every non-delta vertex
 * (camera_importance.cl), shadow-tested and splatted into the pixels its image position lands in
 * (splat_film.cl), weighted by the pixel filter. The `light` integrator traces these
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
#include "trace_lanes.cl"

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

/* The adjoint BSDF's shading-normal factor at a vertex (see the top of the file), by lane. */
static inline LaneF shading_normal_factor(Lane3 w_light, Lane3 w_out, Lane3 ns, Lane3 ng) {
  LaneF num = fabs(pc_dot(w_light, ns)) * fabs(pc_dot(w_out, ng));
  LaneF den = fabs(pc_dot(w_light, ng)) * fabs(pc_dot(w_out, ns));
  return select((LaneF)(0.0f), num / den, den > 0.0f);
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
 * events) depth_lo .. depth_hi but light tracing (t = 1; light_tracing_count), weighted. Its subpaths stop
 * where those strategies need no more vertices (mlt_light_stop, mlt_camera_stop), and its light tracing
 * connection is kept in *splat instead of splatted. */
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
/* A Metropolis sample's light tracing contribution (one strategy, t = 1): its raster position and value
 * (mlt.cl). */
typedef struct {
  float2 raster;
  float3 value;
} MltSplat;
#endif

/* Light vertex slots per light path of a unit (runtime/light_transport.h's light_vertex_slots). */
static inline uint light_vertex_slots(__constant const SceneHeader* h) { return max(h->max_depth, 1u); }

/* The density with which next-event estimation from x (lights.cl's sample_light) picks light `index` at y
 * (normal ny), or in direction d for a light at infinity: per solid angle at x, light choice included;
 * for a point or spot light the choice times the squared distance (its solid-angle density at the light
 * being a delta of area density 1; SmallVCM's convention). */
static inline LaneF nee_pdf_w(const SceneData* sc, LaneU index, Lane3 x, Lane3 y, Lane3 ny, Lane3 d, LaneI m) {
  LaneU type = lane_gather_uint(PC_FIELD_U(sc->lights, type), lane_safe_index(index, m));
  LaneF pdf = (LaneF)(0.0f);
#ifdef PC_HAS_AREA_LIGHTS
  LaneI area = m & (type == PC_LIGHT_AREA);
  if (pc_any_(area)) pdf = select(pdf, light_pdf_lanes(sc, index, x, y, ny, area), area);
#endif
  /* The others: their choice, times the squared distance for point and spot lights, the map's density for
     the environment. */
  LaneI chosen = m & (type != PC_LIGHT_AREA);
  if (pc_any_(chosen)) {
    LaneU unused;
    LaneF choice = light_choice_lanes(sc, x, index, (LaneF)(0.0f), chosen, &unused);
#ifdef PC_HAS_POINT_LIGHTS
    LaneI point = chosen & ((type == PC_LIGHT_POINT) | (type == PC_LIGHT_SPOT));
    Lane3 to = lane3_sub(y, x);
    pdf = select(pdf, choice * pc_dot(to, to), point);
#endif
#ifdef PC_HAS_DIRECTIONAL_LIGHTS
    pdf = select(pdf, choice, chosen & (type == PC_LIGHT_DIRECTIONAL));
#endif
#ifdef PC_HAS_ENVIRONMENT
    LaneI env = chosen & (type == PC_LIGHT_ENVIRONMENT);
    if (pc_any_(env))
      pdf = select(pdf, choice * env_pdf_lanes(sc->lights[sc->h->env_light], sc->textures, sc->env_dist, d, env), env);
#endif
  }
  return pdf;
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

/* Light tracing's count in the weights of *mis's samples: 0 where it is not a strategy, in a Metropolis
 * sample of every strategy (mlt.cl's pixels' own samples of depths 0 and 1). */
#ifdef PC_MLT
static inline float light_tracing_count(const MisFactors* mis) {
  return mis->only_s == PC_INVALID ? 0.0f : PC_BDPT_LIGHT_TRACING_COUNT;
}
#else
static inline float light_tracing_count(const MisFactors* mis) { return PC_BDPT_LIGHT_TRACING_COUNT; }
#endif

/* The balance heuristic's weight of strategy (s light vertices, t camera vertices) from the sum of the
 * other strategies' densities relative to its own; with lt->only_strategy (tests) that strategy alone,
 * unweighted, and no other; for a Metropolis sample (mis->only) that strategy alone, weighted. */
static inline LaneF strategy_weight(__constant const LightTransportHeader* lt, const MisFactors* mis, LaneU s, LaneU t,
                                    LaneF others) {
#ifdef PC_MLT
  if (mis->only_s == PC_INVALID ? s + t < mis->depth_lo + 2u || s + t > mis->depth_hi + 2u : s != mis->only_s || t != mis->only_t)
    return 0.0f;
#endif
  if (lt->only_strategy != PC_INVALID) return select((LaneF)(0.0f), (LaneF)(1.0f), (LaneU)(lt->only_strategy) == (s | (t << 16)));
  return 1.0f / (1.0f + others);
}
#endif

/* The four numbers of sample group `group` of each lane's path (key.sample, key.seed; lane j's pixel or light
 * path index path[j]): sample4 of key with one lane (a Metropolis chain's state included), sample4_lanes with
 * more. */
static inline void key_sample4_lanes(__constant const SceneHeader* h, SampleKey key, LaneU path, uint group, LaneF* x,
                                     LaneF* y, LaneF* z, LaneF* w) {
#if PC_LANES == 1
  float4 u = sample4(h, key, group);
  *x = u.x;
  *y = u.y;
  *z = u.z;
  *w = u.w;
#else
  sample4_lanes(h, path, (LaneU)(key.sample), key.seed, (LaneU)(group), x, y, z, w);
#endif
}

#ifdef PC_HAS_CUTOUTS
/* The cut-out seed of ray ray_index of each lane's path (cutout.cl's cutout_seed of its key; with more lanes
 * than one, the key's seed is the scene's). */
static inline LaneU key_cutout_seed_lanes(__constant const SceneHeader* h, SampleKey key, LaneU path, uint ray_index) {
#if PC_LANES == 1
  return cutout_seed(key, ray_index);
#else
  return cutout_seed_lanes(h, path, (LaneU)(key.sample), (LaneU)(ray_index));
#endif
}
#endif

/* The camera rays of each lane's camera path (keyed as key_sample4_lanes) through pixel (px, py): BDPT's camera
 * subpaths, the gathering integrators'. */
static inline void camera_path_rays(__constant const SceneHeader* h, SampleKey key, LaneU path, LaneU px, LaneU py,
                                    RayLanes* ray) {
  LaneF u0, u1, u2, u3;
  key_sample4_lanes(h, key, path, PC_DIM_CAMERA, &u0, &u1, &u2, &u3);
  camera_ray_lanes(h, px, py, u0, u1, u2, u3, &ray->o, &ray->d);
  ray->tmin = (LaneF)(0.0f);
  ray->tmax = (LaneF)(INFINITY);
  ray->skip_prim = ray->skip_instance = (LaneU)(PC_INVALID);
  ray->cutout_seed = (LaneU)(0u);
#ifdef PC_HAS_CUTOUTS
  ray->cutout_seed = key_cutout_seed_lanes(h, key, path, PC_RAY_CAMERA);
#endif
}

#if defined(PC_MLT) && PC_LANES > 1
#error "mlt's programs are one lane wide: a chain's light subpath keeps one splat"
#endif
#if PC_LANES > 1
PC_CAMERA_DIRECTION_PDF(Lane3, LaneF, lane3_splat(h->cam_forward.xyz))
#endif

/* Traces the light paths of the lanes in m, lane j's keyed by (path[j], key.sample) (with one lane: key, whose
 * pixel is path; mlt and the gathering integrators pass one lane, 1), and splats their camera
 * connections: the lanes go bounce by bounce together, each doing the one-lane operations (the emission and
 * the camera's lens point lane by lane, with the one-lane code), so a path's splats are the same bits at
 * every width; the film's fixed-point sums do not depend on their order.
 * BDPT: with MIS weights (and the merging factors *mis), and lane j's non-delta vertices in
 * vertices[j max_depth .. j max_depth + count[j]) (room for max_depth each). */
static inline void trace_light_paths_lanes(const SceneData* sc, __constant const LightTransportHeader* lt,
                                           __global const float* emission_cdf, __global uint* film, SampleKey key,
                                           LaneU path, LaneI m, SplatCounts* n
#ifdef PC_BDPT
                                    , const MisFactors* mis, __global LightVertex* vertices, uint* count
#endif
#ifdef PC_MLT
                                    , MltSplat* splat
#endif
) {
  __constant const SceneHeader* h = sc->h;
  if (h->max_depth == 0u) return; /* no scattering: only directly seen lights, which light paths cannot see */
  LaneF up0, up1, up2, up3, ud0, ud1, ud2, ud3;
  key_sample4_lanes(h, key, path, PC_LT_EMIT_POS(h), &up0, &up1, &up2, &up3);
  key_sample4_lanes(h, key, path, PC_LT_EMIT_DIR(h), &ud0, &ud1, &ud2, &ud3);
  /* The lanes' first rays and throughputs, lane by lane into arrays (one vector load each after). */
  float beta_x[PC_LANES], beta_y[PC_LANES], beta_z[PC_LANES], beta_max[PC_LANES];
  float o_x[PC_LANES], o_y[PC_LANES], o_z[PC_LANES], d_x[PC_LANES], d_y[PC_LANES], d_z[PC_LANES];
  uint skip[PC_LANES];
  for (uint j = 0u; j < PC_LANES; ++j) {
    beta_x[j] = beta_y[j] = beta_z[j] = o_x[j] = o_y[j] = o_z[j] = d_x[j] = d_y[j] = d_z[j] = 0.0f;
    beta_max[j] = 1.0f;
    skip[j] = PC_INVALID;
  }
#ifdef PC_BDPT
  /* dVC starts as the emission's cosine over its density (0 for a delta light: no strategy but this one
   * reaches its paths' first vertex); dVCM needs next-event estimation's density, which the light tree
   * makes depend on the receiver, and is set at the first vertex (from the light, its point and normal). */
  float p_x[PC_LANES], p_y[PC_LANES], p_z[PC_LANES], n_x[PC_LANES], n_y[PC_LANES], n_z[PC_LANES];
  float emit_pdf_of[PC_LANES], cos_light_of[PC_LANES], dvc_of[PC_LANES];
  uint light_of[PC_LANES];
  for (uint j = 0u; j < PC_LANES; ++j) {
    p_x[j] = p_y[j] = p_z[j] = n_x[j] = n_y[j] = n_z[j] = dvc_of[j] = 0.0f;
    emit_pdf_of[j] = cos_light_of[j] = 1.0f;
    light_of[j] = 0u;
  }
#endif
  uint emitted = 0u; /* the lanes whose light emits */
  PC_EACH_LANE(j, pc_lane_bits(m)) {
    EmissionSample e;
    if (!sample_emission(sc, lt, emission_cdf, pc_lane(up0, j), (float3)(pc_lane(up1, j), pc_lane(up2, j), pc_lane(up3, j)),
                         (float2)(pc_lane(ud0, j), pc_lane(ud1, j)), &e))
      continue;
    emitted |= 1u << j;
    float3 b = emission_weight(&e);
    float3 o = e.prim != PC_INVALID ? offset_ray_origin(e.p, e.p_err, e.n, e.d) : e.p;
    beta_x[j] = b.x, beta_y[j] = b.y, beta_z[j] = b.z, beta_max[j] = max_component(b);
    o_x[j] = o.x, o_y[j] = o.y, o_z[j] = o.z, d_x[j] = e.d.x, d_y[j] = e.d.y, d_z[j] = e.d.z;
    skip[j] = e.prim;
#ifdef PC_BDPT
    float emit_pdf = e.pdf_choice * e.pdf_pos * e.pdf_dir;
    bool area = e.prim != PC_INVALID;
    float cos_light = area ? fabs(pc_dot(e.n, e.d)) : 1.0f;
    emit_pdf_of[j] = emit_pdf, cos_light_of[j] = cos_light;
    dvc_of[j] = e.delta_pos || e.delta_dir ? 0.0f : cos_light / emit_pdf;
    p_x[j] = e.p.x, p_y[j] = e.p.y, p_z[j] = e.p.z, n_x[j] = e.n.x, n_y[j] = e.n.y, n_z[j] = e.n.z;
    light_of[j] = e.light;
#endif
  }
  Lane3 beta = lane3(lane_load(beta_x), lane_load(beta_y), lane_load(beta_z));
  LaneF beta0 = lane_load(beta_max);
  RayLanes ray;
  ray.o = lane3(lane_load(o_x), lane_load(o_y), lane_load(o_z));
  ray.d = lane3(lane_load(d_x), lane_load(d_y), lane_load(d_z));
  ray.tmin = (LaneF)(0.0f);
  ray.tmax = (LaneF)(INFINITY);
  ray.skip_prim = lane_load(skip);
  ray.skip_instance = (LaneU)(0u);
  ray.cutout_seed = (LaneU)(0u);
#ifdef PC_BDPT
  LaneF emit_pdf = lane_load(emit_pdf_of), cos_light = lane_load(cos_light_of), dvc = lane_load(dvc_of), dvcm = (LaneF)(0.0f);
  LaneF dvm = dvc * mis->vc;
  Lane3 prev_p = lane3(lane_load(p_x), lane_load(p_y), lane_load(p_z)), light_n = lane3(lane_load(n_x), lane_load(n_y), lane_load(n_z));
  LaneU light = lane_load(light_of);
#endif
  LaneI live = pc_lanes_of_bits(emitted, m);
  if (!pc_any_(live)) return;
#ifdef PC_HAS_CUTOUTS
  ray.cutout_seed = key_cutout_seed_lanes(h, key, path, PC_LT_CUTOUT_BASE);
#endif
  uint parity = key.sample & 1u;
  for (uint v = 0;; ++v) { /* v + 1 scattering events at the vertex found now */
    HitLanes hit;
    n->rays += lane_count(live);
    live = trace_lanes(sc, &ray, live, false, &hit);
    if (!pc_any_(live)) break;
    ShadingLanes sh;
    SurfaceLanes s = scene_surface_lanes(sc, &ray, &hit, live, &sh);
    MaterialLanes mat = material_at_lanes(sc, sh.material, &s, &sh, &hit, live);
    FrameLanes frame;
    frame_about(s.ns, &frame);
    Lane3 w_light = lane3_neg(ray.d); /* back along the light path */
    Lane3 wl_local = to_local(&frame, w_light);
    LaneF wl_ng = pc_dot(w_light, s.ng);
    LaneF uc0, uc1, uc2, uc3;
    key_sample4_lanes(h, key, path, PC_LT_CONNECT(h, v), &uc0, &uc1, &uc2, &uc3);
#ifdef PC_BDPT
    /* The densities of reaching this vertex, per area: dVCM /= p(light path reaches it), in solid angle
     * times cos / dist^2 (Georgiev's eq. 31-33; the cosines are the geometric normal's throughout). */
    LaneF cos_in = fabs(wl_ng);
    if (v == 0u) { /* prev_p is the light's point, ray.d the emitted direction */
      LaneF direct = nee_pdf_w(sc, light, s.p, prev_p, light_n, lane3_neg(ray.d), live);
      dvcm = direct * cos_light / emit_pdf;
    } else {
      Lane3 seg = lane3_sub(s.p, prev_p);
      dvcm *= pc_dot(seg, seg);
    }
    dvcm /= cos_in;
    dvc /= cos_in;
    dvm /= cos_in;
    prev_p = s.p;
#endif
    LaneI connect = live & !bsdf_is_delta_lanes(mat.type);
#ifdef PC_BDPT
    if (!mis->connect) connect = (LaneI)(0);
#endif

    /* Connection to the camera: the lens point lane by lane, into arrays. */
    float cp_x[PC_LANES], cp_y[PC_LANES], cp_z[PC_LANES], cw_x[PC_LANES], cw_y[PC_LANES], cw_z[PC_LANES];
    float c_dist[PC_LANES], c_we[PC_LANES], c_pdf[PC_LANES], r_x[PC_LANES], r_y[PC_LANES];
    for (uint j = 0u; j < PC_LANES; ++j) {
      cp_x[j] = cp_y[j] = cp_z[j] = cw_x[j] = cw_y[j] = cw_z[j] = c_we[j] = r_x[j] = r_y[j] = 0.0f;
      c_dist[j] = c_pdf[j] = 1.0f;
    }
    uint seen = 0u;
    PC_EACH_LANE(j, pc_lane_bits(connect)) {
      CameraWiSample cs;
      if (!camera_sample_wi(h, lane3_at(s.p, j), (float2)(pc_lane(uc0, j), pc_lane(uc1, j)), &cs)) continue;
      seen |= 1u << j;
      cp_x[j] = cs.p.x, cp_y[j] = cs.p.y, cp_z[j] = cs.p.z, cw_x[j] = cs.wi.x, cw_y[j] = cs.wi.y, cw_z[j] = cs.wi.z;
      c_dist[j] = cs.dist, c_we[j] = cs.We, c_pdf[j] = cs.pdf, r_x[j] = cs.raster.x, r_y[j] = cs.raster.y;
    }
    Lane3 cs_p = lane3(lane_load(cp_x), lane_load(cp_y), lane_load(cp_z));
    Lane3 cs_wi = lane3(lane_load(cw_x), lane_load(cw_y), lane_load(cw_z));
    LaneF cs_dist = lane_load(c_dist), cs_we = lane_load(c_we), cs_pdf = lane_load(c_pdf);
    LaneF raster_x = lane_load(r_x), raster_y = lane_load(r_y);
    connect = pc_lanes_of_bits(seen, connect);
    if (pc_any_(connect)) {
      Lane3 wc_local = to_local(&frame, cs_wi);
      Lane3 f = bsdf_eval_lanes(&mat, wc_local, wl_local, connect);
      /* Reflection only (no non-delta material transmits): the camera on the light's side of the surface. */
      connect &= (pc_dot(cs_wi, s.ng) * wl_ng > 0.0f) & lane3_any_positive(f);
      if (pc_any_(connect)) {
        RayLanes shadow;
        spawn_ray_lanes(s.p, s.p_err, s.ng, s.prim, s.instance, cs_wi, &shadow);
        shadow.d = lane3_sub(cs_p, shadow.o);
        shadow.tmax = (LaneF)(1.0f - PC_SHADOW_EPSILON);
        shadow.cutout_seed = (LaneU)(0u);
#ifdef PC_HAS_CUTOUTS
        shadow.cutout_seed = key_cutout_seed_lanes(h, key, path, PC_LT_CUTOUT_BASE + 2u * v + 1u);
#endif
        LaneF g = fabs(wc_local.z) * shading_normal_factor(w_light, cs_wi, s.ns, s.ng);
        /* over the width x height paths of a sample: the film sums to the pixel mean times spp */
        LaneF per_path = g * cs_we / (cs_pdf * (float)(h->width * h->height));
#ifdef PC_BDPT
        /* Against the camera subpath reaching this vertex (t >= 2): its density per area here, with the
         * image position uniform over the image, over the light subpath's (times the light paths per
         * sample, which is the pixel count: camera_direction_pdf is per whole image, so they cancel). No
         * merge here: vcm takes none at the camera's first vertex (bdpt.cl). */
        LaneF cam_pdf_a = camera_direction_pdf(h, lane3_neg(cs_wi)) * fabs(pc_dot(cs_wi, s.ng)) / (cs_dist * cs_dist);
        LaneF rev = bsdf_pdf_lanes(&mat, wc_local, wl_local, connect);
        per_path *= strategy_weight(lt, mis, (LaneU)(v + 2u), (LaneU)(1u),
                                    cam_pdf_a * (dvcm + dvc * rev) / light_tracing_count(mis));
#endif
        LaneI shoot = connect & (per_path != 0.0f); /* a NaN goes on, to be counted */
        if (pc_any_(shoot)) {
          n->rays += lane_count(shoot);
          HitLanes blocker;
          LaneI reach = shoot & !trace_lanes(sc, &shadow, shoot, true, &blocker);
          Lane3 value = lane3_scale(lane3_mul(beta, f), per_path);
          PC_EACH_LANE(j, pc_lane_bits(reach)) {
#ifdef PC_MLT
            splat->raster = (float2)(raster_x, raster_y);
            splat->value = value;
#else
            splat_filtered(film, h, lt, (float2)(pc_lane(raster_x, j), pc_lane(raster_y, j)), parity, lane3_at(value, j), n);
#endif
          }
        }
      }
    }
#ifdef PC_BDPT
    /* The non-delta vertices, lane j's at vertices[j max_depth + count[j]]. */
    if (v + 1u >= mis->first_length) {
      LaneF p_err = lane3_max_component(s.p_err);
      PC_EACH_LANE(j, pc_lane_bits(live & !bsdf_is_delta_lanes(mat.type))) {
        __global LightVertex* lv = vertices + j * light_vertex_slots(h) + count[j]++;
        ++n->light_vertices;
        lv->p = (float4)(lane3_at(s.p, j), pc_lane(p_err, j));
        lv->ng = (float4)(lane3_at(s.ng, j), pc_lane(dvcm, j));
        lv->ns = (float4)(lane3_at(s.ns, j), pc_lane(dvc, j));
        lv->wl = (float4)(lane3_at(w_light, j), pc_lane(dvm, j));
        lv->beta = (float4)(lane3_at(beta, j), 0.0f);
        lv->color = (float4)(lane3_at(mat.color, j), 0.0f);
        lv->material = pc_lane(sh.material, j);
        lv->prim = pc_lane(s.prim, j);
        lv->instance = pc_lane(s.instance, j);
        lv->length = v + 1u;
      }
    }
#endif
    if (v + 1u >= h->max_depth) break;
#ifdef PC_MLT
    if (v + 2u >= mlt_light_stop(mis)) break; /* the strategies' last light vertex was this one */
#endif

    /* The next vertex. */
    LaneF ub0, ub1, ub2, ub3;
    key_sample4_lanes(h, key, path, PC_LT_BSDF(h, v), &ub0, &ub1, &ub2, &ub3);
    BsdfSampleLanes bs;
    Lane3 wi;
    live = scatter_lanes(&mat, &frame, s.ng, wl_local, wl_ng, ub0, ub1, ub2, live, &bs, &wi);
    if (!pc_any_(live)) break;
#ifdef PC_BDPT
    vcm_scatter_lanes(&mat, &bs, wl_local, wi, s.ng, live, mis->vm, mis->vc, 1.0f, &dvcm, &dvc, &dvm);
#endif
    /* Importance is not scaled by refraction: undo the radiance scaling (bs.eta2) the sample applied. */
    beta = lane3_select(beta, lane3_mul(beta, lane3_scale(bs.weight, bs.eta2 * shading_normal_factor(w_light, wi, s.ns, s.ng))),
                        live);
    /* Russian roulette on the throughput relative to the emitted one (light paths start at power scale). */
    live = roulette_lanes(lane3_max_component(beta) / beta0, uc2, pc_lanes_of_bits(v + 1u > h->rr_depth ? ~0u : 0u, live),
                          live, &beta);
    if (!pc_any_(live)) break;
    spawn_ray_lanes(s.p, s.p_err, s.ng, s.prim, s.instance, wi, &ray);
    ray.cutout_seed = (LaneU)(0u);
#ifdef PC_HAS_CUTOUTS
    ray.cutout_seed = key_cutout_seed_lanes(h, key, path, PC_LT_CUTOUT_BASE + 2u * v + 2u);
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
