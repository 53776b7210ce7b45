/* The megakernel of the path integrator: a work item renders W = PC_LANES pixels at once, one per lane
 * (kernels/lanes.cl: 1 on GPUs, 16 or 8 on CPU devices), each lane its pixel's samples one after the other,
 * whole paths each, added to the pixel's accumulators one by one (so any split into passes sums in the
 * same order). A lane starts its next sample as soon as its path ends, so the lanes stay busy until each
 * has done its pixel. Every lane does the one-lane program's operations: the pixels are the same bits at
 * every W. */
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
#include "lanes.cl"
#include "trace_lanes.cl"
#include "direct_light.cl"
#include "pixel_film.cl"

/* Light along the rays of the lanes in m that escaped: the environment, weighted against light sampling
 * by MIS. */
static inline Lane3 escaped_radiance_lanes(const SceneData* sc, Lane3 x, Lane3 d, LaneF prev_bsdf_pdf, LaneI prev_delta,
                                           LaneI m) {
#ifdef PC_HAS_ENVIRONMENT
  if (sc->h->env_light != PC_INVALID) {
    Light env = sc->lights[sc->h->env_light];
    Lane3 le = env_radiance_lanes(env, sc->textures, sc->texels, d, m);
    LaneI weighted = m & !prev_delta;
    if (!pc_any_(weighted)) return le;
    LaneF w = power_heuristic(prev_bsdf_pdf, environment_light_pdf_lanes(sc, x, d, weighted));
    return lane3_select(lane3_scale(le, w), le, prev_delta);
  }
#endif
  return lane3_splat((float3)(0.0f));
}

/* The paths in flight of a work item's lanes, bounce by bounce (path_begin_lanes, path_shade_lanes, then
 * the shadow rays' results). */
typedef struct {
  RayLanes ray;      /* the next ray to trace */
  Lane3 throughput, radiance;
  Lane3 nee;         /* the light sample's contribution, added when its shadow ray is not blocked */
  Lane3 prev_p;      /* the previous vertex */
  LaneF eta_scale;   /* product of the (n_t / n_i)^2 that refraction divided the throughput by */
  LaneF prev_bsdf_pdf;
  LaneU depth;
  LaneI prev_delta;  /* the camera ray counts as a delta: what it sees directly is not MIS-weighted */
} PathLanes;

/* The camera rays of sample `sample` of each lane's pixel (with cut-outs, their seeds). */
typedef struct {
  Lane3 o, d;
  LaneU cutout_seed;
} CameraRayLanes;
static inline void camera_rays_lanes(const SceneData* sc, LaneU pixel, LaneU sample, CameraRayLanes* c) {
  __constant const SceneHeader* h = sc->h;
  LaneF u0, u1, u2, u3;
  sample4_lanes(h, pixel, sample, h->seed, (LaneU)(PC_DIM_CAMERA), &u0, &u1, &u2, &u3);
  camera_ray_lanes(h, pixel % h->width, pixel / h->width, u0, u1, u2, u3, &c->o, &c->d);
#ifdef PC_DEBUG_PERTURB
  /* Test builds only (DeviceFault::perturb): one operation rounded the other way, as a device of another
   * arithmetic class would, so that the start-up probe must tell the device apart. */
  c->d.x = nextafter(c->d.x, (LaneF)(INFINITY));
#endif
  c->cutout_seed = (LaneU)(0u);
#ifdef PC_HAS_CUTOUTS
  c->cutout_seed = cutout_seed_lanes(h, pixel, sample, (LaneU)(PC_RAY_CAMERA));
#endif
}

