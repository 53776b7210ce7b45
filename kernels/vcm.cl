/* Photon merging, W = PC_LANES paths at once (kernels/lanes.cl): vertex connection and merging (`vcm`; Georgiev et al., "Light Transport
 * Simulation with Vertex Connection and Merging", 2012, in SmallVCM's formulation with the partial sums
 * dVCM, dVC and dVM), bidirectional photon mapping (`bpm`: merging without connections) and stochastic
 * progressive photon mapping (`sppm`: camera paths to their first non-delta vertex, next-event estimation
 * there, photons of one scattering event or more merged there, unweighted).
 *
 * An iteration is a sample index: its N = width x height light paths are BDPT's (light_path.cl, keyed by
 * (path, sample)); camera path p of the iteration connects to light path p (bdpt.cl) and merges with every
 * light vertex of the iteration within radius r_i = r_1 (i + 1)^((alpha - 1) / 2) (Knaus and Zwicker's
 * probabilistic progressive photon mapping: each iteration is an estimate of its own, a global radius
 * schedule instead of per-pixel statistics, so iterations are independent and any device may run any).
 *
 * A unit is light paths [b, b + c) of one iteration (Technique::per_sample runs its phases once per
 * sample), its phases:
 *   vcm_clear    the grid's buckets to zero
 *   vcm_light    traces the c light paths, their non-delta vertices at slots (path - b) max_depth + k of
 *                light_vertices (never an atomic counter), their camera connections splatted, and counts
 *                the vertices in each bucket of the hash grid (cells 2 r wide; integer atomics)
 *   vcm_scan_*   bucket ends by a prefix sum (blocks of buckets in parallel, then their offsets)
 *   vcm_scatter  each vertex's slot into its bucket's entries
 *   vcm_camera   every pixel's camera path: its own strategies where light path p is the unit's (the
 *                connections need it), and its merges with the unit's vertices
 * so that a pixel's merges are split over the units by light path. Each merge is converted to fixed point
 * on its own and the conversions added in 64-bit integers (MergeSums), so the film is the same bits
 * whichever units, order of the grid's entries or order of arrival: the sums are over the same set of
 * integers. A pixel's camera path is traced again by each unit of its iteration (the price of splitting
 * an iteration; one unit per iteration where the device's memory and its unit time allow). */
#define PC_BDPT 1
#define PC_VCM 1
#include "light_path.cl"
#include "direct_light.cl"
#include "scan.cl"

/* The hash grid of a unit's light vertices in iteration i: cells 2 r_i wide about the scene's centre,
 * hashed into `table` buckets (a power of two >= PC_GRID_BUCKETS_PER_PATH times the unit's paths: with
 * one a path, a bucket held 2.5 vertices of the Cornell box, other cells' nearly all, and a query's walk
 * made its camera phase 10 % longer than with four); cells[b] .. cells[b + 1] are bucket
 * b's entries, each a vertex's position and (the bits of w) its slot of light_vertices: a query reads its
 * buckets' positions one after the other, and a vertex only where it is within the radius (those of a
 * large image are far beyond the caches: the Cornell box's camera phase at 512 x 512 was 1.27 x longer
 * with slots alone). */
typedef struct {
  __global const LightVertex* vertices;
  __global const uint* cells;
  __global const float4* entries;
  uint table;
  float3 origin;
  float inv_cell, radius2;
  float normalization; /* 1 / (pi r^2 N): a merge's density estimate over the iteration's N light paths */
} MergeGrid;

/* A camera path's merges: each in fixed point (the splat film's scales) on its own, then added. */
typedef struct {
  ulong sum[3], squares[3];
  uint overflows;
} MergeSums;

static inline uint grid_table(uint paths) {
  uint t = 1u;
  while (t < paths * PC_GRID_BUCKETS_PER_PATH) t <<= 1;
  return t;
}

static inline float iteration_radius2(__constant const LightTransportHeader* lt, uint iteration) {
  return lt->radius * lt->radius * pc_powr((float)(iteration + 1u), lt->alpha - 1.0f);
}

