#include "scene/texture_load.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <memory>
#include <sstream>
#include <vector>

#include <ImfArray.h>
#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfInputFile.h>
#include <ImfRgbaFile.h>
#include <Imath/half.h>
#include <stb_image.h>

#include "kernels/shared/srgb_table.h"
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

const float kSrgbToLinear[256] = PC_SRGB_TO_LINEAR_TABLE;

// Words for n texels of `format`; a half image ends on a whole word.
size_t texel_words(uint32_t format, size_t n) {
  return format == PC_TEXELS_SRGB8 ? n : format == PC_TEXELS_HALF ? (3 * n + 1) / 2 : 3 * n;
}

TextureImage empty_image(uint32_t width, uint32_t height, uint32_t format) {
  TextureImage image;
  image.width = width;
  image.height = height;
  image.format = format;
  image.words.assign(texel_words(format, size_t(width) * height), 0);
  return image;
}

// RGB files are read as they are stored: all of R, G, B (those present) HALF as halves, anything else as
// floats (missing channels read as 0). Only files without R, G and B (luminance / chroma) go through the
// RGBA interface, which converts them to halves.
TextureImage load_exr(const std::string& path) {
  try {
    Imf::InputFile file(path.c_str());
    Imath::Box2i dw = file.header().dataWindow();
    // In 64 bits: the window's corners are ints, and its width can overflow one.
    int64_t width = int64_t(dw.max.x) - dw.min.x + 1, height = int64_t(dw.max.y) - dw.min.y + 1;
    check_size(path, width, height);
    const Imf::ChannelList& channels = file.header().channels();
    const char* names[3] = {"R", "G", "B"};
    bool any = false, all_half = true;
    for (const char* name : names)
      if (const Imf::Channel* c = channels.findChannel(name)) {
        any = true;
        all_half = all_half && c->type == Imf::HALF;
      }
    if (any) {
      const uint32_t format = all_half ? PC_TEXELS_HALF : PC_TEXELS_FLOAT;
      const size_t channel_bytes = all_half ? 2 : 4;
      TextureImage image = empty_image(uint32_t(width), uint32_t(height), format);
      // The frame buffer is addressed by data-window coordinates.
      size_t xs = 3 * channel_bytes, ys = xs * size_t(width);
      char* base = reinterpret_cast<char*>(image.words.data()) - (dw.min.x + long(dw.min.y) * width) * long(xs);
      Imf::FrameBuffer fb;
      for (size_t c = 0; c < 3; ++c)
        fb.insert(names[c], Imf::Slice(all_half ? Imf::HALF : Imf::FLOAT, base + c * channel_bytes, xs, ys));
      file.setFrameBuffer(fb);
      file.readPixels(dw.min.y, dw.max.y);
      return image;
    }
    Imf::RgbaInputFile rgba(path.c_str());
    Imf::Array2D<Imf::Rgba> pixels(height, width);
    rgba.setFrameBuffer(&pixels[0][0] - dw.min.x - dw.min.y * width, 1, width);
    rgba.readPixels(dw.min.y, dw.max.y);
    TextureImage image = empty_image(uint32_t(width), uint32_t(height), PC_TEXELS_HALF);
    uint16_t* halves = reinterpret_cast<uint16_t*>(image.words.data());
    for (long y = 0; y < height; ++y)
      for (long x = 0; x < width; ++x) {
        const Imf::Rgba& p = pixels[y][x];
        uint16_t* t = halves + 3 * (size_t(y) * width + x);
        t[0] = p.r.bits();
        t[1] = p.g.bits();
        t[2] = p.b.bits();
      }
    return image;
  } catch (const SceneError&) {
    throw;
  } catch (const std::exception&) {
    // OpenEXR's own message names the file again and its internals ("Cannot read image file ...").
    throw SceneError(path + ": cannot decode the OpenEXR image (corrupt or truncated)");
  }
}

