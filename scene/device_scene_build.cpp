#include "scene/device_scene_build.h"

#include <algorithm>
#include <chrono>
#include <array>
#include <cfloat>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <stdexcept>
#include <string>

#include <glm/geometric.hpp>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/quaternion.hpp>
#include <glm/matrix.hpp>
#include <glm/trigonometric.hpp>

#include "scene/bvh_build.h"
#include "scene/environment_distribution.h"
#include "scene/light_bvh_build.h"
#include "scene/scene_error.h"

namespace {

pc_float4 f4(const glm::vec3& v, float w = 0) { return {v.x, v.y, v.z, w}; }
float bits_to_float(uint32_t u) {
  float f;
  std::memcpy(&f, &u, 4);
  return f;
}
// In double: an emission of 1e-45 in blue alone still has a (tiny) positive power.
double luminance(const glm::vec3& c) { return 0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z; }

constexpr uint32_t kMaterialFeature[] = {kFeatureDiffuse, kFeatureOrenNayar, kFeaturePhong, kFeatureMirror,
                                         kFeatureDielectric, kFeatureRoughConductor, kFeaturePlastic,
                                         kFeatureDielectric};  // by PC_MAT_*

Material device_material(const MaterialDesc& m) {
  Material mat{};
  mat.color = f4(m.color);
  mat.specular = f4(m.specular);
  mat.k = f4(m.k);
  mat.type = m.type_id;
  mat.color_texture = m.color_texture;
  mat.alpha = m.alpha;
  mat.sigma = m.sigma;
  mat.exponent = m.exponent;
  mat.ior = m.ior;
  mat.opacity = m.opacity;
  mat.opacity_texture = PC_INVALID;  // set with the opacity maps' texture entries
  return mat;
}

bool is_cutout(const MaterialDesc& m) { return m.opacity < 1 || m.opacity_texture != PC_INVALID; }

// The texel format an image is read in as an opacity map: an 8-bit image's alpha when it is not all
// opaque, else its red channel (a grey map), both linear; half and float images as they are (red).
uint32_t opacity_format(const TextureImage& t) {
  if (t.format != PC_TEXELS_SRGB8) return t.format;
  for (uint32_t w : t.words)
    if ((w >> 24) != 255u) return PC_TEXELS_OPACITY8_ALPHA;
  return PC_TEXELS_OPACITY8_RED;
}

// An environment's rotation as kernels/environment.cl takes it: the unit quaternion (x, y, z, w), or all
// 0 for none (the identity), which leaves the map's lookups as they were bit for bit.
pc_float4 environment_rotation(const glm::dmat3& rotation) {
  if (rotation == glm::dmat3(1.0)) return pc_float4{};
  glm::dquat q = glm::normalize(glm::quat_cast(rotation));
  return f4(glm::vec3(q.x, q.y, q.z), float(q.w));
}

SceneHeader camera_header(const CameraDesc& c, const glm::dvec3& origin) {
  SceneHeader h{};
  glm::dvec3 forward = glm::normalize(c.look_at - c.position);
  glm::dvec3 right = glm::normalize(glm::cross(forward, c.up));
  glm::dvec3 up = glm::cross(right, forward);
  if (c.left_handed) right = -right;  // the mirrored image of a left-handed camera frame
  double tan_half = std::tan(glm::radians(double(c.fov_y_degrees)) * 0.5);
  double aspect = double(c.width) / double(c.height);
  h.cam_position = f4(glm::vec3(c.position - origin));  // 0 for DeviceOrigin::camera
  h.cam_right = f4(glm::vec3(right * tan_half * aspect));
  h.cam_up = f4(glm::vec3(up * tan_half));
  h.cam_forward = f4(glm::vec3(forward));
  h.width = c.width;
  h.height = c.height;
  h.lens_radius = c.aperture_radius;
  h.focus_distance = c.focus_distance;
  h.filter = c.filter;
  h.filter_radius = c.filter == PC_FILTER_BOX ? 0.5f : c.filter_radius;
  h.filter_sigma = c.filter_sigma;
  h.env_light = PC_INVALID;
  return h;
}

}  // namespace


Primitive scene_primitive(const DeviceScene& scene, uint32_t prim_index) {
  return scene.prims[scene.leaf_slot[prim_index]];
}

