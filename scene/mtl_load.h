// Wavefront MTL material files, mapped onto our materials (docs/scene-format.md, "Materials from MTL
// files"): Kd -> diffuse; Ks (non-zero) -> phong with Kd, Ks and Ns; illum 7 or d < 1 -> dielectric
// with Ni and Tf; Ke -> emission; map_Kd -> texture multiplying the colour.
#pragma once
#include <set>
#include <string>
#include <vector>

#include "kernels/shared/types.h"
#include "scene/scene_description.h"

struct MtlMaterial {
  std::string name;
  std::string file;             // the MTL file
  std::string where;            // "FILE:LINE" of its newmtl statement, for messages
  MaterialDesc material;        // type and parameters; color multiplies the texture when there is one
  glm::vec3 emission{0};        // Ke: radiance of the faces that use the material
  std::string texture;          // map_Kd resolved against the MTL file's directory, or ""
  std::string texture_where;    // "FILE:LINE" of map_Kd
  uint32_t texture_wrap = PC_WRAP_REPEAT;  // PC_WRAP_CLAMP with "-clamp on"
  std::string opacity_texture;  // map_d resolved likewise, or "" (material.opacity holds a constant d)
  std::string opacity_texture_where;
  uint32_t opacity_texture_wrap = PC_WRAP_REPEAT;
  // What to say if the material is rendered (and only then: a library's other materials are not):
  // warnings naming their line, and the statements it has that pathcl does not use (Ka, map_Bump, ...).
  std::vector<std::string> warnings;
  std::set<std::string> ignored;
};

// Reads an MTL file. Throws SceneError naming the file and line on a statement it cannot read, a value
// out of range or a map_Kd option it does not support.
std::vector<MtlMaterial> load_mtl(const std::string& path);

// Phong from MTL: where diffuse_max + specular exceeds 1 in some channel (diffuse_max is the largest
// diffuse value, Kd times the texture's largest texel), scales color and specular by one factor so that
// the largest channel sum is 1, and says so in a warning naming `where`.
void limit_phong_energy(MaterialDesc& m, glm::vec3 diffuse_max, const std::string& where,
                        std::vector<std::string>& warnings);