// stb_image reads TGA, BMP, Radiance HDR and JPEG data past the end of a truncated file as zeros, and
// decodes it without complaint: a 19-byte TGA file that says 32771 x 2304 texels took 3 s and 600 MB
// (fuzz_texture, a slow unit). A file smaller than its texels take at the format's densest encoding is
// refused as truncated: TGA 1 byte a texel uncompressed (more for more bits) and 2 bytes per RLE packet of
// at most 128; BMP at least 1 bit a texel (stb_image reads no compressed BMP); Radiance HDR 2 bytes per run
// of at most 127 texels in each of 4 channels; JPEG at least 1 bit per 8 x 8 block. PNG's zlib stream
// cannot be cut short unnoticed.
void check_not_truncated(const std::string& name, const std::string& bytes, const std::string& format, uint64_t texels) {
  uint64_t least = 0;
  if (format == "TGA") {
    // stb_image reads a header cut short as zeros too (fuzz_texture: 17 bytes for 11008 x 22572 texels of 32 bits).
    auto byte = [&](size_t i) -> unsigned { return i < bytes.size() ? static_cast<unsigned char>(bytes[i]) : 0u; };
    const unsigned type = byte(2), bits = byte(16);
    least = type >= 8 ? (texels + 127) / 128 * 2 : texels * std::max(1u, bits / 8);
  } else if (format == "BMP") {
    least = texels / 8;
  } else if (format == "Radiance HDR") {
    least = texels / 16;
  } else if (format == "JPEG") {
    least = texels / 512;
  }
  if (bytes.size() < least)
    throw SceneError(name + ": truncated " + format + " image: its " + std::to_string(texels) + " texels take at least " +
                     std::to_string(least) + " bytes, the file has " + std::to_string(bytes.size()));
}

// stb_image 2.27 loops forever on an RLE packet of length 0 in a Radiance HDR scanline, which is also what
// it reads past the end of a truncated file (fuzz_texture, a timeout; stb_image 2.28 refuses the packet).
// The scanlines are walked here as stb_image reads them (scanlines 8 to 32767 wide are RLE when they begin
// 2 2 and their width; anything else is flat from there on), and such a packet refused.
void check_hdr_runs(const std::string& name, const std::string& bytes, int width, int height) {
  if (width < 8 || width >= 32768) return;  // flat: 4 bytes a texel, read without a loop on their values
  const size_t n = bytes.size();
  auto byte = [&](size_t i) -> unsigned { return i < n ? static_cast<unsigned char>(bytes[i]) : 0u; };  // 0 past the end, as stb
  // The header's lines up to the empty one, then the resolution line.
  size_t at = 0;
  auto line = [&] {
    size_t end = bytes.find('\n', at), start = at;
    at = end == std::string::npos ? n : end + 1;
    return (end == std::string::npos ? n : end) - start;
  };
  while (at < n && line() > 0) {
  }
  line();
  for (int y = 0; y < height; ++y) {
    if (byte(at) != 2 || byte(at + 1) != 2 || (byte(at + 2) & 0x80)) return;  // flat from here on
    if ((byte(at + 2) << 8 | byte(at + 3)) != unsigned(width)) return;       // stb_image refuses it
    at += 4;
    for (int channel = 0; channel < 4; ++channel)
      for (int i = 0; i < width;) {
        unsigned count = byte(at++);
        if (count > 128) {  // a run of count - 128 (1 to 127) copies of the next byte
          count -= 128;
          ++at;
        } else if (count == 0) {
          throw SceneError(name + ": corrupt or truncated Radiance HDR image: scanline " + std::to_string(y) +
                           " has an RLE packet of length 0" + (at > n ? " (the file ends there)" : ""));
        } else {
          at += count;
        }
        if (count > unsigned(width - i)) return;  // stb_image refuses it
        i += int(count);
      }
  }
}

// Through stb_image from the file's bytes: 8-bit formats as sRGB bytes (RGBA), Radiance HDR (`hdr`) as floats.
TextureImage decode_stb(const std::string& name, const std::string& bytes, const char* format_name, bool hdr) {
  int width = 0, height = 0, channels = 0;
  const auto* data_bytes = reinterpret_cast<const stbi_uc*>(bytes.data());
  const int size = bytes.size() > size_t(INT32_MAX) ? INT32_MAX : int(bytes.size());
  // The header alone first: stb_image would decode anything it can allocate.
  if (stbi_info_from_memory(data_bytes, size, &width, &height, &channels)) {
    check_size(name, width, height);
    check_not_truncated(name, bytes, format_name, uint64_t(width) * uint64_t(height));
    if (hdr) check_hdr_runs(name, bytes, width, height);
  }
  std::unique_ptr<void, void (*)(void*)> data(
      hdr ? static_cast<void*>(stbi_loadf_from_memory(data_bytes, size, &width, &height, &channels, 3))
          : static_cast<void*>(stbi_load_from_memory(data_bytes, size, &width, &height, &channels, 4)),
      stbi_image_free);
  // stb_image's reasons are terse internals ("bad zlib header"), not for users.
  if (!data) throw SceneError(name + ": cannot decode the " + format_name + " image (corrupt or truncated)");
  // Again, for a file whose header stbi_info did not read (it is stricter than the decoders).
  check_size(name, width, height);
  check_not_truncated(name, bytes, format_name, uint64_t(width) * uint64_t(height));
  TextureImage image = empty_image(uint32_t(width), uint32_t(height), hdr ? PC_TEXELS_FLOAT : PC_TEXELS_SRGB8);
  std::memcpy(image.words.data(), data.get(), image.words.size() * sizeof(uint32_t));
  return image;
}

