// Image textures: bilinear lookup and wrap modes on the device, sRGB decoding, reflectance clamping, and
// textured surfaces rendered under a uniform sky, where a diffuse surface that sees only the sky
// reflects exactly its reflectance times the sky's radiance. Checkerboards: the tile at each uv on the
// device and the host, rendered tiles and cut-outs, and the JSON's checks.
#include <array>
#include <cmath>
#include <cstring>
#include <functional>
#include <random>
#include <sstream>

#include <ImfRgbaFile.h>
#include <Imath/half.h>
#include <stb_image_write.h>

#include <gtest/gtest.h>

#include "runtime/image_io.h"
#include "scene/device_scene_build.h"
#include "scene/scene_error.h"
#include "scene/texture_load.h"
#include "test_support.h"

namespace {

// The sRGB transfer function (IEC 61966-2-1), decoding an 8-bit value to linear.
double srgb_decode(int byte) {
  double c = byte / 255.0;
  return c <= 0.04045 ? c / 12.92 : std::pow((c + 0.055) / 1.055, 2.4);
}

// ---- Device lookups ----------------------------------------------------------------------------------

struct HostTexture {
  uint32_t width, height, wrap;
  std::vector<glm::vec3> texels;  // rows from the top
  glm::vec3 at(int x, int y) const { return texels[size_t(y) * width + x]; }
};

// A float texture image (PC_TEXELS_FLOAT) of a host texture.
TextureImage float_image(const HostTexture& t) {
  TextureImage image;
  image.width = t.width;
  image.height = t.height;
  image.wrap = t.wrap;
  image.format = PC_TEXELS_FLOAT;
  image.words.resize(3 * t.texels.size());
  std::memcpy(image.words.data(), t.texels.data(), image.words.size() * 4);
  return image;
}

// Runs texture_lookup on the device for texture `index` of `textures` at each uv.
std::vector<glm::vec3> device_lookups(const std::vector<TextureImage>& textures, uint32_t index,
                                      const std::vector<glm::vec2>& uvs) {
  ClContext& cl = test_device();
  static KernelProgram program = build_kernel_program(cl, "tests.cl", kernel_options(kFeatureAll));
  std::vector<Texture> headers;
  std::vector<pc_uint> texels;
  for (const TextureImage& t : textures) {
    headers.push_back({t.width, t.height, uint32_t(texels.size()), t.wrap, t.format, {}});
    texels.insert(texels.end(), t.words.begin(), t.words.end());
  }
  std::vector<float> flat;
  for (const glm::vec2& uv : uvs) flat.insert(flat.end(), {uv.x, uv.y});
  ClBuffer tb = upload(cl, headers), xb = upload(cl, texels), ub = upload(cl, flat);
  ClBuffer out(cl, CL_MEM_WRITE_ONLY, uvs.size() * sizeof(pc_float4));
  ClKernel k(program.kernel("texture_lookup_test"));
  k.arg(0, tb.mem);
  k.arg(1, xb.mem);
  k.arg(2, index);
  k.arg(3, ub.mem);
  k.arg(4, out.mem);
  run_kernel(cl, k.k, uvs.size());
  std::vector<pc_float4> values(uvs.size());
  CL_CHECK(clEnqueueReadBuffer(cl.queue, out.mem, CL_TRUE, 0, values.size() * sizeof(pc_float4), values.data(), 0,
                               nullptr, nullptr));
  std::vector<glm::vec3> result;
  for (const pc_float4& v : values) result.push_back({v.x, v.y, v.z});
  return result;
}

// A 4 x 3 texture whose texels all differ: (column, row, 1 + column * row).
HostTexture grid_texture(uint32_t wrap) {
  HostTexture t{4, 3, wrap, {}};
  for (int y = 0; y < 3; ++y)
    for (int x = 0; x < 4; ++x) t.texels.push_back({float(x), float(y), float(1 + x * y)});
  return t;
}

// The uv of the centre of texel (x, y), row y counted from the top (v = 0 is the bottom row).
glm::vec2 centre_uv(const HostTexture& t, double x, double y) {
  return {float((x + 0.5) / t.width), float(1.0 - (y + 0.5) / t.height)};
}

void expect_near(const glm::vec3& got, const glm::vec3& want, float tol, const std::string& what) {
  EXPECT_NEAR(got.x, want.x, tol) << what;
  EXPECT_NEAR(got.y, want.y, tol) << what;
  EXPECT_NEAR(got.z, want.z, tol) << what;
}

TEST(TextureLookup, TexelCentresGiveTexelsAndBilinearBetweenThem) {
  HostTexture t = grid_texture(PC_WRAP_CLAMP);
  std::vector<glm::vec2> uvs;
  std::vector<glm::vec3> want;
  for (int y = 0; y < 3; ++y)
    for (int x = 0; x < 4; ++x) {
      uvs.push_back(centre_uv(t, x, y));
      want.push_back(t.at(x, y));
    }
  // Between two centres along u, along v, and a quarter of the way in both (bilinear weights).
  uvs.push_back(centre_uv(t, 1.5, 1));
  want.push_back(0.5f * (t.at(1, 1) + t.at(2, 1)));
  uvs.push_back(centre_uv(t, 2, 0.5));
  want.push_back(0.5f * (t.at(2, 0) + t.at(2, 1)));
  uvs.push_back(centre_uv(t, 0.25, 1.75));
  want.push_back(0.75f * 0.25f * t.at(0, 1) + 0.25f * 0.25f * t.at(1, 1) + 0.75f * 0.75f * t.at(0, 2) +
                 0.25f * 0.75f * t.at(1, 2));
  std::vector<glm::vec3> got = device_lookups({float_image(t)}, 0, uvs);
  for (size_t i = 0; i < uvs.size(); ++i)
    expect_near(got[i], want[i], 1e-5f, "uv (" + std::to_string(uvs[i].x) + ", " + std::to_string(uvs[i].y) + ")");
}

TEST(TextureLookup, WrapModesOutsideTheUnitSquare) {
  // Three textures in one texel array, so offsets are exercised too.
  std::vector<HostTexture> textures = {grid_texture(PC_WRAP_REPEAT), grid_texture(PC_WRAP_CLAMP),
                                       grid_texture(PC_WRAP_MIRROR)};
  const HostTexture& t = textures[0];
  struct Case {
    glm::vec2 uv;
    glm::vec3 repeat, clamp, mirror;
  };
  glm::vec2 c12 = centre_uv(t, 1, 2);  // texel (1, 2)
  std::vector<Case> cases = {
      // One period to the right and two up: the same texel when repeating; clamped to the edge column
      // / row; mirrored across u = 1: column 3 - 1 = 2, and across v = 1 twice (the same row).
      {c12 + glm::vec2(1, 2), t.at(1, 2), t.at(3, 0), t.at(2, 2)},
      // Reflected through u = 0 and v = 0: the next period when repeating, the corner texel when
      // clamping, the same texel when mirroring.
      {glm::vec2(-c12.x, -c12.y), t.at(2, 0), t.at(0, 2), t.at(1, 2)},
      // Far away: 1000 periods to the left.
      {c12 - glm::vec2(1000, 0), t.at(1, 2), t.at(0, 2), t.at(1, 2)},
      // Half a texel beyond the right edge: repeat blends the last column with the first, clamp and
      // mirror give the last column.
      {glm::vec2(1.0f, c12.y), 0.5f * (t.at(3, 2) + t.at(0, 2)), t.at(3, 2), t.at(3, 2)},
  };
  std::vector<glm::vec2> uvs;
  for (const Case& c : cases) uvs.push_back(c.uv);
  std::vector<TextureImage> images;
  for (const HostTexture& h : textures) images.push_back(float_image(h));
  std::vector<glm::vec3> repeat = device_lookups(images, 0, uvs), clamp = device_lookups(images, 1, uvs),
                         mirror = device_lookups(images, 2, uvs);
  for (size_t i = 0; i < cases.size(); ++i) {
    std::string where = "case " + std::to_string(i);
    // 1000 periods away the uv itself is only good to about 6e-5, a few thousandths of a texel.
    float tol = i == 2 ? 2e-2f : 1e-4f;
    expect_near(repeat[i], cases[i].repeat, tol, where + " repeat");
    expect_near(clamp[i], cases[i].clamp, tol, where + " clamp");
    expect_near(mirror[i], cases[i].mirror, tol, where + " mirror");
  }
}

// ---- Image files --------------------------------------------------------------------------------------

const char* const kQuad = R"({"type": "triangles", "positions": [[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]],
      "indices": [[0, 1, 2], [0, 2, 3]], "uvs": [[0, 0], [1, 0], [1, 1], [0, 1]], "material": "m"})";


