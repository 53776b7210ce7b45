/* Image textures: linear RGB texels (sRGB images are converted on the host), bilinear filtering,
 * repeat / clamp / mirror wrapping. v = 0 is the bottom row of the image, as in OBJ files. */
#ifndef PATHCL_TEXTURE_CL
#define PATHCL_TEXTURE_CL

/* Texel index along an axis of n texels for integer coordinate i under the wrap mode. */
inline int wrap_texel(int i, int n, uint wrap) {
  if (wrap == PC_WRAP_CLAMP) return clamp(i, 0, n - 1);
  if (wrap == PC_WRAP_MIRROR) {
    int period = 2 * n;
    int m = ((i % period) + period) % period;
    return m < n ? m : period - 1 - m;
  }
  return ((i % n) + n) % n;
}

inline float3 texel_at(__global const float4* texels, Texture t, int x, int y) {
  return texels[t.offset + (uint)y * t.width + (uint)x].xyz;
}

/* Bilinear lookup at (u, v); texel centres at half-integer coordinates. */
inline float3 texture_lookup(__global const Texture* textures, __global const float4* texels, uint index, float2 uv) {
  Texture t = textures[index];
  float x = uv.x * (float)t.width - 0.5f, y = (1.0f - uv.y) * (float)t.height - 0.5f;
  /* Far outside [0, 1] the coordinates lose precision; keep them bounded. */
  x = clamp(x, -1.0e6f, 1.0e6f);
  y = clamp(y, -1.0e6f, 1.0e6f);
  float fx = floor(x), fy = floor(y);
  float ax = x - fx, ay = y - fy;
  int x0 = (int)fx, y0 = (int)fy;
  int w = (int)t.width, h = (int)t.height;
  int xa = wrap_texel(x0, w, t.wrap), xb = wrap_texel(x0 + 1, w, t.wrap);
  int ya = wrap_texel(y0, h, t.wrap), yb = wrap_texel(y0 + 1, h, t.wrap);
  return (1.0f - ay) * ((1.0f - ax) * texel_at(texels, t, xa, ya) + ax * texel_at(texels, t, xb, ya)) +
         ay * ((1.0f - ax) * texel_at(texels, t, xa, yb) + ax * texel_at(texels, t, xb, yb));
}

#endif