/* Whether the iteration merges (vcm with "merge": false does not: bdpt's estimator, and no grid is built). */
static inline bool vcm_merges(__constant const LightTransportHeader* lt) { return (lt->vcm_mode & PC_VCM_MERGE) != 0u; }

/* The merging factors of an iteration (light_path.cl's MisFactors). Merging's density in the weights is
 * eta = merge_mis pi r^2 N. SmallVCM's balance heuristic (merge_mis 1) takes a merge for a sample of density
 * pi r^2 N p; but how many light vertices fall within r fluctuates too, which that density does not see, so
 * it gave merges more of the paths that connections sample than their noise deserves (the Cornell box: vcm's
 * relMSE 1.4 times bdpt's at 4 spp). Any factor keeps the weights of a path summing to one, and paths that
 * only merging samples keep weight 1 (variance-aware MIS, Grittmann et al. 2019). The contributions' density
 * estimate (MergeGrid.normalization) is not scaled. */
static inline MisFactors iteration_factors(__constant const LightTransportHeader* lt, __constant const SceneHeader* h, float radius2) {
  MisFactors m;
  bool merge = vcm_merges(lt), sppm = (lt->vcm_mode & PC_VCM_SPPM) != 0u;
  m.connect = (lt->vcm_mode & PC_VCM_CONNECT) != 0u;
  float eta = lt->merge_mis * (PC_PI * radius2 * (float)(h->width * h->height));
  m.vm = merge && !sppm ? eta : 0.0f;
  m.vc = merge && m.connect ? 1.0f / eta : 0.0f;
  m.first_length = sppm ? 2u : 1u;
  return m;
}

/* Cells are 2 r wide: what a position is scaled by to find its cell (one expression for the grid's build and
 * its queries, which must agree). */
static inline float grid_inv_cell(float radius2) { return 0.5f / sqrt(radius2); }

/* A cell's coordinate from its floor (a float or the lanes'), and its bucket: one expression for the grid's
 * build (one vertex at a time) and its queries (the lanes' at once). */
#define PC_GRID_COORDINATE(q) pc_to_int_(clamp((q), -1.0e9f, 1.0e9f))
#define PC_GRID_BUCKET(as_u, x, y, z, table) \
  (((as_u(x) * 73856093u) ^ (as_u(y) * 19349663u) ^ (as_u(z) * 83492791u)) & ((table) - 1u))

static inline uint grid_bucket_of(float3 p, float3 origin, float inv_cell, uint table) {
  float3 q = floor((p - origin) * inv_cell);
  return PC_GRID_BUCKET(as_uint, PC_GRID_COORDINATE(q.x), PC_GRID_COORDINATE(q.y), PC_GRID_COORDINATE(q.z), table);
}

/* Adds merge c to the sums (NaN, infinite or negative ones counted and dropped, as splats are). */
static inline void merge_add(MergeSums* m, float3 c, __constant const LightTransportHeader* lt, SplatCounts* n) {
  if (!splat_is_valid(c, n)) return;
  float v[3] = {c.x, c.y, c.z};
  for (uint k = 0; k < 3u; ++k) {
    if (!(v[k] > 0.0f)) continue;
    float q = v[k] * lt->splat_scale, q2 = v[k] * v[k] * lt->square_scale;
    if (!(q < PC_SPLAT_LIMIT) || !(q2 < PC_SPLAT_LIMIT)) {
      ++m->overflows;
      continue;
    }
    ulong a = convert_ulong_rte(q), a2 = convert_ulong_rte(q2);
    if (m->sum[k] + a < m->sum[k] || m->squares[k] + a2 < m->squares[k]) {
      ++m->overflows;
      continue;
    }
    m->sum[k] += a;
    m->squares[k] += a2;
  }
}

/* The entries [begin[c][j], end[c][j]) of the grid buckets a ball of radius r about lane j's p can reach:
 * the 2 x 2 x 2 cells c about it (cells are 2 r wide), each bucket once (two cells hashed into one bucket:
 * its entries once); empty ranges for the others. The lanes' buckets at once, their ranges by gathers. */
