#include "scene/texture_load.h"

#include <cmath>
#include <filesystem>
#include <memory>
#include <vector>

#include <ImfArray.h>
#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfInputFile.h>
#include <ImfRgbaFile.h>
#include <stb_image.h>

#include "scene/input_file.h"
#include "scene/scene_error.h"
#include "scene/scene_limits.h"

namespace {

// Refuses images beyond kMaxTextureTexels before they are decoded.
void check_size(const std::string& path, int64_t width, int64_t height) {
  if (width <= 0 || height <= 0) throw SceneError(path + ": the image has no texels");
  if (width > int64_t(kMaxTextureTexels) || height > int64_t(kMaxTextureTexels) ||
      uint64_t(width) * uint64_t(height) > kMaxTextureTexels)
    throw SceneError(path + ": an image of " + std::to_string(width) + " x " + std::to_string(height) +
                     " texels is larger than the largest of " + std::to_string(kMaxTextureTexels) + " texels");
}

float srgb_to_linear(float c) { return c <= 0.04045f ? c / 12.92f : std::pow((c + 0.055f) / 1.055f, 2.4f); }

// RGB files are read as 32-bit floats (missing channels read as 0); only files without R, G and B
// (luminance / chroma) go through the RGBA interface, which converts them but rounds to half floats.
TextureImage load_exr(const std::string& path) {
  TextureImage image;
  try {
    Imf::InputFile file(path.c_str());
    Imath::Box2i dw = file.header().dataWindow();
    // In 64 bits: the window's corners are ints, and its width can overflow one.
    int64_t width = int64_t(dw.max.x) - dw.min.x + 1, height = int64_t(dw.max.y) - dw.min.y + 1;
    check_size(path, width, height);
    image.width = uint32_t(width);
    image.height = uint32_t(height);
    image.texels.reserve(size_t(width) * height);
    const Imf::ChannelList& channels = file.header().channels();
    if (channels.findChannel("R") || channels.findChannel("G") || channels.findChannel("B")) {
      std::vector<float> rgb(size_t(width) * height * 3);
      // The frame buffer is addressed by data-window coordinates.
      char* base = reinterpret_cast<char*>(rgb.data()) - (dw.min.x + long(dw.min.y) * width) * 3 * long(sizeof(float));
      size_t xs = 3 * sizeof(float), ys = xs * size_t(width);
      Imf::FrameBuffer fb;
      fb.insert("R", Imf::Slice(Imf::FLOAT, base, xs, ys));
      fb.insert("G", Imf::Slice(Imf::FLOAT, base + sizeof(float), xs, ys));
      fb.insert("B", Imf::Slice(Imf::FLOAT, base + 2 * sizeof(float), xs, ys));
      file.setFrameBuffer(fb);
      file.readPixels(dw.min.y, dw.max.y);
      for (size_t i = 0; i < size_t(width) * height; ++i)
        image.texels.push_back({rgb[3 * i], rgb[3 * i + 1], rgb[3 * i + 2], 1.0f});
      return image;
    }
    Imf::RgbaInputFile rgba(path.c_str());
    Imf::Array2D<Imf::Rgba> pixels(height, width);
    rgba.setFrameBuffer(&pixels[0][0] - dw.min.x - dw.min.y * width, 1, width);
    rgba.readPixels(dw.min.y, dw.max.y);
    for (long y = 0; y < height; ++y)
      for (long x = 0; x < width; ++x) {
        const Imf::Rgba& p = pixels[y][x];
        image.texels.push_back({float(p.r), float(p.g), float(p.b), 1.0f});
      }
  } catch (const SceneError&) {
    throw;
  } catch (const std::exception&) {
    // OpenEXR's own message names the file again and its internals ("Cannot read image file ...").
    throw SceneError(path + ": cannot decode the OpenEXR image (corrupt or truncated)");
  }
  return image;
}

TextureImage load_8bit(const std::string& path) {
  int width = 0, height = 0, channels = 0;
  // The header alone first: stb_image would decode anything it can allocate.
  if (stbi_info(path.c_str(), &width, &height, &channels)) check_size(path, width, height);
  std::unique_ptr<unsigned char, void (*)(void*)> data(stbi_load(path.c_str(), &width, &height, &channels, 3),
                                                       stbi_image_free);
  // stb_image's reasons are terse internals ("bad zlib header"), not for users.
  if (!data) throw SceneError(path + ": cannot decode the PNG or JPEG image (corrupt or truncated)");
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

// Image formats pathcl does not read (stb_image could read some of them, but they are neither the 8-bit
// sRGB nor the linear float images the format defines), by how their files begin and by extension.
struct ImageFormat {
  const char* name;
  std::vector<std::string> extensions, starts;
};
const ImageFormat kOtherImageFormats[] = {
    {"GIF", {".gif"}, {"GIF87a", "GIF89a"}},
    {"BMP", {".bmp"}, {"BM"}},
    {"TIFF", {".tif", ".tiff"}, {std::string("II*\0", 4), std::string("MM\0*", 4)}},
    {"WebP", {".webp"}, {}},
    {"Radiance HDR", {".hdr", ".pic"}, {"#?RADIANCE", "#?RGBE"}},
    {"Photoshop", {".psd"}, {"8BPS"}},
    {"DDS", {".dds"}, {"DDS "}},
    {"KTX", {".ktx", ".ktx2"}, {"\xabKTX"}},
    {"PFM", {".pfm"}, {"PF\n", "Pf\n"}},
    {"TGA", {".tga"}, {}},
    {"PNM", {".ppm", ".pgm", ".pnm", ".pbm"}, {}},
    {"JPEG 2000", {".jp2", ".j2k"}, {std::string("\0\0\0\x0cjP  ", 8)}},
    {"HEIF", {".heic", ".heif", ".avif"}, {}},
};

// Names the format of an image that is not PNG, JPEG or OpenEXR, by content, then by extension.
[[noreturn]] void refuse_image_format(const std::string& path, const std::string& head) {
  const char* accepted = " (expected PNG, JPEG or OpenEXR: .png, .jpg, .jpeg or .exr)";
  std::string ext = std::filesystem::path(path).extension().string();
  for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
  for (const ImageFormat& f : kOtherImageFormats)
    for (const std::string& s : f.starts)
      if (head.rfind(s, 0) == 0) throw SceneError(path + ": " + f.name + " images are not supported" + accepted);
  for (const ImageFormat& f : kOtherImageFormats)
    for (const std::string& e : f.extensions)
      if (ext == e) throw SceneError(path + ": " + f.name + " images are not supported" + accepted);
  throw SceneError(path + ": unrecognised image format" + accepted);
}

}  // namespace

TextureImage load_texture_image(const std::string& path) {
  const std::string head = read_input_file(path, kImageInput, 64);
  auto starts = [&](const char* magic) { return head.rfind(magic, 0) == 0; };
  TextureImage image;
  // The format is told by the content, which is what the readers go by, not by the name.
  if (starts("\x76\x2f\x31\x01"))
    image = load_exr(path);
  else if (starts("\x89PNG\r\n\x1a\n") || starts("\xff\xd8\xff"))
    image = load_8bit(path);
  else
    refuse_image_format(path, head);
  for (const glm::vec4& t : image.texels)
    if (!(std::isfinite(t.x) && std::isfinite(t.y) && std::isfinite(t.z)) || t.x < 0 || t.y < 0 || t.z < 0)
      throw SceneError(path + ": texels must be finite and non-negative");
  image.file = path;
  return image;
}