TEST(TextureFile, PngIsDecodedWithTheSrgbCurveRowsFromTheTop) {
  std::vector<unsigned char> rgb;
  for (int row = 0; row < 2; ++row)
    for (int i = 0; i < 256; ++i) {
      int r = row == 0 ? i : 255 - i;
      rgb.insert(rgb.end(), {(unsigned char)r, (unsigned char)(255 - r), (unsigned char)((37 * i) % 256)});
    }
  TextureImage image = load_texture_image(write_temp_png("srgb.png", 256, 2, rgb));
  ASSERT_EQ(image.width, 256u);
  ASSERT_EQ(image.height, 2u);
  // Stored as the file's bytes, 4 a texel (alpha 255 for an RGB file), decoded by the shared table to
  // the float nearest to the formula.
  ASSERT_EQ(image.format, PC_TEXELS_SRGB8);
  ASSERT_EQ(image.words.size(), 512u);
  for (size_t i = 0; i < 512; ++i) {
    const unsigned char* bytes = reinterpret_cast<const unsigned char*>(&image.words[i]);
    ASSERT_EQ(bytes[3], 255) << "texel " << i;
    for (int c = 0; c < 3; ++c) {
      ASSERT_EQ(bytes[c], rgb[3 * i + c]) << "texel " << i << " channel " << c;
      ASSERT_EQ(texel_linear(image, i)[c], float(srgb_decode(rgb[3 * i + c]))) << "texel " << i << " channel " << c;
    }
  }
}

// ---- Texel formats on the device ----------------------------------------------------------------------

// A w x h image of `format` whose texels hold the given linear values (exactly representable in it).
TextureImage image_of(uint32_t format, uint32_t w, uint32_t h, const std::vector<glm::vec3>& values) {
  TextureImage image;
  image.width = w;
  image.height = h;
  image.wrap = PC_WRAP_REPEAT;
  image.format = format;
  if (format == PC_TEXELS_FLOAT) {
    image.words.resize(3 * values.size());
    std::memcpy(image.words.data(), values.data(), 12 * values.size());
  } else if (format == PC_TEXELS_HALF) {
    std::vector<uint16_t> halves;
    for (const glm::vec3& v : values)
      for (int c = 0; c < 3; ++c) halves.push_back(half(v[c]).bits());
    image.words.resize((halves.size() + 1) / 2);
    std::memcpy(image.words.data(), halves.data(), 2 * halves.size());
  }
  return image;
}

// The same texels as 8-bit sRGB, half and float textures (one texel array, so offsets and the half
// image's odd length are exercised) give bit-identical lookups: the decoding is exact and the bilinear
// arithmetic is the same, so an 8-bit texture renders exactly as the float image of its decoded values.
TEST(TextureLookup, SrgbHalfAndFloatTexelsGiveTheSameLookups) {
  const uint32_t w = 5, h = 3;
  TextureImage srgb;
  srgb.width = w;
  srgb.height = h;
  srgb.format = PC_TEXELS_SRGB8;
  std::vector<glm::vec3> values;
  for (uint32_t i = 0; i < w * h; ++i) {
    unsigned char b[4] = {(unsigned char)(17 * i), (unsigned char)(255 - 13 * i), (unsigned char)(i * i), 0};
    uint32_t word;
    std::memcpy(&word, b, 4);
    srgb.words.push_back(word);
    values.push_back(texel_linear(srgb, i));
  }
  // Halves hold sRGB-decoded floats only approximately: the half image gets values halves hold exactly.
  std::vector<glm::vec3> half_values;
  for (const glm::vec3& v : values) half_values.push_back({float(half(v.x)), float(half(v.y)), float(half(v.z))});
  std::vector<TextureImage> images = {image_of(PC_TEXELS_FLOAT, w, h, half_values), srgb,
                                      image_of(PC_TEXELS_HALF, w, h, half_values), image_of(PC_TEXELS_FLOAT, w, h, values)};
  std::vector<glm::vec2> uvs;
  for (int i = 0; i < 64; ++i) uvs.push_back({0.37f * float(i) - 3.0f, 0.113f * float(i * i % 29) - 1.0f});
  std::vector<glm::vec3> from_float = device_lookups(images, 3, uvs), from_srgb = device_lookups(images, 1, uvs);
  std::vector<glm::vec3> from_half = device_lookups(images, 2, uvs), from_half_float = device_lookups(images, 0, uvs);
  for (size_t i = 0; i < uvs.size(); ++i)
    for (int c = 0; c < 3; ++c) {
      ASSERT_EQ(from_srgb[i][c], from_float[i][c]) << "uv " << i << " channel " << c;
      ASSERT_EQ(from_half[i][c], from_half_float[i][c]) << "uv " << i << " channel " << c;
    }
  // And at texel centres, the texel itself (within the rounding of the float uv of a centre).
  std::vector<glm::vec2> centres;
  for (uint32_t y = 0; y < h; ++y)
    for (uint32_t x = 0; x < w; ++x) centres.push_back({(x + 0.5f) / w, 1.0f - (y + 0.5f) / h});
  std::vector<glm::vec3> at_centres = device_lookups(images, 1, centres);
  for (size_t i = 0; i < centres.size(); ++i) expect_near(at_centres[i], values[i], 1e-6f, "texel " + std::to_string(i));
}

