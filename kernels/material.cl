/* The material at a surface point, its colour texture looked up (path and light integrators). */
#ifndef PATHCL_MATERIAL_CL
#define PATHCL_MATERIAL_CL

#include "scene.cl"
#include "surface.cl"
#include "texture.cl"
#include "intersect.cl"

#ifdef PC_HAS_TEXTURES
/* Texture coordinates at a surface point. Triangles interpolate their corners' uvs. A sphere is mapped
 * lat-long in its own frame (x, y = the pole, z = handedness * cross(x, y): the rotation and mirroring
 * of its transform): with d the unit direction from the centre in that frame,
 *   u = phi / (2 pi), phi = atan2(-d.z, d.x) in [0, 2 pi),   v = 1 - theta / pi, theta = acos(d.y),
 * so v = 1 (the image's top row) is the +y pole, and u grows from +x towards -z: seen from outside
 * with y up, the image is not mirrored (u grows to the right). The environment map uses the mirror
 * image of this (phi = atan2(z, x)), as it is seen from inside. */
inline float2 surface_uv(const SceneData* sc, const Surface* s, const Hit* hit) {
#ifdef PC_HAS_SPHERES
  if (sc->shading[s->prim].kind == PC_PRIM_SPHERE) {
    float4 a = sc->uvs[2 * s->prim], b = sc->uvs[2 * s->prim + 1];
    float3 d = pc_normalize(s->p - sc->prims[hit->slot].a.xyz);
    float3 x = a.xyz, y = b.xyz, z = a.w * pc_cross(x, y);
    float dx = pc_dot(d, x), dy = pc_dot(d, y), dz = pc_dot(d, z);
    float u = pc_atan2(-dz, dx) * (0.5f * PC_INV_PI);
    if (u < 0.0f) u += 1.0f;
    return (float2)(u, 1.0f - pc_acos(clamp(dy, -1.0f, 1.0f)) * PC_INV_PI);
  }
#endif
  return triangle_uv(sc->uvs, s->prim, hit->u, hit->v);
}
#endif

/* The material at a surface point; a textured colour is the texture's value times the material's
 * colour (1 for textures from the scene file; MTL's Kd, possibly scaled down, for map_Kd). Vertex
 * colours, interpolated over the triangle, multiply it too (glTF's base colour = factor x texture x
 * COLOR_0); a sphere's are white. */
inline Material material_at(const SceneData* sc, uint material, const Surface* s, const Hit* hit) {
  Material m = sc->materials[material];
#ifdef PC_HAS_TEXTURES
  if (m.color_texture != PC_INVALID)
    m.color.xyz *= texture_lookup(sc->textures, sc->texels, m.color_texture, surface_uv(sc, s, hit));
#endif
#ifdef PC_HAS_VERTEX_COLORS
  if (sc->shading[s->prim].flags & PC_FLAG_VERTEX_COLORS) {
    __global const float4* c = sc->colors + 3 * s->prim;
    m.color.xyz *= ((1.0f - hit->u - hit->v) * c[0].xyz + hit->u * c[1].xyz) + hit->v * c[2].xyz;
  }
#endif
  return m;
}

#endif
