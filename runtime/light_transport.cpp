#include "runtime/light_transport.h"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "runtime/device.h"
#include "runtime/film.h"
#include "runtime/technique.h"

namespace {
double luminance(const pc_float4& c) { return 0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z; }

// The scene's bounding sphere in device coordinates: the box of the instance BVH's root (every placed
// shape), grown by the point and spot lights' positions.
void scene_bounds(const DeviceScene& scene, double lo[3], double hi[3]) {
  for (int k = 0; k < 3; ++k) lo[k] = INFINITY, hi[k] = -INFINITY;
  if (!scene.instance_bvh.empty()) {
    const BvhNode& root = scene.instance_bvh[0];
    for (int k = 0; k < 3; ++k) lo[k] = root.lo[k], hi[k] = root.hi[k];
  }
  for (const Light& l : scene.lights)
    if (l.type == PC_LIGHT_POINT || l.type == PC_LIGHT_SPOT) {
      const float p[3] = {l.position.x, l.position.y, l.position.z};
      for (int k = 0; k < 3; ++k) lo[k] = std::min(lo[k], double(p[k])), hi[k] = std::max(hi[k], double(p[k]));
    }
  if (!(lo[0] <= hi[0])) {  // nothing in the scene: a unit sphere about the camera
    for (int k = 0; k < 3; ++k) lo[k] = -1, hi[k] = 1;
  }
}
}  // namespace

LightTransportSetup light_transport_setup(const DeviceScene& scene, uint32_t spp) {
  LightTransportSetup out;
  double lo[3], hi[3];
  scene_bounds(scene, lo, hi);
  double c[3], r2 = 0;
  for (int k = 0; k < 3; ++k) {
    c[k] = 0.5 * (lo[k] + hi[k]);
    r2 += 0.25 * (hi[k] - lo[k]) * (hi[k] - lo[k]);
  }
  // A little larger than the box's sphere, so that rays from the disk start outside every surface.
  double radius = std::max(std::sqrt(r2) * 1.01, 1e-6);
  out.header.bounds = {float(c[0]), float(c[1]), float(c[2]), float(radius)};

  const double pi = M_PI, disk = pi * radius * radius;
  double total = 0;
  for (const Light& l : scene.lights) {
    double p = 0, lum = luminance(l.emission);
    switch (l.type) {
      case PC_LIGHT_AREA: {
        bool two_sided = scene.shading[l.prim].flags & PC_FLAG_TWO_SIDED;
        double area = l.area;
        const Primitive& prim = scene.prims[l.slot];
        uint32_t kind;
        std::memcpy(&kind, &prim.b.w, sizeof kind);
        if (kind == PC_PRIM_SPHERE) area = 4 * pi * double(prim.b.x) * prim.b.x;
        p = pi * area * lum * (two_sided ? 2 : 1);
        break;
      }
      case PC_LIGHT_POINT: p = 4 * pi * lum; break;
      case PC_LIGHT_SPOT: p = 2 * pi * lum * (1 - 0.5 * (double(l.cos_inner) + l.cos_outer)); break;
      case PC_LIGHT_DIRECTIONAL: p = disk * lum; break;
      case PC_LIGHT_ENVIRONMENT: p = disk * 4 * double(scene.header.infinite_irradiance) * l.infinite_share; break;
    }
    if (!(p > 0) || !std::isfinite(p)) p = 0;
    out.power.push_back(p);
    total += p;
  }
  out.header.light_count = uint32_t(scene.lights.size());
  out.emission_cdf.push_back(0);
  double running = 0;
  for (size_t i = 0; i < out.power.size(); ++i) {
    running += out.power[i];
    out.emission_cdf.push_back(i + 1 == out.power.size() ? 1.0f : float(total > 0 ? running / total : 0));
  }
  if (out.power.empty()) out.emission_cdf.push_back(1);

  // Fixed-point scales: a pixel 2^20 times the typical radiance, over spp samples, fits below 2^62.
  double typical = total > 0 ? total / (4 * pi * pi * radius * radius) : 1;
  double bright = std::max(typical, 1e-30) * double(1 << 20);
  auto scale_for = [&](double peak_sum) {
    int e = int(std::floor(62 - std::log2(peak_sum)));
    return std::ldexp(1.0f, std::clamp(e, -100, 100));
  };
  out.header.splat_scale = scale_for(bright * std::max<uint32_t>(spp, 1));
  out.header.square_scale = scale_for(bright * bright * std::max<uint32_t>(spp, 1));
  return out;
}

