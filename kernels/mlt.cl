/* Metropolis light transport (`mlt`, lane width 1) in primary sample space over BDPT's strategies: Kelemen
 * et al. 2002's mutations, Hachisuka et al. 2014's multiplexing (pbrt-v4's MLTIntegrator). A state is a
 * path depth d (its scattering events, 2 .. D; a large step may change it) and the uniform numbers a BDPT sample reads
 * (sampler.cl's slots: the camera and light subpaths' groups, and the strategy's). Its contribution: the
 * strategy (s, t) its strategy number picks among the d + 2 that make paths of depth d, that strategy alone
 * (bdpt.cl, light_path.cl with PC_MLT: the subpaths stop where it needs no more), weighted by the balance
 * heuristic and times d + 2; a camera subpath's value goes to the pixel its image position is in, a light
 * tracing connection's (t = 1) is splatted through the filter where it lands. Its importance I is the
 * luminance of that value.
 *
 * Paths of depths 0 and 1 (emitters seen directly, direct light) are left to each pixel's own BDPT sample
 * without light tracing, one a step with the render's sampler (stratified over the image and, with Sobol, over
 * a pixel's steps: a lamp in view would otherwise hold a large share of the chains on a flat region, and
 * direct light is what next-event estimation does best); the chains take the rest.
 *
 * A render: chains, one per pixel index (the schedule's pixel units are runs of chains and levels of steps),
 * each making spp steps; a chain's state lives in the film's ordered layer "chains" (so units on any device,
 * checkpoints and resumes carry it), the splats in the commutative layers "splats", "large" and "independent"
 * (fixed point, the same bits in any order). The first step of a chain starts it: B bootstrap candidates per depth
 * 2 .. D (B = lt->bootstrap; independent uniform numbers) are evaluated and their importances summed by a
 * prefix sum of fixed order (mlt_bootstrap, mlt_scan_*; each device once, with the same bits), and the chain
 * takes a candidate in proportion to its importance (systematic resampling: chain i at (i + u) / chains of
 * the sum, u one number for the render). Each step proposes a state: a large step (probability
 * lt->large_step) takes fresh numbers and a uniform depth, a small step keeps the depth and moves each number
 * by Kelemen's mutation (sampler.cl's mlt_mutate) of size up to lt->mutation_size. It is accepted with
 * probability a = min(1, I' / I). Numbers are mutated lazily, when the evaluation reads them (sampler.cl's
 * MltSampler). Splats (Kelemen et al.'s combination of the two techniques, Metropolis samples of density
 * I / b and large steps of density 1 / (D - 1) over (depth, numbers), taken p = lt->large_step times a step,
 * by the balance heuristic; q = p / (D - 1)): the current state's value L times (1 - a) / (I / b0 + q) and the
 * proposal's times a / (I' / b0 + q) into the "splats" layer, and a large step's proposal's times
 * 1 / (I' / b0 + q) into "large"; the image is (independent + large + splats b / b0) / spp, "independent"
 * holding the pixels' own samples (below). A chain splats into the film's half of its set of chains (first or
 * second half, in the order of their starts), the pixels' own samples into their step's parity. Where the image is
 * uniform the large steps carry it, as plain Monte Carlo would; where it is not, the chains.
 * b = (D - 1) E[I] over uniform (depth, numbers) is the image's mean luminance beyond depth 1. b0 is its
 * bootstrap estimate (the candidates' importance sum over B), which the weights take; b the host's
 * (runtime/technique_mlt.cpp), from the candidates and every large step's proposal (each an independent
 * uniform state), so that it converges with the render (without the lamp's pixels, which depth 0 holds, the
 * importance is not so heavy-tailed: over 4 seeds on the Cornell box the image means were within 1.3 %, as
 * close as with stratified full BDPT samples for b at a sixth of the steps' cost more). The depths' shares
 * converge with the chains: their states move between depths through large steps (pbrt-v4's chains keep
 * theirs, its b is the bootstrap's, and its image keeps the bootstrap's error in the scale and in each depth's
 * share: 4 % on the Cornell box here, depth 0 included).
 *
 * Start-up bias: a chain starts from a bootstrap candidate drawn in proportion to its importance, an
 * approximation of the stationary distribution with B (D - 1) candidates; the estimate is consistent as the
 * steps grow. Every random number of a chain is a function of (chain, step, seed): the image is the same bits
 * for any split into units, device set and implementation. */