/* New paths where m is set: lane j on the camera ray of lane src[j] of c. */
static inline void path_begin_lanes(const CameraRayLanes* c, LaneU src, LaneI m, PathLanes* st) {
  PathLanes n;
  n.ray.o = lane3_permute(c->o, src);
  n.ray.d = lane3_permute(c->d, src);
  n.ray.tmin = (LaneF)(0.0f);
  n.ray.tmax = (LaneF)(INFINITY);
  n.ray.skip_prim = n.ray.skip_instance = (LaneU)(PC_INVALID);
  n.ray.cutout_seed = (LaneU)(0u);
#ifdef PC_HAS_CUTOUTS
  n.ray.cutout_seed = pc_permute(c->cutout_seed, src);
#endif
  Lane3 zero = lane3_splat((float3)(0.0f));
  n.throughput = lane3_splat((float3)(1.0f));
  n.radiance = n.nee = zero;
  n.eta_scale = (LaneF)(1.0f);
  n.prev_bsdf_pdf = (LaneF)(0.0f);
  n.prev_delta = (LaneI)(-1);
  n.prev_p = n.ray.o;
  n.depth = (LaneU)(0u);
  st->ray.o = lane3_select(st->ray.o, n.ray.o, m);
  st->ray.d = lane3_select(st->ray.d, n.ray.d, m);
  st->ray.tmin = select(st->ray.tmin, n.ray.tmin, m);
  st->ray.tmax = select(st->ray.tmax, n.ray.tmax, m);
  st->ray.skip_prim = select(st->ray.skip_prim, n.ray.skip_prim, m);
  st->ray.skip_instance = select(st->ray.skip_instance, n.ray.skip_instance, m);
  st->ray.cutout_seed = select(st->ray.cutout_seed, n.ray.cutout_seed, m);
  st->throughput = lane3_select(st->throughput, n.throughput, m);
  st->radiance = lane3_select(st->radiance, n.radiance, m);
  st->nee = lane3_select(st->nee, n.nee, m);
  st->prev_p = lane3_select(st->prev_p, n.prev_p, m);
  st->eta_scale = select(st->eta_scale, n.eta_scale, m);
  st->prev_bsdf_pdf = select(st->prev_bsdf_pdf, n.prev_bsdf_pdf, m);
  st->depth = select(st->depth, n.depth, m);
  st->prev_delta = select(st->prev_delta, n.prev_delta, m);
}

/* One bounce of the lanes in m, at the hit of st->ray (found) or where it escaped: adds the light seen
 * there; where a light sample wants a shadow ray, sets direct->shadow, st->nee and the lane in *has_shadow
 * (the caller adds st->nee where the shadow ray is not blocked, before the next bounce); samples the BSDF
 * for st->ray's successor. Returns the lanes whose paths go on. The light sample is the caller's, so that
 * its shadow ray is traced where it was made: a copy to another ray (352 bytes at 8 lanes) was a call to
 * memcpy at every bounce. */
