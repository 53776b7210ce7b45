#include "scene/device_scene.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>

#include <glm/geometric.hpp>
#include <glm/trigonometric.hpp>

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

SceneHeader camera_header(const CameraDesc& c, const glm::dvec3& origin) {
  SceneHeader h{};
  glm::dvec3 forward = glm::normalize(c.look_at - c.position);
  glm::dvec3 right = glm::normalize(glm::cross(forward, c.up));
  glm::dvec3 up = glm::cross(right, forward);
  double tan_half = std::tan(glm::radians(double(c.fov_y_degrees)) * 0.5);
  double aspect = double(c.width) / double(c.height);
  h.cam_position = f4(glm::vec3(c.position - origin));  // 0 for DeviceOrigin::camera
  h.cam_right = f4(glm::vec3(right * tan_half * aspect));
  h.cam_up = f4(glm::vec3(up * tan_half));
  h.cam_forward = f4(glm::vec3(forward));
  h.width = c.width;
  h.height = c.height;
  return h;
}

}  // namespace

Primitive scene_primitive(const DeviceScene& scene, uint32_t prim_index) {
  return scene.prims[scene.leaf_slot[prim_index]];
}

DeviceScene build_device_scene(const SceneDescription& scene, DeviceOrigin origin) {
  DeviceScene out;
  out.origin = origin == DeviceOrigin::camera ? scene.camera.position : glm::dvec3(0);
  out.header = camera_header(scene.camera, out.origin);
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
    Material mat{};
    mat.reflectance = f4(m.reflectance);
    mat.type = PC_MAT_DIFFUSE;
    out.materials.push_back(mat);
    out.features |= kFeatureDiffuse;
  }

  // Primitives in scene order, with their boxes and (for emitters) light candidates.
  std::vector<Primitive> prims;
  std::vector<Aabb> boxes;
  struct Emitter { uint32_t prim; glm::vec3 emission; double area; bool two_sided; };
  std::vector<Emitter> emitters;
  for (const ShapeDesc& s : scene.shapes) {
    bool emits = s.emission.x > 0 || s.emission.y > 0 || s.emission.z > 0;
    uint32_t flags = (s.two_sided ? PC_FLAG_TWO_SIDED : 0) | (s.flip_normals ? PC_FLAG_FLIP_NORMAL : 0);
    if (s.is_sphere) {
      uint32_t index = uint32_t(prims.size());
      glm::vec3 center = to_device(s, s.center, s.radius);
      float radius = float(s.radius);
      prims.push_back({f4(center, bits_to_float(index)), {radius, 0, 0, bits_to_float(PC_PRIM_SPHERE)}, {}});
      boxes.push_back({center - glm::vec3(radius), center + glm::vec3(radius)});
      out.shading.push_back({s.material, PC_INVALID, flags, PC_PRIM_SPHERE});
      out.normals.insert(out.normals.end(), 3, pc_float4{0, 0, 0, 0});  // 3 per primitive, as for triangles
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
    bool smooth = !s.mesh.normals.empty();
    if (smooth) out.features |= kFeatureSmoothNormals;
    std::vector<glm::vec3> positions;
    positions.reserve(s.mesh.positions.size());
    for (const glm::dvec3& p : s.mesh.positions) positions.push_back(to_device(s, p));
    for (const auto& t : s.mesh.triangles) {
      uint32_t index = uint32_t(prims.size());
      glm::vec3 a = positions[t[0]], b = positions[t[1]], c = positions[t[2]];
      prims.push_back({f4(a, bits_to_float(index)), f4(b, bits_to_float(PC_PRIM_TRIANGLE)), f4(c)});
      Aabb box;
      box.grow(a);
      box.grow(b);
      box.grow(c);
      boxes.push_back(box);
      out.shading.push_back({s.material, PC_INVALID, flags | (smooth ? PC_FLAG_SMOOTH : 0), PC_PRIM_TRIANGLE});
      if (smooth) {
        // A vertex without a normal (zero: CGAL found none, e.g. where the normals of its faces cancel)
        // takes this face's geometric normal at this corner.
        const glm::dvec3 &wa = s.mesh.positions[t[0]], &wb = s.mesh.positions[t[1]], &wc = s.mesh.positions[t[2]];
        glm::dvec3 face = glm::cross(wb - wa, wc - wa);
        double face_length = glm::length(face);
        glm::vec3 fallback = face_length > 0 ? glm::vec3(face / face_length) : glm::vec3(0);
        for (int k = 0; k < 3; ++k) {
          const glm::vec3& n = s.mesh.normals[t[k]];
          out.normals.push_back(f4(glm::dot(n, n) > 0 ? n : fallback));
        }
      } else {
        out.normals.insert(out.normals.end(), 3, pc_float4{0, 0, 0, 0});
      }
      // The area of the float triangle the device samples (computed in double from its vertices).
      double area = 0.5 * glm::length(glm::cross(glm::dvec3(b) - glm::dvec3(a), glm::dvec3(c) - glm::dvec3(a)));
      if (emits) {
        if (float(area) > 0)
          emitters.push_back({index, s.emission, area, s.two_sided});
        else
          out.skipped_zero_area_emitters++;
      }
      out.triangle_count++;
      out.features |= kFeatureTriangles;
    }
  }
  if (!(out.features & kFeatureSmoothNormals)) out.normals.clear();

  // One distribution over all emitters, proportional to emitted power. Every power is positive (a
  // positive area and a non-zero emission) and finite (areas are bounded by kMaxSceneExtent), so the
  // total is too and every select_pdf and cdf entry is a finite number in [0, 1].
  double total = 0;
  std::vector<double> power;
  for (const Emitter& e : emitters) {
    power.push_back(luminance(e.emission) * e.area * M_PI * (e.two_sided ? 2 : 1));
    total += power.back();
  }
  out.light_cdf.push_back(0);
  double running = 0;
  for (size_t i = 0; i < emitters.size(); ++i) {
    const Emitter& e = emitters[i];
    Light light{};
    light.emission = f4(e.emission);
    light.prim = e.prim;
    light.area = float(e.area);
    light.select_pdf = float(power[i] / total);
    out.shading[e.prim].light = uint32_t(out.lights.size());
    out.lights.push_back(light);
    running += power[i];
    out.light_cdf.push_back(i + 1 == emitters.size() ? 1.0f : float(running / total));
  }
  if (!out.lights.empty()) out.features |= kFeatureAreaLights;

  out.bvh = build_bvh(boxes);
  out.nodes = std::move(out.bvh.nodes);
  out.prims.reserve(prims.size());
  out.leaf_slot.resize(prims.size());
  for (uint32_t slot = 0; slot < prims.size(); ++slot) {
    out.prims.push_back(prims[out.bvh.prim_order[slot]]);
    out.leaf_slot[out.bvh.prim_order[slot]] = slot;
  }
  for (Light& light : out.lights) light.slot = out.leaf_slot[light.prim];
  out.header.prim_count = uint32_t(prims.size());
  out.header.light_count = uint32_t(out.lights.size());
  out.header.node_count = uint32_t(out.nodes.size());
  return out;
}
