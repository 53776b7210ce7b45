/* Photon merging (lane width 1): vertex connection and merging (`vcm`; Georgiev et al., "Light Transport
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
 *                light_vertices (never an atomic counter), their camera connections splatted
 *   vcm_count    counts the vertices in each bucket of the hash grid (cells 2 r wide; integer atomics)
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
 * hashed into `table` buckets (a power of two >= the unit's paths); cells[b] .. cells[b + 1] are bucket
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
  while (t < paths) t <<= 1;
  return t;
}

static inline float iteration_radius2(__constant const LightTransportHeader* lt, uint iteration) {
  return lt->radius * lt->radius * pc_powr((float)(iteration + 1u), lt->alpha - 1.0f);
}

/* The merging factors of an iteration (light_path.cl's MisFactors). */
static inline MisFactors iteration_factors(__constant const LightTransportHeader* lt, __constant const SceneHeader* h, float radius2) {
  MisFactors m;
  bool merge = (lt->vcm_mode & PC_VCM_MERGE) != 0u, sppm = (lt->vcm_mode & PC_VCM_SPPM) != 0u;
  m.connect = (lt->vcm_mode & PC_VCM_CONNECT) != 0u;
  float eta = PC_PI * radius2 * (float)(h->width * h->height);
  m.vm = merge && !sppm ? eta : 0.0f;
  m.vc = merge && m.connect ? 1.0f / eta : 0.0f;
  m.first_length = sppm ? 2u : 1u;
  return m;
}

/* Cells are 2 r wide: what a position is scaled by to find its cell (one expression for the grid's build and
 * its queries, which must agree). */
static inline float grid_inv_cell(float radius2) { return 0.5f / sqrt(radius2); }

static inline int grid_coordinate(float q) { return (int)clamp(q, -1.0e9f, 1.0e9f); }

static inline uint grid_bucket(int x, int y, int z, uint table) {
  return (((uint)x * 73856093u) ^ ((uint)y * 19349663u) ^ ((uint)z * 83492791u)) & (table - 1u);
}

