/* The environment light: radiance from every direction no surface blocks, a constant or a map in one of
 * two parameterisations (the Light's slot, PC_ENV_* of shared/types.h):
 * - lat-long (PC_ENV_LAT_LONG), looked up bilinearly (texture.cl; columns wrap around, rows clamp at the
 *   poles). Directions: +y is up; v = theta / pi from +y (row 0 = top of the image), u = phi / (2 pi)
 *   with phi = atan2(z, x). Its sampling distribution is piecewise constant over texel cells in (u, v),
 *   proportional to sin(theta) times the largest luminance the bilinear lookup takes in the cell;
 * - pbrt-v4's equal-area octahedral square (PC_ENV_EQUAL_AREA bilinear, PC_ENV_EQUAL_AREA_NEAREST the
 *   nearest texel, as pbrt-v4's ImageInfiniteLight looks its maps up), below. Its distribution is piecewise
 *   constant over texel cells of the square, proportional to the largest luminance the lookup takes in the
 *   cell (no Jacobian: the map preserves area).
 * Either distribution (built on the host, env_dist, scene/environment_distribution.cpp) bounds the radiance
 * it samples and is > 0 wherever the radiance is; env_pdf is exactly that density:
 *   env_dist[0 .. h]                      marginal cdf over rows (h + 1 entries)
 *   env_dist[h + 1 + r (w + 1) .. + w]    conditional cdf over the columns of row r (w + 1 entries) */
#ifndef PATHCL_ENVIRONMENT_CL
#define PATHCL_ENVIRONMENT_CL

#include "texture.cl"
#include "lanes.cl"

static inline float3 env_direction(float2 uv) {
  float phi = 2.0f * PC_PI * uv.x, theta = PC_PI * uv.y;
  float2 c, s = pc_sincos((float2)(theta, phi), &c); /* one call for both angles */
  return (float3)(s.x * c.y, c.x, s.x * s.y);
}

/* theta from atan2, not acos(d.y): near a pole a float d.y keeps few digits of theta (within 0.05 degrees
 * of it, sin(theta) and with it env_pdf came out 1 % off), while d.x and d.z keep sin(theta) exactly. */
static inline float2 env_uv(float3 d) {
  float u = pc_atan2(d.z, d.x) * (0.5f * PC_INV_PI);
  if (u < 0.0f) u += 1.0f;
  return (float2)(fmin(u, 1.0f), pc_atan2(sqrt(d.x * d.x + d.z * d.z), d.y) * PC_INV_PI);
}

/* A map placed by a rotation (the environment's `transform`): light.position holds the unit quaternion
 * (x, y, z, w) that takes the map's directions to the world's, or is all 0 for the map as it is, which
 * then stays bit for bit untouched. q v q* written out as v + 2 w (q x v) + 2 q x (q x v). */
static inline float3 env_rotated(float3 axis, float w, float3 v) {
  float3 t = 2.0f * (float3)(axis.y * v.z - axis.z * v.y, axis.z * v.x - axis.x * v.z, axis.x * v.y - axis.y * v.x);
  return v + w * t + (float3)(axis.y * t.z - axis.z * t.y, axis.z * t.x - axis.x * t.z, axis.x * t.y - axis.y * t.x);
}
static inline bool env_is_rotated(Light light) {
  return light.position.x != 0.0f || light.position.y != 0.0f || light.position.z != 0.0f || light.position.w != 0.0f;
}
static inline float3 env_to_map(Light light, float3 world) {
  return env_is_rotated(light) ? env_rotated(-light.position.xyz, light.position.w, world) : world;
}
static inline float3 env_to_world(Light light, float3 map) {
  return env_is_rotated(light) ? env_rotated(light.position.xyz, light.position.w, map) : map;
}

static inline uint2 env_texel(Texture t, float2 uv) {
  return (uint2)(min((uint)(uv.x * (float)t.width), t.width - 1u), min((uint)(uv.y * (float)t.height), t.height - 1u));
}

