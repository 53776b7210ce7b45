#include "scene/texture_load.h"

#include <cmath>
#include <filesystem>
#include <memory>

#include <ImfArray.h>
#include <ImfRgbaFile.h>
#include <stb_image.h>

#include "scene/scene_error.h"

namespace {

float srgb_to_linear(float c) { return c <= 0.04045f ? c / 12.92f : std::pow((c + 0.055f) / 1.055f, 2.4f); }

TextureImage load_exr(const std::string& path) {
  TextureImage image;
  try {
    Imf::RgbaInputFile file(path.c_str());
    Imath::Box2i dw = file.dataWindow();
    long width = dw.max.x - dw.min.x + 1, height = dw.max.y - dw.min.y + 1;
    if (width <= 0 || height <= 0 || width * height > (1l << 28)) throw SceneError(path + ": unsupported image size");
    Imf::Array2D<Imf::Rgba> pixels(height, width);
    file.setFrameBuffer(&pixels[0][0] - dw.min.x - dw.min.y * width, 1, width);
    file.readPixels(dw.min.y, dw.max.y);
    image.width = uint32_t(width);
    image.height = uint32_t(height);
    for (long y = 0; y < height; ++y)
      for (long x = 0; x < width; ++x) {
        const Imf::Rgba& p = pixels[y][x];
        image.texels.push_back({float(p.r), float(p.g), float(p.b), 1.0f});
      }
  } catch (const SceneError&) {
    throw;
  } catch (const std::exception& e) {
    throw SceneError(path + ": cannot read the EXR file: " + e.what());
  }
  return image;
}

TextureImage load_8bit(const std::string& path) {
  int width = 0, height = 0, channels = 0;
  std::unique_ptr<unsigned char, void (*)(void*)> data(stbi_load(path.c_str(), &width, &height, &channels, 3),
                                                       stbi_image_free);
  if (!data) throw SceneError(path + ": cannot read the image: " + stbi_failure_reason());
  TextureImage image;
  image.width = uint32_t(width);
  image.height = uint32_t(height);
  float table[256];
  for (int i = 0; i < 256; ++i) table[i] = srgb_to_linear(i / 255.0f);
  const unsigned char* p = data.get();
  image.texels.reserve(size_t(width) * height);
  for (size_t i = 0; i < size_t(width) * height; ++i)
    image.texels.push_back({table[p[3 * i]], table[p[3 * i + 1]], table[p[3 * i + 2]], 1.0f});
  return image;
}

}  // namespace

TextureImage load_texture_image(const std::string& path) {
  if (!std::filesystem::is_regular_file(path)) throw SceneError(path + ": cannot open the image file");
  std::string ext = std::filesystem::path(path).extension().string();
  for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
  TextureImage image;
  if (ext == ".exr")
    image = load_exr(path);
  else if (ext == ".png" || ext == ".jpg" || ext == ".jpeg")
    image = load_8bit(path);
  else
    throw SceneError(path + ": unsupported image format (expected .png, .jpg, .jpeg or .exr)");
  for (const glm::vec4& t : image.texels)
    if (!(std::isfinite(t.x) && std::isfinite(t.y) && std::isfinite(t.z)) || t.x < 0 || t.y < 0 || t.z < 0)
      throw SceneError(path + ": texels must be finite and non-negative");
  image.file = path;
  return image;
}
