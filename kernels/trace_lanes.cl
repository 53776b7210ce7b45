/* The rays of a work item's lanes (kernels/lanes.cl) and their hits: traced together as one packet where
 * the device's layout has packets (the 8- or 16-wide BVH without instances, kernels/packet.cl), else lane by lane
 * with trace_scene. Either way each lane's hit is its single ray's, bit for bit. */
#ifndef PATHCL_TRACE_LANES_CL
#define PATHCL_TRACE_LANES_CL

#include "lanes.cl"
#include "intersect.cl"
#include "packet.cl"

/* intersect.cl's Ray and Hit by lane; one lane is a Ray and a Hit. */
#if PC_LANES == 1
typedef Ray RayLanes;
typedef Hit HitLanes;
#else
typedef struct {
  Lane3 o, d;
  LaneF tmin, tmax;
  LaneU skip_prim, skip_instance, cutout_seed;
} RayLanes;

typedef struct {
  LaneF t, u, v;
  LaneU slot, prim, instance;
} HitLanes;
#endif

#if PC_LANES > 1 && defined(PC_BVH_WIDE) && !defined(PC_HAS_INSTANCES)
#define PC_TRACE_PACKETS
#define PC_PACKET_OF_LANES_(N) RayPacket##N
#define PC_HITS_OF_LANES_(N) HitPacket##N
#define PC_PACKET_OF_LANES(N) PC_PACKET_OF_LANES_(N)
#define PC_HITS_OF_LANES(N) PC_HITS_OF_LANES_(N)
#endif

/* The cut-out seed of ray ray_index (PC_RAY_* of sampler.cl) of each lane's path: cutout.cl's cutout_seed
 * by lane. */
static inline LaneU cutout_seed_lanes(__constant const SceneHeader* h, LaneU pixel, LaneU sample, LaneU ray_index) {
  return hash4(pixel, sample, (LaneU)(h->seed ^ 0x3c6ef372u), ray_index);
}

/* The rays of the lanes in m: the nearest hits (with any_hit: whether each is blocked). Returns the lanes
 * with a hit; lanes outside m have none. */
static inline LaneI trace_lanes(const SceneData* sc, const RayLanes* r, LaneI m, bool any_hit, HitLanes* hit) {
#ifdef PC_TRACE_PACKETS
  PC_PACKET_OF_LANES(PC_LANES) p;
  p.o = r->o;
  p.d = r->d;
  p.tmin = r->tmin;
  p.skip_prim = r->skip_prim;
  p.cutout_seed = r->cutout_seed;
  PC_HITS_OF_LANES(PC_LANES) h;
  h.t = r->tmax;
  h.u = h.v = (LaneF)(0.0f);
  h.slot = h.prim = (LaneU)(PC_INVALID);
  LaneI found = trace_packet(sc, PC_SCENE_BVH(sc), sc->prims, 0u, &p, m, any_hit, &h);
  hit->t = h.t;
  hit->u = h.u;
  hit->v = h.v;
  hit->slot = h.slot;
  hit->prim = h.prim;
  hit->instance = (LaneU)(PC_INVALID);
  return found & m;
#else
  float t[PC_LANES], u[PC_LANES], v[PC_LANES];
  uint slot[PC_LANES], prim[PC_LANES], instance[PC_LANES], bits = pc_lane_bits(m), found = 0u;
  for (uint j = 0u; j < PC_LANES; ++j) {
    Hit h;
    h.t = h.u = h.v = 0.0f;
    h.slot = h.prim = h.instance = PC_INVALID;
    if ((bits >> j) & 1u) {
      Ray ray;
      ray.o = lane3_at(r->o, j);
      ray.d = lane3_at(r->d, j);
      ray.tmin = pc_lane(r->tmin, j);
      ray.tmax = pc_lane(r->tmax, j);
      ray.skip_prim = pc_lane(r->skip_prim, j);
      ray.skip_instance = pc_lane(r->skip_instance, j);
      ray.cutout_seed = pc_lane(r->cutout_seed, j);
      if (trace_scene(sc, sc, &ray, any_hit, &h)) found |= 1u << j;
    }
    t[j] = h.t;
    u[j] = h.u;
    v[j] = h.v;
    slot[j] = h.slot;
    prim[j] = h.prim;
    instance[j] = h.instance;
  }
  hit->t = lane_load(t);
  hit->u = lane_load(u);
  hit->v = lane_load(v);
  hit->slot = lane_load(slot);
  hit->prim = lane_load(prim);
  hit->instance = lane_load(instance);
  return pc_lanes_of_bits(found, m);
#endif
}

#endif
