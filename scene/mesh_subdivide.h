// Uniform subdivision of a cleaned triangle mesh: each triangle into n x n triangles of its own plane (the
// surface unchanged), for estimators whose unknowns are per triangle (the radiosity integrator's power sums:
// a finer mesh shows less of its discretisation).
#pragma once
#include <cstdint>

#include "scene/mesh_clean.h"

// Splits every triangle of `mesh` into n^2 (n >= 1; 1 leaves it as it is): its edges into n equal parts,
// the points of an edge that two triangles share computed once from its lower-numbered end, so the mesh
// stays watertight. Per-corner normals, uvs and colours are interpolated (normals renormalised; a triangle
// with a corner without a normal keeps none on its parts), per-triangle materials and sources copied.
void subdivide_mesh(TriangleMesh& mesh, uint32_t n);
