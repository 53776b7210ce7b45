// Generated shading normals for triangle meshes: smooth across edges whose faces meet at less than a
// crease angle, sharp across the others. Plain types only; needs neither a manifold nor a consistently
// oriented mesh.
#pragma once
#include <array>
#include <cstdint>
#include <vector>

#include <glm/vec3.hpp>

// For every triangle t with fill[t] (all when fill is empty), sets normals[t][k], the shading normal of
// its corner k at vertex v = triangles[t][k]: the sum of the unit normals of the triangles around v that
// t reaches by crossing edges at v whose two faces' normals are at most crease_degrees apart, each
// weighted by its angle at v (Thürmer and Wüthrich's weights: a normal that does not depend on how the
// faces around v are split into triangles), then normalized. Zero where that sum is zero.
//
// Orientation comes from the edges, not from a global orientation step: two faces on an edge agree when
// they run along it in opposite directions, and a face that runs along it the same way as its neighbour
// counts with its normal reversed, both for the angle test and in the sum. So an inconsistently oriented
// or non-manifold mesh (an edge of three or more faces, two fans meeting at a vertex) smooths as well as a
// clean one; the renderer turns each shading normal to its face's side. `normals` must have one entry per
// triangle; entries without fill are left alone.
void generate_smooth_normals(const std::vector<glm::dvec3>& positions,
                             const std::vector<std::array<uint32_t, 3>>& triangles, float crease_degrees,
                             const std::vector<bool>& fill, std::vector<std::array<glm::vec3, 3>>& normals);