static inline uint grid_bucket_of(float3 p, float3 origin, float inv_cell, uint table) {
  float3 q = floor((p - origin) * inv_cell);
  return grid_bucket(grid_coordinate(q.x), grid_coordinate(q.y), grid_coordinate(q.z), table);
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

/* Merges camera vertex s (material m, frame f, wo_local towards the previous camera vertex; depth scattering
 * events before it, throughput, partial sums dvcm and dvm) with the grid's light vertices within the
 * radius: each as if the light path had scattered here towards the camera, its density estimate
 * f(wo, wl) beta / (pi r^2 N) times the shading normal's cosine over the geometric one (the photon's
 * density is per area, the camera's integral over the shading normal's cosine, as in path tracing), weighted
 * by MIS against every strategy making the path (SmallVCM's eq.), or not at all for SPPM. */
static inline void merge_at(const SceneData* sc, const MergeGrid* g, const Surface* s, const MaterialLanes* m, const FrameLanes* f,
                            float3 wo_local, float wo_ng, uint depth, float3 throughput, float dvcm, float dvm, float vc,
                            bool sppm, __constant const LightTransportHeader* lt, MergeSums* out, SplatCounts* n) {
  __constant const SceneHeader* h = sc->h;
  /* The 2 x 2 x 2 cells about s->p that a ball of radius r about it can reach (cells are 2 r wide). */
  float3 q = (s->p - g->origin) * g->inv_cell, fl = floor(q);
  int x = grid_coordinate(fl.x), y = grid_coordinate(fl.y), z = grid_coordinate(fl.z);
  int dx = q.x - fl.x < 0.5f ? -1 : 1, dy = q.y - fl.y < 0.5f ? -1 : 1, dz = q.z - fl.z < 0.5f ? -1 : 1;
  uint seen[8];
  for (uint corner = 0; corner < 8u; ++corner) {
    uint b = grid_bucket(x + ((corner & 1u) ? dx : 0), y + ((corner & 2u) ? dy : 0), z + ((corner & 4u) ? dz : 0), g->table);
    seen[corner] = b;
    bool again = false; /* two cells hashed into one bucket: its entries once */
    for (uint j = 0; j < corner; ++j) again |= seen[j] == b;
    if (again) continue;
    for (uint e = g->cells[b]; e < g->cells[b + 1u]; ++e) {
      float4 entry = g->entries[e];
      float3 d = entry.xyz - s->p;
      if (!(pc_dot(d, d) <= g->radius2)) continue;
      __global const LightVertex* v = g->vertices + as_uint(entry.w);
      if (v->length + depth > h->max_depth) continue;
      float3 wl = v->wl.xyz;
      float wl_ng = pc_dot(wl, s->ng);
      if (!(wl_ng * wo_ng > 0.0f)) continue; /* light arriving on the camera's side */
      float3 wl_local = to_local(f, wl);
      float3 fv = bsdf_eval_lanes(m, wo_local, wl_local, 1);
      if (!(fv.x > 0.0f || fv.y > 0.0f || fv.z > 0.0f)) continue;
      float w = 1.0f;
      if (!sppm) {
        float camera_dir = bsdf_pdf_lanes(m, wo_local, wl_local, 1), camera_rev = bsdf_pdf_lanes(m, wl_local, wo_local, 1);
        float w_light = v->ng.w * vc + v->wl.w * camera_dir;
        float w_camera = dvcm * vc + dvm * camera_rev;
        w = 1.0f / (w_light + 1.0f + w_camera);
      }
      float scale = w * fabs(wl_local.z) / fabs(wl_ng) * g->normalization;
      merge_add(out, throughput * fv * v->beta.xyz * scale, lt, n);
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

PC_KERNEL_BODY void vcm_light_item(const SceneData* scene, __constant const LightTransportHeader* lt,
                                   __global const float* emission_cdf, __global uint* film, __global SplatStats* stats,
                                   __global LightVertex* light_vertices, __global uint* vertex_counts, PC_VCM_UNIT,
                                   uint item) {
  SceneData sc = *scene;
  __constant const SceneHeader* h = sc.h;
  if (item >= path_count) return;
  SampleKey key = light_path_key(h, path_begin + item, sample_begin);
  SplatCounts n = {0u, 0u, 0u, 0u, 0u, 0u};
  MisFactors mis = iteration_factors(lt, h, iteration_radius2(lt, sample_begin));
  uint count = 0u;
  trace_light_paths_lanes(&sc, lt, emission_cdf, film, key, key.pixel, 1, &n, &mis, light_vertices + item * light_vertex_slots(h),
                          &count);
  vertex_counts[item] = count;
  add_splat_counts(stats, &n);
}
__kernel void vcm_light(PC_SCENE_PARAMS, __constant const LightTransportHeader* lt, __global const float* emission_cdf,
                        __global uint* film, __global SplatStats* stats, __global LightVertex* light_vertices,
                        __global uint* vertex_counts, PC_VCM_UNIT) {
  SceneData sc = PC_SCENE_DATA;
  vcm_light_item(&sc, lt, emission_cdf, film, stats, light_vertices, vertex_counts, path_begin, path_count,
                 sample_begin, sample_count, get_global_id(0));
}

__kernel void vcm_count(PC_SCENE_PARAMS, __constant const LightTransportHeader* lt, __global const LightVertex* light_vertices,
                        __global const uint* vertex_counts, __global uint* cells, PC_VCM_UNIT) {
  uint item = get_global_id(0);
  if (item >= path_count) return;
  float inv_cell = grid_inv_cell(iteration_radius2(lt, sample_begin));
  uint table = grid_table(path_count), slots = light_vertex_slots(h);
  for (uint k = 0; k < vertex_counts[item]; ++k)
    atomic_inc(cells + grid_bucket_of(light_vertices[item * slots + k].p.xyz, lt->bounds.xyz, inv_cell, table));
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
  if (item >= path_count) return;
  float inv_cell = grid_inv_cell(iteration_radius2(lt, sample_begin));
  uint table = grid_table(path_count), slots = light_vertex_slots(h);
  for (uint k = 0; k < vertex_counts[item]; ++k) {
    uint slot = item * slots + k;
    float3 p = light_vertices[slot].p.xyz;
    entries[atomic_dec(cells + grid_bucket_of(p, lt->bounds.xyz, inv_cell, table)) - 1u] = (float4)(p, as_float(slot));
  }
}

/* One work item per pixel of the image. */
PC_KERNEL_BODY void vcm_camera_item(const SceneData* scene, __constant const LightTransportHeader* lt,
                                    __global const float* emission_cdf, __global uint* film, __global SplatStats* stats,
                                    __global const LightVertex* light_vertices, __global const uint* vertex_counts,
                                    __global const uint* cells, __global const float4* entries, PC_VCM_UNIT, uint pixel) {
  SceneData sc = *scene;
  __constant const SceneHeader* h = sc.h;
  if (path_count == 0u || pixel >= h->width * h->height) return;
  SampleKey key = light_path_key(h, pixel, sample_begin);
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
  grid.normalization = 1.0f / (PC_PI * radius2 * (float)(h->width * h->height));
  uint item = pixel - path_begin; /* the pixel's light path in the unit, if it is there */
  bool own = pixel >= path_begin && item < path_count;
  uint slots = light_vertex_slots(h);
  MergeSums merged = {{0ul, 0ul, 0ul}, {0ul, 0ul, 0ul}, 0u};
  SplatCounts n = {0u, 0u, 0u, 0u, 0u, 0u};
  uint count = own ? vertex_counts[item] : 0u;
  float3 L = trace_camera_subpaths(&sc, lt, emission_cdf, key, pixel, pixel % h->width, pixel / h->width, 1, &mis, own,
                                   light_vertices + (own ? item * slots : 0u), &count, &n.rays, &grid, &merged, &n);
  uint parity = sample_begin & 1u;
  if (own && splat_is_valid(L, &n)) n.overflows += splat_camera(film, lt, pixel, parity, L);
  volatile __global uint* p = (volatile __global uint*)film + 2u * (PC_SPLAT_WORDS * pixel);
  for (uint k = 0; k < 3u; ++k) {
    if (merged.sum[k]) splat_add_u64(p + 2u * (3u * parity + k), merged.sum[k]);
    if (merged.squares[k]) splat_add_u64(p + 2u * (6u + k), merged.squares[k]);
  }
  n.overflows += merged.overflows;
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