/* ---- pbrt-v4's equal-area octahedral maps (Clarberg's mapping, pbrt-v4's EqualAreaSquareToSphere and
 * EqualAreaSphereToSquare, util/math.cpp). A direction d of the map's frame lies at (u, v) in [0, 1]^2: +z
 * at the centre, the circle z = 0 on the diamond through the middles of the edges, -z at the four corners;
 * x has the sign of u - 1/2, y that of v - 1/2. Its texel is column u w, row v h, row 0 the image's first
 * (its top), as pbrt indexes images. The mapping preserves area (a region of area A of the square covers
 * 4 pi A steradians), so the density of a direction is p_uv / (4 pi) with nothing that depends on it. */

/* The direction at (u, v); r = |u'| + |v'| near +z and 2 - (|u'| + |v'|) near -z (u' = 2u - 1, v' = 2v - 1):
 * pbrt's 1 - |1 - (|u'| + |v'|)|, without the subtraction from 1 that loses r's digits where it is small. */
static inline float3 env_square_to_sphere(float2 p) {
  float u = 2.0f * p.x - 1.0f, v = 2.0f * p.y - 1.0f;
  float up = fabs(u), vp = fabs(v), sum = up + vp;
  float signed_distance = 1.0f - sum; /* > 0: the northern hemisphere (+z) */
  float r = signed_distance >= 0.0f ? sum : 2.0f - sum;
  float phi = (r == 0.0f ? 1.0f : (vp - up) / r + 1.0f) * (0.25f * PC_PI);
  float c, s = pc_sincos(phi, &c);
  float k = r * sqrt(fmax(2.0f - r * r, 0.0f));
  return (float3)(copysign(c, u) * k, copysign(s, v) * k, copysign(1.0f - r * r, signed_distance));
}

/* (u, v) of a direction, which need not be of unit length. r^2 = 1 - |z| / |d|, written as
 * (x^2 + y^2) / (|d| (|d| + |z|)): near the poles a float z keeps few digits of 1 - |z| (pbrt's
 * sqrt(1 - |z|) is 0 for every direction within 2e-4 of +z, up to a third of a texel of a 4096^2 map
 * off), while x and y keep r. phi = atan(min / max of |x|, |y|) (pc_atan2), where pbrt-v4 evaluates a
 * polynomial within 4e-6 of it. */
static inline float2 env_sphere_to_square(float3 d) {
  float x = fabs(d.x), y = fabs(d.y), z = fabs(d.z);
  float q = x * x + y * y, len = sqrt(q + z * z);
  float r = len > 0.0f ? fmin(sqrt(q / (len * (len + z))), 1.0f) : 0.0f;
  float phi = pc_atan2(fmin(x, y), fmax(x, y)) * (2.0f * PC_INV_PI); /* in [0, 1/2]: the angle from the nearer axis */
  if (x < y) phi = 1.0f - phi;
  float v = phi * r, u = r - v;
  if (d.z < 0.0f) { /* the southern hemisphere: the triangle outside the diamond, mirrored */
    float t = u;
    u = 1.0f - v;
    v = 1.0f - t;
  }
  return (float2)(0.5f * (copysign(u, d.x) + 1.0f), 0.5f * (copysign(v, d.y) + 1.0f));
}

/* Texel (x, y) of an equal-area map, at most one texel beyond an edge. Each edge of the square folds at its
 * middle onto itself ((0, v) and (0, 1 - v) are one direction, and so on), so the texel beyond an edge is
 * the one mirrored across the edge's middle: column -1 of row y is column 0 of row h - 1 - y, and the
 * texel beyond a corner is the opposite corner's. The lookup is then continuous across every edge.
 * (pbrt-v4's WrapMode::OctahedralSphere takes column 1, not 0, beyond the left edge and row 1 above the
 * top: a texel off at those two edges.) */
static inline float3 env_octahedral_texel(__global const uint* texels, Texture t, int x, int y) {
  int w = (int)t.width, h = (int)t.height;
  if (x < 0 || x >= w) {
    x = x < 0 ? -1 - x : 2 * w - 1 - x;
    y = h - 1 - y;
  }
  if (y < 0 || y >= h) {
    y = y < 0 ? -1 - y : 2 * h - 1 - y;
    x = w - 1 - x;
  }
  return texel_at(texels, t, x, y);
}

