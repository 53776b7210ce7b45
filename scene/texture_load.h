// Image files for textures and environment maps.
#pragma once
#include <string>

#include "scene/scene_description.h"

// Reads a PNG or JPEG file (8-bit sRGB, converted to linear) or an OpenEXR file (linear) into linear
// RGB texels, rows from the top; the format is recognised by the file's content, whatever its name.
// Throws SceneError naming the file on anything it cannot read (another image format is named, with
// the formats accepted), or on texels that are not finite and non-negative.
TextureImage load_texture_image(const std::string& path);
