// Image files for textures and environment maps.
#pragma once
#include <string>

#include "scene/scene_description.h"

// Reads a PNG or JPEG file (8-bit sRGB, converted to linear) or an OpenEXR file (linear) into linear
// RGB texels, rows from the top. Throws SceneError naming the file on anything it cannot read, or on
// texels that are not finite and non-negative.
TextureImage load_texture_image(const std::string& path);