void develop_splats(Film& f, const LightTransportHeader& lt, uint64_t* overflows) {
  develop_splat_layer(f, lt, overflows, "splats");
}

void develop_splat_layer(Film& f, const LightTransportHeader& lt, uint64_t* overflows, const char* layer,
                         double first_share) {
  size_t pixels = size_t(f.width) * f.height;
  const uint32_t spp = f.spp;
  f.mean.assign(3 * pixels, 0.0f);
  f.variance.assign(3 * pixels, 0.0f);
  f.even_mean.assign(3 * pixels, 0.0f);
  f.odd_mean.assign(3 * pixels, 0.0f);
  double n_even = (spp + 1) / 2, n_odd = spp / 2, paths = double(pixels);
  if (first_share > 0) n_even = spp * first_share, n_odd = spp * (1 - first_share);
  double unit = 1.0 / lt.splat_scale, unit2 = 1.0 / lt.square_scale;
  const uint32_t* plane = f.layer(size_t(f.layout.find(layer)));
  for (size_t p = 0; p < pixels; ++p) {
    uint64_t s[PC_SPLAT_WORDS];
    std::memcpy(s, plane + 2 * PC_SPLAT_WORDS * p, sizeof s);
    for (int c = 0; c < 3; ++c) {
      for (int k : {c, 3 + c, 6 + c, 9 + c})
        if (s[k] >> 63) ++*overflows;
      double even = double(s[c]) * unit, odd = double(s[3 + c]) * unit, squares = double(s[6 + c]) * unit2;
      double mean = spp > 0 ? (even + odd) / spp : 0;
      double even_mean = n_even > 0 ? even / n_even : 0, odd_mean = n_odd > 0 ? odd / n_odd : 0;
      f.mean[3 * p + c] = float(mean);
      f.even_mean[3 * p + c] = float(even_mean);
      f.odd_mean[3 * p + c] = float(odd_mean);
      if (first_share > 0) {
        const double d = even_mean - odd_mean;
        f.variance[3 * p + c] = float(first_share * (1 - first_share) * d * d);
        continue;
      }
      // BDPT's camera part (one sample per pixel and sample) and the light part (from `paths` paths).
      double camera = spp > 0 ? double(s[9 + c]) * unit / spp : 0, light = mean - camera;
      double per_sample = spp > 0 ? std::max(0.0, squares / spp - camera * camera - light * light / paths) : 0;
      f.variance[3 * p + c] = float(spp > 0 ? per_sample / spp : 0);
    }
  }
}

std::string splat_build_options(const TechniqueBuild& b) {
  return !b.splat_pairs && device_has_extension(*b.device, "cl_khr_int64_base_atomics") ? " -DPC_SPLAT_ATOMIC64" : "";
}

size_t light_vertex_slots(const TechniqueSizes& s) { return std::max<uint32_t>(s.max_depth, 1); }

size_t light_vertex_bytes(const TechniqueSizes& s) { return size_t(s.unit_items) * light_vertex_slots(s) * sizeof(LightVertex); }

uint32_t light_vertex_unit_paths(const TechniqueSizes& s, size_t extra_bytes) {
  const size_t vertices = light_vertex_slots(s) * sizeof(LightVertex);
  const uint64_t alloc = std::max<uint64_t>(s.device->max_alloc, 1 << 20), memory = std::max<uint64_t>(s.device->global_memory, 1 << 22);
  const uint64_t paths = std::min(alloc / vertices, memory / 4 / (vertices + extra_bytes));
  return uint32_t(std::min<uint64_t>(paths, s.pixels));
}

double default_merging_radius(const DeviceScene& scene, const LightTransportHeader& lt) {
  const SceneHeader& h = scene.header;
  double d = scene.view_distance;
  if (!(d > 0)) {  // no look_at (a glTF camera): the distance to the scene's centre, or its radius from inside
    const double dx = h.cam_position.x - lt.bounds.x, dy = h.cam_position.y - lt.bounds.y, dz = h.cam_position.z - lt.bounds.z;
    d = std::sqrt(dx * dx + dy * dy + dz * dz);
    if (!(d > 0.1 * lt.bounds.w)) d = lt.bounds.w;
  }
  const double tan_half = std::sqrt(double(h.cam_up.x) * h.cam_up.x + double(h.cam_up.y) * h.cam_up.y + double(h.cam_up.z) * h.cam_up.z);
  return d * 2 * tan_half / std::max<uint32_t>(h.height, 1);
}