namespace {

// Where a BVH appended to the device scene starts, and what it bounds.
struct TreeRoots {
  uint32_t root4 = 0, root8 = 0, root16 = 0;  // root node in nodes, word offsets of the root in bvh8, bvh16
  Aabb box;                        // of its primitives, in the coordinates they are stored in
};

// Builds the BVH over prims[first, end) (in scene order; boxes alike) and appends it to out: those
// primitives in its leaf order (out.prims must hold exactly `first` of them before), their leaf slots,
// the 4-, 8- and 16-wide nodes of out.bvh_layouts after out's with references offset, and their leaf blocks.
TreeRoots append_tree(DeviceScene& out, const std::vector<Primitive>& prims, const std::vector<Aabb>& boxes, uint32_t first,
                      uint32_t end, BvhStats* stats) {
  Bvh bvh = build_bvh(std::vector<Aabb>(boxes.begin() + first, boxes.begin() + end));
  auto collapse_start = std::chrono::steady_clock::now();
  const uint32_t layouts = out.bvh_layouts;
  Bvh4 wide = layouts & kBvhLayout4 ? collapse_to_bvh4(bvh.nodes) : Bvh4{};
  Bvh8 wide8 = layouts & kBvhLayout8 ? collapse_to_bvh8(bvh.nodes) : Bvh8{};
  Bvh16 wide16 = layouts & kBvhLayout16 ? collapse_to_bvh16(bvh.nodes) : Bvh16{};
  bvh.build_ms += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - collapse_start).count();
  bvh.node_count = uint32_t(bvh.nodes.size());
  *stats = bvh;
  for (uint32_t slot = 0; slot < end - first; ++slot) {
    out.prims.push_back(prims[first + bvh.prim_order[slot]]);
    out.leaf_slot[first + bvh.prim_order[slot]] = first + slot;
  }
  TreeRoots roots;
  roots.root4 = uint32_t(out.nodes.size());
  const BvhNode& top = bvh.nodes[0];
  roots.box = {{top.lo[0], top.lo[1], top.lo[2]}, {top.hi[0], top.hi[1], top.hi[2]}};
  // Interior references by the node offset, leaf references (primitive slots) by `first`.
  auto offset = [](pc_uint& ref, uint32_t nodes, uint32_t slots) {
    if (ref == PC_INVALID) return;
    if (ref & PC_BVH4_LEAF)
      ref = PC_LEAF_REF(PC_LEAF_FIRST(ref) + slots, PC_LEAF_COUNT(ref));
    else
      ref += nodes;
  };
  for (Bvh4Node& n : wide.nodes)
    for (pc_uint& ref : n.child) offset(ref, roots.root4, first);
  // Leaf slots as in out.prims; append_wide_bvh places the rest.
  auto offset_leaves = [&](auto& nodes) {
    for (auto& n : nodes)
      for (pc_uint& ref : n.child)
        if (ref != PC_INVALID && (ref & PC_BVH4_LEAF)) offset(ref, 0, first);
  };
  offset_leaves(wide8.nodes);
  offset_leaves(wide16.nodes);
  out.nodes.insert(out.nodes.end(), wide.nodes.begin(), wide.nodes.end());
  if (layouts & kBvhLayout8) roots.root8 = append_wide_bvh(wide8.nodes, out.prims, out.bvh8);
  if (layouts & kBvhLayout16) roots.root16 = append_wide_bvh(wide16.nodes, out.prims, out.bvh16);
  out.wide8_nodes += uint32_t(wide8.nodes.size());
  out.wide16_nodes += uint32_t(wide16.nodes.size());
  out.wide_depth = std::max(out.wide_depth, wide.depth);
  out.wide8_depth = std::max(out.wide8_depth, wide8.depth);
  out.wide16_depth = std::max(out.wide16_depth, wide16.depth);
  return roots;
}

// An affine transform's three rows (x, y, z, translation) as floats.
void set_rows(pc_float4 (&rows)[3], const glm::dmat4& m) {
  for (int i = 0; i < 3; ++i) rows[i] = {float(m[0][i]), float(m[1][i]), float(m[2][i]), float(m[3][i])};
}

Instance instance_of_transform(const glm::dmat4& to_device, const TreeRoots& tree) {
  Instance inst{};
  set_rows(inst.to_device, to_device);
  set_rows(inst.to_mesh, glm::inverse(to_device));
  inst.root4 = tree.root4;
  inst.root8 = tree.root8;
  inst.root16 = tree.root16;
  return inst;
}

