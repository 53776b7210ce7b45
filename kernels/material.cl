/* The material at a surface point, its colour texture looked up (path and light integrators). */
#ifndef PATHCL_MATERIAL_CL
#define PATHCL_MATERIAL_CL

#include "scene.cl"
#include "surface.cl"
#include "texture.cl"
#include "intersect.cl"
#include "bsdf.cl"

#ifdef PC_HAS_TEXTURES
/* Texture coordinates at a surface point. Triangles interpolate their corners' uvs. A sphere is mapped
 * lat-long in its own frame (x, y = the pole, z = handedness * cross(x, y): the rotation and mirroring
 * of its transform): with d the unit direction from the centre in that frame,
 *   u = phi / (2 pi), phi = atan2(-d.z, d.x) in [0, 2 pi),   v = 1 - theta / pi, theta = acos(d.y),
 * so v = 1 (the image's top row) is the +y pole, and u grows from +x towards -z: seen from outside
 * with y up, the image is not mirrored (u grows to the right). The environment map uses the mirror
 * image of this (phi = atan2(z, x)), as it is seen from inside. */
static inline float2 surface_uv(const SceneData* sc, const Surface* s, const Hit* hit) {
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

/* The material at the surface points of the lanes in m (the others get the first such lane's; kernels/
 * lanes.cl; MaterialLanes: kernels/bsdf.cl); a textured colour is the texture's value times the material's
 * colour (1 for textures from the scene file; MTL's Kd, possibly scaled down, for map_Kd). Vertex colours,
 * interpolated over the triangle, multiply it too (glTF's base colour = factor x texture x COLOR_0); a
 * sphere's are white. */
/* materials[material] of the lanes in m into *out, its colour the table's (the others get the first such
 * lane's); *at the lanes' groups of materials, for more fields. (Through pointers: surface.cl's
 * spawn_ray_lanes says why.) */
PC_LANE_INLINE void material_lanes_gather(const SceneData* sc, LaneU material, LaneI m, LaneGroups* at, MaterialLanes* out) {
  lane_groups(material, m, at); /* a scene has few materials */
  __global const Material* all = sc->materials;
  out->type = lane_group_gather_uint(PC_FIELD_U(all, type), at);
  out->color = lane_group_gather3(PC_FIELD_F(all, color), at);
  /* Only the fields that the program's material types read (material_at_lanes is out of line, so the
   * compiler cannot drop the others); the rest are 0. */
  Lane3 zero3 = lane3_splat((float3)(0.0f));
  out->specular = out->k = zero3;
  out->alpha = out->sigma = out->exponent = out->ior = (LaneF)(0.0f);
#if defined(PC_HAS_PHONG) || defined(PC_HAS_MIRROR) || defined(PC_HAS_ROUGH_CONDUCTOR)
  out->specular = lane_group_gather3(PC_FIELD_F(all, specular), at);
#endif
#if defined(PC_HAS_MIRROR) || defined(PC_HAS_ROUGH_CONDUCTOR)
  out->k = lane_group_gather3(PC_FIELD_F(all, k), at);
#endif
#if defined(PC_HAS_ROUGH_CONDUCTOR) || defined(PC_HAS_PLASTIC)
  out->alpha = lane_group_gather_float(PC_FIELD_F(all, alpha), at);
#endif
#ifdef PC_HAS_OREN_NAYAR
  out->sigma = lane_group_gather_float(PC_FIELD_F(all, sigma), at);
#endif
#ifdef PC_HAS_PHONG
  out->exponent = lane_group_gather_float(PC_FIELD_F(all, exponent), at);
#endif
#if defined(PC_HAS_DIELECTRIC) || defined(PC_HAS_PLASTIC)
  out->ior = lane_group_gather_float(PC_FIELD_F(all, ior), at);
#endif
}

PC_OUT_OF_LINE MaterialLanes material_at_lanes(const SceneData* sc, LaneU material, const SurfaceLanes* s,
                                               const ShadingLanes* shading, const HitLanes* hit, LaneI m) {
  LaneGroups at;
  MaterialLanes out;
  material_lanes_gather(sc, material, m, &at, &out);
#ifdef PC_HAS_TEXTURES
  LaneU texture = lane_group_gather_uint(PC_FIELD_U(sc->materials, color_texture), &at);
  LaneI textured = m & (texture != PC_INVALID);
  PC_EACH_LANE(j, pc_lane_bits(textured)) {
    Surface one;
    one.p = lane3_at(s->p, j);
    one.prim = pc_lane(s->prim, j);
    Hit h;
    h.slot = pc_lane(hit->slot, j);
    h.u = pc_lane(hit->u, j);
    h.v = pc_lane(hit->v, j);
    float3 color =
        lane3_at(out.color, j) * texture_lookup(sc->textures, sc->texels, pc_lane(texture, j), surface_uv(sc, &one, &h));
    out.color = lane3_with(out.color, j, color);
  }
#endif
#ifdef PC_HAS_VERTEX_COLORS
  LaneI colored = m & ((shading->flags & PC_FLAG_VERTEX_COLORS) != 0u);
  if (pc_any_(colored)) {
    Lane3 blend = vertex_blend_lanes(sc->colors, lane_safe_index(s->prim, colored), 1.0f - hit->u - hit->v, hit->u,
                                     hit->v);
    out.color = lane3_select(out.color, lane3_mul(out.color, blend), colored);
  }
#endif
  return out;
}

#if PC_LANES == 1
/* material_at_lanes for one surface point: the material with its colour looked up. */
static inline Material material_at(const SceneData* sc, uint material, const Surface* s, const Hit* hit) {
  ShadingLanes shading;
  shading.material = material;
  shading.flags = sc->shading[s->prim].flags;
  shading.light = sc->shading[s->prim].light;
  Material m = sc->materials[material];
  m.color.xyz = material_at_lanes(sc, material, s, &shading, hit, 1).color;
  return m;
}
#endif

#endif