// The host's texel bytes for a large texture, and that the device scene takes them without a copy.
TEST(TextureFile, TexelsAreStoredAtTheFilesPrecisionAndHeldOnceOnTheHost) {
  const int w = 1024, h = 512;
  std::vector<unsigned char> rgb(size_t(w) * h * 3);
  for (size_t i = 0; i < rgb.size(); ++i) rgb[i] = (unsigned char)(i * 7919 % 251);
  write_temp_png("big/big.png", w, h, rgb);
  Image exr;
  exr.width = w;
  exr.height = h;
  exr.rgb.assign(size_t(w) * h * 3, 0.5f);
  write_exr(temp_dir() + "/big/big.exr", exr);
  std::string json = R"({"camera": {"position": [0, 0, 3], "look_at": [0, 0, 0], "width": 4, "height": 4},
    "materials": {"m": {"type": "diffuse", "reflectance": {"texture": "big/big.png"}}},
    "shapes": [)" + std::string(kQuad) + R"(], "lights": [{"type": "environment", "file": "big/big.exr"}]})";
  SceneDescription scene = load_scene(write_temp_file("big.json", json));
  ASSERT_EQ(scene.textures.size(), 2u);
  const size_t texels = size_t(w) * h;
  EXPECT_EQ(scene.textures[0].words.size() * 4, 4 * texels);   // 8-bit sRGB: 4 bytes a texel (was 16)
  EXPECT_EQ(scene.textures[1].words.size() * 4, 12 * texels);  // 32-bit float EXR: 12 bytes a texel (was 16)
  DeviceScene copied = build_device_scene(scene);
  EXPECT_EQ(copied.texels.size() * 4, 16 * texels);
  DeviceScene taken = build_device_scene_taking_texels(scene);
  EXPECT_EQ(taken.texels, copied.texels);
  EXPECT_TRUE(scene.textures[0].words.empty() && scene.textures[1].words.empty());
  EXPECT_EQ(taken.textures[1].offset, texels);
  EXPECT_EQ(taken.textures[1].format, PC_TEXELS_FLOAT);
  std::printf("  %d x %d: 8-bit texture %zu bytes, float texture %zu bytes, device texel array %zu bytes\n", w, h,
              4 * texels, 12 * texels, taken.texels.size() * 4);
}

TEST(TextureFile, ExrReflectanceAboveOneIsClampedWithAWarningButAnEnvironmentMapIsNot) {
  Image exr;
  exr.width = 2;
  exr.height = 1;
  exr.rgb = {2.0f, 0.5f, 1.0f, 0.25f, 3.0f, 0.0f};
  std::string file = temp_dir() + "/bright.exr";
  write_exr(file, exr);
  // The same file as a reflectance texture and as an environment map.
  std::string text = R"({"camera": {"position": [0, 0, 3], "look_at": [0, 0, 0], "width": 4, "height": 4},
    "materials": {"m": {"type": "diffuse", "reflectance": {"texture": "bright.exr", "wrap": "clamp"}}},
    "shapes": [)" + std::string(kQuad) + R"(], "lights": [{"type": "environment", "file": "bright.exr"}]})";
  SceneDescription scene = load_scene(write_temp_file("bright.json", text));
  ASSERT_EQ(scene.textures.size(), 2u);
  const TextureImage& reflectance = scene.textures[scene.materials[0].color_texture];
  EXPECT_TRUE(reflectance.reflectance);
  EXPECT_EQ(reflectance.wrap, PC_WRAP_CLAMP);
  EXPECT_EQ(texel_linear(reflectance, 0), glm::vec3(1.0f, 0.5f, 1.0f));
  EXPECT_EQ(texel_linear(reflectance, 1), glm::vec3(0.25f, 1.0f, 0.0f));
  const TextureImage& env = scene.textures[scene.lights[0].texture];
  EXPECT_FALSE(env.reflectance);
  EXPECT_EQ(texel_linear(env, 0).x, 2.0f);
  ASSERT_EQ(scene.warnings.size(), 1u);
  EXPECT_NE(scene.warnings[0].find("materials.m.reflectance.texture"), std::string::npos) << scene.warnings[0];
  EXPECT_NE(scene.warnings[0].find("2 texels above 1 clamped to 1"), std::string::npos) << scene.warnings[0];
  EXPECT_EQ(scene.materials[0].color, glm::vec3(1));
}

// A PNG whose header claims width x height (its pixel data are missing: only the header is read).
std::string png_header_only(const std::string& name, uint32_t width, uint32_t height) {
  auto be32 = [](uint32_t v) {
    return std::string{char(v >> 24), char(v >> 16), char(v >> 8), char(v)};
  };
  // stb_image does not check CRCs, so they are left 0.
  std::string ihdr = be32(13) + "IHDR" + be32(width) + be32(height) + std::string("\x08\x02\x00\x00\x00", 5) + be32(0);
  return write_temp_file(name, std::string("\x89PNG\r\n\x1a\n", 8) + ihdr + be32(0) + "IEND" + be32(0));
}

// Images beyond 2^28 texels (3 GiB as float texels) are refused from their header, before decoding.
TEST(TextureFile, ImagesBeyondTheTexelLimitAreRefusedFromTheirHeader) {
  std::string path = png_header_only("huge.png", 16384, 16385);
  try {
    load_texture_image(path);
    ADD_FAILURE() << "expected a SceneError";
  } catch (const SceneError& e) {
    EXPECT_EQ(std::string(e.what()),
              path + ": an image of 16384 x 16385 texels is larger than the largest of 268435456 texels");
  }
}

// TGA (plain and run-length encoded) and BMP files load to the same bytes as the PNG of the same pixels.
TEST(TextureFile, TgaAndBmpGiveThePngsTexels) {
  const int w = 37, h = 5;  // rows of 37 * 3 bytes: BMP pads them to 4
  std::vector<unsigned char> rgb(size_t(w) * h * 3);
  for (size_t i = 0; i < rgb.size(); ++i) rgb[i] = (unsigned char)(i * 31 % 256 / (i % 5 == 0 ? 64 : 1));
  TextureImage png = load_texture_image(write_temp_png("images/pixels.png", w, h, rgb));
  ASSERT_EQ(png.format, PC_TEXELS_SRGB8);
  std::string dir = temp_dir() + "/images/";
  stbi_write_tga_with_rle = 0;
  ASSERT_TRUE(stbi_write_tga((dir + "plain.tga").c_str(), w, h, 3, rgb.data()));
  stbi_write_tga_with_rle = 1;
  ASSERT_TRUE(stbi_write_tga((dir + "rle.TGA").c_str(), w, h, 3, rgb.data()));
  ASSERT_TRUE(stbi_write_bmp((dir + "pixels.bmp").c_str(), w, h, 3, rgb.data()));
  for (const char* name : {"plain.tga", "rle.TGA", "pixels.bmp"}) {
    TextureImage t = load_texture_image(dir + name);
    EXPECT_EQ(t.width, uint32_t(w)) << name;
    EXPECT_EQ(t.height, uint32_t(h)) << name;
    EXPECT_EQ(t.format, PC_TEXELS_SRGB8) << name;
    EXPECT_EQ(t.words, png.words) << name;
  }
}

