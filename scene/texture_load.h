// Image files for textures and environment maps.
#pragma once
#include <cstddef>
#include <string>

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include "scene/scene_description.h"

// Reads an image file into texels at the precision of the file (TextureImage::format), rows from the top:
// PNG, JPEG, BMP and TGA as 8-bit sRGB (4 bytes a texel, alpha kept), OpenEXR as half or float (float when
// any of R, G, B is not HALF), Radiance HDR as float. The format is recognised by the file's content,
// whatever its name; TGA, which has no signature, by the extension .tga. Throws SceneError naming the
// file on anything it cannot read (another image format is named, with the formats accepted), or on
// texels that are not finite and non-negative.
TextureImage load_texture_image(const std::string& path);

// The same for an image in memory (embedded in a glTF file), `bytes` being its encoded file; `name` is
// for messages (and tells TGA by its extension). OpenEXR is read from files only: refused here.
TextureImage decode_texture_image(const std::string& name, const std::string& bytes);

// Mitsuba's checkerboard as a texture (PC_TEXELS_CHECKER): with x = u tiles.x + offset.x and
// y = (1 - v) tiles.y + offset.y, color1 where floor(x) + floor(y) is odd, else color0 (kernels/texture.cl).
// Its 10 words are the colours, tiles and offset as floats; width 2 and height 1, so that texel_linear,
// clamp_texels_to_one and every loop over width x height texels see the two colours as a 2 x 1 float image.
// `file` names it by its exact values (textures are shared by name); offsets are taken modulo 2 tiles, the
// pattern's period, which keeps them small.
TextureImage checkerboard_texture(glm::vec3 color0, glm::vec3 color1, glm::vec2 tiles, glm::vec2 offset);

// Linear RGB of texel i (rows from the top), as the device decodes it (kernels/texture.cl); a
// checkerboard's texels 0 and 1 are its two colours.
glm::vec3 texel_linear(const TextureImage& image, size_t i);

// Linear RGB of the texel nearest to (u, v) (v = 0 the bottom row), wrapped by image.wrap; a
// checkerboard's colour at (u, v).
glm::vec3 texel_nearest(const TextureImage& image, glm::vec2 uv);

// The linear value of an sRGB-encoded value in [0, 1] (IEC 61966-2-1), clamped to [0, 1] (NaN to 0); for vertex
// colours, which files store as display values like 8-bit images.
float srgb_to_linear(double encoded);

// Clamps every channel above 1 to 1 (an 8-bit texel never is above 1); returns the number of texels
// that changed.
size_t clamp_texels_to_one(TextureImage& image);
