// libFuzzer target: an image file through pathcl's texture loaders (scene/texture_load.cpp: stb_image for
// PNG, JPEG, BMP, TGA and Radiance HDR, OpenEXR for .exr) and the texel accessors the scene builder uses.
// The first input byte selects how (bits 0 to 2: the file's extension, which only TGA's detection and
// the messages depend on: .png .jpg .bmp .tga .hdr .exr .gif .img; bit 3: decode the bytes in memory,
// as for an image embedded in a glTF file, instead of reading the file); the seeds begin with '0' to '7'
// (a file of that extension) and '8' to '?' (the same in memory). The rest is the image. Bad input must
// end in SceneError; any other exception, crash, sanitizer report or broken invariant below is a bug.
// Run by scripts/fuzz.
#include <cmath>
#include <cstdint>
#include <string>

#include "fuzz/fuzz_common.h"
#include "kernels/shared/types.h"
#include "scene/gltf_load.h"
#include "scene/scene_description.h"
#include "scene/scene_error.h"
#include "scene/scene_limits.h"
#include "scene/texture_load.h"

namespace {

bool finite_non_negative(glm::vec3 t) {
  return std::isfinite(t.x) && std::isfinite(t.y) && std::isfinite(t.z) && t.x >= 0 && t.y >= 0 && t.z >= 0;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1 || size > fuzz::kMaxInputBytes) return 0;
  const char* extensions[] = {".png", ".jpg", ".bmp", ".tga", ".hdr", ".exr", ".gif", ".img"};
  const std::string name = std::string("t") + extensions[data[0] & 7];
  const bool in_memory = (data[0] & 8) != 0;
  try {
    TextureImage image;
    if (in_memory) {
      image = decode_texture_image(name, std::string(reinterpret_cast<const char*>(data + 1), size - 1));
    } else {
      image = load_texture_image(fuzz::scratch().write(name.c_str(), data + 1, size - 1));
    }

    // What build_device_scene and the kernels rely on.
    if (image.width == 0 || image.height == 0) fuzz::invariant_failed("an image without texels");
    const uint64_t texels = uint64_t(image.width) * image.height;
    if (texels > kMaxTextureTexels) fuzz::invariant_failed("an image above kMaxTextureTexels");
    const uint64_t words = image.format == PC_TEXELS_SRGB8  ? texels
                           : image.format == PC_TEXELS_HALF ? (3 * texels + 1) / 2
                           : image.format == PC_TEXELS_FLOAT ? 3 * texels
                                                             : 0;
    if (words == 0) fuzz::invariant_failed("unknown texel format");
    if (image.words.size() != words) fuzz::invariant_failed("texel words do not match the size and format");
    for (uint64_t i = 0; i < texels; ++i)
      if (!finite_non_negative(texel_linear(image, size_t(i)))) fuzz::invariant_failed("a texel negative or not finite");
    for (uint32_t wrap : {PC_WRAP_REPEAT, PC_WRAP_CLAMP, PC_WRAP_MIRROR}) {
      image.wrap = wrap;
      for (float u : {-1.5f, -0.0f, 0.25f, 0.999999f, 1.0f, 7.5f, 1e30f, -1e30f, NAN, INFINITY})
        if (!finite_non_negative(texel_nearest(image, glm::vec2(u, 1 - u))))
          fuzz::invariant_failed("texel_nearest gave a texel negative or not finite");
    }
    if (image.format == PC_TEXELS_SRGB8) {
      // A glTF base colour's alpha as an opacity map, thresholded (MASK) and not (BLEND).
      for (float cutoff : {0.5f, -1.0f}) {
        TextureImage opacity = alpha_as_opacity(image, 0.75f, cutoff);
        if (opacity.words.size() != image.words.size()) fuzz::invariant_failed("opacity map of another size");
      }
    } else {
      clamp_texels_to_one(image);
      for (uint64_t i = 0; i < texels; ++i) {
        glm::vec3 t = texel_linear(image, size_t(i));
        if (!(t.x <= 1 && t.y <= 1 && t.z <= 1)) fuzz::invariant_failed("a texel above 1 after clamp_texels_to_one");
      }
    }
  } catch (const SceneError&) {
    // Rejected input: expected.
  }
  return 0;
}