static inline LaneI path_shade_lanes(const SceneData* sc, LaneU pixel, LaneU sample, PathLanes* st, LaneI m, LaneI found,
                                     const HitLanes* hit, DirectLanes* direct, LaneI* has_shadow) {
  __constant const SceneHeader* h = sc->h;
  *has_shadow = (LaneI)(0);
  LaneI escaped = m & !found;
  if (pc_any_(escaped)) {
    Lane3 le = escaped_radiance_lanes(sc, st->prev_p, st->ray.d, st->prev_bsdf_pdf, st->prev_delta, escaped);
    st->radiance = lane3_select(st->radiance, lane3_add(st->radiance, lane3_mul(st->throughput, le)), escaped);
  }
  LaneI live = m & found;
  if (!pc_any_(live)) return live;
  LaneU depth = st->depth;
  ShadingLanes sh;
  SurfaceLanes s = scene_surface_lanes(sc, &st->ray, hit, live, &sh);
  Lane3 wo = lane3_neg(st->ray.d);
#ifdef PC_HAS_AREA_LIGHTS
  LaneI lit = live & (sh.light != PC_INVALID);
  if (pc_any_(lit)) {
    LightLanes light;
    gather_lights(sc->lights, sh.light, lit, &light);
    Lane3 le = emitted_towards_lanes(light.emission, sh.flags, s.ng, s.p, st->ray.o);
    LaneI weighted = lit & !st->prev_delta;
    LaneF w = (LaneF)(1.0f);
    if (pc_any_(weighted))
      w = select(w, power_heuristic(st->prev_bsdf_pdf, light_pdf_lanes(sc, sh.light, st->prev_p, s.p, s.ng, weighted)),
                 weighted);
    st->radiance = lane3_select(st->radiance, lane3_add(st->radiance, lane3_scale(lane3_mul(st->throughput, le), w)), lit);
  }
#endif
  live &= depth < h->max_depth;
  if (!pc_any_(live)) return live;

  MaterialLanes mat = material_at_lanes(sc, sh.material, &s, &sh, hit, live);
  FrameLanes frame;
  frame_about(s.ns, &frame);
  Lane3 wo_local = to_local(&frame, wo);
  LaneF wo_ng = pc_dot(wo, s.ng);
  LaneF ul0, ul1, ul2, ul3, ub0, ub1, ub2, ub3;
  sample4_lanes(h, pixel, sample, h->seed, PC_DIM_LIGHT(depth), &ul0, &ul1, &ul2, &ul3);
  sample4_lanes(h, pixel, sample, h->seed, PC_DIM_BSDF(depth), &ub0, &ub1, &ub2, &ub3);

  /* Next-event estimation, weighted against BSDF sampling by the power heuristic. */
  LaneI nee = direct_light_lanes(sc, &s, &frame, &mat, wo_local, wo_ng, ul0, ul1, ul2, live & !bsdf_is_delta_lanes(mat.type),
                                 direct);
  if (pc_any_(nee)) {
#ifdef PC_HAS_CUTOUTS
    direct->shadow.cutout_seed = cutout_seed_lanes(h, pixel, sample, PC_RAY_SHADOW(depth));
#endif
    LaneF w = select(power_heuristic(direct->ls.pdf, bsdf_pdf_lanes(&mat, wo_local, direct->wi_local, nee)), (LaneF)(1.0f),
                     direct->ls.delta);
    st->nee = lane3_select(st->nee, direct_contribution_lanes(st->throughput, direct, w), nee);
    *has_shadow = nee;
  }

  BsdfSampleLanes bs;
  Lane3 wi;
  live = scatter_lanes(&mat, &frame, s.ng, wo_local, wo_ng, ub0, ub1, ub2, live, &bs, &wi);
  if (!pc_any_(live)) return live;
  st->throughput = lane3_select(st->throughput, lane3_mul(st->throughput, bs.weight), live);
  st->eta_scale = select(st->eta_scale, st->eta_scale * bs.eta2, live);
  st->prev_bsdf_pdf = select(st->prev_bsdf_pdf, bs.pdf, live);
  st->prev_delta = select(st->prev_delta, bs.delta, live);
  st->prev_p = lane3_select(st->prev_p, s.p, live);
  /* A path whose throughput is zero (it met a black surface, such as the Cornell box's lamp) can add
   * nothing more: it ends here, as Mitsuba's do, instead of bouncing on until the roulette. The same
   * image; NaN goes on, so that the film counts it. */
  Lane3 t = st->throughput;
  live &= (t.x != 0.0f) | (t.y != 0.0f) | (t.z != 0.0f);
  /* Russian roulette on the throughput without the radiance scaling of refraction (pbrt-v4's etaScale):
   * inside glass it is (n_i / n_t)^2 = 0.44 times lower only until the path leaves again, and killing paths
   * for it there made glass scenes noisier (peer benchmark, glass-metal). */
  live = roulette_lanes(lane3_max_component(st->throughput) * st->eta_scale, ul3, depth + 1u > h->rr_depth, live,
                        &st->throughput);
  RayLanes next;
  spawn_ray_lanes(s.p, s.p_err, s.ng, s.prim, s.instance, wi, &next);
  next.cutout_seed = (LaneU)(0u);
#ifdef PC_HAS_CUTOUTS
  next.cutout_seed = cutout_seed_lanes(h, pixel, sample, PC_RAY_NEXT(depth));
#endif
  st->ray.o = lane3_select(st->ray.o, next.o, live);
  st->ray.d = lane3_select(st->ray.d, next.d, live);
  st->ray.tmin = select(st->ray.tmin, next.tmin, live);
  st->ray.tmax = select(st->ray.tmax, next.tmax, live);
  st->ray.skip_prim = select(st->ray.skip_prim, next.skip_prim, live);
  st->ray.skip_instance = select(st->ray.skip_instance, next.skip_instance, live);
  st->ray.cutout_seed = select(st->ray.cutout_seed, next.cutout_seed, live);
  st->depth = select(st->depth, depth + 1u, live);
  return live;
}

