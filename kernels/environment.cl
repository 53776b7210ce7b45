/* The environment light: radiance from every direction no surface blocks, a constant or a lat-long map
 * (nearest texel, so that the importance-sampling density is exactly proportional to what is seen).
 * Directions: +y is up; v = theta / pi from +y (row 0 = top of the image), u = phi / (2 pi) with
 * phi = atan2(z, x). The map's sampling distribution (built on the host, env_dist) is piecewise
 * constant over texels in (u, v), proportional to luminance times sin(theta):
 *   env_dist[0 .. h]                      marginal cdf over rows (h + 1 entries)
 *   env_dist[h + 1 + r (w + 1) .. + w]    conditional cdf over the columns of row r (w + 1 entries) */
#ifndef PATHCL_ENVIRONMENT_CL
#define PATHCL_ENVIRONMENT_CL

inline float3 env_direction(float2 uv) {
  float phi = 2.0f * PC_PI * uv.x, theta = PC_PI * uv.y;
  float2 c, s = pc_sincos((float2)(theta, phi), &c); /* one call for both angles */
  return (float3)(s.x * c.y, c.x, s.x * s.y);
}

/* theta from atan2, not acos(d.y): near a pole a float d.y keeps few digits of theta (within 0.05 degrees
 * of it, sin(theta) and with it env_pdf came out 1 % off), while d.x and d.z keep sin(theta) exactly. */
inline float2 env_uv(float3 d) {
  float u = pc_atan2(d.z, d.x) * (0.5f * PC_INV_PI);
  if (u < 0.0f) u += 1.0f;
  return (float2)(fmin(u, 1.0f), pc_atan2(sqrt(d.x * d.x + d.z * d.z), d.y) * PC_INV_PI);
}

inline uint2 env_texel(Texture t, float2 uv) {
  return (uint2)(min((uint)(uv.x * (float)t.width), t.width - 1u), min((uint)(uv.y * (float)t.height), t.height - 1u));
}

inline float3 env_radiance(Light light, __global const Texture* textures, __global const float4* texels, float3 d) {
#ifdef PC_HAS_ENVIRONMENT_MAP
  if (light.texture != PC_INVALID) {
    Texture t = textures[light.texture];
    uint2 c = env_texel(t, env_uv(d));
    return light.emission.xyz * texels[t.offset + c.y * t.width + c.x].xyz;
  }
#endif
  return light.emission.xyz;
}

/* Solid-angle density of direction d, light choice excluded. */
inline float env_pdf(Light light, __global const Texture* textures, __global const float* dist, float3 d) {
#ifdef PC_HAS_ENVIRONMENT_MAP
  if (light.texture != PC_INVALID) {
    Texture t = textures[light.texture];
    float2 uv = env_uv(d);
    float sin_theta = pc_sin(PC_PI * uv.y);
    if (sin_theta <= 0.0f) return 0.0f;
    uint2 c = env_texel(t, uv);
    __global const float* row = dist + t.height + 1 + c.y * (t.width + 1);
    float p_uv = (dist[c.y + 1] - dist[c.y]) * (row[c.x + 1] - row[c.x]) * (float)(t.width * t.height);
    return p_uv / (2.0f * PC_PI * PC_PI * sin_theta);
  }
#endif
  return 0.25f * PC_INV_PI;
}

/* A direction drawn from the map's distribution: *pdf its density and *le its radiance, both of the texel
 * it was drawn from. The radiance is not looked up again from the direction: the float direction of a
 * sample at a texel's edge may lie in the neighbouring texel, and a radiance from one texel over the
 * density of a dimmer one would be a firefly (next to a sun, a very bright one). */
inline float3 env_sample(Light light, __global const Texture* textures, __global const float4* texels,
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
    /* Keep the sample inside its texel despite rounding, so its density is the one sampled. */
    uu = clamp(uu, (float)c / (float)t.width, nextafter((float)(c + 1) / (float)t.width, 0.0f));
    v = clamp(v, (float)r / (float)t.height, nextafter((float)(r + 1) / (float)t.height, 0.0f));
    float3 d = env_direction((float2)(uu, v));
    float sin_theta = pc_sin(PC_PI * v);
    *pdf = sin_theta > 0.0f ? dr * dc * (float)(t.width * t.height) / (2.0f * PC_PI * PC_PI * sin_theta) : 0.0f;
    *le = light.emission.xyz * texels[t.offset + r * t.width + c].xyz;
    return d;
  }
#endif
  *pdf = 0.25f * PC_INV_PI;
  *le = light.emission.xyz;
  return sample_uniform_sphere(u);
}

#endif
