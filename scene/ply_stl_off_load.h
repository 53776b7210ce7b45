// PLY, STL and OFF meshes through CGAL's readers (CGAL/IO), as polygon soups with their normals and
// texture coordinates.
#pragma once
#include <string>
#include <vector>

#include "scene/mesh_clean.h"

// Whether pathcl reads `path` with load_ply_stl_off: its extension is .ply, .stl or .off (any case).
bool is_ply_stl_off_file(const std::string& path);

// Loads a PLY (ASCII or binary, either byte order), STL (ASCII or binary) or OFF file, by its extension.
// PLY vertex normals (nx, ny, nz) and texture coordinates (u, v; s, t; texture_u, texture_v), or per-face
// corner texture coordinates (texcoord, as MeshLab writes them), and OFF's NOFF/STOFF normals and uvs
// become the soup's per-corner normals and uvs; STL's facet normals are the faces' own, and are not read.
// Vertex and face colours are not used: a warning says so. Throws SceneError "FILE: what is wrong" for a
// file that cannot be read, is truncated or garbled, has a face index out of range, a coordinate that is
// not finite or beyond float range, or no faces.
PolygonSoup load_ply_stl_off(const std::string& path, std::vector<std::string>& warnings);