#define PC_BDPT 1
#define PC_MLT 1
#include "light_path.cl"
#include "direct_light.cl"
#include "bdpt.cl"
#include "scan.cl"

/* The unit's range (pixel units: chains pixel_begin + i pixel_stride, i < pixel_count, steps
 * [sample_begin, sample_begin + sample_count)). */
#define PC_MLT_UNIT uint pixel_begin, uint pixel_count, uint pixel_stride, uint sample_begin, uint sample_count

/* The largest max_depth (runtime/technique_mlt.cpp's limit): a state's slots in private memory. */
#define PC_MLT_MAX_DEPTH 16u
#define PC_MLT_MAX_SLOTS (4u * PC_MLT_MAX_DEPTH + 4u)
/* A chain's state in the "chains" layer (runtime/technique_mlt.cpp reads it): a header (word 0 its depth, 1
 * the bootstrap candidates' importance sum, 2 its importance I, 3 its contribution's kind, 4-5 its raster
 * position, 6-8 its value, 9 its large steps, 10-11 their proposals' importance sum and its compensation, 12
 * its sampler's iteration, 13-14 its last large step's iteration and step), then 4 numbers per slot, then
 * each slot's last change (an iteration). */
#define PC_MLT_HEADER_WORDS 16u
/* Work items of the bootstrap (runtime/technique_mlt.cpp's bootstrap_items: at most 4096, at most the pixels). */
#define PC_MLT_BOOTSTRAP_ITEMS 4096u
static inline uint mlt_bootstrap_items(__constant const SceneHeader* h) { return min(PC_MLT_BOOTSTRAP_ITEMS, h->width * h->height); }
/* The key (b of MltSampler and SampleKey.sample) of the bootstrap's candidates, beyond any step. */
#define PC_MLT_BOOTSTRAP_SAMPLE 0xfffff000u
/* The seed of the pixels' own samples of depths 0 and 1, xor the render's (their keys are (pixel, step) as a
 * chain's: this keeps their cut-out seeds and numbers apart). */
#define PC_MLT_NEAR_SEED 0x6e656172u

static inline uint mlt_state_words(__constant const SceneHeader* h) { return PC_MLT_HEADER_WORDS + 5u * mlt_slots(h); }
/* The chains take paths of depth 2 .. D (PC_MLT_FIRST_DEPTH); depths 0 and 1 are each pixel's BDPT sample. */
#define PC_MLT_FIRST_DEPTH 2u
static inline uint mlt_depths(__constant const SceneHeader* h) { return max(h->max_depth + 1u, PC_MLT_FIRST_DEPTH) - PC_MLT_FIRST_DEPTH; }
static inline uint mlt_candidates(__constant const LightTransportHeader* lt, __constant const SceneHeader* h) {
  return lt->bootstrap * mlt_depths(h);
}
/* The bootstrap buffer: the candidates' importances, summed in place by scan.cl's prefix sum (the total at
 * bootstrap[C], the blocks' offsets after it), then a mark. The bootstrap is the same for every unit: a
 * device computes it once (its buffer is kept for the render) and marks it done (bootstrap[C + 1 +
 * PC_SCAN_BLOCKS]). */
