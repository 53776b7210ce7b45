/* The megakernel: one work item renders sample_count samples of one pixel, whole paths each, and adds
 * them to the film one by one (so any split into passes sums in the same order). */
#include "shared/types.h"
#include "math.cl"
#include "rng.cl"
#include "sampler.cl"
#include "sampling.cl"
#include "camera.cl"
#include "intersect.cl"
#include "surface.cl"
#include "bsdf_diffuse.cl"
#include "lights.cl"

inline float3 trace_path(__constant const SceneHeader* h, __global const BvhNode* nodes,
                         __global const Primitive* prims, __global const PrimShading* shading,
                         __global const float4* normals, __global const Material* materials,
                         __global const Light* lights, __global const float* light_cdf, SampleKey key, uint px,
                         uint py, uint* rays) {
  float4 u0 = sample4(h, key, 0);
  Ray ray;
  ray.o = h->cam_position.xyz;
  ray.d = camera_direction(h, px, py, u0.xy);
  ray.tmin = 0.0f;
  ray.tmax = INFINITY;
  ray.skip_prim = PC_INVALID;
  float3 throughput = (float3)(1.0f), radiance = (float3)(0.0f);
  float prev_bsdf_pdf = 0.0f;
  float3 prev_p = ray.o;
  for (uint depth = 0;; ++depth) {
    Hit hit;
    ++*rays;
    if (!trace_bvh(nodes, prims, &ray, false, &hit)) break;
    Surface s = surface_at(prims, shading, normals, &ray, &hit);
    PrimShading sh = shading[s.prim];
    float3 wo = -ray.d;
#ifdef PC_HAS_AREA_LIGHTS
    if (sh.light != PC_INVALID) {
      float3 le = emitted_towards(lights[sh.light].emission.xyz, sh.flags, s.ng, s.p, ray.o);
      float w = depth == 0 ? 1.0f : power_heuristic(prev_bsdf_pdf, light_pdf(lights, prims, sh.light, prev_p, s.p, s.ng));
      radiance += throughput * le * w;
    }
#endif
    if (depth >= h->max_depth) break;

    Material m = materials[sh.material];
    float3 n = dot(s.ns, wo) < 0.0f ? -s.ns : s.ns; /* shading normal on the side of wo */
    float3 ng = dot(s.ng, wo) < 0.0f ? -s.ng : s.ng;
    float4 u_light = sample4(h, key, 1 + 2 * depth);
    float4 u_bsdf = sample4(h, key, 2 + 2 * depth);

#ifdef PC_HAS_AREA_LIGHTS
    /* Next-event estimation, weighted against BSDF sampling by the power heuristic. */
    LightSample ls;
    if (h->light_count > 0 &&
        sample_light(lights, light_cdf, h->light_count, prims, shading, s.p, u_light.x, u_light.yz, &ls)) {
      float3 wi = normalize(ls.p - s.p);
      float3 f = diffuse_eval(m, n, wo, wi);
      if (dot(wi, ng) > 0.0f && (f.x > 0.0f || f.y > 0.0f || f.z > 0.0f)) {
        Ray shadow = spawn_ray_to(s.p, s.p_err, s.ng, s.prim, ls.p, ls.p_err, ls.n);
        Hit blocker;
        ++*rays;
        if (!trace_bvh(nodes, prims, &shadow, true, &blocker)) {
          float w = power_heuristic(ls.pdf, diffuse_pdf(n, wo, wi));
          radiance += throughput * f * ls.Le * (dot(n, wi) * w / ls.pdf);
        }
      }
    }
#endif

    float3 wi, weight;
    float pdf;
    if (!diffuse_sample(m, n, wo, u_bsdf.xy, &wi, &weight, &pdf)) break;
    if (dot(wi, ng) <= 0.0f) break; /* below the geometric surface (shading normals): no light leaks */
    throughput *= weight;
    prev_bsdf_pdf = pdf;
    prev_p = s.p;
    if (depth + 1 > h->rr_depth) {
      /* Russian roulette: survive with probability min(1, max throughput), reweighted to stay unbiased. */
      float q = fmin(1.0f, max_component(throughput));
      if (u_light.w >= q) break;
      throughput /= q;
    }
    ray.o = offset_ray_origin(s.p, s.p_err, s.ng, wi);
    ray.d = wi;
    ray.tmin = 0.0f;
    ray.tmax = INFINITY;
    ray.skip_prim = s.prim;
  }
  return radiance;
}

/* The film holds three float4 per pixel: the sums of the even-numbered and of the odd-numbered samples
 * (w counts them) and the sum of squares. The two half sums give a noise estimate from the image itself. */
__kernel void render_pass(__constant const SceneHeader* h, __global const BvhNode* nodes,
                          __global const Primitive* prims, __global const PrimShading* shading,
                          __global const float4* normals, __global const Material* materials,
                          __global const Light* lights, __global const float* light_cdf, __global float4* film,
                          __global PassStats* stats, uint sample_begin, uint sample_count) {
  uint pixel = get_global_id(0);
  if (pixel >= h->width * h->height) return;
  uint px = pixel % h->width, py = pixel / h->width;
  SampleKey key;
  key.pixel = pixel;
  key.seed = h->seed;
  PassStats st = {0u, 0u, 0u, 0u};
  float4 half_sum[2] = {film[3 * pixel], film[3 * pixel + 1]};
  float4 squares = film[3 * pixel + 2];
  for (uint s = sample_begin; s < sample_begin + sample_count; ++s) {
    key.sample = s;
    float3 L = trace_path(h, nodes, prims, shading, normals, materials, lights, light_cdf, key, px, py, &st.rays);
#ifdef PC_DEBUG_INJECT_HAZARDS
    /* Test builds only (RenderOptions::debug_inject_hazards): proves that the hazard counters count. */
    if (s % 7u == 3u) L.x = NAN;
    if (s % 11u == 5u) L.y = INFINITY;
    if (s % 13u == 6u) L.z = -1.0f;
#endif
    /* A sample that is not a finite non-negative radiance is counted and dropped: it is a bug to find. */
    if (isnan(L.x) || isnan(L.y) || isnan(L.z)) {
      ++st.nan_samples;
      L = (float3)(0.0f);
    } else if (isinf(L.x) || isinf(L.y) || isinf(L.z)) {
      ++st.inf_samples;
      L = (float3)(0.0f);
    } else if (L.x < 0.0f || L.y < 0.0f || L.z < 0.0f) {
      ++st.negative_samples;
      L = (float3)(0.0f);
    }
    half_sum[s & 1u] += (float4)(L, 1.0f);
    squares.xyz += L * L;
  }
  film[3 * pixel] = half_sum[0];
  film[3 * pixel + 1] = half_sum[1];
  film[3 * pixel + 2] = squares;
  stats[pixel] = st;
}
