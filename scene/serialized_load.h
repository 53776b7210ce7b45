// Mitsuba's binary meshes (.serialized, format versions 3 and 4, as Mitsuba 0.6 writes them and Mitsuba 3
// reads them): one shape of a file as a polygon soup of triangles, with its normals, texture coordinates
// and vertex colours.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "scene/mesh_clean.h"

// Loads shape `shape_index` (0 for the first; the serialized shape's shape_index) of a .serialized file:
// its positions (single or double precision in the file, double here), one polygon per triangle, and
// laid out per triangle corner as PolygonSoup documents: the vertex normals (none when the shape asks for
// face normals, flag 0x0010: it renders flat), the texture coordinates as (u, 1 - v) (Mitsuba's v = 0 is
// an image's top row, pathcl's its bottom row: the same texel either way) and the vertex colours (linear
// RGB; values outside [0, 1] are clamped, with a warning). `materials` stays empty. Shape 0 is read from
// the start of the file, as Mitsuba does, without the table of shapes at its end; any other through that
// table. Bytes of a shape's decompressed data after its triangles are ignored, with a warning.
// Throws SceneError "FILE: what is wrong" ("FILE: shape N: ..." inside a shape's data) for a file that
// cannot be read, does not begin with the format identifier 0x041C, has another version, has no shape
// `shape_index`, has a garbled table of shapes, zlib data that is cut short or corrupt (its checksum
// included), counts that the decompressed data does not hold (checked as the data arrives: a garbled
// count allocates nothing beyond the data there is), more than 2^32 vertices or 2^32 - 1 triangles, both precision
// flags, a triangle index out of range, a coordinate that is not finite or beyond float range, a normal,
// texture coordinate or colour that is not finite, or no triangles.
// Whether pathcl reads `path` with load_serialized: its extension is .serialized (any case).
bool is_serialized_file(const std::string& path);

PolygonSoup load_serialized(const std::string& path, uint32_t shape_index, std::vector<std::string>& warnings);