#define PC_MLT_BOOTSTRAP_DONE 0x444f4e45u
static inline bool mlt_bootstrapped(__constant const LightTransportHeader* lt, __constant const SceneHeader* h, __global const float* bootstrap) {
  return as_uint(bootstrap[mlt_candidates(lt, h) + 1u + PC_SCAN_BLOCKS]) == PC_MLT_BOOTSTRAP_DONE;
}
/* Bootstrap candidate c: depth 2 + c % (D - 1), fresh numbers of key (c, PC_MLT_BOOTSTRAP_SAMPLE). */
static inline uint mlt_candidate_depth(__constant const SceneHeader* h, uint c) { return PC_MLT_FIRST_DEPTH + c % mlt_depths(h); }

/* A state's contribution: where it goes (PC_MLT_PIXEL: the pixel of raster, PC_MLT_SPLAT: through the
 * filter, PC_MLT_NONE: nowhere) and its value. */
#define PC_MLT_NONE 0u
#define PC_MLT_PIXEL 1u
#define PC_MLT_SPLAT 2u
typedef struct {
  uint kind;
  float2 raster;
  float3 value;
} MltContribution;

/* Private arrays for a sampler's slots. */
typedef struct {
  float x[4u * PC_MLT_MAX_SLOTS], backup[4u * PC_MLT_MAX_SLOTS];
  uint modified[PC_MLT_MAX_SLOTS], backup_modified[PC_MLT_MAX_SLOTS], changed[PC_MLT_MAX_SLOTS];
} MltSlots;

static inline void mlt_sampler_on(MltSampler* m, MltSlots* slots, uint seed) {
  m->x = slots->x;
  m->backup = slots->backup;
  m->modified = slots->modified;
  m->backup_modified = slots->backup_modified;
  m->changed = slots->changed;
  m->changed_count = 0u;
  m->seed = seed;
}

/* A fresh state's sampler: every slot's numbers from (a, b) when read. */
static inline void mlt_fresh(MltSampler* m, MltSlots* slots, __constant const SceneHeader* h, uint a, uint b) {
  mlt_sampler_on(m, slots, h->seed);
  m->fresh = 1u;
  m->large = 0u;
  m->a = a;
  m->b = b;
  m->iteration = 1u;
  for (uint k = 0; k < mlt_slots(h); ++k) slots->modified[k] = 0u;
}

/* The contribution of the state sampler m reads at depth `depth` (key: chain and step, for cut-out seeds),
 * and its importance (0 where it is nowhere or not a finite non-negative value). With `all`, instead every
 * strategy of the depths depth .. depth_hi but light tracing (below) at pixel `pixel` (BDPT's sample, its
 * camera subpath's value there), its importance that value's luminance. */