// stb_image 2.27 (Debian's) builds a JPEG Huffman table of as many codes as its 16 counts sum to, up to
// 4080, into arrays of 256 (fuzz_texture: UBSan, index 257 out of bounds in stbi__build_huffman; stb_image
// 2.28 refuses the table). The segments are walked here as stb_image reads them, and such a table refused.
void check_jpeg_huffman_tables(const std::string& name, const std::string& bytes) {
  const size_t n = bytes.size();
  auto byte = [&](size_t i) -> unsigned { return i < n ? static_cast<unsigned char>(bytes[i]) : 0u; };  // 0 past the end, as stb
  size_t at = 2;  // after SOI
  while (at < n) {
    // The next marker: 0xFF, fill bytes 0xFF, then its code.
    while (at < n && byte(at) != 0xFF) ++at;
    while (at < n && byte(at) == 0xFF) ++at;
    if (at >= n) return;
    const unsigned marker = byte(at++);
    if (marker == 0xD9) return;                                               // EOI
    if (marker == 0x00 || marker == 0x01 || (marker >= 0xD0 && marker <= 0xD8)) continue;  // no length
    const size_t length = byte(at) << 8 | byte(at + 1);
    if (marker != 0xC4) {
      at += length;
      if (marker == 0xDA)  // SOS: the entropy-coded data, to the next marker (0xFF not followed by 0 or RSTn)
        while (at + 1 < n && !(byte(at) == 0xFF && byte(at + 1) != 0 && !(byte(at + 1) >= 0xD0 && byte(at + 1) <= 0xD7))) ++at;
      continue;
    }
    long left = long(length) - 2;  // DHT: tables while stb_image's count of the segment's bytes is positive
    at += 2;
    while (left > 0) {
      size_t codes = 0;
      for (size_t i = 0; i < 16; ++i) codes += byte(at + 1 + i);
      if (codes > 256)
        throw SceneError(name + ": corrupt JPEG image: a Huffman table of " + std::to_string(codes) +
                         " codes (at most 256)");
      at += 17 + codes;
      left -= long(17 + codes);
      if (at >= n) return;
    }
    if (left != 0) return;  // stb_image refuses the segment
  }
}

// Image formats pathcl does not read (stb_image could read some of them: GIF's palettes, Photoshop's
// layers and PNM are not what users bring as textures), by how their files begin and by extension.
struct ImageFormat {
  const char* name;
  std::vector<std::string> extensions, starts;
};
const ImageFormat kOtherImageFormats[] = {
    {"GIF", {".gif"}, {"GIF87a", "GIF89a"}},
    {"TIFF", {".tif", ".tiff"}, {std::string("II*\0", 4), std::string("MM\0*", 4)}},
    {"WebP", {".webp"}, {}},
    {"Photoshop", {".psd"}, {"8BPS"}},
    {"DDS", {".dds"}, {"DDS "}},
    {"KTX", {".ktx", ".ktx2"}, {"\xabKTX"}},
    {"PFM", {".pfm"}, {"PF\n", "Pf\n"}},
    {"PNM", {".ppm", ".pgm", ".pnm", ".pbm"}, {}},
    {"JPEG 2000", {".jp2", ".j2k"}, {std::string("\0\0\0\x0cjP  ", 8)}},
    {"HEIF", {".heic", ".heif", ".avif"}, {}},
};