static inline void merge_buckets(const MergeGrid* g, Lane3 p, uint begin[8][PC_LANES], uint end[8][PC_LANES]) {
  LaneF qx = (p.x - g->origin.x) * g->inv_cell, qy = (p.y - g->origin.y) * g->inv_cell, qz = (p.z - g->origin.z) * g->inv_cell;
  LaneF fx = floor(qx), fy = floor(qy), fz = floor(qz);
  LaneI x = PC_GRID_COORDINATE(fx), y = PC_GRID_COORDINATE(fy), z = PC_GRID_COORDINATE(fz);
  LaneI dx = select((LaneI)(1), (LaneI)(-1), qx - fx < 0.5f), dy = select((LaneI)(1), (LaneI)(-1), qy - fy < 0.5f),
        dz = select((LaneI)(1), (LaneI)(-1), qz - fz < 0.5f);
  LaneU seen[8];
  for (uint corner = 0; corner < 8u; ++corner) {
    LaneU b = PC_GRID_BUCKET(lane_as_u, (corner & 1u) ? x + dx : x, (corner & 2u) ? y + dy : y, (corner & 4u) ? z + dz : z,
                             g->table);
    seen[corner] = b;
    LaneI again = (LaneI)(0);
    for (uint k = 0; k < corner; ++k) again |= seen[k] == b;
    lane_store(select(lane_gather_uint(g->cells, 1u, b), (LaneU)(0u), again), begin[corner]);
    lane_store(select(lane_gather_uint(g->cells + 1, 1u, b), (LaneU)(0u), again), end[corner]);
  }
}

/* The light vertices a lane finds within the radius before their merges are taken, W at a time. */
#define PC_MERGE_BATCH 8u

/* Merges camera vertex s of the lanes in m (material mat, frame f, wo_local towards the previous camera
 * vertex; depth scattering events before it, throughput, partial sums dvcm and dvm) with the grid's light
 * vertices within the radius, lane j's into out[j]: each as if the light path had scattered here towards the
 * camera, its density estimate f(wo, wl) beta / (pi r^2 N) times the shading normal's cosine over the
 * geometric one (the photon's density is per area, the camera's integral over the shading normal's cosine,
 * as in path tracing), weighted by MIS against every strategy making the path (SmallVCM's eq.), or not at
 * all for SPPM. Each lane walks its buckets alone (most entries are beyond the radius: a distance test each),
 * keeping up to PC_MERGE_BATCH vertices within it; then the lanes take their k-th vertices' merges together.
 * Each merge is the one-lane value, and its fixed-point sum does not depend on the order. */