static inline float mlt_evaluate(const SceneData* sc, __constant const LightTransportHeader* lt, __global const float* emission_cdf,
                                 __global LightVertex* vertices, MltSampler* m, uint depth, bool all, uint depth_hi, uint pixel,
                                 uint sample, SplatCounts* n, MltContribution* out, MltSplat* splat) {
  __constant const SceneHeader* h = sc->h;
  SampleKey key;
  key.pixel = pixel;
  key.sample = sample;
  key.seed = all ? h->seed ^ PC_MLT_NEAR_SEED : h->seed;
  key.mlt = m; /* 0 for the pixels' own samples: the render's sampler (sampler.cl's sample4) */
  uint strategies = depth + 2u;
  uint s = all ? PC_INVALID : min((uint)(sample4(h, key, PC_MLT_STRATEGY_GROUP(h)).x * (float)strategies), strategies - 1u);
  uint t = all ? PC_INVALID : depth + 2u - s;
  /* The pixels' own samples (all, depths 0 and 1) leave light tracing (t = 1) out (light_tracing_count), and
   * with it the light subpath, a fifth of a step's time: no light path connects its emitter's own vertex
   * (light_path.cl), so at these depths it connects a non-delta vertex after one scattering event, whose
   * path next-event estimation from that vertex makes too, for every kind of light and camera. */
  MisFactors mis = {0.0f, 0.0f, true, 1u, s, t, depth, depth_hi};
  out->kind = PC_MLT_NONE;
  out->value = (float3)(0.0f);
  uint count = 0u;
  splat->value = (float3)(0.0f);
  if (!all && s >= 2u)
    trace_light_paths_lanes(sc, lt, emission_cdf, (__global uint*)0, key, key.pixel, 1, n, &mis, vertices, &count, splat);
  if (t == 1u) {
    out->kind = PC_MLT_SPLAT;
    out->raster = splat->raster;
    out->value = splat->value * (float)strategies;
  } else {
    uint px = pixel % h->width, py = pixel / h->width;
    if (!all) { /* the pixel the state's image position is in */
      uint2 p = mlt_pixel(h, mlt_numbers(m, 0u).xy);
      px = p.x;
      py = p.y;
    }
    out->kind = PC_MLT_PIXEL;
    out->raster = (float2)((float)px, (float)py);
    const uint first_slot = 0u;
    out->value = trace_camera_subpaths(sc, lt, emission_cdf, key, key.pixel, px, py, 1, &mis, 1, vertices, &first_slot, &count,
                                       &n->rays) *
                 (all ? 1.0f : (float)strategies);
  }
  if (!splat_is_valid(out->value, n)) out->value = (float3)(0.0f);
  float importance = luminance(out->value);
  if (!(importance > 0.0f) || !(importance < INFINITY)) {
    out->kind = PC_MLT_NONE;
    return 0.0f;
  }
  return importance;
}

/* The candidates' importances (every unit at step 0; nothing otherwise). */
PC_KERNEL_BODY void mlt_bootstrap_item(const SceneData* scene, __constant const LightTransportHeader* lt,
                                       __global const float* emission_cdf, __global SplatStats* stats,
                                       __global LightVertex* light_vertices, __global float* bootstrap, PC_MLT_UNIT,
                                       uint item) {
  SceneData sc = *scene;
  __constant const SceneHeader* h = sc.h;
  if (pixel_count == 0u || sample_begin != 0u || item >= mlt_bootstrap_items(h) || mlt_bootstrapped(lt, h, bootstrap)) return;
  SplatCounts n = {0u, 0u, 0u, 0u, 0u, 0u};
  MltSlots slots;
  MltSampler m;
  __global LightVertex* vertices = light_vertices + item * light_vertex_slots(h);
  for (uint c = item; c < mlt_candidates(lt, h); c += mlt_bootstrap_items(h)) {
    mlt_fresh(&m, &slots, h, c, PC_MLT_BOOTSTRAP_SAMPLE);
    MltContribution contribution;
    MltSplat splat;
    bootstrap[c] = mlt_evaluate(&sc, lt, emission_cdf, vertices, &m, mlt_candidate_depth(h, c), false, 0u, c,
                                PC_MLT_BOOTSTRAP_SAMPLE, &n, &contribution, &splat);
  }
  add_splat_counts(stats, &n);
}
__kernel void mlt_bootstrap(PC_SCENE_PARAMS, __constant const LightTransportHeader* lt,
                            __global const float* emission_cdf, __global SplatStats* stats,
                            __global LightVertex* light_vertices, __global float* bootstrap, PC_MLT_UNIT) {
  SceneData sc = PC_SCENE_DATA;
  mlt_bootstrap_item(&sc, lt, emission_cdf, stats, light_vertices, bootstrap, pixel_begin, pixel_count, pixel_stride,
                     sample_begin, sample_count, get_global_id(0));
}

/* The candidates' running sums (scan.cl), once per device. */
__kernel void mlt_scan_blocks(PC_SCENE_PARAMS, __constant const LightTransportHeader* lt, __global float* bootstrap, PC_MLT_UNIT) {
  uint block = get_global_id(0);
  if (pixel_count == 0u || sample_begin != 0u || block >= PC_SCAN_BLOCKS || mlt_bootstrapped(lt, h, bootstrap)) return;
  scan_block_float(bootstrap, mlt_candidates(lt, h), block);
}