// Whether the file begins like one of kOtherImageFormats.
bool is_other_image_format(const std::string& head) {
  for (const ImageFormat& f : kOtherImageFormats)
    for (const std::string& s : f.starts)
      if (head.rfind(s, 0) == 0) return true;
  return false;
}

// Names the format of an image pathcl does not read, by content, then by extension.
[[noreturn]] void refuse_image_format(const std::string& path, const std::string& head) {
  const char* accepted =
      " (expected PNG, JPEG, BMP, TGA, Radiance HDR or OpenEXR: .png, .jpg, .jpeg, .bmp, .tga, .hdr or .exr)";
  const std::string ext = lower_extension(path);
  for (const ImageFormat& f : kOtherImageFormats)
    for (const std::string& s : f.starts)
      if (head.rfind(s, 0) == 0) throw SceneError(path + ": " + f.name + " images are not supported" + accepted);
  for (const ImageFormat& f : kOtherImageFormats)
    for (const std::string& e : f.extensions)
      if (ext == e) throw SceneError(path + ": " + f.name + " images are not supported" + accepted);
  throw SceneError(path + ": unrecognised image format" + accepted);
}

}  // namespace

namespace {

bool starts_with(const std::string& bytes, const char* magic) { return bytes.rfind(magic, 0) == 0; }

// Every format but OpenEXR (which OpenEXR reads from the file), told by the content, which is what the
// readers go by, not by the name; TGA files have no signature, so a .tga `name` that is no other format
// is read as TGA. Checks the texels of linear formats.
TextureImage decode_not_exr(const std::string& name, const std::string& bytes) {
  TextureImage image;
  if (starts_with(bytes, "\x89PNG\r\n\x1a\n"))
    image = decode_stb(name, bytes, "PNG", false);
  else if (starts_with(bytes, "\xff\xd8\xff"))
    check_jpeg_huffman_tables(name, bytes), image = decode_stb(name, bytes, "JPEG", false);
  else if (starts_with(bytes, "BM"))
    image = decode_stb(name, bytes, "BMP", false);
  else if (starts_with(bytes, "#?RADIANCE") || starts_with(bytes, "#?RGBE"))
    image = decode_stb(name, bytes, "Radiance HDR", true);
  else if (lower_extension(name) == ".tga" && !is_other_image_format(bytes.substr(0, 64)))
    image = decode_stb(name, bytes, "TGA", false);
  else
    refuse_image_format(name, bytes.substr(0, 64));
  return image;
}

// Linear texels (OpenEXR, Radiance HDR) must be finite and non-negative.
void check_texels(const std::string& name, const TextureImage& image) {
  if (image.format == PC_TEXELS_SRGB8) return;
  for (size_t i = 0, n = size_t(image.width) * image.height; i < n; ++i) {
    glm::vec3 t = texel_linear(image, i);
    if (!(std::isfinite(t.x) && std::isfinite(t.y) && std::isfinite(t.z)) || t.x < 0 || t.y < 0 || t.z < 0)
      throw SceneError(name + ": texels must be finite and non-negative");
  }
}

}  // namespace

TextureImage load_texture_image(const std::string& path) {
  const std::string head = read_input_file(path, kImageInput, 64);
  TextureImage image = starts_with(head, "\x76\x2f\x31\x01") ? load_exr(path)
                                                             : decode_not_exr(path, read_input_file(path, kImageInput));
  check_texels(path, image);
  image.file = path;
  return image;
}

TextureImage decode_texture_image(const std::string& name, const std::string& bytes) {
  if (starts_with(bytes, "\x76\x2f\x31\x01"))
    throw SceneError(name + ": an embedded OpenEXR image is not supported (OpenEXR images are read from files)");
  TextureImage image = decode_not_exr(name, bytes);
  check_texels(name, image);
  image.file = name;
  return image;
}

TextureImage checkerboard_texture(glm::vec3 color0, glm::vec3 color1, glm::vec2 tiles, glm::vec2 offset) {
  // An offset of 2 tiles gives the same pattern; reduced modulo 2 exactly, in double.
  for (int a = 0; a < 2; ++a) offset[a] = float(double(offset[a]) - 2.0 * std::floor(double(offset[a]) / 2.0));
  const float values[10] = {color0.x, color0.y, color0.z, color1.x, color1.y, color1.z,
                            tiles.x,  tiles.y,  offset.x, offset.y};
  TextureImage image;
  image.width = 2;
  image.height = 1;
  image.format = PC_TEXELS_CHECKER;
  image.words.resize(10);
  std::memcpy(image.words.data(), values, sizeof values);
  std::ostringstream name;  // the exact floats: equal checkerboards share one texture
  name.precision(9);
  name << "checkerboard (color0";
  for (int k = 0; k < 10; ++k) {
    if (k == 3) name << "; color1";
    if (k == 6) name << "; tiles";
    if (k == 8) name << "; offset";
    name << ' ' << values[k];
  }
  name << ')';
  image.file = name.str();
  return image;
}