// A mesh box placed by a transform: the box of its eight corners, widened so that the float rounding of
// the ray's transform into the mesh's coordinates (kernels/intersect.cl) can never miss what the mesh's
// own BVH would hit.
Aabb placed_box(const Aabb& box, const glm::dmat4& m) {
  glm::dvec3 lo(INFINITY), hi(-INFINITY);
  for (int corner = 0; corner < 8; ++corner) {
    glm::dvec3 c(corner & 1 ? box.hi.x : box.lo.x, corner & 2 ? box.hi.y : box.lo.y, corner & 4 ? box.hi.z : box.lo.z);
    glm::dvec3 p(m * glm::dvec4(c, 1.0));
    lo = glm::min(lo, p);
    hi = glm::max(hi, p);
  }
  glm::dvec3 margin = 1e-5 * (glm::abs(lo) + glm::abs(hi) + (hi - lo));
  return {glm::vec3(lo - margin), glm::vec3(hi + margin)};
}

// Emitter groups (scene/light_bvh_build.h): the emitting triangles of a shape, when they are in one plane and of
// one emission and sidedness, and either at most kMaxEmitterGroup (a quad lamp, a small polygon) or within a
// box of at most a quarter of the scene's diagonal (a disk lamp, which the Mitsuba and pbrt importers make of 256
// or more triangles), are one leaf of the light BVH, their triangles chosen in proportion to their areas. The
// tree's importance would tell them apart by little over so small a planar piece, and such a lamp no longer
// costs a walk of the tree at every choice (the Cornell box's samples 1.14x faster, docs/benchmarks-notes.md);
// a large panel of many triangles keeps the tree, which samples its near part more. Grouping only changes which
// light is chosen with what probability, never the estimate's mean. lights[0, area_lights) are the area
// lights, bounds theirs (boxes of their primitives), scene the scene's box: marks bounds[i].with_previous and
// sets each one's group_share and group_cdf (1 alone).
constexpr size_t kMaxEmitterGroup = 8;
void group_emitters(const std::vector<Primitive>& prims, const std::vector<PrimShading>& shading,
                    const std::vector<uint32_t>& prim_shapes, const Aabb& scene, size_t area_lights,
                    std::vector<Light>& lights, std::vector<LightBounds>& bounds) {
  auto vertex = [&](uint32_t prim, int k) {
    const pc_float4& v = k == 0 ? prims[prim].a : k == 1 ? prims[prim].b : prims[prim].c;
    return glm::dvec3(v.x, v.y, v.z);
  };
  const double scene_diagonal = glm::length(glm::dvec3(scene.hi) - glm::dvec3(scene.lo));
  for (size_t begin = 0, end = 0; begin < area_lights; begin = end) {
    const uint32_t shape = prim_shapes[lights[begin].prim];
    for (end = begin + 1; end < area_lights && prim_shapes[lights[end].prim] == shape;) ++end;
    Aabb box;
    for (size_t i = begin; i < end; ++i) box.grow(Aabb{bounds[i].lo, bounds[i].hi});
    const double diagonal = glm::length(glm::dvec3(box.hi) - glm::dvec3(box.lo));
    bool group = shape != PC_INVALID && end - begin >= 2 &&
                 (end - begin <= kMaxEmitterGroup || diagonal <= 0.25 * scene_diagonal);
    const glm::dvec3 normal(bounds[begin].axis);
    const double offset = glm::dot(normal, vertex(lights[begin].prim, 0)), tolerance = 1e-5 * diagonal;
    double area = 0;
    for (size_t i = begin; i < end && group; ++i) {
      const Light &l = lights[i], &first = lights[begin];
      group = shading[l.prim].kind == PC_PRIM_TRIANGLE && l.emission.x == first.emission.x &&
              l.emission.y == first.emission.y && l.emission.z == first.emission.z &&
              bounds[i].two_sided == bounds[begin].two_sided &&
              glm::dot(glm::dvec3(bounds[i].axis), normal) >= 1 - 1e-6;
      for (int k = 0; k < 3; ++k) group = group && std::abs(glm::dot(normal, vertex(l.prim, k)) - offset) <= tolerance;
      area += l.area;
    }
    double running = 0;
    for (size_t i = begin; i < end; ++i) {
      bounds[i].with_previous = group && i > begin;
      running += lights[i].area;
      lights[i].group_share = group ? float(lights[i].area / area) : 1.0f;
      lights[i].group_cdf = group && i + 1 < end ? float(running / area) : 1.0f;
    }
  }
}

}  // namespace

