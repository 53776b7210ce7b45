// Placing meshes by transforms after clean-up: instances flattened into world geometry.
#include <utility>

#include <glm/common.hpp>
#include <glm/geometric.hpp>
#include <glm/mat3x3.hpp>
#include <glm/matrix.hpp>

#include "scene/scene_description.h"

TriangleMesh placed_mesh(TriangleMesh mesh, const glm::dmat4& transform) {
  for (glm::dvec3& p : mesh.positions) p = glm::dvec3(transform * glm::dvec4(p, 1.0));
  const glm::dmat3 normal_matrix = glm::transpose(glm::inverse(glm::dmat3(transform)));
  for (auto& corners : mesh.normals)
    for (glm::vec3& n : corners) {
      glm::dvec3 m = normal_matrix * glm::dvec3(n);
      double length = glm::length(m);
      n = length > 0 ? glm::vec3(m / length) : glm::vec3(0);  // a corner without a normal stays without
    }
  if (glm::determinant(glm::dmat3(transform)) < 0) {
    // Counter-clockwise became clockwise: swap two corners of every triangle, and their attributes.
    for (size_t t = 0; t < mesh.triangles.size(); ++t) {
      std::swap(mesh.triangles[t][1], mesh.triangles[t][2]);
      if (!mesh.normals.empty()) std::swap(mesh.normals[t][1], mesh.normals[t][2]);
      if (!mesh.uvs.empty()) std::swap(mesh.uvs[t][1], mesh.uvs[t][2]);
      if (!mesh.colors.empty()) std::swap(mesh.colors[t][1], mesh.colors[t][2]);
      if (!mesh.source_corners.empty()) std::swap(mesh.source_corners[t][1], mesh.source_corners[t][2]);
    }
  }
  return mesh;
}

ShapeDesc flattened_shape(const SceneDescription& scene, const ShapeDesc& s) {
  if (s.instance_of == PC_INVALID) return s;
  const InstancedMesh& m = scene.instanced_meshes[s.instance_of];
  ShapeDesc out = s;
  out.instance_of = PC_INVALID;
  out.transform = glm::dmat4(1.0);
  out.mesh = placed_mesh(m.mesh, s.transform);
  out.clean = m.clean;
  out.triangle_materials = m.triangle_materials;
  return out;
}

void set_bounds(InstancedMesh& m) {
  m.lo = m.hi = m.mesh.positions.empty() ? glm::dvec3(0) : m.mesh.positions[0];
  for (const glm::dvec3& p : m.mesh.positions) {
    m.lo = glm::min(m.lo, p);
    m.hi = glm::max(m.hi, p);
  }
}

size_t shape_triangle_count(const SceneDescription& scene, const ShapeDesc& s) {
  if (s.is_sphere) return 0;
  return s.instance_of == PC_INVALID ? s.mesh.triangles.size() : scene.instanced_meshes[s.instance_of].mesh.triangles.size();
}