static inline void merge_at(const SceneData* sc, const MergeGrid* g, const SurfaceLanes* s, const MaterialLanes* mat,
                            const FrameLanes* f, Lane3 wo_local, LaneF wo_ng, uint depth, Lane3 throughput, LaneF dvcm,
                            LaneF dvm, float vc, bool sppm, LaneI m, __constant const LightTransportHeader* lt,
                            MergeSums* out, SplatCounts* n) {
  __constant const SceneHeader* h = sc->h;
  const uint stride = (uint)(sizeof(LightVertex) / sizeof(float4));
  uint begin_of[8][PC_LANES], end_of[8][PC_LANES], corner_of[PC_LANES], e_of[PC_LANES], found[PC_MERGE_BATCH][PC_LANES],
      count_of[PC_LANES];
  for (uint j = 0u; j < PC_LANES; ++j) {
    corner_of[j] = e_of[j] = 0u;
    for (uint k = 0; k < PC_MERGE_BATCH; ++k) found[k][j] = 0u;
  }
  merge_buckets(g, s->p, begin_of, end_of);
  for (uint j = 0u; j < PC_LANES; ++j) e_of[j] = begin_of[0][j];
  __global const LightVertex* lv = g->vertices;
  for (uint left = pc_lane_bits(m); left != 0u;) { /* the lanes with entries to walk */
    uint most = 0u;
    for (uint j = 0u; j < PC_LANES; ++j) count_of[j] = 0u;
    PC_EACH_LANE(j, left) {
      float3 p = lane3_at(s->p, j);
      uint c = corner_of[j], e = e_of[j], k = 0u;
      while (c < 8u && k < PC_MERGE_BATCH) {
        if (e >= end_of[c][j]) {
          if (++c < 8u) e = begin_of[c][j];
          continue;
        }
        float4 entry = g->entries[e++];
        float3 d = entry.xyz - p;
        if (pc_dot(d, d) <= g->radius2) found[k++][j] = as_uint(entry.w);
      }
      corner_of[j] = c, e_of[j] = e, count_of[j] = k;
      most = max(most, k);
      if (c == 8u) left &= ~(1u << j);
    }
    for (uint k = 0; k < most; ++k) {
      uint valid = 0u;
      for (uint j = 0u; j < PC_LANES; ++j) valid |= (uint)(count_of[j] > k) << j;
      LaneI near = pc_lanes_of_bits(valid, m);
      LaneU slot = lane_safe_index(lane_load(found[k]), near);
      LaneU length = lane_gather_uint(PC_FIELD_U(lv, length), slot);
      near &= length + depth <= h->max_depth;
      if (!pc_any_(near)) continue;
      Lane3 wl, beta, unused3;
      LaneF v_dvm, v_dvcm, unused;
      lane_gather4(&lv->wl, stride, slot, &wl, &v_dvm);
      LaneF wl_ng = pc_dot(wl, s->ng);
      near &= wl_ng * wo_ng > 0.0f; /* light arriving on the camera's side */
      if (!pc_any_(near)) continue;
      Lane3 wl_local = to_local(f, wl);
      Lane3 fv = bsdf_eval_lanes(mat, wo_local, wl_local, near);
      near &= lane3_any_positive(fv);
      if (!pc_any_(near)) continue;
      lane_gather4(&lv->ng, stride, slot, &unused3, &v_dvcm);
      lane_gather4(&lv->beta, stride, slot, &beta, &unused);
      LaneF w = (LaneF)(1.0f);
      if (!sppm) {
        LaneF camera_dir = bsdf_pdf_lanes(mat, wo_local, wl_local, near), camera_rev = bsdf_pdf_lanes(mat, wl_local, wo_local, near);
        LaneF w_light = v_dvcm * vc + v_dvm * camera_dir;
        LaneF w_camera = dvcm * vc + dvm * camera_rev;
        w = 1.0f / (w_light + 1.0f + w_camera);
      }
      LaneF scale = w * fabs(wl_local.z) / fabs(wl_ng) * g->normalization;
      Lane3 c = lane3_scale(lane3_mul(lane3_mul(throughput, fv), beta), scale);
      PC_EACH_LANE(j, pc_lane_bits(near)) merge_add(out + j, lane3_at(c, j), lt, n);
    }
  }
}

#include "bdpt.cl"


/* The unit's range: light paths [path_begin, path_begin + path_count) of iteration sample_begin
 * (sample_count is 1: Technique::per_sample). */
#define PC_VCM_UNIT uint path_begin, uint path_count, uint sample_begin, uint sample_count

__kernel void vcm_clear(PC_SCENE_PARAMS, __global uint* cells, PC_VCM_UNIT) {
  uint i = get_global_id(0);
  if (path_count > 0u && i <= grid_table(path_count)) cells[i] = 0u;
}

/* Work item i traces light paths i G .. i G + G - 1 of the unit (G = PC_ITEM_PIXELS), W at a time, and
 * counts their vertices into the grid's buckets. */
