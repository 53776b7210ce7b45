/* Image textures: texels at the precision of their file (8-bit sRGB, half or float; PC_TEXELS_* of
 * shared/types.h), decoded to linear RGB here, bilinear filtering, repeat / clamp / mirror wrapping.
 * v = 0 is the bottom row of the image, as in OBJ files. Checkerboards (PC_TEXELS_CHECKER) are evaluated
 * exactly at the point. */
#ifndef PATHCL_TEXTURE_CL
#define PATHCL_TEXTURE_CL

#include "shared/types.h"
#include "shared/srgb_table.h"

/* A table, not pow(): every implementation then decodes a byte to the same float (srgb_table.h). */
__constant float pc_srgb_to_linear[256] = PC_SRGB_TO_LINEAR_TABLE;

/* Texel index along an axis of n texels for integer coordinate i under the wrap mode. */
static inline int wrap_texel(int i, int n, uint wrap) {
  if (wrap == PC_WRAP_CLAMP) return clamp(i, 0, n - 1);
  if (wrap == PC_WRAP_MIRROR) {
    int period = 2 * n;
    int m = ((i % period) + period) % period;
    return m < n ? m : period - 1 - m;
  }
  return ((i % n) + n) % n;
}

/* The linear RGB of texel (x, y); the conversions from bytes and halves are exact. */
static inline float3 texel_at(__global const uint* texels, Texture t, int x, int y) {
  uint i = (uint)y * t.width + (uint)x;
  __global const uint* image = texels + t.offset;
  if (t.format == PC_TEXELS_SRGB8) {
    uchar4 b = vload4(i, (__global const uchar*)image);
    return (float3)(pc_srgb_to_linear[b.x], pc_srgb_to_linear[b.y], pc_srgb_to_linear[b.z]);
  }
  if (t.format == PC_TEXELS_HALF) return vload_half3(i, (__global const half*)image);
#ifdef PC_HAS_CUTOUTS
  if (t.format == PC_TEXELS_OPACITY8_RED || t.format == PC_TEXELS_OPACITY8_ALPHA) {
    uchar byte = ((__global const uchar*)image)[4u * i + (t.format == PC_TEXELS_OPACITY8_ALPHA ? 3u : 0u)];
    return (float3)((float)byte / 255.0f);
  }
#endif
  return vload3(i, (__global const float*)image);
}

/* Bilinear interpolation at texel coordinates (x, y), texel centres at integers, columns wrapped by
 * wrap_x and rows by wrap_y. */
static inline float3 texture_bilinear(__global const uint* texels, Texture t, float x, float y, uint wrap_x, uint wrap_y) {
  /* Far outside the image the coordinates lose precision; keep them bounded. */
  x = clamp(x, -1.0e6f, 1.0e6f);
  y = clamp(y, -1.0e6f, 1.0e6f);
  float fx = floor(x), fy = floor(y);
  float ax = x - fx, ay = y - fy;
  int x0 = (int)fx, y0 = (int)fy;
  int w = (int)t.width, h = (int)t.height;
  int xa = wrap_texel(x0, w, wrap_x), xb = wrap_texel(x0 + 1, w, wrap_x);
  int ya = wrap_texel(y0, h, wrap_y), yb = wrap_texel(y0 + 1, h, wrap_y);
  return (1.0f - ay) * ((1.0f - ax) * texel_at(texels, t, xa, ya) + ax * texel_at(texels, t, xb, ya)) +
         ay * ((1.0f - ax) * texel_at(texels, t, xa, yb) + ax * texel_at(texels, t, xb, yb));
}

/* uv at barycentrics (u, v) of triangle prim (uvs: 2 per primitive, kernels/scene.cl). */
static inline float2 triangle_uv(__global const float4* uvs, uint prim, float u, float v) {
  float4 a = uvs[2 * prim], b = uvs[2 * prim + 1];
  return (1.0f - u - v) * a.xy + u * a.zw + v * b.xy;
}

/* A checkerboard (PC_TEXELS_CHECKER) at (u, v), evaluated at the point: with x = u tiles_u + offset_u and
 * y = (1 - v) tiles_v + offset_v (the axes of an image's columns and rows, so that row 0 is at the top),
 * color1 where floor(x) + floor(y) is odd, else color0. It is tested as Mitsuba's checkerboard tests its
 * (src/textures/checkerboard.cpp: frac(s) > 0.5 along each axis, s = x / 2), so that on a tile's edge the
 * same side wins; halving, floor and the subtraction are exact. */
static inline float3 checker_lookup(__global const uint* texels, Texture t, float2 uv) {
  __global const float* w = (__global const float*)(texels + t.offset);
  float2 s = 0.5f * ((float2)(uv.x, 1.0f - uv.y) * vload2(3, w) + vload2(4, w));
  int2 upper = isgreater(s - floor(s), (float2)(0.5f));
  return upper.x == upper.y ? vload3(0, w) : vload3(1, w);
}

/* Bilinear lookup at (u, v) under the texture's wrap mode; texel centres at half-integer coordinates. */
static inline float3 texture_lookup(__global const Texture* textures, __global const uint* texels, uint index, float2 uv) {
  Texture t = textures[index];
  if (t.format == PC_TEXELS_CHECKER) return checker_lookup(texels, t, uv);
  return texture_bilinear(texels, t, uv.x * (float)t.width - 0.5f, (1.0f - uv.y) * (float)t.height - 0.5f, t.wrap,
                          t.wrap);
}

#endif