// A Radiance HDR file loads to the same floats as the 32-bit EXR of the same pixels. The values are
// those RGBE holds exactly (8-bit mantissas under the largest channel's exponent), over 60 octaves, far
// beyond half's range; widths 5 and 40 are written without and with run-length encoding.
TEST(TextureFile, RadianceHdrGivesTheExrsTexels) {
  for (int w : {5, 40}) {
    const int h = 3;
    std::vector<float> rgb;
    std::mt19937 gen{uint32_t(w)};
    for (int i = 0; i < w * h; ++i) {
      int exponent = int(gen() % 60) - 30;
      unsigned char b[3] = {(unsigned char)(128 + gen() % 128), (unsigned char)(gen() % 256), (unsigned char)(gen() % 256)};
      for (int c = 0; c < 3; ++c) rgb.push_back(std::ldexp(float(b[(c + i) % 3]), exponent - 8));
    }
    std::string hdr = temp_dir() + "/images/sky" + std::to_string(w) + ".hdr";
    ASSERT_TRUE(stbi_write_hdr(hdr.c_str(), w, h, 3, rgb.data()));
    Image exr;
    exr.width = uint32_t(w);
    exr.height = uint32_t(h);
    exr.rgb = rgb;
    write_exr(temp_dir() + "/images/sky.exr", exr);
    TextureImage from_hdr = load_texture_image(hdr), from_exr = load_texture_image(temp_dir() + "/images/sky.exr");
    ASSERT_EQ(from_hdr.format, PC_TEXELS_FLOAT);
    ASSERT_EQ(from_exr.format, PC_TEXELS_FLOAT);
    EXPECT_EQ(from_hdr.width, uint32_t(w));
    EXPECT_EQ(from_hdr.words, from_exr.words) << "width " << w;
    for (int i = 0; i < w * h; ++i)
      for (int c = 0; c < 3; ++c) ASSERT_EQ(texel_linear(from_hdr, i)[c], rgb[3 * i + c]) << "texel " << i;
  }
}

// A half-float EXR is kept as halves, 6 bytes a texel.
TEST(TextureFile, HalfExrIsKeptAsHalves) {
  const int w = 3, h = 1;
  std::string path = temp_dir() + "/images/half.exr";
  Imf::Rgba pixels[3] = {{half(0.5f), half(2.0f), half(60000.0f), half(1.0f)},
                         {half(1e-3f), half(0.0f), half(3.25f), half(1.0f)},
                         {half(7.0f), half(0.1f), half(0.2f), half(1.0f)}};
  {
    Imf::RgbaOutputFile out(path.c_str(), w, h, Imf::WRITE_RGB);
    out.setFrameBuffer(pixels, 1, w);
    out.writePixels(h);
  }
  TextureImage t = load_texture_image(path);
  ASSERT_EQ(t.format, PC_TEXELS_HALF);
  EXPECT_EQ(t.words.size(), 5u);  // 9 halves
  for (int i = 0; i < 3; ++i)
    EXPECT_EQ(texel_linear(t, i), glm::vec3(float(pixels[i].r), float(pixels[i].g), float(pixels[i].b))) << i;
}

// Images are recognised by content: another format is named, with the formats accepted; an undecodable
// file is corrupt or truncated, in our words rather than stb_image's ("unknown image type", "bad IHDR
// len") or OpenEXR's.
TEST(TextureFile, OtherFormatsAndBrokenFilesAreNamed) {
  std::string png = read_text_file(write_temp_png("formats/real.png", 2, 1, {255, 0, 0, 0, 255, 0}));
  const std::string accepted =
      " (expected PNG, JPEG, BMP, TGA, Radiance HDR or OpenEXR: .png, .jpg, .jpeg, .bmp, .tga, .hdr or .exr)";
  struct Case {
    std::string file, content, expected;  // expected "" = it loads
  } cases[] = {
      {"anim.gif", "GIF89a\x01\x00\x01\x00", "GIF images are not supported" + accepted},
      {"gif-inside.png", "GIF87a\x01\x00\x01\x00", "GIF images are not supported" + accepted},
      {"sky.hdr", "#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n", "cannot decode the Radiance HDR image (corrupt or truncated)"},
      {"old.tga", std::string("\x00\x00\x02\x00", 4), "cannot decode the TGA image (corrupt or truncated)"},
      {"old.bmp", "BM\x10\x00", "cannot decode the BMP image (corrupt or truncated)"},
      {"gif-inside.tga", "GIF89a\x01\x00\x01\x00", "GIF images are not supported" + accepted},
      {"layers.psd", "8BPS\x00\x01", "Photoshop images are not supported" + accepted},
      {"notes.bmp", "not a bitmap", "unrecognised image format" + accepted},
      {"scan.tiff", std::string("II*\x00", 4), "TIFF images are not supported" + accepted},
      {"notes.png", "these are not pixels", "unrecognised image format" + accepted},
      {"empty.png", "", "unrecognised image format" + accepted},
      {"lfs.png", "version https://git-lfs.github.com/spec/v1\noid sha256:00\nsize 1\n",
       "looks like a Git LFS pointer, not an image (run git lfs pull)"},
      {"truncated.png", png.substr(0, 40), "cannot decode the PNG image (corrupt or truncated)"},
      {"truncated.exr", std::string("\x76\x2f\x31\x01\x02\x00\x00\x00", 8), "cannot decode the OpenEXR image (corrupt or truncated)"},
      {"png-inside.jpg", png, ""},
  };
  for (const Case& c : cases) {
    std::string path = write_temp_file("formats/" + c.file, c.content);
    std::string error;
    try {
      load_texture_image(path);
    } catch (const SceneError& e) {
      error = e.what();
    }
    EXPECT_EQ(error, c.expected.empty() ? "" : path + ": " + c.expected) << c.file;
  }
}

// ---- Rendering -------------------------------------------------------------------------------------

// A 4 x 4 texture of 2 x 2 blocks, four colours given as sRGB bytes; block (column, row from the top).
const unsigned char kBlockBytes[2][2][3] = {{{200, 40, 40}, {40, 40, 200}}, {{40, 200, 40}, {230, 220, 60}}};

std::string write_block_png() {
  std::vector<unsigned char> rgb;
  for (int y = 0; y < 4; ++y)
    for (int x = 0; x < 4; ++x)
      for (int c = 0; c < 3; ++c) rgb.push_back(kBlockBytes[x / 2][y / 2][c]);
  return write_temp_png("blocks.png", 4, 4, rgb);
}

// The mean over [a, b] of the weight of the second block along one axis of the block texture under
// bilinear filtering with clamping: 0 up to the first block's last texel centre (0.375), 1 from the
// second block's first centre (0.625), linear between.
double mean_ramp(double a, double b) {
  const double c0 = 0.375, c1 = 0.625, len = c1 - c0;
  auto integral = [&](double u) {  // of the ramp from 0 to u
    if (u <= c0) return 0.0;
    if (u <= c1) return (u - c0) * (u - c0) / (2 * len);
    return len / 2 + (u - c1);
  };
  return (integral(b) - integral(a)) / (b - a);
}

