// Times the phases of loading one mesh, as `pathcl render` and `pathcl info` run them (scripts/bench/load):
//   load_phases MESH [THREADS]
// parse (load_obj_file, or the PLY/STL/OFF reader), clean-up without and with smooth normals (clean_mesh),
// and the BVH build over the cleaned triangles (build_bvh, then the collapse to the 4- and 8-wide trees).
// THREADS (default: all) caps the task scheduler's threads. Prints one JSON object; messages go to stderr.
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include <tbb/global_control.h>

#include "scene/bvh_build.h"
#include "scene/mesh_clean.h"
#include "scene/obj_load.h"
#include "scene/ply_stl_off_load.h"
#include "scene/scene_error.h"

namespace {

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2 || argc > 3) {
    std::fprintf(stderr, "usage: load_phases MESH [THREADS]\n");
    return 2;
  }
  const std::string path = argv[1];
  const size_t threads = argc == 3 ? std::strtoul(argv[2], nullptr, 10)
                                   : tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism);
  tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
  try {
    auto start = std::chrono::steady_clock::now();
    std::vector<std::string> warnings;
    PolygonSoup soup = is_ply_stl_off_file(path) ? load_ply_stl_off(path, warnings) : load_obj_file(path, false, warnings).soup;
    const double parse = seconds_since(start);

    CleanReport report;
    start = std::chrono::steady_clock::now();
    clean_mesh(soup, CleanOptions{}, report);
    const double clean = seconds_since(start);

    CleanOptions smooth;
    smooth.smooth_normals = true;
    start = std::chrono::steady_clock::now();
    TriangleMesh mesh = clean_mesh(soup, smooth, report);
    const double clean_smooth = seconds_since(start);

    std::vector<Aabb> boxes(mesh.triangles.size());
    for (size_t t = 0; t < boxes.size(); ++t)
      for (uint32_t v : mesh.triangles[t]) boxes[t].grow(glm::vec3(mesh.positions[v]));
    start = std::chrono::steady_clock::now();
    Bvh bvh = build_bvh(boxes);
    const double bvh_binary = seconds_since(start);
    Bvh4 bvh4 = collapse_to_bvh4(bvh.nodes);
    Bvh8 bvh8 = collapse_to_bvh8(bvh.nodes);
    const double bvh_total = seconds_since(start);

    std::printf("{\"mesh\": \"%s\", \"threads\": %zu, \"triangles\": %zu, \"parse_s\": %.4f, \"clean_s\": %.4f, "
                "\"clean_smooth_s\": %.4f, \"bvh_binary_s\": %.4f, \"bvh_s\": %.4f, \"bvh_nodes\": %u, "
                "\"sah_cost\": %.6f, \"bvh4_nodes\": %zu, \"bvh8_nodes\": %zu}\n",
                path.c_str(), threads, mesh.triangles.size(), parse, clean, clean_smooth, bvh_binary, bvh_total,
                bvh.node_count, bvh.sah_cost, bvh4.nodes.size(), bvh8.nodes.size());
  } catch (const SceneError& e) {
    std::fprintf(stderr, "load_phases: %s\n", e.what());
    return 2;
  }
  return 0;
}