/* The map's radiance at (u, v), scale included: bilinear between texel centres (the same blend as
 * texture_bilinear), or the texel (u, v) lies in. */
static inline float3 env_equal_area_radiance(Light light, Texture t, __global const uint* texels, float2 uv) {
  if (light.slot == PC_ENV_EQUAL_AREA_NEAREST) {
    uint2 c = env_texel(t, uv);
    return light.emission.xyz * texel_at(texels, t, (int)c.x, (int)c.y);
  }
  /* uv is in [0, 1]^2 (NaN would read outside the image: clamped, to -0.5) */
  float x = fmin(fmax(uv.x * (float)t.width - 0.5f, -0.5f), (float)t.width - 0.5f);
  float y = fmin(fmax(uv.y * (float)t.height - 0.5f, -0.5f), (float)t.height - 0.5f);
  float fx = floor(x), fy = floor(y);
  float ax = x - fx, ay = y - fy;
  int x0 = (int)fx, y0 = (int)fy;
  return light.emission.xyz *
         ((1.0f - ay) * ((1.0f - ax) * env_octahedral_texel(texels, t, x0, y0) + ax * env_octahedral_texel(texels, t, x0 + 1, y0)) +
          ay * ((1.0f - ax) * env_octahedral_texel(texels, t, x0, y0 + 1) + ax * env_octahedral_texel(texels, t, x0 + 1, y0 + 1)));
}

static inline bool env_is_equal_area(Light light) { return light.slot != PC_ENV_LAT_LONG; }

/* The density of the map's cell c: its row's probability times its own within the row, over the cell's
 * area in the square (1 / (w h)) and 4 pi. env_sample computes the same expression from the same floats. */
static inline float env_equal_area_pdf(float p_row, float p_column, Texture t) {
  return p_row * p_column * (float)(t.width * t.height) / (4.0f * PC_PI);
}

/* sin(theta) from the direction itself: near the -y pole v is close to 1, where a float keeps few digits
 * of pi - theta (at 1e-4 of the pole, pc_sin(PC_PI * v) came out 0.2 % off). pc_dot: dot() may fuse or
 * reorder. */
static inline float env_sin_theta(float3 d) { return sqrt((d.x * d.x + d.z * d.z) / pc_dot(d, d)); }

/* The map's bilinear radiance at (u, v), scale included. */
static inline float3 env_map_radiance(Light light, Texture t, __global const uint* texels, float2 uv) {
  return light.emission.xyz * texture_bilinear(texels, t, uv.x * (float)t.width - 0.5f, uv.y * (float)t.height - 0.5f,
                                               PC_WRAP_REPEAT, PC_WRAP_CLAMP);
}

static inline float3 env_radiance(Light light, __global const Texture* textures, __global const uint* texels, float3 d) {
#ifdef PC_HAS_ENVIRONMENT_MAP
  if (light.texture != PC_INVALID) {
    if (env_is_equal_area(light))
      return env_equal_area_radiance(light, textures[light.texture], texels, env_sphere_to_square(env_to_map(light, d)));
    return env_map_radiance(light, textures[light.texture], texels, env_uv(env_to_map(light, d)));
  }
#endif
  return light.emission.xyz;
}

/* Solid-angle density of direction d, light choice excluded. */
static inline float env_pdf(Light light, __global const Texture* textures, __global const float* dist, float3 d) {
#ifdef PC_HAS_ENVIRONMENT_MAP
  if (light.texture != PC_INVALID) {
    Texture t = textures[light.texture];
    float3 m = env_to_map(light, d);
    if (env_is_equal_area(light)) {
      uint2 c = env_texel(t, env_sphere_to_square(m));
      __global const float* row = dist + t.height + 1 + c.y * (t.width + 1);
      return env_equal_area_pdf(dist[c.y + 1] - dist[c.y], row[c.x + 1] - row[c.x], t);
    }
    float2 uv = env_uv(m);
    float sin_theta = env_sin_theta(m);
    if (sin_theta <= 0.0f) return 0.0f;
    uint2 c = env_texel(t, uv);
    __global const float* row = dist + t.height + 1 + c.y * (t.width + 1);
    float p_uv = (dist[c.y + 1] - dist[c.y]) * (row[c.x + 1] - row[c.x]) * (float)(t.width * t.height);
    return p_uv / (2.0f * PC_PI * PC_PI * sin_theta);
  }
#endif
  return 0.25f * PC_INV_PI;
}