// Renders a head-on view of the square [-1, 1]^2 at z = 0 that exactly fills a width x width film,
// with the square's material textured by the block texture, under a sky of radiance 1 with one
// scattering event, and checks every pixel against the texture's mean over the pixel's footprint.
// mirrored_u: the texture appears mirrored left to right.
void expect_textured_square(const std::string& shape_json, bool mirrored_u, const std::string& name) {
  const int width = 16;
  const double distance = 1.0 / std::tan(20.0 * M_PI / 180.0);  // fov 40 degrees covers [-1, 1]
  std::ostringstream scene;
  scene.precision(17);
  scene << R"({"camera": {"position": [0, 0, )" << distance << R"(], "look_at": [0, 0, 0], "fov_y_degrees": 40,
    "width": )" << width << R"(, "height": )" << width << R"(},
    "materials": {"m": {"type": "diffuse", "reflectance": {"texture": "blocks.png", "wrap": "clamp"}}},
    "shapes": [)" << shape_json << R"(], "lights": [{"type": "environment", "radiance": [1, 1, 1]}]})";
  write_block_png();
  DeviceScene d = load_device_scene(write_temp_file(name + ".json", scene.str()));
  ASSERT_TRUE(d.features & kFeatureTextures);
  RenderOptions opt;
  opt.spp = 256;
  opt.max_depth = 1;
  opt.seed = 7;
  RenderResult r = render(test_device(), d, opt);
  EXPECT_EQ(r.nan_samples + r.inf_samples + r.negative_samples, 0u);

  double sum_diff = 0, sum_var = 0;
  int beyond_3 = 0;
  for (int py = 0; py < width; ++py)
    for (int px = 0; px < width; ++px) {
      double u0 = double(px) / width, u1 = double(px + 1) / width;
      if (mirrored_u) std::tie(u0, u1) = std::make_pair(1 - u1, 1 - u0);
      double right = mean_ramp(u0, u1);                                      // weight of block column 1
      double top = mean_ramp(1 - double(py + 1) / width, 1 - double(py) / width);  // weight of block row 0
      for (int c = 0; c < 3; ++c) {
        double want = 0;
        for (int bx = 0; bx < 2; ++bx)
          for (int by = 0; by < 2; ++by)
            want += (bx ? right : 1 - right) * (by ? 1 - top : top) * srgb_decode(kBlockBytes[bx][by][c]);
        size_t i = 3 * (size_t(py) * width + px) + c;
        double got = r.film.mean[i], var = r.film.variance[i];
        ASSERT_GT(var, 0) << name << " pixel " << px << "," << py;
        double z = (got - want) / std::sqrt(var);
        EXPECT_LT(std::abs(z), 5.0) << name << " pixel " << px << "," << py << " channel " << c << ": " << got
                                    << " expected " << want;
        beyond_3 += std::abs(z) > 3;
        sum_diff += got - want;
        sum_var += var;
      }
    }
  // All pixels together: within 4 standard errors, and no more pixels beyond 3 than chance allows
  // (0.27% of 768, about 2).
  EXPECT_LT(std::abs(sum_diff) / std::sqrt(sum_var), 4.0) << name;
  EXPECT_LE(beyond_3, 10) << name;
}

TEST(TextureRender, InlineTrianglesWithUvsReflectTheTextureTimesTheSky) {
  expect_textured_square(kQuad, false, "square-inline");
}

TEST(TextureRender, ObjQuadWithTexcoordsReflectsTheTextureTimesTheSky) {
  // The vt order differs from the v order; the quad is triangulated by the clean-up.
  write_temp_file("square.obj", "v -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\nvt 1 1\nvt 0 0\nvt 1 0\nvt 0 1\n"
                                "f 1/2 2/3 3/1 4/4\n");
  expect_textured_square(R"({"type": "mesh", "file": "square.obj", "material": "m"})", false, "square-obj");
}

// An 8-bit texture renders exactly as the 32-bit float EXR of its decoded texels: bit for bit, since
// the device decodes the bytes to those same floats and filters them by the same arithmetic. (Before
// texels were kept at their file's precision, the host decoded them with powf in float arithmetic,
// up to a few ulps from the nearest float that the shared table now holds: the images of that time
// differ from these by that rounding, far below the noise.)
TEST(TextureRender, EightBitTextureRendersExactlyAsTheFloatImageOfItsTexels) {
  TextureImage png = load_texture_image(write_block_png());
  Image exr;
  exr.width = png.width;
  exr.height = png.height;
  for (size_t i = 0; i < size_t(png.width) * png.height; ++i) {
    glm::vec3 t = texel_linear(png, i);
    exr.rgb.insert(exr.rgb.end(), {t.x, t.y, t.z});
  }
  write_exr(temp_dir() + "/blocks.exr", exr);
  std::vector<float> images[2];
  for (int k = 0; k < 2; ++k) {
    std::string json = R"({"camera": {"position": [0.3, 0.2, 2.5], "look_at": [0, 0, 0], "width": 16, "height": 16},
      "materials": {"m": {"type": "diffuse", "reflectance": {"texture": ")" + std::string(k ? "blocks.exr" : "blocks.png") +
                       R"(", "wrap": "mirror"}}},
      "shapes": [)" + std::string(kQuad) + R"(], "lights": [{"type": "environment", "radiance": [1, 1, 1]}]})";
    DeviceScene d = load_device_scene(write_temp_file("blocks-" + std::to_string(k) + ".json", json));
    ASSERT_EQ(d.textures[0].format, k ? PC_TEXELS_FLOAT : PC_TEXELS_SRGB8);
    RenderOptions opt;
    opt.spp = 16;
    opt.max_depth = 2;
    opt.seed = 3;
    images[k] = render(test_device(), d, opt).film.mean;
  }
  ASSERT_EQ(images[0].size(), images[1].size());
  EXPECT_EQ(std::memcmp(images[0].data(), images[1].data(), images[0].size() * sizeof(float)), 0);
}

TEST(TextureRender, MirroringTransformMirrorsTheTexture) {
  // Mirrored in x, the corner with uv (0, 0) is at (1, -1): the image shows the texture mirrored. The
  // loader reverses the winding, and the uvs must go with their corners.
  std::string mirrored = std::string(kQuad);
  mirrored.insert(mirrored.size() - 1, R"(, "transform": {"scale": [-1, 1, 1]})");
  expect_textured_square(mirrored, true, "square-mirrored");
}

// A sphere seen from above the equator (latitude 45 degrees, direction (-0.5, 0.707, 0.5) from its
// centre) through a narrow field of view: every pixel sees one block of an 8 x 4 texture of 2 x 2
// blocks, block (u column, v row from the top) of the lat-long mapping (kernels/integrator.cl):
// u = atan2(-z, x) / (2 pi) = 0.625 -> column 2, v = 1 - 45/180 = 0.75 -> row 0 (a block's middle, so
// that bilinear filtering within the footprint only sees that block). A convex surface under a
// uniform sky reflects its reflectance times the sky: every pixel's mean is the block's colour.
const unsigned char kSphereBlocks[4][2][3] = {{{250, 10, 10}, {10, 250, 10}},
                                              {{10, 10, 250}, {250, 250, 10}},
                                              {{10, 250, 250}, {250, 10, 250}},
                                              {{120, 120, 120}, {250, 250, 250}}};