PC_KERNEL_BODY void vcm_light_item(const SceneData* scene, __constant const LightTransportHeader* lt,
                                   __global const float* emission_cdf, __global uint* film, __global SplatStats* stats,
                                   __global LightVertex* light_vertices, __global uint* vertex_counts,
                                   __global uint* cells, PC_VCM_UNIT, uint item) {
  SceneData sc = *scene;
  __constant const SceneHeader* h = sc.h;
  uint first = item * PC_ITEM_PIXELS;
  if (first >= path_count) return;
  LaneU lane = lane_indices();
  SampleKey key = light_path_key(h, path_begin + first, sample_begin);
  SplatCounts n = {0u, 0u, 0u, 0u, 0u, 0u};
  float radius2 = iteration_radius2(lt, sample_begin), inv_cell = grid_inv_cell(radius2);
  MisFactors mis = iteration_factors(lt, h, radius2);
  const uint table = grid_table(path_count), slots = light_vertex_slots(h);
  const bool merge = vcm_merges(lt);
  for (uint b = first; b < min(first + PC_ITEM_PIXELS, path_count); b += PC_LANES) {
    LaneU index = (LaneU)(b) + lane;
    LaneI m = index < path_count;
    key.pixel = path_begin + b;
    uint count[PC_LANES];
    for (uint j = 0u; j < PC_LANES; ++j) count[j] = 0u;
    trace_light_paths_lanes(&sc, lt, emission_cdf, film, key, (LaneU)(path_begin) + index, m, &n, &mis,
                            light_vertices + b * slots, count);
    PC_EACH_LANE(j, pc_lane_bits(m)) {
      vertex_counts[b + j] = count[j];
      for (uint k = 0; merge && k < count[j]; ++k)
        atomic_inc(cells + grid_bucket_of(light_vertices[(b + j) * slots + k].p.xyz, lt->bounds.xyz, inv_cell, table));
    }
  }
  add_splat_counts(stats, &n);
}
__kernel void vcm_light(PC_SCENE_PARAMS, __constant const LightTransportHeader* lt, __global const float* emission_cdf,
                        __global uint* film, __global SplatStats* stats, __global LightVertex* light_vertices,
                        __global uint* vertex_counts, __global uint* cells, PC_VCM_UNIT) {
  SceneData sc = PC_SCENE_DATA;
  vcm_light_item(&sc, lt, emission_cdf, film, stats, light_vertices, vertex_counts, cells, path_begin, path_count,
                 sample_begin, sample_count, get_global_id(0));
}

/* The buckets' ends by scan.cl's prefix sum (the blocks' offsets after the buckets' end, cells[table + 1 +
 * block]; the total at cells[table]). */
__kernel void vcm_scan_blocks(PC_SCENE_PARAMS, __global uint* cells, PC_VCM_UNIT) {
  uint block = get_global_id(0);
  if (path_count == 0u || block >= PC_SCAN_BLOCKS) return;
  scan_block_uint(cells, grid_table(path_count), block);
}

__kernel void vcm_scan_offsets(PC_SCENE_PARAMS, __global uint* cells, PC_VCM_UNIT) {
  if (get_global_id(0) != 0u || path_count == 0u) return;
  scan_offsets_uint(cells, grid_table(path_count));
}

/* After it cells[b] is bucket b's end: vcm_scatter counts it down to the bucket's start. */
__kernel void vcm_scan_add(PC_SCENE_PARAMS, __global uint* cells, PC_VCM_UNIT) {
  uint block = get_global_id(0);
  if (path_count == 0u || block >= PC_SCAN_BLOCKS) return;
  scan_add_uint(cells, grid_table(path_count), block);
}

__kernel void vcm_scatter(PC_SCENE_PARAMS, __constant const LightTransportHeader* lt, __global const LightVertex* light_vertices,
                          __global const uint* vertex_counts, __global uint* cells, __global float4* entries, PC_VCM_UNIT) {
  uint item = get_global_id(0);
  if (item >= path_count || !vcm_merges(lt)) return;
  float inv_cell = grid_inv_cell(iteration_radius2(lt, sample_begin));
  uint table = grid_table(path_count), slots = light_vertex_slots(h);
  for (uint k = 0; k < vertex_counts[item]; ++k) {
    uint slot = item * slots + k;
    float3 p = light_vertices[slot].p.xyz;
    entries[atomic_dec(cells + grid_bucket_of(p, lt->bounds.xyz, inv_cell, table)) - 1u] = (float4)(p, as_float(slot));
  }
}