glm::vec3 texel_linear(const TextureImage& image, size_t i) {
  const char* bytes = reinterpret_cast<const char*>(image.words.data());
  if (image.format == PC_TEXELS_SRGB8) {
    const unsigned char* b = reinterpret_cast<const unsigned char*>(bytes + 4 * i);
    return {kSrgbToLinear[b[0]], kSrgbToLinear[b[1]], kSrgbToLinear[b[2]]};
  }
  if (image.format == PC_TEXELS_HALF) {
    uint16_t h[3];
    std::memcpy(h, bytes + 6 * i, 6);
    half r, g, b;
    r.setBits(h[0]);
    g.setBits(h[1]);
    b.setBits(h[2]);
    return {float(r), float(g), float(b)};
  }
  float f[3];  // FLOAT, and a checkerboard's two colours
  std::memcpy(f, bytes + 12 * i, 12);
  return {f[0], f[1], f[2]};
}

glm::vec3 texel_nearest(const TextureImage& image, glm::vec2 uv) {
  if (image.format == PC_TEXELS_CHECKER) {  // as kernels/texture.cl's checker_lookup, in the same float steps
    float w[10];
    std::memcpy(w, image.words.data(), sizeof w);
    const float s[2] = {0.5f * (uv.x * w[6] + w[8]), 0.5f * ((1.0f - uv.y) * w[7] + w[9])};
    const bool upper_u = s[0] - std::floor(s[0]) > 0.5f, upper_v = s[1] - std::floor(s[1]) > 0.5f;
    return texel_linear(image, upper_u == upper_v ? 0 : 1);
  }
  // Texel coordinates with the texel centres at half-integers, as kernels/texture.cl places them.
  auto index = [&](float t, uint32_t n) {
    double x = std::floor(double(t) * n);
    // NaN (a coordinate not finite) takes texel 0, as the wrapped modes below do (fuzz_texture: the clamp
    // passed NaN through to the integer conversion, undefined behaviour).
    if (image.wrap == PC_WRAP_CLAMP) return x >= 0 ? uint32_t(std::min(x, double(n - 1))) : 0u;
    double period = image.wrap == PC_WRAP_MIRROR ? 2.0 * n : n;
    double m = x - period * std::floor(x / period);
    if (!(m >= 0 && m < period)) m = 0;  // not finite
    return uint32_t(m >= n ? period - 1 - m : m);
  };
  uint32_t x = index(uv.x, image.width), y = image.height - 1 - index(uv.y, image.height);
  return texel_linear(image, size_t(y) * image.width + x);
}

float srgb_to_linear(double encoded) {
  const double c = encoded > 0 ? std::min(encoded, 1.0) : 0.0;  // NaN too becomes 0
  return float(c <= 0.04045 ? c / 12.92 : std::pow((c + 0.055) / 1.055, 2.4));
}

size_t clamp_texels_to_one(TextureImage& image) {
  if (image.format == PC_TEXELS_SRGB8) return 0;
  size_t clamped = 0;
  char* bytes = reinterpret_cast<char*>(image.words.data());
  for (size_t i = 0, n = size_t(image.width) * image.height; i < n; ++i) {
    glm::vec3 t = texel_linear(image, i);
    if (!(t.x > 1 || t.y > 1 || t.z > 1)) continue;
    ++clamped;
    for (int c = 0; c < 3; ++c) {
      if (!(t[c] > 1)) continue;
      if (image.format == PC_TEXELS_HALF) {
        uint16_t one = half(1.0f).bits();
        std::memcpy(bytes + 6 * i + 2 * c, &one, 2);
      } else {
        float one = 1.0f;
        std::memcpy(bytes + 12 * i + 4 * c, &one, 4);
      }
    }
  }
  return clamped;
}