void expect_sphere_view(const std::string& transform_json, int block_column, int block_row) {
  std::vector<unsigned char> rgb;
  for (int y = 0; y < 4; ++y)
    for (int x = 0; x < 8; ++x)
      for (int c = 0; c < 3; ++c) rgb.push_back(kSphereBlocks[x / 2][y / 2][c]);
  write_temp_png("sphere-blocks.png", 8, 4, rgb);
  std::string scene = R"({"camera": {"position": [-2.5, 3.5355339, 2.5], "look_at": [0, 0, 0], "fov_y_degrees": 2,
      "width": 8, "height": 8},
    "materials": {"m": {"type": "diffuse", "reflectance": {"texture": "sphere-blocks.png"}}},
    "shapes": [{"type": "sphere", "radius": 1, "material": "m")" + transform_json + R"(}],
    "lights": [{"type": "environment", "radiance": [1, 1, 1]}]})";
  DeviceScene d = load_device_scene(write_temp_file("sphere-texture.json", scene));
  RenderOptions opt;
  opt.spp = 64;
  opt.max_depth = 1;
  opt.seed = 3;
  RenderResult r = render(test_device(), d, opt);
  EXPECT_EQ(r.nan_samples + r.inf_samples + r.negative_samples, 0u);
  const size_t pixels = r.film.mean.size() / 3;
  for (int c = 0; c < 3; ++c) {
    const double want = srgb_decode(kSphereBlocks[block_column][block_row][c]);
    double sum_diff = 0, sum_var = 0;
    for (size_t p = 0; p < pixels; ++p) {
      double got = r.film.mean[3 * p + c], var = r.film.variance[3 * p + c];
      EXPECT_LT(std::abs(got - want), 5 * std::sqrt(var)) << transform_json << " pixel " << p << " channel " << c
                                                          << ": " << got << " expected " << want;
      sum_diff += got - want;
      sum_var += var;
    }
    EXPECT_LT(std::abs(sum_diff), 4 * std::sqrt(sum_var)) << transform_json << " channel " << c;
  }
}

TEST(TextureRender, SphereLatLongUvsInItsOwnFrame) {
  expect_sphere_view("", 2, 0);
  // Rotated 90 degrees about y, the same view sees local direction (-0.5, 0.707, -0.5): u = 0.375.
  expect_sphere_view(R"(, "transform": {"rotate": {"axis": [0, 1, 0], "degrees": 90}})", 1, 0);
  // Scaled by -1 (a point reflection), it sees local direction (0.5, -0.707, -0.5): u = 0.125, v = 0.25.
  expect_sphere_view(R"(, "transform": {"scale": -1})", 0, 1);
}


// ---- Checkerboards ------------------------------------------------------------------------------------

const glm::vec3 kColor0(0.75f, 0.25f, 0.125f), kColor1(0.0625f, 0.5f, 0.875f);

// The colour the checkerboard rule gives at (u, v): tile (floor(u tiles + offset), floor((1 - v) tiles +
// offset)), colour 1 where the tile's column plus row is odd. For points away from the tiles' edges.
glm::vec3 checker_colour(glm::dvec2 uv, glm::dvec2 tiles, glm::dvec2 offset) {
  const long long x = (long long)std::floor(uv.x * tiles.x + offset.x), y = (long long)std::floor((1 - uv.y) * tiles.y + offset.y);
  return ((x + y) % 2 + 2) % 2 ? kColor1 : kColor0;
}

// Device lookups of checkerboards beside an image (so that texel offsets are exercised): tile (0, 0), at the
// top left of the uv square (u from 0, v from 1 down, the rows of an image), is color0 and its neighbours along
// u and v are color1; far from the square and at negative uvs the pattern goes on; tiles [3, 5] give 3 columns and
// 5 rows a unit; an offset shifts it by whole and half tiles; the host's texel_nearest agrees everywhere.
TEST(Checkerboard, DeviceLookupsGiveEachTilesColourWithImageOrientation) {
  std::vector<TextureImage> textures = {float_image(grid_texture(PC_WRAP_REPEAT)),
                                        checkerboard_texture(kColor0, kColor1, {2, 2}, {0, 0}),
                                        checkerboard_texture(kColor0, kColor1, {3, 5}, {0, 0}),
                                        checkerboard_texture(kColor0, kColor1, {3, 5}, {-7.5f, 1})};
  EXPECT_EQ(textures[1].format, PC_TEXELS_CHECKER);
  EXPECT_EQ(textures[1].width, 2u);
  EXPECT_EQ(textures[1].height, 1u);
  EXPECT_EQ(textures[1].words.size(), 10u);
  EXPECT_EQ(texel_linear(textures[1], 0), kColor0);
  EXPECT_EQ(texel_linear(textures[1], 1), kColor1);
  // The offset is kept modulo 2 tiles: -7.5 becomes 0.5.
  float offset[2];
  std::memcpy(offset, &textures[3].words[8], 8);
  EXPECT_EQ(offset[0], 0.5f);
  EXPECT_EQ(offset[1], 1.0f);

  // Mitsuba's default pattern, 2 tiles a unit: tile (0, 0) is u in [0, 0.5), v in (0.5, 1].
  struct Case {
    glm::vec2 uv;
    glm::vec3 want;
  } cases[] = {
      {{0.25f, 0.75f}, kColor0},   // tile (0, 0)
      {{0.75f, 0.75f}, kColor1},   // (1, 0): the next along u
      {{0.25f, 0.25f}, kColor1},   // (0, 1): the next along v, downwards
      {{0.75f, 0.25f}, kColor0},   // (1, 1)
      {{0.1f, 0.99f}, kColor0},    // near the top left corner
      {{-0.25f, 0.75f}, kColor1},  // (-1, 0)
      {{0.25f, 1.25f}, kColor1},   // (0, -1)
      {{-0.25f, 1.25f}, kColor0},  // (-1, -1)
      {{10.25f, -20.75f}, kColor1},  // (20, 43): far away, v negative
  };
  std::vector<glm::vec2> uvs;
  for (const Case& c : cases) uvs.push_back(c.uv);
  std::vector<glm::vec3> got = device_lookups(textures, 1, uvs);
  for (size_t i = 0; i < uvs.size(); ++i) {
    EXPECT_EQ(got[i], cases[i].want) << "uv (" << uvs[i].x << ", " << uvs[i].y << ")";
    EXPECT_EQ(texel_nearest(textures[1], uvs[i]), cases[i].want) << "host, uv (" << uvs[i].x << ", " << uvs[i].y << ")";
  }

  // Tiles [3, 5]: the centre of tile (column i, row j from the top) is at u = (i + 0.5) / 3, v = 1 - (j + 0.5) / 5.
  uvs.clear();
  for (int j = 0; j < 5; ++j)
    for (int i = 0; i < 3; ++i) uvs.push_back({(i + 0.5f) / 3, 1 - (j + 0.5f) / 5});
  got = device_lookups(textures, 2, uvs);
  for (int j = 0; j < 5; ++j)
    for (int i = 0; i < 3; ++i)
      EXPECT_EQ(got[size_t(j * 3 + i)], (i + j) % 2 ? kColor1 : kColor0) << "tile " << i << ", " << j;
  // Offset [0.5, 1] (given as -7.5, 1): half a tile along u, and one tile along v, which swaps the colours of rows.
  for (int j = 0; j < 5; ++j)
    for (int i = 0; i < 3; ++i) uvs.push_back({(i + 0.1f) / 3, 1 - (j + 0.5f) / 5});  // x = i + 0.6, y = j + 1.5
  got = device_lookups(textures, 3, uvs);
  for (size_t k = 15; k < 30; ++k) {
    int i = int(k - 15) % 3, j = int(k - 15) / 3;
    EXPECT_EQ(got[k], (i + j + 1) % 2 ? kColor1 : kColor0) << "offset tile " << i << ", " << j;
  }

  // Many points: the device, the host and the rule agree away from the tiles' edges.
  std::mt19937 gen(5);
  std::uniform_real_distribution<float> coordinate(-3, 3);
  uvs.clear();
  for (int i = 0; i < 2000; ++i) uvs.push_back({coordinate(gen), coordinate(gen)});
  for (uint32_t index : {1u, 2u, 3u}) {
    const float* w = reinterpret_cast<const float*>(textures[index].words.data());
    glm::dvec2 tiles(w[6], w[7]), off(w[8], w[9]);
    got = device_lookups(textures, index, uvs);
    int checked = 0;
    for (size_t i = 0; i < uvs.size(); ++i) {
      double x = uvs[i].x * tiles.x + off.x, y = (1 - double(uvs[i].y)) * tiles.y + off.y;
      if (std::abs(x - std::round(x)) < 1e-4 || std::abs(y - std::round(y)) < 1e-4) continue;
      ++checked;
      ASSERT_EQ(got[i], checker_colour(uvs[i], tiles, off)) << "texture " << index << " uv " << uvs[i].x << ", " << uvs[i].y;
      ASSERT_EQ(texel_nearest(textures[index], uvs[i]), got[i]) << "texture " << index << " uv " << uvs[i].x << ", " << uvs[i].y;
    }
    EXPECT_GT(checked, 1900);
  }
}