/* A direction drawn from the map's distribution: *pdf the density of the cell it was drawn from and *le
 * the radiance at the (u, v) drawn. Neither is looked up again from the direction: the float direction of
 * a sample at a cell's edge may lie in the neighbouring cell, whose density need not bound this radiance
 * (the bilinear radiance itself is continuous across the edge). */
static inline float3 env_sample(Light light, __global const Texture* textures, __global const uint* texels,
                                __global const float* dist, float2 u, float* pdf, float3* le) {
#ifdef PC_HAS_ENVIRONMENT_MAP
  if (light.texture != PC_INVALID) {
    Texture t = textures[light.texture];
    uint r = find_interval(dist, t.height, u.y);
    float dr = dist[r + 1] - dist[r];
    float v = ((float)r + clamp((u.y - dist[r]) / dr, 0.0f, 1.0f)) / (float)t.height;
    __global const float* row = dist + t.height + 1 + r * (t.width + 1);
    uint c = find_interval(row, t.width, u.x);
    float dc = row[c + 1] - row[c];
    float uu = ((float)c + clamp((u.x - row[c]) / dc, 0.0f, 1.0f)) / (float)t.width;
    /* Keep the sample inside its cell despite rounding, so its density is the one sampled. */
    uu = clamp(uu, (float)c / (float)t.width, nextafter((float)(c + 1) / (float)t.width, 0.0f));
    v = clamp(v, (float)r / (float)t.height, nextafter((float)(r + 1) / (float)t.height, 0.0f));
    if (env_is_equal_area(light)) {
      *pdf = env_equal_area_pdf(dr, dc, t);
      *le = env_equal_area_radiance(light, t, texels, (float2)(uu, v));
      return env_to_world(light, env_square_to_sphere((float2)(uu, v)));
    }
    float3 d = env_direction((float2)(uu, v));
    float sin_theta = env_sin_theta(d); /* as env_pdf computes it, so that MIS sees one density */
    *pdf = sin_theta > 0.0f ? dr * dc * (float)(t.width * t.height) / (2.0f * PC_PI * PC_PI * sin_theta) : 0.0f;
    *le = env_map_radiance(light, t, texels, (float2)(uu, v));
    return env_to_world(light, d);
  }
#endif
  *pdf = 0.25f * PC_INV_PI;
  *le = light.emission.xyz;
  return sample_uniform_sphere(u);
}

/* env_radiance and env_pdf by lane (kernels/lanes.cl), for the lanes in m: a constant for all lanes at
 * once, a map lane by lane. */
static inline Lane3 env_radiance_lanes(Light light, __global const Texture* textures, __global const uint* texels, Lane3 d,
                                       LaneI m) {
  Lane3 le = lane3_splat(light.emission.xyz);
#ifdef PC_HAS_ENVIRONMENT_MAP
  if (light.texture != PC_INVALID) {
    PC_EACH_LANE(j, pc_lane_bits(m)) le = lane3_with(le, j, env_radiance(light, textures, texels, lane3_at(d, j)));
  }
#endif
  return le;
}

static inline LaneF env_pdf_lanes(Light light, __global const Texture* textures, __global const float* dist, Lane3 d,
                                  LaneI m) {
  LaneF pdf = (LaneF)(0.25f * PC_INV_PI);
#ifdef PC_HAS_ENVIRONMENT_MAP
  if (light.texture != PC_INVALID) {
    PC_EACH_LANE(j, pc_lane_bits(m)) pdf = pc_with_lane(pdf, j, env_pdf(light, textures, dist, lane3_at(d, j)));
  }
#endif
  return pdf;
}

#endif