__kernel void mlt_scan_offsets(PC_SCENE_PARAMS, __constant const LightTransportHeader* lt, __global float* bootstrap, PC_MLT_UNIT) {
  if (get_global_id(0) != 0u || pixel_count == 0u || sample_begin != 0u || mlt_bootstrapped(lt, h, bootstrap)) return;
  scan_offsets_float(bootstrap, mlt_candidates(lt, h));
}

__kernel void mlt_scan_add(PC_SCENE_PARAMS, __constant const LightTransportHeader* lt, __global float* bootstrap, PC_MLT_UNIT) {
  uint block = get_global_id(0);
  if (pixel_count == 0u || sample_begin != 0u || block >= PC_SCAN_BLOCKS || mlt_bootstrapped(lt, h, bootstrap)) return;
  scan_add_float(bootstrap, mlt_candidates(lt, h), block);
}

__kernel void mlt_bootstrap_done(PC_SCENE_PARAMS, __constant const LightTransportHeader* lt, __global float* bootstrap, PC_MLT_UNIT) {
  if (get_global_id(0) != 0u || pixel_count == 0u || sample_begin != 0u) return;
  bootstrap[mlt_candidates(lt, h) + 1u + PC_SCAN_BLOCKS] = as_float(PC_MLT_BOOTSTRAP_DONE);
}

/* Adds contribution c times `weight` to a splat layer. */
static inline void mlt_splat(__global uint* splats, __constant const SceneHeader* h, __constant const LightTransportHeader* lt,
                             const MltContribution* c, float weight, uint parity, SplatCounts* n) {
  if (c->kind == PC_MLT_NONE || !(weight > 0.0f)) return;
  float3 v = c->value * weight;
  if (c->kind == PC_MLT_PIXEL)
    n->overflows += splat_pixel(splats, lt, (uint)c->raster.y * h->width + (uint)c->raster.x, parity, v);
  else
    splat_filtered(splats, h, lt, c->raster, parity, v, n);
}

/* Pixel `chain`'s BDPT sample of depths 0 and 1 at step `step` (without light tracing, mlt_evaluate):
 * emitters seen directly and direct light, which the chains leave out, into the independent samples' layer
 * at weight 1. Its numbers are the render's sampler's, sample `step` of the pixel (Sobol's by default: the
 * steps of a pixel are then stratified, as the path integrator's samples are), not a chain's. */
static inline void mlt_near_sample(const SceneData* sc, __constant const LightTransportHeader* lt,
                                   __global const float* emission_cdf, __global LightVertex* vertices,
                                   __global uint* independent, uint chain, uint step, SplatCounts* n) {
  __constant const SceneHeader* h = sc->h;
  MltContribution camera;
  MltSplat splat;
  mlt_evaluate(sc, lt, emission_cdf, vertices, (MltSampler*)0, 0u, true, min(h->max_depth, PC_MLT_FIRST_DEPTH - 1u),
               chain, step, n, &camera, &splat);
  mlt_splat(independent, h, lt, &camera, 1.0f, step & 1u, n);
}