/* The unit's counters into stats (UnitStats) with integer atomics. */
static inline void add_unit_stats(__global UnitStats* stats, uint rays, uint nan_samples, uint inf_samples,
                                  uint negative_samples) {
  volatile __global uint* counters = (volatile __global uint*)&stats->rays_lo;
  add_counter64(counters, rays);
  if (nan_samples) atomic_add(counters + 2, nan_samples);
  if (inf_samples) atomic_add(counters + 3, inf_samples);
  if (negative_samples) atomic_add(counters + 4, negative_samples);
}

/* One work unit: samples [sample_begin, sample_begin + sample_count) of pixels pixel_begin + i * pixel_stride,
 * i < pixel_count (stride 1 for the render's units, larger for the start-up probe). Work item g renders
 * the samples of i = G g .. G g + G - 1 (G = PC_ITEM_PIXELS: 1 where W = 1, W x PC_LANE_PIXELS otherwise) as
 * tasks in order (pixel by pixel, sample by sample). A lane whose path has ended takes the next task, so
 * every lane stays busy until the work item's last tasks; a finished sample waits in a ring of
 * PC_RESULTS radiances until the samples before it are added, and a lane waits while the ring is full.
 * So each pixel's samples are added one by one, in order, to the accumulators it carries from the film:
 * any split into units, on any device, at any W, sums in the same order.
 * The film holds three float4 per pixel: the sums of the even-numbered and of the odd-numbered samples
 * (w counts them) and the sum of squares. The two half sums give a noise estimate from the image itself.
 * stats (UnitStats): rays (64 bits) and hazard counts, added with integer atomics. */
/* The camera rays of tasks batch .. batch + PC_LANES - 1 of render_pass_item's work item, task batch + j in
 * lane j (task t: sample sample_begin + t % sample_count of pixel item first + t / sample_count; those
 * past the item's last task are made too, and not taken). */
static inline void task_camera_rays(const SceneData* sc, uint batch, uint first, uint pixel_begin, uint pixel_stride,
                                    uint sample_begin, uint sample_count, CameraRayLanes* c) {
  uint pixel_of[PC_LANES], sample_of[PC_LANES], item = first + batch / sample_count, s = batch % sample_count;
  for (uint j = 0u; j < PC_LANES; ++j) {
    pixel_of[j] = pixel_begin + item * pixel_stride;
    sample_of[j] = sample_begin + s;
    if (++s == sample_count) s = 0u, ++item;
  }
  camera_rays_lanes(sc, lane_load(pixel_of), lane_load(sample_of), c);
}