// Everything but the texel words (DeviceScene::texels), which the two public functions below copy or move.
static DeviceScene build_device_scene_without_texels(const SceneDescription& scene, DeviceOrigin origin,
                                                     Instancing instancing, uint32_t layouts) {
  if ((layouts & kBvhLayoutsAll) == 0 || (layouts & ~kBvhLayoutsAll) != 0)
    throw std::logic_error("build_device_scene: layouts " + std::to_string(layouts) + " (expected kBvhLayout4, 8, 16)");
  DeviceScene out;
  out.bvh_layouts = layouts;
  out.origin = origin == DeviceOrigin::camera ? scene.camera.position : glm::dvec3(0);
  out.header = camera_header(scene.camera, out.origin);
  if (scene.camera.aimed) out.view_distance = glm::length(scene.camera.look_at - scene.camera.position);
  // World (double) to device (float) coordinates: the subtraction first, in double, then the rounding.
  // Geometry farther than kMaxSceneExtent would overflow squared distances on the device.
  auto to_device = [&](const ShapeDesc& s, const glm::dvec3& world, double radius = 0) {
    glm::dvec3 d = world - out.origin;
    double reach = std::max({std::abs(d.x), std::abs(d.y), std::abs(d.z)}) + radius;
    if (!(reach <= kMaxSceneExtent)) {
      char what[200];
      std::snprintf(what, sizeof what, ": geometry reaches %g from the %s, beyond the largest distance of %g",
                    reach, origin == DeviceOrigin::camera ? "camera" : "origin", kMaxSceneExtent);
      throw SceneError(scene.path + ": " + s.label + what + " (squared distances would overflow float)");
    }
    return glm::vec3(d);
  };
  for (const MaterialDesc& m : scene.materials) {
    out.materials.push_back(device_material(m));
    out.features |= kMaterialFeature[m.type_id];
    if (m.color_texture != PC_INVALID) out.features |= kFeatureTextures;
  }
  // The texel words themselves are appended by the callers (build_device_scene copies them,
  // build_device_scene_taking_texels moves them).
  uint64_t texel_words = 0;
  std::vector<uint32_t> offsets;
  for (const TextureImage& t : scene.textures) {
    offsets.push_back(uint32_t(texel_words));
    out.textures.push_back({t.width, t.height, uint32_t(texel_words), t.wrap, t.format, {}});
    texel_words += t.words.size();
  }
  // Opacity maps: texture entries of their own over the same texel words, read as opacity.
  for (size_t i = 0; i < scene.materials.size(); ++i) {
    const MaterialDesc& m = scene.materials[i];
    if (is_cutout(m)) out.features |= kFeatureCutouts;
    if (m.opacity_texture == PC_INVALID) continue;
    const TextureImage& t = scene.textures[m.opacity_texture];
    out.materials[i].opacity_texture = uint32_t(out.textures.size());
    out.textures.push_back({t.width, t.height, offsets[m.opacity_texture], t.wrap, opacity_format(t), {}});
    out.features |= kFeatureTextures;  // the uvs
  }

  // Primitives in scene order, with their boxes and (for emitters) light candidates.
  std::vector<Primitive> prims;
  std::vector<Aabb> boxes;
  struct Emitter { uint32_t prim; glm::vec3 emission; double area; bool two_sided; };
  std::vector<Emitter> emitters;
  const bool textures = out.features & kFeatureTextures;
  // A mesh's triangles (positions: its vertices in the coordinates they are stored in, device or the
  // instanced mesh's own), in mesh order, with their shading, uvs, normals and emitters.
  // shape: the index of the shape in scene.shapes (PC_INVALID for an instanced mesh's triangles).
  auto add_triangles = [&](const ShapeDesc& s, uint32_t shape, const TriangleMesh& mesh,
                           const std::vector<glm::vec3>& positions, const std::vector<uint32_t>& triangle_materials) {
    uint32_t flags = s.two_sided ? PC_FLAG_TWO_SIDED : 0;
    auto material_of = [&](size_t t) { return triangle_materials.empty() ? s.material : triangle_materials[t]; };
    const bool has_normals = !mesh.normals.empty();
    for (size_t ti = 0; ti < mesh.triangles.size(); ++ti) {
      const auto& t = mesh.triangles[ti];
      glm::vec3 emission = triangle_emission(s, ti);
      bool emits = emission.x > 0 || emission.y > 0 || emission.z > 0;
      if (emits && is_cutout(scene.materials[material_of(ti)]))
        throw SceneError(scene.path + ": " + s.label + ": an emitter cannot be a cut-out (material \"" +
                         scene.materials[material_of(ti)].name + "\" has an opacity)");
      uint32_t index = uint32_t(prims.size());
      glm::vec3 a = positions[t[0]], b = positions[t[1]], c = positions[t[2]];
      prims.push_back({f4(a, bits_to_float(index)), f4(b, bits_to_float(PC_PRIM_TRIANGLE)), f4(c)});
      out.prim_shapes.push_back(shape);
      Aabb box;
      box.grow(a);
      box.grow(b);
      box.grow(c);
      boxes.push_back(box);
      // Flat unless some corner has a shading normal (from the file or generated).
      bool smooth = false;
      if (has_normals)
        for (const glm::vec3& n : mesh.normals[ti]) smooth = smooth || glm::dot(n, n) > 0;
      if (smooth) out.features |= kFeatureSmoothNormals;
      const uint32_t colored = mesh.colors.empty() ? 0 : PC_FLAG_VERTEX_COLORS;
      out.shading.push_back(
          {material_of(ti), PC_INVALID, flags | (smooth ? PC_FLAG_SMOOTH : 0) | colored, PC_PRIM_TRIANGLE});
      if (textures) {
        // (u0, v0, u1, v1), (u2, v2, 0, 0); a mesh without uvs has no textured material (scene_load.cpp).
        std::array<glm::vec2, 3> uv{};
        if (!mesh.uvs.empty()) uv = mesh.uvs[ti];
        out.uvs.push_back({uv[0].x, uv[0].y, uv[1].x, uv[1].y});
        out.uvs.push_back({uv[2].x, uv[2].y, 0, 0});
      }
      if (mesh.colors.empty()) {
        out.colors.insert(out.colors.end(), 3, pc_float4{1, 1, 1, 1});
      } else {
        for (const glm::vec3& c : mesh.colors[ti]) out.colors.push_back(f4(c, 1.0f));
        out.features |= kFeatureVertexColors;
      }
      if (smooth) {
        // A corner without a normal (zero: a zero normal in the file, or generated normals that cancel,
        // as on a mesh folded flat) takes this face's geometric normal.
        const glm::dvec3 &wa = mesh.positions[t[0]], &wb = mesh.positions[t[1]], &wc = mesh.positions[t[2]];
        glm::dvec3 face = glm::cross(wb - wa, wc - wa);
        double face_length = glm::length(face);
        glm::vec3 fallback = face_length > 0 ? glm::vec3(face / face_length) : glm::vec3(0);
        for (int k = 0; k < 3; ++k) {
          const glm::vec3& n = mesh.normals[ti][k];
          out.normals.push_back(f4(glm::dot(n, n) > 0 ? n : fallback));
        }
      } else {
        out.normals.insert(out.normals.end(), 3, pc_float4{0, 0, 0, 0});
      }
      // The area of the float triangle the device samples (computed in double from its vertices).
      double area = 0.5 * glm::length(glm::cross(glm::dvec3(b) - glm::dvec3(a), glm::dvec3(c) - glm::dvec3(a)));
      if (emits) {
        if (float(area) > 0)
          emitters.push_back({index, emission, area, s.two_sided});
        else
          out.skipped_zero_area_emitters++;
      }
      out.triangle_count++;
      out.features |= kFeatureTriangles;
    }
  };
  std::vector<const ShapeDesc*> placements;  // instances, kept as such
  std::vector<ShapeDesc> flattened;          // instances flattened (Instancing::flatten)
  if (instancing == Instancing::flatten)
    for (const ShapeDesc& s : scene.shapes)
      if (s.instance_of != PC_INVALID) flattened.push_back(flattened_shape(scene, s));
  size_t next_flattened = 0;
  for (const ShapeDesc& placed : scene.shapes) {
    if (placed.instance_of != PC_INVALID && instancing == Instancing::keep) {
      placements.push_back(&placed);
      continue;
    }
    const ShapeDesc& s = placed.instance_of == PC_INVALID ? placed : flattened[next_flattened++];
    const uint32_t shape = uint32_t(&placed - scene.shapes.data());
    uint32_t flags = (s.two_sided ? PC_FLAG_TWO_SIDED : 0) | (s.flip_normals ? PC_FLAG_FLIP_NORMAL : 0);
    if (s.is_sphere) {
      bool emits = s.emission.x > 0 || s.emission.y > 0 || s.emission.z > 0;
      const MaterialDesc& m = scene.materials[s.material];
      if (m.opacity_texture != PC_INVALID)
        throw SceneError(scene.path + ": " + s.label + ": material \"" + m.name +
                         "\" has an opacity texture, which spheres do not take (a constant opacity they do)");
      if (emits && is_cutout(m))
        throw SceneError(scene.path + ": " + s.label + ": an emitter cannot be a cut-out (material \"" + m.name +
                         "\" has an opacity)");
      uint32_t index = uint32_t(prims.size());
      glm::vec3 center = to_device(s, s.center, s.radius);
      float radius = float(s.radius);
      prims.push_back({f4(center, bits_to_float(index)), {radius, 0, 0, bits_to_float(PC_PRIM_SPHERE)}, {}});
      out.prim_shapes.push_back(shape);
      boxes.push_back({center - glm::vec3(radius), center + glm::vec3(radius)});
      out.shading.push_back({s.material, PC_INVALID, flags, PC_PRIM_SPHERE});
      out.normals.insert(out.normals.end(), 3, pc_float4{0, 0, 0, 0});  // 3 per primitive, as for triangles
      out.colors.insert(out.colors.end(), 3, pc_float4{1, 1, 1, 1});
      if (textures) {
        // The sphere's own frame for its lat-long uvs (kernels/integrator.cl, surface_uv): x axis and
        // handedness, y axis (the pole).
        float handedness = glm::determinant(s.frame) < 0 ? -1.0f : 1.0f;
        out.uvs.push_back(f4(s.frame[0], handedness));
        out.uvs.push_back(f4(s.frame[1]));
      }
      // The area of the float sphere the device samples; 0 for a radius below about 1e-23.
      double area = 4 * M_PI * double(radius) * double(radius);
      if (emits) {
        if (float(area) > 0)
          emitters.push_back({index, s.emission, area, s.two_sided});
        else
          out.skipped_zero_area_emitters++;
      }
      out.sphere_count++;
      out.features |= kFeatureSpheres;
      continue;
    }
    std::vector<glm::vec3> positions;
    positions.reserve(s.mesh.positions.size());
    for (const glm::dvec3& p : s.mesh.positions) positions.push_back(to_device(s, p));
    add_triangles(s, shape, s.mesh, positions, s.triangle_materials);
  }
  const uint32_t world_prims = uint32_t(prims.size());
  // Each instanced mesh that a shape places: its triangles once, in the mesh's own coordinates.
  std::vector<uint32_t> mesh_first(scene.instanced_meshes.size(), PC_INVALID);
  std::vector<uint32_t> mesh_used;
  for (const ShapeDesc* p : placements) {
    if (mesh_first[p->instance_of] != PC_INVALID) continue;
    const InstancedMesh& m = scene.instanced_meshes[p->instance_of];
    mesh_first[p->instance_of] = uint32_t(prims.size());
    mesh_used.push_back(p->instance_of);
    std::vector<glm::vec3> positions(m.mesh.positions.begin(), m.mesh.positions.end());
    add_triangles(*p, PC_INVALID, m.mesh, positions, m.triangle_materials);
  }
  if (!(out.features & kFeatureSmoothNormals)) out.normals.clear();
  if (!(out.features & kFeatureVertexColors)) out.colors.clear();

  if (boxes.size() >= PC_BVH4_MAX_LEAF_FIRST)
    throw SceneError(scene.path + ": " + std::to_string(boxes.size()) + " primitives; at most " +
                     std::to_string(PC_BVH4_MAX_LEAF_FIRST - 1) + " are supported");
  // One BVH over the rest of the scene, then one per instanced mesh, each over its range of primitives.
  out.leaf_slot.resize(prims.size());
  out.prims.reserve(prims.size());
  TreeRoots world = append_tree(out, prims, boxes, 0, world_prims, &out.bvh);
  std::vector<TreeRoots> mesh_tree(scene.instanced_meshes.size());
  for (size_t i = 0; i < mesh_used.size(); ++i) {
    uint32_t m = mesh_used[i];
    uint32_t end = i + 1 < mesh_used.size() ? mesh_first[mesh_used[i + 1]] : uint32_t(prims.size());
    BvhStats stats;
    mesh_tree[m] = append_tree(out, prims, boxes, mesh_first[m], end, &stats);
    out.bvh.build_ms += stats.build_ms;
  }
  // The instances: the rest of the scene (untransformed), then each placement, in the order of the
  // instance BVH's leaves.
  std::vector<Instance> items;
  std::vector<Aabb> item_boxes;
  std::vector<uint32_t> item_shapes;
  if (world_prims > 0) {
    Instance world_instance{};
    world_instance.root4 = world.root4;
    world_instance.root8 = world.root8;
    world_instance.root16 = world.root16;
    world_instance.flags = PC_INSTANCE_IDENTITY;
    items.push_back(world_instance);
    item_boxes.push_back(world.box);
    item_shapes.push_back(PC_INVALID);
  }
  for (const ShapeDesc* p : placements) {
    const TreeRoots& tree = mesh_tree[p->instance_of];
    if (scene.instanced_meshes[p->instance_of].mesh.triangles.empty()) continue;  // nothing to place
    glm::dmat4 to_device = glm::translate(glm::dmat4(1.0), -out.origin) * p->transform;
    items.push_back(instance_of_transform(to_device, tree));
    item_shapes.push_back(uint32_t(p - scene.shapes.data()));
    item_boxes.push_back(placed_box(tree.box, to_device));
    out.instance_count++;
    out.instanced_triangle_count += scene.instanced_meshes[p->instance_of].mesh.triangles.size();
  }
  if (out.instance_count > 0) out.features |= kFeatureInstances;
  Bvh instance_bvh = build_bvh(item_boxes);
  out.instance_bvh = std::move(instance_bvh.nodes);
  for (uint32_t slot : instance_bvh.prim_order) {
    out.instances.push_back(items[slot]);
    out.instance_shapes.push_back(item_shapes[slot]);
  }
  // Every light: area lights first, in primitive order, then point and spot lights, then the lights at
  // infinity (directional, environment). The first two kinds go into the light BVH with their bounds.
  std::vector<LightBounds> bounds;
  for (const Emitter& e : emitters) {
    Light light{};
    light.type = PC_LIGHT_AREA;
    light.emission = f4(e.emission);
    light.prim = e.prim;
    light.area = float(e.area);
    out.shading[e.prim].light = uint32_t(out.lights.size());
    out.lights.push_back(light);
    const Primitive& p = prims[e.prim];
    LightBounds b;
    b.lo = boxes[e.prim].lo;
    b.hi = boxes[e.prim].hi;
    b.two_sided = e.two_sided;
    if (out.shading[e.prim].kind == PC_PRIM_SPHERE) {
      b.intensity = luminance(e.emission) * e.area / 4;  // L x pi r^2, the projected area in every direction
      b.theta_o = M_PI;
      b.theta_e = M_PI / 2;
    } else {
      // The normal the device computes (kernels/surface.cl: triangle_normal); emission on its side.
      glm::dvec3 pa(p.a.x, p.a.y, p.a.z), pb(p.b.x, p.b.y, p.b.z), pc(p.c.x, p.c.y, p.c.z);
      b.axis = glm::vec3(glm::normalize(glm::cross(pb - pa, pc - pa)));
      b.intensity = luminance(e.emission) * e.area;  // L x area, along the normal
      b.theta_o = 0;
      b.theta_e = M_PI / 2;
    }
    bounds.push_back(b);
  }
  // Point and spot lights, then the lights at infinity with their irradiance estimates: a directional
  // light's irradiance on a surface facing it, and a quarter of the environment's radiance integrated over
  // the sphere (its irradiance averaged over the orientations of a surface: pi L for a constant L).
  std::vector<double> infinite_irradiance;
  for (int pass = 0; pass < 2; ++pass)
    for (const LightDesc& l : scene.lights) {
      bool infinite = l.type == PC_LIGHT_DIRECTIONAL || l.type == PC_LIGHT_ENVIRONMENT;
      if (infinite != (pass == 1)) continue;
      Light light{};
      light.type = l.type;
      light.emission = f4(l.emission);
      const bool environment = l.type == PC_LIGHT_ENVIRONMENT;
      // Point and spot lights camera-relative, like the geometry; an environment's rotation in its place.
      light.position = environment ? environment_rotation(l.rotation) : f4(glm::vec3(l.position - out.origin));
      light.direction = f4(l.direction);
      light.prim = PC_INVALID;
      // An environment map's parameterisation in its slot (it has no primitive): PC_ENV_LAT_LONG is
      // PC_INVALID, so a lat-long map's light is as it was.
      light.slot = environment && l.texture != PC_INVALID ? l.mapping : PC_INVALID;
      light.cos_inner = l.cos_inner;
      light.cos_outer = l.cos_outer;
      light.texture = l.texture;
      double lum = luminance(l.emission), e = 0;
      uint32_t features = 0;
      LightBounds b;
      b.lo = b.hi = glm::vec3(light.position.x, light.position.y, light.position.z);
      b.intensity = lum;
      b.theta_e = M_PI / 2;
      if (l.type == PC_LIGHT_POINT) {
        b.theta_o = M_PI;
        features = kFeaturePointLights;
      } else if (l.type == PC_LIGHT_SPOT) {
        // Nothing outside the outer cone; widened a little so that rounding never cuts off its edge.
        b.axis = l.direction;
        b.theta_o = std::min(M_PI, std::acos(std::clamp(double(l.cos_outer), -1.0, 1.0)) + 1e-3);
        b.theta_e = 0;
        features = kFeaturePointLights;
      } else if (l.type == PC_LIGHT_DIRECTIONAL) {
        e = lum;
        features = kFeatureDirectionalLights;
      } else if (l.type == PC_LIGHT_ENVIRONMENT) {
        double integral = 4 * M_PI;  // of the radiance (times emission) over the sphere
        features = kFeatureEnvironment;
        if (l.texture != PC_INVALID) {
          integral = build_env_distribution(scene.textures[l.texture], out.env_dist, l.mapping);
          features |= kFeatureEnvironmentMap;
        }
        e = 0.25 * lum * integral;
        if (e > 0) out.header.env_light = uint32_t(out.lights.size());
      }
      if (!((infinite ? e : b.intensity) > 0)) continue;  // emits nothing: never chosen, never seen, no code for it
      out.features |= features;
      out.lights.push_back(light);
      if (infinite)
        infinite_irradiance.push_back(e);
      else
        bounds.push_back(b);
    }
  Aabb scene_box;  // the instance BVH's items: the world's primitives and every placement, in device coordinates
  for (const Aabb& b : item_boxes) scene_box.grow(b);
  group_emitters(prims, out.shading, out.prim_shapes, scene_box, emitters.size(), out.lights, bounds);
  for (size_t i = emitters.size(); i < bounds.size(); ++i) out.lights[i].group_share = out.lights[i].group_cdf = 1.0f;
  out.header.tree_light_count = uint32_t(bounds.size());
  LightBvh tree = build_light_bvh(bounds);
  out.light_bvh = std::move(tree.nodes);
  for (size_t i = 0; i < bounds.size(); ++i) out.lights[i].tree_leaf = tree.leaf_of[i];
  // The lights at infinity among themselves in proportion to irradiance: a choice that no scene size
  // enters (kernels/light_tree.cl weighs them against the tree from each shading point).
  double total = 0;
  for (double e : infinite_irradiance) total += e;
  out.header.infinite_irradiance = float(std::min(total, double(FLT_MAX)));
  out.light_cdf.push_back(0);
  double running = 0;
  for (size_t i = 0; i < infinite_irradiance.size(); ++i) {
    Light& light = out.lights[bounds.size() + i];
    light.infinite_share = float(infinite_irradiance[i] / total);
    light.tree_leaf = PC_INVALID;
    running += infinite_irradiance[i];
    out.light_cdf.push_back(i + 1 == infinite_irradiance.size() ? 1.0f : float(running / total));
  }
  if (!emitters.empty()) out.features |= kFeatureAreaLights;

  for (Light& light : out.lights)
    if (light.type == PC_LIGHT_AREA) light.slot = out.leaf_slot[light.prim];
  out.header.prim_count = uint32_t(prims.size());
  out.header.light_count = uint32_t(out.lights.size());
  out.header.node_count = uint32_t(out.nodes.size());
  return out;
}

DeviceScene build_device_scene(const SceneDescription& scene, DeviceOrigin origin, Instancing instancing,
                               uint32_t layouts) {
  DeviceScene out = build_device_scene_without_texels(scene, origin, instancing, layouts);
  for (const TextureImage& t : scene.textures) out.texels.insert(out.texels.end(), t.words.begin(), t.words.end());
  return out;
}

DeviceScene build_device_scene_taking_texels(SceneDescription& scene, DeviceOrigin origin, Instancing instancing,
                                             uint32_t layouts) {
  DeviceScene out = build_device_scene_without_texels(scene, origin, instancing, layouts);
  if (scene.textures.size() == 1) {
    out.texels = std::move(scene.textures[0].words);
    scene.textures[0].words.clear();  // a moved-from vector is only valid; now it is empty
  } else {
    for (TextureImage& t : scene.textures) {
      out.texels.insert(out.texels.end(), t.words.begin(), t.words.end());
      std::vector<uint32_t>().swap(t.words);  // freed now: the peak is all texels plus one image's
    }
  }
  return out;
}