/* Each chain of the unit: started at step 0, then its steps of the unit. */
PC_KERNEL_BODY void mlt_chains_item(const SceneData* scene, __constant const LightTransportHeader* lt,
                                    __global const float* emission_cdf, __global uint* film, __global SplatStats* stats,
                                    __global LightVertex* light_vertices, __global const float* bootstrap, PC_MLT_UNIT,
                                    uint item) {
  SceneData sc = *scene;
  __constant const SceneHeader* h = sc.h;
  if (item >= pixel_count || sample_count == 0u) return;
  uint chain = pixel_begin + item * pixel_stride, words = mlt_state_words(h), slot_count = mlt_slots(h);
  __global uint* state = film + chain * words;
  __global uint* splats = film + h->width * h->height * words;
  __global uint* independent = splats + h->width * h->height * 2u * PC_SPLAT_WORDS;
  __global uint* large = independent + h->width * h->height * 2u * PC_SPLAT_WORDS;
  /* The chain's half of the film's two halves (the splat film's parities): the first half of the chains in
   * the order of their starts, or the second. Two sets of chains are two independent estimates (each with
   * its own candidates to start from: systematic resampling starts chain i at (i + u) / chains of the
   * candidates' running sum), so their difference measures a render's error, the chains' correlation
   * included; a chain's even and odd steps, nearly the same paths, did not (runtime/technique_mlt.cpp). */
  const uint chain_half = 2u * chain >= h->width * h->height ? 1u : 0u;
  __global LightVertex* vertices = light_vertices + item * light_vertex_slots(h);
  SplatCounts n = {0u, 0u, 0u, 0u, 0u, 0u};
  MltSlots slots;
  MltSampler m;
  mlt_sampler_on(&m, &slots, h->seed);
  m.fresh = 0u;
  m.a = chain;
  m.size = lt->mutation_size;
  MltContribution now = {PC_MLT_NONE, (float2)(0.0f), (float3)(0.0f)};
  float importance = 0.0f;
  uint depth = PC_MLT_FIRST_DEPTH;
  /* The large steps for b: their count and the sum of their proposals' importances (Kahan's compensated sum). */
  uint b_samples = 0u;
  float b_sum = 0.0f, b_error = 0.0f;
  if (sample_begin == 0u) {
    /* A bootstrap candidate in proportion to its importance: the first whose running sum exceeds
     * (chain + u) / chains of the total, u one number for the render (systematic resampling: a candidate of
     * importance I is the start of I / total of the chains, rounded up or down, where independent draws
     * left some of the candidates that should start a chain with none, and others with several). */
    uint candidates = mlt_candidates(lt, h);
    float total = bootstrap[candidates];
    state[1] = as_uint(total);
    if (candidates > 0u && total > 0.0f) {
      float u = uint_to_unit(hash4(0u, h->seed, 0x5354u, 0x41525431u));
      float target = ((float)chain + u) / (float)(h->width * h->height) * total;
      uint lo = 0u, hi = candidates - 1u;
      while (lo < hi) {
        uint mid = (lo + hi) / 2u;
        if (bootstrap[mid] > target) hi = mid;
        else lo = mid + 1u;
      }
      depth = mlt_candidate_depth(h, lo);
      /* Its numbers, every slot's, as the bootstrap read them (then the chain's, at iteration 0). */
      MltSampler start;
      mlt_fresh(&start, &slots, h, lo, PC_MLT_BOOTSTRAP_SAMPLE);
      for (uint slot = 0; slot < slot_count; ++slot) mlt_ensure_ready(&start, slot);
      MltSplat splat;
      importance = mlt_evaluate(&sc, lt, emission_cdf, vertices, &start, depth, false, 0u, lo, PC_MLT_BOOTSTRAP_SAMPLE, &n,
                                &now, &splat);
    }
    for (uint k = 0; k < slot_count; ++k) slots.modified[k] = 0u;
    m.iteration = m.last_large = m.last_large_step = 0u;
  } else {
    depth = state[0];
    importance = as_float(state[2]);
    now.kind = state[3];
    now.raster = (float2)(as_float(state[4]), as_float(state[5]));
    now.value = (float3)(as_float(state[6]), as_float(state[7]), as_float(state[8]));
    b_samples = state[9];
    b_sum = as_float(state[10]);
    b_error = as_float(state[11]);
    m.iteration = state[12];
    m.last_large = state[13];
    m.last_large_step = state[14];
    for (uint k = 0; k < 4u * slot_count; ++k) slots.x[k] = as_float(state[PC_MLT_HEADER_WORDS + k]);
    for (uint k = 0; k < slot_count; ++k) slots.modified[k] = state[PC_MLT_HEADER_WORDS + 4u * slot_count + k];
  }
  float b0 = as_float(state[1]) / (float)lt->bootstrap;
  /* The large steps' density over (depth, numbers), times their share of the steps. */
  float large_density = lt->large_step / (float)max(mlt_depths(h), 1u);
  for (uint step = sample_begin; step < sample_begin + sample_count; ++step) {
    mlt_near_sample(&sc, lt, emission_cdf, vertices, independent, chain, step, &n);
    if (!(importance > 0.0f)) continue; /* a chain that found no light (a black scene) stays */
    m.large = uint_to_unit(hash4(chain, step, h->seed, 0x6d757461u)) < lt->large_step;
    m.b = step;
    m.changed_count = 0u;
    ++m.iteration;
    uint next_depth = m.large ? PC_MLT_FIRST_DEPTH + min((uint)(uint_to_unit(hash4(chain, step, h->seed, 0x64707468u)) *
                                                               (float)mlt_depths(h)),
                                                         mlt_depths(h) - 1u)
                              : depth;
    MltContribution next;
    MltSplat splat;
    float next_importance = mlt_evaluate(&sc, lt, emission_cdf, vertices, &m, next_depth, false, 0u, chain, step, &n,
                                         &next, &splat);
    if (m.large) { /* an independent uniform state: a sample of b / (D - 1) */
      ++b_samples;
      float y = next_importance - b_error, t = b_sum + y;
      b_error = (t - b_sum) - y;
      b_sum = t;
    }
    float accept = min(1.0f, next_importance / importance);
    mlt_splat(splats, h, lt, &now, (1.0f - accept) / (importance / b0 + large_density), chain_half, &n);
    if (next_importance > 0.0f) {
      float denominator = next_importance / b0 + large_density;
      mlt_splat(splats, h, lt, &next, accept / denominator, chain_half, &n);
      if (m.large) mlt_splat(large, h, lt, &next, 1.0f / denominator, chain_half, &n);
    }
    if (uint_to_unit(hash4(chain, step, h->seed, 0x61636370u)) < accept) {
      now = next;
      importance = next_importance;
      depth = next_depth;
      if (m.large) {
        m.last_large = m.iteration;
        m.last_large_step = step;
      }
    } else {
      mlt_reject(&m);
    }
  }
  state[0] = depth;
  state[2] = as_uint(importance);
  state[3] = now.kind;
  state[4] = as_uint(now.raster.x);
  state[5] = as_uint(now.raster.y);
  state[6] = as_uint(now.value.x);
  state[7] = as_uint(now.value.y);
  state[8] = as_uint(now.value.z);
  state[9] = b_samples;
  state[10] = as_uint(b_sum);
  state[11] = as_uint(b_error);
  state[12] = m.iteration;
  state[13] = m.last_large;
  state[14] = m.last_large_step;
  for (uint k = 0; k < 4u * slot_count; ++k) state[PC_MLT_HEADER_WORDS + k] = as_uint(slots.x[k]);
  for (uint k = 0; k < slot_count; ++k) state[PC_MLT_HEADER_WORDS + 4u * slot_count + k] = slots.modified[k];
  add_splat_counts(stats, &n);
}
__kernel void mlt_chains(PC_SCENE_PARAMS, __constant const LightTransportHeader* lt, __global const float* emission_cdf,
                         __global uint* film, __global SplatStats* stats, __global LightVertex* light_vertices,
                         __global const float* bootstrap, PC_MLT_UNIT) {
  SceneData sc = PC_SCENE_DATA;
  mlt_chains_item(&sc, lt, emission_cdf, film, stats, light_vertices, bootstrap, pixel_begin, pixel_count, pixel_stride,
                  sample_begin, sample_count, get_global_id(0));
}