#if PC_LANES > 1
#define PC_RESULTS (4u * PC_LANES) /* at most 64: a bit each in `ready` */
#else
#define PC_RESULTS 1u
#endif
PC_KERNEL_BODY void render_pass_item(const SceneData* scene, __global float4* film, __global UnitStats* stats,
                                     uint pixel_begin, uint pixel_count, uint pixel_stride, uint sample_begin,
                                     uint sample_count, uint global_id) {
  SceneData sc = *scene;
  __constant const SceneHeader* h = sc.h;
  uint first = global_id * PC_ITEM_PIXELS;
  if (first >= pixel_count || sample_count == 0u) return;
  uint tasks = (min(first + PC_ITEM_PIXELS, pixel_count) - first) * sample_count;
  uint rays = 0u, nan_samples = 0u, inf_samples = 0u, negative_samples = 0u;
  /* Tasks handed out (the next one's pixel item and sample), added to the film, and those finished
     beyond the added ones (bit k % PC_RESULTS of ready, radiance in result). */
  uint issued = 0u, next_item = first, next_sample = sample_begin, added = 0u;
  ulong ready = 0ul;
  float3 result[PC_RESULTS];
  float4 half_sum[2], squares; /* the accumulators of the pixel being added to */
  uint task_of[PC_LANES], pixel_of[PC_LANES], sample_of[PC_LANES];
  for (uint j = 0u; j < PC_LANES; ++j) task_of[j] = pixel_of[j] = sample_of[j] = 0u;
  LaneU pixel = lane_load(pixel_of), sample = lane_load(sample_of);
  LaneI active = (LaneI)(0);
  /* The camera rays of tasks batch .. batch + PC_LANES - 1, made together and handed to the lanes as they
   * take those tasks: a lane taking its task alone paid for a camera ray in every lane (the Cornell box's
   * lanes end their paths a few at a time). */
  uint batch = 0u;
  CameraRayLanes cam;
  task_camera_rays(&sc, batch, first, pixel_begin, pixel_stride, sample_begin, sample_count, &cam);
  PathLanes st;
  path_begin_lanes(&cam, lane_indices(), (LaneI)(-1), &st); /* every lane's state defined */
  for (uint idle = (1u << (PC_LANES - 1u) << 1u) - 1u;;) {
    /* Idle lanes take the next tasks while the ring has room for their results. */
    uint taken = 0u;
    PC_EACH_LANE(j, idle) {
      if (issued == tasks || issued == added + PC_RESULTS) break;
      task_of[j] = issued++;
      pixel_of[j] = pixel_begin + next_item * pixel_stride;
      sample_of[j] = next_sample;
      if (++next_sample == sample_begin + sample_count) next_sample = sample_begin, ++next_item;
      taken |= 1u << j;
    }
    if (taken != 0u) {
      LaneI take = pc_lanes_of_bits(taken, active);
      pixel = lane_load(pixel_of);
      sample = lane_load(sample_of);
      /* The tasks taken lie in this batch and the next: they are at most PC_LANES from the first untaken. */
      LaneU src = lane_load(task_of) - batch;
      LaneI in_batch = take & (src < PC_LANES);
      if (pc_any_(in_batch)) path_begin_lanes(&cam, src & (PC_LANES - 1u), in_batch, &st);
      if (pc_any_(take & !in_batch)) {
        batch += PC_LANES;
        task_camera_rays(&sc, batch, first, pixel_begin, pixel_stride, sample_begin, sample_count, &cam);
        path_begin_lanes(&cam, (src - PC_LANES) & (PC_LANES - 1u), take & !in_batch, &st);
      }
      active |= take;
    }
    if (!pc_any_(active)) break;
    HitLanes hit;
    LaneI found = trace_lanes(&sc, &st.ray, active, false, &hit);
    rays += lane_count(active);
    DirectLanes direct;
    LaneI has_shadow;
    LaneI more = path_shade_lanes(&sc, pixel, sample, &st, active, found, &hit, &direct, &has_shadow);
    if (pc_any_(has_shadow)) {
      HitLanes blocker;
      LaneI blocked = trace_lanes(&sc, &direct.shadow, has_shadow, true, &blocker);
      rays += lane_count(has_shadow);
      st.radiance = lane3_select(st.radiance, lane3_add(st.radiance, st.nee), has_shadow & !blocked);
    }
    LaneI ended = active & !more;
    uint ended_bits = pc_lane_bits(ended);
    /* Idle lanes that found the ring full stay idle, for a task once it has room. */
    idle = (idle & ~taken) | ended_bits;
    if (ended_bits == 0u) continue;
    active &= !ended;
    /* Finished samples into the ring, then every sample whose predecessors are in, in order. */
    PC_EACH_LANE(j, ended_bits) {
      uint slot = task_of[j] % PC_RESULTS;
      result[slot] = lane3_at(st.radiance, j);
      ready |= 1ul << slot;
    }
    for (uint slot = added % PC_RESULTS; (ready >> slot) & 1ul; slot = added % PC_RESULTS) {
      uint s = sample_begin + added % sample_count, at = 3u * (pixel_begin + (first + added / sample_count) * pixel_stride);
      if (s == sample_begin) {
        half_sum[0] = film[at];
        half_sum[1] = film[at + 1u];
        squares = film[at + 2u];
      }
      accumulate_sample(result[slot], s, half_sum, &squares, &nan_samples, &inf_samples, &negative_samples);
      if (s + 1u == sample_begin + sample_count) {
        film[at] = half_sum[0];
        film[at + 1u] = half_sum[1];
        film[at + 2u] = squares;
      }
      ready &= ~(1ul << slot);
      ++added;
    }
  }
  add_unit_stats(stats, rays, nan_samples, inf_samples, negative_samples);
}
__kernel void render_pass(PC_SCENE_PARAMS, __global float4* film, __global UnitStats* stats, uint pixel_begin,
                          uint pixel_count, uint pixel_stride, uint sample_begin, uint sample_count) {
  SceneData sc = PC_SCENE_DATA;
  render_pass_item(&sc, film, stats, pixel_begin, pixel_count, pixel_stride, sample_begin, sample_count,
                   get_global_id(0));
}
