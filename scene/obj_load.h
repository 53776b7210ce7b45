// Wavefront OBJ files: positions, faces, texture coordinates and (for "material": "from_mtl") the
// materials of their MTL files.
#pragma once
#include <string>
#include <vector>

#include "scene/mesh_clean.h"
#include "scene/mtl_load.h"

struct ObjFile {
  PolygonSoup soup;                    // uvs when some face has vt; material ids into materials when asked for
  std::vector<size_t> face_lines;      // per polygon: its line in the file, for messages
  std::vector<MtlMaterial> materials;  // of the mtllib files in the order they are named, when asked for
};

// Loads an OBJ file, validating indices and coordinates; with_materials also reads its mtllib files
// (relative to the OBJ file) and gives every face the material of the usemtl in effect. Throws
// SceneError naming the file and line (a missing MTL file or an unknown material name names the OBJ
// line of the mtllib or usemtl statement). Warnings (e.g. ignored MTL statements) are appended.
ObjFile load_obj_file(const std::string& path, bool with_materials, std::vector<std::string>& warnings);