// A scene of the square [-1, 1]^2 (uvs [0, 1]^2) seen head-on, filling a 15 x 15 film, under a sky of radiance 1
// with one scattering event, its material given by `material_json`.
RenderResult render_checker_square(const std::string& material_json, const std::string& name) {
  const int width = 15;
  const double distance = 1.0 / std::tan(20.0 * M_PI / 180.0);  // fov 40 degrees covers [-1, 1]
  std::ostringstream scene;
  scene.precision(17);
  scene << R"({"camera": {"position": [0, 0, )" << distance << R"(], "look_at": [0, 0, 0], "fov_y_degrees": 40,
    "width": )" << width << R"(, "height": )" << width << R"(}, "materials": {"m": )" << material_json << R"(},
    "shapes": [)" << kQuad << R"(], "lights": [{"type": "environment", "radiance": [1, 1, 1]}]})";
  DeviceScene d = load_device_scene(write_temp_file(name + ".json", scene.str()));
  EXPECT_TRUE(d.features & kFeatureTextures);
  RenderOptions opt;
  opt.spp = 64;
  opt.max_depth = 1;
  opt.seed = 11;
  RenderResult r = render(test_device(), d, opt);
  EXPECT_EQ(r.nan_samples + r.inf_samples + r.negative_samples, 0u);
  return r;
}

// Checks each pixel's mean against want(px, py) (row py from the top) within 5 standard errors, and all
// together within 4.
void expect_pixels(const RenderResult& r, int width, const std::function<glm::vec3(int, int)>& want,
                   const std::string& name) {
  double sum_diff = 0, sum_var = 0;
  for (int py = 0; py < width; ++py)
    for (int px = 0; px < width; ++px)
      for (int c = 0; c < 3; ++c) {
        size_t i = 3 * (size_t(py) * width + px) + c;
        double got = r.film.mean[i], var = r.film.variance[i], w = want(px, py)[c];
        EXPECT_LE(std::abs(got - w), 5 * std::sqrt(var) + 1e-6)
            << name << " pixel " << px << "," << py << " channel " << c << ": " << got << " expected " << w;
        sum_diff += got - w;
        sum_var += var;
      }
  EXPECT_LE(std::abs(sum_diff), 4 * std::sqrt(sum_var) + 1e-5) << name;
}

// Tiles [3, 5] on the square seen head-on, 15 x 15 pixels: tile boundaries fall on pixel boundaries, pixel
// column px in tile column px / 5 and row py (from the top) in tile row py / 3, so every pixel reflects one
// tile's colour times the sky: color0 at the top left, alternating along both axes.
TEST(Checkerboard, SquareSeenFromAboveShowsEachTilesColour) {
  RenderResult r = render_checker_square(
      R"({"type": "diffuse", "reflectance": {"checkerboard": {"color0": [0.75, 0.25, 0.125], "color1": [0.0625, 0.5, 0.875], "tiles": [3, 5]}}})",
      "checker-square");
  expect_pixels(r, 15, [](int px, int py) { return (px / 5 + py / 3) % 2 ? kColor1 : kColor0; }, "tiles [3, 5]");
  // Mitsuba's defaults: colours 0.4 and 0.2, 2 tiles a unit; pixel column px in tile px * 2 / 15 (away from the
  // middle column, 7, which straddles the edge).
  RenderResult d = render_checker_square(R"({"type": "diffuse", "reflectance": {"checkerboard": {}}})", "checker-default");
  expect_pixels(
      d, 15,
      [](int px, int py) {
        if (px == 7 || py == 7) return glm::vec3(0.3f);  // half of each
        return glm::vec3(((px > 7) + (py > 7)) % 2 ? 0.2f : 0.4f);
      },
      "defaults");
}

// A checkerboard as an opacity map (its red channel): where it is 1 the square reflects 0.5 of the sky, where it
// is 0 the camera sees the sky through it.
TEST(Checkerboard, OpacityTakesTheRedChannel) {
  RenderResult r = render_checker_square(
      R"({"type": "diffuse", "reflectance": [0.5, 0.5, 0.5],
          "opacity": {"checkerboard": {"color0": [1, 0, 0], "color1": [0, 1, 1], "tiles": [3, 5]}}})",
      "checker-opacity");
  expect_pixels(r, 15, [](int px, int py) { return glm::vec3((px / 5 + py / 3) % 2 ? 1.0f : 0.5f); }, "opacity");
}