/* Work item i takes pixels i G .. i G + G - 1 of the image (G = PC_ITEM_PIXELS), W at a time. */
PC_KERNEL_BODY void vcm_camera_item(const SceneData* scene, __constant const LightTransportHeader* lt,
                                    __global const float* emission_cdf, __global uint* film, __global SplatStats* stats,
                                    __global const LightVertex* light_vertices, __global const uint* vertex_counts,
                                    __global const uint* cells, __global const float4* entries, PC_VCM_UNIT, uint item) {
  SceneData sc = *scene;
  __constant const SceneHeader* h = sc.h;
  const uint pixels = h->width * h->height, first = item * PC_ITEM_PIXELS;
  if (path_count == 0u || first >= pixels) return;
  float radius2 = iteration_radius2(lt, sample_begin);
  MisFactors mis = iteration_factors(lt, h, radius2);
  MergeGrid grid;
  grid.vertices = light_vertices;
  grid.cells = cells;
  grid.entries = entries;
  grid.table = grid_table(path_count);
  grid.origin = lt->bounds.xyz;
  grid.inv_cell = grid_inv_cell(radius2);
  grid.radius2 = radius2;
  grid.normalization = 1.0f / (PC_PI * radius2 * (float)pixels);
  const uint slots = light_vertex_slots(h), parity = sample_begin & 1u;
  LaneU lane = lane_indices();
  SampleKey key = light_path_key(h, first, sample_begin);
  SplatCounts n = {0u, 0u, 0u, 0u, 0u, 0u};
  for (uint b = first; b < min(first + PC_ITEM_PIXELS, pixels); b += PC_LANES) {
    LaneU pixel = (LaneU)(b) + lane;
    LaneI m = pixel < pixels;
    key.pixel = b;
    /* A pixel's own strategies where its light path (pixel - path_begin of the unit) is the unit's. */
    uint count[PC_LANES], first_slot[PC_LANES], own_bits = 0u;
    MergeSums merged[PC_LANES];
    for (uint j = 0u; j < PC_LANES; ++j) {
      uint p = b + j;
      bool own = p >= path_begin && p - path_begin < path_count;
      own_bits |= own ? 1u << j : 0u;
      count[j] = own ? vertex_counts[p - path_begin] : 0u;
      first_slot[j] = own ? (p - path_begin) * slots : 0u;
      merged[j] = (MergeSums){{0ul, 0ul, 0ul}, {0ul, 0ul, 0ul}, 0u};
    }
    LaneI own = pc_lanes_of_bits(own_bits, m);
    Lane3 L = trace_camera_subpaths(&sc, lt, emission_cdf, key, pixel, pixel % h->width, pixel / h->width, m, &mis, own,
                                    light_vertices, first_slot, count, &n.rays, &grid, merged, &n);
    PC_EACH_LANE(j, pc_lane_bits(m)) {
      float3 value = lane3_at(L, j);
      if ((own_bits >> j & 1u) != 0u && splat_is_valid(value, &n)) n.overflows += splat_camera(film, lt, b + j, parity, value);
      volatile __global uint* p = (volatile __global uint*)film + 2u * (PC_SPLAT_WORDS * (b + j));
      for (uint k = 0; k < 3u; ++k) {
        if (merged[j].sum[k]) splat_add_u64(p + 2u * (3u * parity + k), merged[j].sum[k]);
        if (merged[j].squares[k]) splat_add_u64(p + 2u * (6u + k), merged[j].squares[k]);
      }
      n.overflows += merged[j].overflows;
    }
  }
  add_splat_counts(stats, &n);
}
__kernel void vcm_camera(PC_SCENE_PARAMS, __constant const LightTransportHeader* lt, __global const float* emission_cdf,
                         __global uint* film, __global SplatStats* stats, __global const LightVertex* light_vertices,
                         __global const uint* vertex_counts, __global const uint* cells, __global const float4* entries,
                         PC_VCM_UNIT) {
  SceneData sc = PC_SCENE_DATA;
  vcm_camera_item(&sc, lt, emission_cdf, film, stats, light_vertices, vertex_counts, cells, entries, path_begin,
                  path_count, sample_begin, sample_count, get_global_id(0));
}
