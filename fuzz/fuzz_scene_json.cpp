// libFuzzer target: a scene file through load_scene (JSON, OBJ meshes, CGAL clean-up, transforms) and
// build_device_scene (flattening, light distribution, BVH). Bad input must end in SceneError; any
// other exception, crash, sanitizer report or broken invariant below is a bug.
// The scene lies next to a valid unit cube, so shapes may use "file": "m.obj". Run by scripts/fuzz.
#include <cmath>
#include <cstdint>
#include <vector>

#include "fuzz/fuzz_common.h"
#include "scene/bvh_build.h"
#include "scene/device_scene_build.h"
#include "scene/scene_description.h"
#include "scene/scene_error.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size > fuzz::kMaxInputBytes) return 0;
  const std::string path = fuzz::scratch().write("s.json", data, size);
  try {
    const SceneDescription scene = load_scene(path);
    const DeviceScene device = build_device_scene(scene);

    // What the kernels rely on.
    const size_t prims = device.prims.size();
    if (device.header.prim_count != prims || device.leaf_slot.size() != prims || device.shading.size() != prims)
      fuzz::invariant_failed("primitive arrays disagree in size");
    if (device.bvh.depth > kBvhMaxDepth) fuzz::invariant_failed("BVH deeper than the kernel's stack");
    std::vector<bool> seen(prims, false);
    for (uint32_t slot : device.leaf_slot) {
      if (slot >= prims || seen[slot]) fuzz::invariant_failed("leaf slots are not a permutation");
      seen[slot] = true;
    }
    if (!device.normals.empty() && device.normals.size() != 3 * prims)
      fuzz::invariant_failed("smooth normals are not 3 per primitive");
    uint32_t tree_lights = device.header.tree_light_count;
    if (device.light_cdf.size() != device.lights.size() - tree_lights + 1) fuzz::invariant_failed("light CDF size");
    uint32_t leaves = 0;
    for (const LightBvhNode& n : device.light_bvh) leaves += n.second == PC_INVALID;
    if (device.light_bvh.size() != (tree_lights ? 2 * leaves - 1 : 0)) fuzz::invariant_failed("light BVH size");
    for (uint32_t i = 0; i < tree_lights; ++i) {
      uint32_t leaf = device.lights[i].tree_leaf;
      if (leaf >= device.light_bvh.size() || device.light_bvh[leaf].light > i ||
          i - device.light_bvh[leaf].light >= device.light_bvh[leaf].light_count)
        fuzz::invariant_failed("a light's leaf is not its own");
    }
    for (const LightBvhNode& n : device.light_bvh) {
      if (n.second != PC_INVALID) continue;
      double shares = 0;
      float cdf = 0;
      for (uint32_t i = n.light; i < n.light + n.light_count && i < tree_lights; ++i) {
        shares += device.lights[i].group_share;
        if (!(device.lights[i].group_cdf >= cdf)) fuzz::invariant_failed("a leaf's group CDF decreases");
        cdf = device.lights[i].group_cdf;
      }
      if (!(std::abs(shares - 1) <= 1e-5)) fuzz::invariant_failed("a leaf's lights' group shares do not sum to 1");
      if (cdf != 1.0f) fuzz::invariant_failed("a leaf's group CDF does not end at 1");
    }
    for (const LightBvhNode& n : device.light_bvh)
      if (!(n.lo.w >= 0 && n.lo.w <= 3.4e38f)) fuzz::invariant_failed("light BVH intensity negative or not finite");
    for (const Light& light : device.lights) {
      if (light.prim >= prims || light.slot >= prims) fuzz::invariant_failed("light primitive out of range");
      if (!(light.area > 0 && light.area <= 3.4e38f)) fuzz::invariant_failed("light area zero or not finite");
      if (!(light.infinite_share >= 0 && light.infinite_share <= 1)) fuzz::invariant_failed("light infinite_share not in [0, 1]");
    }
    for (size_t i = 0; i < device.light_cdf.size(); ++i)
      if (!(device.light_cdf[i] >= (i ? device.light_cdf[i - 1] : 0.0f) && device.light_cdf[i] <= 1))
        fuzz::invariant_failed("light CDF not finite and non-decreasing in [0, 1]");
  } catch (const SceneError&) {
    // Rejected input: expected.
  }
  return 0;
}