TEST(Checkerboard, JsonIsCheckedAndSharedAndPhongSeesItsLargestColour) {
  const std::string shape = R"({"type": "triangles", "positions": [[0,0,0],[1,0,0],[1,1,0]], "indices": [[0,1,2]],
      "uvs": [[0,0],[1,0],[1,1]], "material": "m"})";
  auto scene_of = [&](const std::string& materials, const std::string& lights = "[]", const std::string& s = "") {
    return R"({"camera": {"position": [0, 0, 3], "look_at": [0, 0, 0], "width": 4, "height": 4},
      "materials": )" + materials + R"(, "shapes": [)" + (s.empty() ? shape : s) + R"(], "lights": )" + lights + "}";
  };
  // Two materials with the same checkerboard share one texture; a third differs; defaults are Mitsuba's.
  SceneDescription scene = load_scene(write_temp_file("checker-shared.json", scene_of(R"({
      "m": {"type": "diffuse", "reflectance": {"checkerboard": {"tiles": [4, 4], "offset": [1, 0]}}},
      "n": {"type": "plastic", "diffuse": {"checkerboard": {"tiles": [4, 4], "offset": [3, 2], "color0": [0.4, 0.4, 0.4]}}},
      "o": {"type": "diffuse", "reflectance": {"checkerboard": {}}, "opacity": {"checkerboard": {"tiles": [4, 4], "offset": [1, 0]}}}})")));
  ASSERT_EQ(scene.materials.size(), 3u);
  EXPECT_EQ(scene.materials[0].color_texture, scene.materials[1].color_texture);
  EXPECT_NE(scene.materials[0].color_texture, scene.materials[2].color_texture);
  EXPECT_EQ(scene.materials[2].opacity_texture, scene.materials[0].color_texture);
  EXPECT_EQ(scene.materials[0].color, glm::vec3(1));
  const TextureImage& shared = scene.textures[scene.materials[0].color_texture];
  EXPECT_EQ(shared.format, PC_TEXELS_CHECKER);
  EXPECT_EQ(texel_linear(shared, 0), glm::vec3(0.4f));
  EXPECT_EQ(texel_linear(shared, 1), glm::vec3(0.2f));
  const TextureImage& defaults = scene.textures[scene.materials[2].color_texture];
  const float* w = reinterpret_cast<const float*>(defaults.words.data());
  EXPECT_EQ(std::vector<float>(w, w + 10), (std::vector<float>{0.4f, 0.4f, 0.4f, 0.2f, 0.2f, 0.2f, 2, 2, 0, 0}));
  for (const std::string& warning : scene.warnings)  // only that the scene has no light
    EXPECT_NE(warning.find("light"), std::string::npos) << warning;
  DeviceScene d = build_device_scene(scene);
  EXPECT_EQ(d.textures[d.materials[2].opacity_texture].format, PC_TEXELS_CHECKER);  // read as it is: red
  EXPECT_EQ(d.textures[d.materials[0].color_texture].offset, d.textures[d.materials[2].opacity_texture].offset);

  // A phong's diffuse checkerboard: its larger colour plus specular must not exceed 1.
  load_scene(write_temp_file("checker-phong-ok.json", scene_of(R"({"m": {"type": "phong", "exponent": 10,
      "diffuse": {"checkerboard": {"color0": [0.2, 0.2, 0.2], "color1": [0.7, 0.1, 0.1]}}, "specular": [0.3, 0.3, 0.3]}})")));
  std::string phong = write_temp_file("checker-phong.json", scene_of(R"({"m": {"type": "phong", "exponent": 10,
      "diffuse": {"checkerboard": {"color0": [0.2, 0.2, 0.2], "color1": [0.8, 0.1, 0.1]}}, "specular": [0.3, 0.3, 0.3]}})"));
  EXPECT_EQ(scene_load_error(phong), phong + ": materials.m: the diffuse texture's largest value + specular exceeds 1 (the surface would create energy)");

  struct Case {
    std::string materials, lights, shape, expected;
  } cases[] = {
      {R"({"m": {"type": "diffuse", "reflectance": {"checkerboard": {"wrap": "repeat"}}}})", "[]", "",
       "materials.m.reflectance.checkerboard: unknown key \"wrap\""},
      {R"({"m": {"type": "diffuse", "reflectance": {"checkerboard": {}, "wrap": "repeat"}}})", "[]", "",
       "materials.m.reflectance: unknown key \"wrap\""},
      {R"({"m": {"type": "diffuse", "reflectance": {"checkerboard": {"color0": [1.5, 0, 0]}}}})", "[]", "",
       "materials.m.reflectance.checkerboard.color0: expected values in [0, 1]"},
      {R"({"m": {"type": "diffuse", "reflectance": {"checkerboard": {"color1": [0.5, 0.5]}}}})", "[]", "",
       "materials.m.reflectance.checkerboard.color1: expected an array of 3 numbers"},
      {R"({"m": {"type": "diffuse", "reflectance": {"checkerboard": {"tiles": [3, 0]}}}})", "[]", "",
       "materials.m.reflectance.checkerboard.tiles[1]: expected a number > 0, got 0"},
      {R"({"m": {"type": "diffuse", "reflectance": {"checkerboard": {"tiles": [3]}}}})", "[]", "",
       "materials.m.reflectance.checkerboard.tiles: expected an array of 2 numbers"},
      {R"({"m": {"type": "diffuse", "reflectance": {"checkerboard": {"tiles": [3, 1e39]}}}})", "[]", "",
       "materials.m.reflectance.checkerboard.tiles[1]: expected a finite number within float range, got"},
      {R"({"m": {"type": "diffuse", "reflectance": {"checkerboard": {"offset": [0, "1"]}}}})", "[]", "",
       "materials.m.reflectance.checkerboard.offset[1]: expected a number"},
      {R"({"m": {"type": "diffuse", "reflectance": {"checkerboard": [0.4, 0.2]}}})", "[]", "",
       "materials.m.reflectance.checkerboard: expected an object"},
      {R"({"m": {"type": "dielectric", "ior": 1.5, "transmittance": "checkerboard"}})", "[]", "",
       "materials.m.transmittance: expected an array of 3 numbers or {\"texture\": FILE} or {\"checkerboard\": {...}}"},
      {R"({"m": {"type": "diffuse", "opacity": {"checkerboard": {"color1": [2, 2, 2]}}}})", "[]", "",
       "materials.m.opacity.checkerboard.color1: expected values in [0, 1]"},
      {R"({"m": {"type": "diffuse", "opacity": "checkerboard"}})", "[]", "",
       "materials.m.opacity: expected a number in [0, 1] or {\"texture\": FILE} or {\"checkerboard\": {...}}"},
      {R"({"m": {"type": "diffuse"}})", R"([{"type": "environment", "file": {"checkerboard": {}}}])", "",
       "lights[0].file: a checkerboard cannot be an environment map (an environment takes a lat-long image file)"},
      {R"({"m": {"type": "diffuse", "reflectance": {"checkerboard": {}}}})", "[]",
       R"({"type": "triangles", "positions": [[0,0,0],[1,0,0],[1,1,0]], "indices": [[0,1,2]], "material": "m"})",
       "shapes[0]: material \"m\" has a texture, but the shape has no \"uvs\""},
  };
  for (const Case& c : cases) {
    std::string path = write_temp_file("checker-error.json", scene_of(c.materials, c.lights, c.shape));
    std::string error = scene_load_error(path);
    EXPECT_EQ(error.rfind(path + ": " + c.expected, 0), 0u) << c.materials << "\n  gave: " << error;
  }
}

}  // namespace
