// Exactly reproducible math (kernels/exact_math.cl) on the test device: every function against a
// double-precision (long double for the vector functions) reference over its whole range, its largest
// error in ulp within the bound the kernel file states, special cases exactly, denormal inputs giving the
// bits of the signed zero, every vector overload giving the scalar overload's bits in every lane, and a
// build that lets the device flush denormals (-cl-denorms-are-zero) giving the same bits.
// The measured errors are printed and recorded as test properties (max_ulp_*). With $PATHCL_EXACT_MATH_DUMP
// set to a directory, every output array is also written there (NAME-K.bin, raw floats), to compare
// implementations bit for bit (cmp -s); a disabled test measures throughput against the builtins.
#include <algorithm>
#include <array>
#include <cfloat>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <functional>
#include <map>
#include <numeric>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "test_support.h"

namespace {

uint32_t bits(float f) {
  uint32_t b;
  std::memcpy(&b, &f, 4);
  return b;
}
float from_bits(uint32_t b) {
  float f;
  std::memcpy(&f, &b, 4);
  return f;
}
const float kNaN = from_bits(0x7fc00000u);  // the NaN every function returns
const long double kPiL = 3.14159265358979323846264338327950288L;

// A denormal as the zero of its sign, as exact_math.cl reads its inputs.
float flushed(float x) { return std::fabs(x) < FLT_MIN ? std::copysign(0.0f, x) : x; }

std::string hex(float x) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%a (%.9g)", x, x);
  return buf;
}

// "(a, b, ...)"
std::string vec_string(const float* v, int n) {
  std::string s = "(";
  for (int i = 0; i < n; ++i) {
    if (i) s += ", ";
    s += hex(v[i]);
  }
  return s + ")";
}

// Correctly rounded divide and sqrt where the device has them (Oclgrind computes with the host's IEEE
// operations but does not say so).
std::string math_options() {
  cl_device_fp_config fp = 0;
  CL_CHECK(clGetDeviceInfo(test_device().info.device, CL_DEVICE_SINGLE_FP_CONFIG, sizeof fp, &fp, nullptr));
  std::string options = "-cl-std=CL1.2";
  if (fp & CL_FP_CORRECTLY_ROUNDED_DIVIDE_SQRT) options += " -cl-fp32-correctly-rounded-divide-sqrt";
  return options;
}

const KernelProgram& math_program() {
  static KernelProgram program = build_kernel_program(test_device(), "tests_math.cl", math_options());
  return program;
}


// Writes $PATHCL_EXACT_MATH_DUMP/NAME-K.bin for the K-th output array of that name.
void dump(const std::string& name, const std::vector<float>& values) {
  static std::map<std::string, int> written;
  const char* dir = std::getenv("PATHCL_EXACT_MATH_DUMP");
  if (!dir || !*dir) return;
  std::ofstream(std::string(dir) + "/" + name + "-" + std::to_string(written[name]++) + ".bin", std::ios::binary)
      .write(reinterpret_cast<const char*>(values.data()), std::streamsize(values.size() * sizeof(float)));
}

// Runs NAME_1 over the inputs (one array per argument) and NAME_N, N = 2, 3, 4, 8, 16, over the same
// inputs packed into vectors; expects every lane to equal the scalar result bit for bit. Returns the
// scalar results, one array per output.
std::vector<std::vector<float>> run_elementwise(const std::string& name, std::vector<std::vector<float>> inputs,
                                                size_t outputs = 1, const KernelProgram& program = math_program()) {
  ClContext& cl = test_device();
  size_t n = inputs[0].size(), padded = (n + 47) / 48 * 48;  // every width divides 48
  std::vector<ClBuffer> in, out;
  for (auto& v : inputs) {
    v.resize(padded, v.back());
    in.push_back(upload(cl, v));
  }
  for (size_t o = 0; o < outputs; ++o) out.emplace_back(cl, CL_MEM_WRITE_ONLY, padded * sizeof(float));
  std::vector<std::vector<float>> scalar;
  for (int width : {1, 2, 3, 4, 8, 16}) {
    ClKernel k(program.kernel((name + "_" + std::to_string(width)).c_str()));
    cl_uint arg = 0;
    for (auto& b : in) k.arg(arg++, b.mem);
    for (auto& b : out) k.arg(arg++, b.mem);
    run_kernel(cl, k.k, padded / width);
    for (size_t o = 0; o < outputs; ++o) {
      std::vector<float> r = read_buffer<float>(cl, out[o], padded);
      r.resize(n);
      if (width == 1) {
        scalar.push_back(r);
        if (&program == &math_program()) dump(name + (outputs > 1 ? std::to_string(o) : ""), r);
        continue;
      }
      size_t i = 0;
      while (i < n && bits(r[i]) == bits(scalar[o][i])) ++i;
      EXPECT_EQ(i, n) << name << " as float" << width << " (output " << o << ") differs from the scalar result at input "
                      << (i < n ? hex(inputs[0][i]) : "") << ": " << (i < n ? hex(r[i]) + " against " + hex(scalar[o][i]) : "");
    }
  }
  return scalar;
}

// Error of r in ulp of the reference's binade (2^-149 below FLT_MIN). A zero of the right sign counts as
// exact where the reference is below FLT_MIN, or within 4 ulp above it (results below FLT_MIN are
// flushed); NaN must be the NaN 0x7fc00000, infinities must be exact.
double ulp_error(float r, long double ref) {
  constexpr double kWrong = INFINITY;
  if (std::isnan(ref)) return bits(r) == 0x7fc00000u ? 0 : kWrong;
  if (std::isnan(r)) return kWrong;
  float rounded = float(ref);
  if (std::isinf(rounded) || std::isinf(r)) return r == rounded ? 0 : kWrong;
  if (ref == 0) return r == 0 ? 0 : kWrong;
  if (r == 0 && std::signbit(r) == std::signbit(ref) && std::fabs(ref) < FLT_MIN * (1 + 4 * FLT_EPSILON)) return 0;
  int e;
  std::frexp(ref, &e);
  long double ulp = std::ldexp(1.0L, std::max(e - 1, -126) - 23);
  return double(std::fabs(r - ref) / ulp);
}

// The largest error seen, where, and how many inputs.
struct ErrorStats {
  double max = 0;
  std::string where;
  size_t count = 0;
  void add(double error, const std::function<std::string()>& at) {
    ++count;
    if (error > max) {
      max = error;
      where = at();
    }
  }
};

void report(const std::string& name, const ErrorStats& s, double bound) {
  char buf[256];
  std::snprintf(buf, sizeof buf, "%.3f", s.max);
  ::testing::Test::RecordProperty("max_ulp_" + name, buf);
  std::printf("  %-13s max error %6.3f ulp (bound %g) over %zu inputs, at %s\n", name.c_str(), s.max, bound, s.count,
              s.where.c_str());
  EXPECT_LE(s.max, bound) << name << " at " << s.where;
}

// ---- inputs ---------------------------------------------------------------------------------------------

// Signed zeros, denormals, FLT_MIN and its neighbours, the largest floats, infinities, NaNs (several payloads).
std::vector<float> edge_values() {
  std::vector<float> v;
  for (uint32_t b : {0x00000000u, 0x00000001u, 0x00000002u, 0x00400000u, 0x007fffffu, 0x00800000u, 0x00800001u,
                     0x00ffffffu, 0x01000000u, 0x3f800000u, 0x3f000000u, 0x7f7fffffu, 0x7f7ffffeu, 0x7f800000u,
                     0x7f800001u, 0x7fc00000u, 0x7fffffffu, 0x7fc12345u})
    for (uint32_t sign : {0u, 0x80000000u}) v.push_back(from_bits(b | sign));
  return v;
}

void add_random_bits(std::vector<float>& v, size_t n, uint64_t seed) {
  std::mt19937 rng{uint32_t(seed)};
  for (size_t i = 0; i < n; ++i) v.push_back(from_bits(rng()));
}

void add_uniform(std::vector<float>& v, double lo, double hi, size_t n, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(lo, hi);
  for (size_t i = 0; i < n; ++i) v.push_back(float(u(rng)));
}

// x and the k floats on each side of it.
void add_neighbours(std::vector<float>& v, float x, int k) {
  v.push_back(x);
  float lo = x, hi = x;
  for (int i = 0; i < k; ++i) {
    v.push_back(lo = std::nextafter(lo, -INFINITY));
    v.push_back(hi = std::nextafter(hi, INFINITY));
  }
}

// The same permutation of every argument array, so that vector lanes mix all kinds of inputs.
void shuffle_together(std::vector<std::vector<float>*> arrays, uint64_t seed) {
  std::vector<size_t> p(arrays[0]->size());
  std::iota(p.begin(), p.end(), 0);
  std::shuffle(p.begin(), p.end(), std::mt19937_64(seed));
  for (auto* a : arrays) {
    std::vector<float> s(a->size());
    for (size_t i = 0; i < p.size(); ++i) s[i] = (*a)[p[i]];
    *a = s;
  }
}

// Every denormal input of a one-argument function gives the bits of the zero of its sign.
void expect_denormals_read_as_zero(const std::string& name) {
  std::vector<float> in;
  for (uint32_t b : {0x00000001u, 0x00000fffu, 0x00400000u, 0x007fffffu, 0x80000001u, 0x80400000u, 0x807fffffu})
    in.push_back(from_bits(b));
  size_t n = in.size();
  for (size_t i = 0; i < n; ++i) in.push_back(flushed(in[i]));
  std::vector<float> r = run_elementwise("pc_" + name, {in})[0];
  for (size_t i = 0; i < n; ++i)
    EXPECT_EQ(bits(r[i]), bits(r[n + i]))
        << name << "(" << hex(in[i]) << ") = " << hex(r[i]) << ", of the zero " << hex(r[n + i]);
}

// Checks a one-argument function over its inputs against a double reference; the special cases (x, expected) exactly.
void check_unary(const std::string& name, std::vector<float> in, const std::function<double(double)>& ref, double bound,
                 const std::vector<std::pair<float, float>>& specials) {
  for (auto& s : specials) in.push_back(s.first);
  shuffle_together({&in}, 17);
  std::vector<float> r = run_elementwise("pc_" + name, {in})[0];
  ErrorStats stats;
  for (size_t i = 0; i < in.size(); ++i)
    stats.add(ulp_error(r[i], ref(flushed(in[i]))), [&] { return "x = " + hex(in[i]) + " -> " + hex(r[i]); });
  report("pc_" + name, stats, bound);
  std::vector<float> x, expected;
  for (auto& s : specials) x.push_back(s.first), expected.push_back(s.second);
  std::vector<float> rs = run_elementwise("pc_" + name, {x})[0];
  for (size_t i = 0; i < x.size(); ++i)
    EXPECT_EQ(bits(rs[i]), bits(expected[i]))
        << name << "(" << hex(x[i]) << ") = " << hex(rs[i]) << ", expected " << hex(expected[i]);
  expect_denormals_read_as_zero(name);
}

}  // namespace

// ---- one-argument functions -----------------------------------------------------------------------------

TEST(ExactMath, SinCos) {
  std::vector<float> in = edge_values();
  add_random_bits(in, 60000, 1);
  add_uniform(in, 0, 2 * M_PI, 40000, 2);  // the renderer's azimuths
  add_uniform(in, -4 * M_PI, 4 * M_PI, 20000, 3);
  add_uniform(in, -1e6, 1e6, 10000, 4);
  // The floats nearest to multiples of pi/2 (the hardest reductions) up to 2^21, around the switch from
  // Cody-Waite to Payne-Hanek at 4096, and the 12 floats of all closest to a multiple of pi/2.
  for (int k = 1; k < 3000; ++k) add_neighbours(in, float(k * kPiL / 2), 2);
  for (int k = 3000; k < (1 << 21); k += 997) add_neighbours(in, float(k * kPiL / 2), 1);
  add_neighbours(in, 4096.0f, 8);
  for (uint32_t b : {0x6f79be45u, 0x50a3e87fu, 0x6ff9be45u, 0x5123e87fu, 0x7079be45u, 0x6a1976f1u, 0x53b146a6u,
                     0x65898498u, 0x51a3e87fu, 0x77584625u, 0x4c2332e9u, 0x6c55da58u, 0x437ce5f2u, 0x4096cbe4u})
    for (uint32_t sign : {0u, 0x80000000u}) add_neighbours(in, from_bits(b | sign), 2);
  check_unary("sin", in, [](double x) { return std::sin(x); }, 1,
              {{0.0f, 0.0f}, {-0.0f, -0.0f}, {INFINITY, kNaN}, {-INFINITY, kNaN}, {kNaN, kNaN}, {-kNaN, kNaN}});
  check_unary("cos", in, [](double x) { return std::cos(x); }, 1,
              {{0.0f, 1.0f}, {-0.0f, 1.0f}, {INFINITY, kNaN}, {-INFINITY, kNaN}, {kNaN, kNaN}});
  // pc_sincos gives both, bit for bit.
  std::vector<float> s = run_elementwise("pc_sin", {in})[0], c = run_elementwise("pc_cos", {in})[0];
  std::vector<std::vector<float>> sc = run_elementwise("pc_sincos", {in}, 2);
  for (size_t i = 0; i < in.size(); ++i) {
    ASSERT_EQ(bits(sc[0][i]), bits(s[i])) << "sincos(" << hex(in[i]) << ") sin";
    ASSERT_EQ(bits(sc[1][i]), bits(c[i])) << "sincos(" << hex(in[i]) << ") cos";
  }
}

TEST(ExactMath, Acos) {
  std::vector<float> in = edge_values();
  add_random_bits(in, 20000, 5);
  add_uniform(in, -1, 1, 60000, 6);
  for (float x : {1.0f, -1.0f, 0.5f, -0.5f}) add_neighbours(in, x, 3000);
  add_uniform(in, -1e-6, 1e-6, 5000, 7);
  check_unary("acos", in, [](double x) { return std::acos(x); }, 1,
              {{1.0f, 0.0f}, {-1.0f, from_bits(0x40490fdbu)}, {0.0f, from_bits(0x3fc90fdbu)},
               {-0.0f, from_bits(0x3fc90fdbu)}, {std::nextafter(1.0f, 2.0f), kNaN}, {-2.0f, kNaN}, {INFINITY, kNaN},
               {-INFINITY, kNaN}, {kNaN, kNaN}});
}

TEST(ExactMath, Log) {
  std::vector<float> in = edge_values();
  add_random_bits(in, 60000, 8);
  add_uniform(in, 0, 4, 40000, 9);
  add_neighbours(in, 1.0f, 5000);
  add_neighbours(in, float(M_SQRT1_2), 200);
  add_neighbours(in, float(M_SQRT2), 200);
  check_unary("log", in, [](double x) { return std::log(x); }, 1,
              {{0.0f, -INFINITY}, {-0.0f, -INFINITY}, {1.0f, 0.0f}, {-1.0f, kNaN}, {INFINITY, INFINITY},
               {-INFINITY, kNaN}, {kNaN, kNaN}, {-FLT_MIN, kNaN}});
}

TEST(ExactMath, ExpExp2) {
  std::vector<float> in = edge_values();
  add_random_bits(in, 40000, 10);
  add_uniform(in, -160, 135, 60000, 11);
  add_uniform(in, -1, 1, 20000, 12);
  for (float x : {88.72283f, -87.33654f, -103.27893f, 128.0f, -126.0f, -149.0f, -150.0f, 0.0f}) add_neighbours(in, x, 300);
  std::vector<std::pair<float, float>> specials = {{0.0f, 1.0f}, {-0.0f, 1.0f}, {INFINITY, INFINITY}, {-INFINITY, 0.0f},
                                                   {kNaN, kNaN}, {-kNaN, kNaN}, {1000.0f, INFINITY}, {-1000.0f, 0.0f}};
  check_unary("exp", in, [](double x) { return std::exp(x); }, 1.5, specials);
  for (int k = -126; k <= 127; ++k) specials.push_back({float(k), std::ldexp(1.0f, k)});  // exact powers of two
  specials.push_back({128.0f, INFINITY});
  specials.push_back({-127.0f, 0.0f});  // 2^-127 is denormal: flushed
  check_unary("exp2", in, [](double x) { return std::exp2(x); }, 1.5, specials);
}

TEST(ExactMath, Erf) {
  std::vector<float> in = edge_values();
  add_random_bits(in, 40000, 13);
  add_uniform(in, -5, 5, 80000, 14);
  for (float x : {1.0f, -1.0f, 4.0f, -4.0f, 0x1p-64f}) add_neighbours(in, x, 500);
  check_unary("erf", in, [](double x) { return std::erf(x); }, 2,
              {{0.0f, 0.0f}, {-0.0f, -0.0f}, {INFINITY, 1.0f}, {-INFINITY, -1.0f}, {kNaN, kNaN}, {10.0f, 1.0f}});
}

// ---- two-argument functions -----------------------------------------------------------------------------

namespace {

// Checks f(x, y) against a reference; pairs (x, y, expected) exactly; denormals in either argument read as zeros.
void check_binary(const std::string& name, std::vector<float> x, std::vector<float> y,
                  const std::function<double(double, double)>& ref, double bound,
                  const std::vector<std::array<float, 3>>& specials) {
  for (auto& s : specials) x.push_back(s[0]), y.push_back(s[1]);
  shuffle_together({&x, &y}, 23);
  std::vector<float> r = run_elementwise("pc_" + name, {x, y})[0];
  ErrorStats stats;
  for (size_t i = 0; i < x.size(); ++i)
    stats.add(ulp_error(r[i], ref(flushed(x[i]), flushed(y[i]))),
              [&] {
                float xy[2] = {x[i], y[i]};
                return vec_string(xy, 2) + " -> " + hex(r[i]);
              });
  report("pc_" + name, stats, bound);
  std::vector<float> sx, sy;
  for (auto& s : specials) sx.push_back(s[0]), sy.push_back(s[1]);
  std::vector<float> rs = run_elementwise("pc_" + name, {sx, sy})[0];
  for (size_t i = 0; i < sx.size(); ++i)
    EXPECT_EQ(bits(rs[i]), bits(specials[i][2]))
        << name << "(" << hex(sx[i]) << ", " << hex(sy[i]) << ") = " << hex(rs[i]) << ", expected " << hex(specials[i][2]);
  // Denormals in either argument: the bits of the signed zero's result.
  std::vector<float> a, b;
  for (float d : {from_bits(1u), from_bits(0x007fffffu), from_bits(0x80000001u), from_bits(0x80400000u)})
    for (float other : {-2.0f, -0.5f, 0.0f, 0.5f, 1.0f, 3.0f, INFINITY}) {
      a.push_back(d), b.push_back(other);
      a.push_back(other), b.push_back(d);
    }
  size_t n = a.size();
  for (size_t i = 0; i < n; ++i) a.push_back(flushed(a[i])), b.push_back(flushed(b[i]));
  std::vector<float> rd = run_elementwise("pc_" + name, {a, b})[0];
  for (size_t i = 0; i < n; ++i)
    EXPECT_EQ(bits(rd[i]), bits(rd[n + i])) << name << "(" << hex(a[i]) << ", " << hex(b[i]) << ") = " << hex(rd[i])
                                            << ", with zeros " << hex(rd[n + i]);
}

}  // namespace

TEST(ExactMath, Atan2) {
  std::vector<float> y, x;
  std::vector<float> edges = edge_values();
  for (float a : {0.0f, -0.0f, 1.0f, -1.0f, 0.5f, 3.0f, FLT_MIN, FLT_MAX, -FLT_MAX, INFINITY, -INFINITY}) edges.push_back(a);
  for (float a : edges)
    for (float b : edges) y.push_back(a), x.push_back(b);
  add_random_bits(y, 50000, 15);
  add_random_bits(x, 50000, 16);
  std::mt19937_64 rng(17);
  std::uniform_real_distribution<double> u(0, 1);
  for (int i = 0; i < 50000; ++i) {  // directions on the unit circle, as the renderer's azimuths
    double t = 2 * M_PI * u(rng);
    y.push_back(float(std::sin(t))), x.push_back(float(std::cos(t)));
  }
  for (int i = 0; i < 20000; ++i) {  // |y| close to |x|, and tiny ratios (results near FLT_MIN)
    float a = float(std::ldexp(u(rng) + 0.5, int(u(rng) * 250) - 125));
    y.push_back(a * float(1 + (u(rng) - 0.5) * 1e-3)), x.push_back(a * (u(rng) < 0.5 ? 1 : -1));
    y.push_back(float(std::ldexp(u(rng) + 0.5, -126 - int(u(rng) * 3)) * std::ldexp(1.0, int(u(rng) * 100)))),
        x.push_back(float(std::ldexp(1.0, int(u(rng) * 100))));
  }
  add_uniform(y, -4, 4, 20000, 18);
  add_uniform(x, -4, 4, 20000, 19);
  const float pi = from_bits(0x40490fdbu), pi2 = from_bits(0x3fc90fdbu), pi4 = from_bits(0x3f490fdbu),
              pi34 = from_bits(0x4016cbe4u);
  check_binary("atan2", y, x, [](double a, double b) { return std::atan2(a, b); }, 2,
               {{0.0f, 0.0f, 0.0f},        {-0.0f, 0.0f, -0.0f},       {0.0f, -0.0f, pi},          {-0.0f, -0.0f, -pi},
                {0.0f, -1.0f, pi},         {-0.0f, -1.0f, -pi},        {0.0f, 1.0f, 0.0f},         {-0.0f, 1.0f, -0.0f},
                {1.0f, 0.0f, pi2},         {1.0f, -0.0f, pi2},         {-1.0f, 0.0f, -pi2},        {-1.0f, -0.0f, -pi2},
                {1.0f, INFINITY, 0.0f},    {-1.0f, INFINITY, -0.0f},   {1.0f, -INFINITY, pi},      {-1.0f, -INFINITY, -pi},
                {INFINITY, 1.0f, pi2},     {-INFINITY, 1.0f, -pi2},    {INFINITY, -1.0f, pi2},     {INFINITY, INFINITY, pi4},
                {-INFINITY, INFINITY, -pi4}, {INFINITY, -INFINITY, pi34}, {-INFINITY, -INFINITY, -pi34}, {kNaN, 1.0f, kNaN},
                {1.0f, kNaN, kNaN},        {kNaN, kNaN, kNaN},         {INFINITY, kNaN, kNaN},     {1.0f, 1.0f, pi4},
                {-1.0f, -1.0f, -pi34},     {FLT_MIN, 4.0f, 0.0f},      {-FLT_MIN, 2.0f, -0.0f}});
}

TEST(ExactMath, Powr) {
  std::vector<float> x, y;
  std::mt19937_64 rng(20);
  std::uniform_real_distribution<double> u(0, 1);
  for (int i = 0; i < 40000; ++i) {  // Phong's lobe cos^n and its sampling u^(1 / (n + 1))
    double n = std::exp(u(rng) * std::log(10001.0)) - 1;
    x.push_back(float(u(rng))), y.push_back(float(n));
    x.push_back(float(u(rng))), y.push_back(float(1 / (n + 1)));
  }
  for (int i = 0; i < 40000; ++i) {  // any bits (x >= 0), and x near the ends of each log reduction interval
    x.push_back(from_bits(uint32_t(rng()) & 0x7fffffffu)), y.push_back(from_bits(uint32_t(rng())));
    double m = std::exp2(std::round(u(rng) * 6 - 3) / 6) * (1 + (u(rng) - 0.5) * 0.02);
    float xm = float(std::ldexp(m, int(u(rng) * 4) - 2));
    x.push_back(xm), y.push_back(float((u(rng) * 2 - 1) * 130 / std::log2(double(xm))));  // |y log2 x| up to 130
  }
  for (int i = 0; i < 20000; ++i) {
    float xm = float(1 + (u(rng) - 0.5) * 1e-3);
    x.push_back(xm), y.push_back(float((u(rng) * 2 - 1) * 140 / std::log2(double(xm))));
  }
  add_uniform(x, 0, 4, 20000, 21);
  add_uniform(y, -60, 60, 20000, 22);
  std::vector<float> edges = {0.0f, -0.0f, FLT_MIN, 0.5f, 1.0f, 2.0f, FLT_MAX, INFINITY, kNaN, -1.0f, -INFINITY};
  std::vector<float> yedges = {0.0f, -0.0f, 1.0f, -1.0f, 0.5f, 2.5f, 1e30f, -1e30f, INFINITY, -INFINITY, kNaN};
  for (float a : edges)
    for (float b : yedges) x.push_back(a), y.push_back(b);
  // OpenCL's powr: reference pow, except where powr is NaN.
  auto ref = [](double a, double b) {
    if (a < 0 || std::isnan(a) || std::isnan(b) || (a == 0 && b == 0) || (std::isinf(a) && b == 0) ||
        (a == 1 && std::isinf(b)))
      return double(NAN);
    if (a == 0) return b < 0 ? double(INFINITY) : 0.0;  // powr(+-0, y): +inf or +0, whatever the sign of zero
    return std::pow(a, b);
  };
  check_binary("powr", x, y, ref, 2,
               {{2.0f, 0.0f, 1.0f},          {2.0f, -0.0f, 1.0f},         {0.0f, -1.0f, INFINITY},
                {-0.0f, -1.0f, INFINITY},     {0.0f, -INFINITY, INFINITY}, {0.0f, 1.0f, 0.0f},
                {-0.0f, 2.0f, 0.0f},          {1.0f, 5.0f, 1.0f},          {1.0f, -1e30f, 1.0f},
                {-1.0f, 2.0f, kNaN},          {0.0f, 0.0f, kNaN},          {-0.0f, -0.0f, kNaN},
                {INFINITY, 0.0f, kNaN},       {INFINITY, -0.0f, kNaN},     {1.0f, INFINITY, kNaN},
                {1.0f, -INFINITY, kNaN},      {2.0f, kNaN, kNaN},          {kNaN, 2.0f, kNaN},
                {kNaN, 0.0f, kNaN},           {0.5f, INFINITY, 0.0f},      {0.5f, -INFINITY, INFINITY},
                {2.0f, INFINITY, INFINITY},   {2.0f, -INFINITY, 0.0f},     {INFINITY, 2.0f, INFINITY},
                {INFINITY, -2.0f, 0.0f},      {INFINITY, INFINITY, INFINITY}, {INFINITY, -INFINITY, 0.0f},
                {0.0f, INFINITY, 0.0f},       {-INFINITY, 2.0f, kNaN},     {-FLT_MIN, 2.0f, kNaN},
                {0.5f, 200.0f, 0.0f},         {2.0f, 128.0f, INFINITY}});
}

// ---- vector functions -----------------------------------------------------------------------------------

namespace {

// The renderer's exact sequence of operations on the host (which keeps denormals, and has no FMA in
// this build): pc_dot and pc_cross must give these bits.
float mul(float a, float b) {
  volatile float p = a * b;
  return p;
}
float flushed_product(float p) { return std::fabs(p) <= FLT_MIN ? std::copysign(0.0f, p) : p; }
float host_dot(const float* a, const float* b, int n) {
  float s = flushed_product(mul(flushed(a[0]), flushed(b[0])));
  for (int i = 1; i < n; ++i) s = flushed(s + flushed_product(mul(flushed(a[i]), flushed(b[i]))));
  return s;
}
void host_cross(const float* a, const float* b, float* c) {
  for (int i = 0; i < 3; ++i) {
    int j = (i + 1) % 3, k = (i + 2) % 3;
    c[i] = flushed(flushed_product(mul(flushed(a[j]), flushed(b[k]))) - flushed_product(mul(flushed(a[k]), flushed(b[j]))));
  }
}

// Random vectors: components of random sign and mantissa with exponents near 0, anywhere (denormals
// included), or one large and the others tiny; zeros; and special values.
std::vector<float> random_vectors(int n, size_t count, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0, 1);
  std::vector<float> v;
  for (size_t i = 0; i < count; ++i) {
    int kind = int(i % 5);
    for (int c = 0; c < n; ++c) {
      double m = (u(rng) + 1) * (u(rng) < 0.5 ? -1 : 1);
      int e = kind == 0 ? int(u(rng) * 6) - 3 : kind >= 2 && c == 0 ? int(u(rng) * 250) - 125 : int(u(rng) * 280) - 150;
      float x = kind == 3 ? float(u(rng) * 2 - 1) : float(std::ldexp(m, e));
      if (kind == 4) x = u(rng) < 0.3 ? 0.0f : u(rng) < 0.1 ? from_bits(uint32_t(rng())) : float(std::ldexp(m, e % 40));
      v.push_back(x);
    }
  }
  return v;
}

std::vector<float> run_vector(const std::string& kernel, const std::vector<float>& a, const std::vector<float>* b,
                              size_t count, size_t out_width, const KernelProgram& program = math_program()) {
  ClContext& cl = test_device();
  ClBuffer ba = upload(cl, a), bb = upload(cl, b ? *b : a), out(cl, CL_MEM_WRITE_ONLY, count * out_width * sizeof(float));
  ClKernel k(program.kernel(kernel.c_str()));
  cl_uint arg = 0;
  k.arg(arg++, ba.mem);
  if (b) k.arg(arg++, bb.mem);
  k.arg(arg++, out.mem);
  run_kernel(cl, k.k, count);
  std::vector<float> r = read_buffer<float>(cl, out, count * out_width);
  if (&program == &math_program()) dump(kernel, r);
  return r;
}

}  // namespace

TEST(ExactMath, DotCross) {
  for (int n : {2, 3, 4}) {
    std::vector<float> a = random_vectors(n, 30000, 30 + n), b = random_vectors(n, 30000, 40 + n);
    shuffle_together({&b}, 50 + n);
    size_t count = a.size() / n;
    std::vector<float> d = run_vector("pc_dot_" + std::to_string(n), a, &b, count, 1);
    size_t wrong = 0;
    for (size_t i = 0; i < count; ++i) {
      float expected = host_dot(&a[n * i], &b[n * i], n);
      if (bits(d[i]) != bits(expected) && !(std::isnan(d[i]) && std::isnan(expected)) && wrong++ < 5)
        ADD_FAILURE() << "pc_dot" << vec_string(&a[n * i], n) << ", " << vec_string(&b[n * i], n) << ") = " << hex(d[i])
                      << ", written out " << hex(expected);
    }
    EXPECT_EQ(wrong, 0u) << "pc_dot float" << n;
    if (n == 2) continue;
    std::vector<float> c = run_vector("pc_cross_" + std::to_string(n), a, &b, count, n);
    wrong = 0;
    for (size_t i = 0; i < count; ++i) {
      float expected[4] = {0, 0, 0, 0};
      host_cross(&a[n * i], &b[n * i], expected);
      for (int j = 0; j < n; ++j)
        if (bits(c[n * i + j]) != bits(expected[j]) && !(std::isnan(c[n * i + j]) && std::isnan(expected[j])) && wrong++ < 5)
          ADD_FAILURE() << "pc_cross" << vec_string(&a[n * i], n) << ", " << vec_string(&b[n * i], n) << ") = "
                        << vec_string(&c[n * i], n) << ", written out " << vec_string(expected, n);
    }
    EXPECT_EQ(wrong, 0u) << "pc_cross float" << n;
  }
}

TEST(ExactMath, LengthNormalize) {
  for (int n : {2, 3, 4}) {
    std::vector<float> v = random_vectors(n, 40000, 60 + n);
    // Special vectors: zeros of both signs, denormals, infinities, NaN, the largest and smallest floats.
    std::vector<std::vector<float>> special = {
        {0.0f, -0.0f, 0.0f, -0.0f},        {from_bits(1u), -0.0f, from_bits(0x807fffffu), 0.0f},
        {INFINITY, 1.0f, 0.0f, -2.0f},     {-INFINITY, INFINITY, -0.0f, 5.0f},
        {kNaN, 1.0f, 0.0f, 0.0f},          {INFINITY, kNaN, 1.0f, 1.0f},
        {FLT_MAX, FLT_MAX, FLT_MAX, FLT_MAX}, {FLT_MIN, 0.0f, -FLT_MIN, 0.0f},
        {1.0f, 1e-30f, -1e-38f, 1e-20f},   {3e38f, -3e38f, 1.0f, 0.0f},
        {1e30f, 1e-30f, 0.0f, 1.0f},       {from_bits(0x00800001u), from_bits(1u), 0.0f, 0.0f}};
    for (auto& s : special) v.insert(v.end(), s.begin(), s.begin() + n);
    size_t count = v.size() / n;
    std::vector<float> len = run_vector("pc_length_" + std::to_string(n), v, nullptr, count, 1);
    std::vector<float> nv = run_vector("pc_normalize_" + std::to_string(n), v, nullptr, count, n);
    ErrorStats len_stats, norm_stats;
    for (size_t i = 0; i < count; ++i) {
      const float* x = &v[n * i];
      bool nan = false, inf = false;
      long double sum = 0;
      for (int j = 0; j < n; ++j) {
        float c = flushed(x[j]);
        nan |= std::isnan(c), inf |= std::isinf(c);
        sum += (long double)c * c;
      }
      long double ref_len = nan ? NAN : inf ? INFINITY : std::sqrt(sum);
      len_stats.add(ulp_error(len[i], ref_len), [&] { return vec_string(x, n) + " -> " + hex(len[i]); });
      for (int j = 0; j < n; ++j) {
        float c = flushed(x[j]), r = nv[n * i + j];
        long double ref;
        if (nan) ref = NAN;
        else if (inf) {  // infinities as +-1, the rest as +-0, then normalised
          int infs = 0;
          for (int k = 0; k < n; ++k) infs += std::isinf(x[k]);
          ref = std::copysign(std::isinf(c) ? 1 / std::sqrt((long double)infs) : 0.0L, (long double)c);
        } else if (sum == 0) ref = c;  // the zero vector as it is
        else ref = c / std::sqrt(sum);
        double e = ulp_error(r, ref);
        if (ref == 0 && r == 0 && std::signbit(r) != std::signbit(ref)) e = INFINITY;  // zeros keep their signs
        norm_stats.add(e, [&] { return vec_string(x, n) + " -> " + vec_string(&nv[n * i], n); });
      }
    }
    report("pc_length" + std::to_string(n), len_stats, (n + 2) / 2.0);
    report("pc_normalize" + std::to_string(n), norm_stats, (n + 4) / 2.0);
  }
}

// Lane geometry (exact_math.cl, lane3f / lane3f8 / lane3f16: 3-vectors stored by component, for issue
// 15's lane-generic kernel) gives, in every lane, the bits of the float3 functions: random vectors and the
// special ones of LengthNormalize (zeros, denormals, infinities, NaN, extremes), with lanes of different
// kinds side by side so that every per-lane select is exercised, and groups of lanes without tiny
// components, where pc_dot and pc_cross skip their flushes.
TEST(ExactMath, LaneGeometryGivesTheFloat3Bits) {
  std::vector<float> a = random_vectors(3, 8000, 91), b = random_vectors(3, 8000, 92);
  const float specials[][3] = {{0.0f, -0.0f, 0.0f},        {from_bits(1u), -0.0f, from_bits(0x807fffffu)},
                               {INFINITY, 1.0f, 0.0f},      {-INFINITY, INFINITY, -0.0f},
                               {kNaN, 1.0f, 0.0f},          {INFINITY, kNaN, 1.0f},
                               {FLT_MAX, FLT_MAX, FLT_MAX}, {FLT_MIN, 0.0f, -FLT_MIN},
                               {1.0f, 1e-30f, -1e-38f},     {3e38f, -3e38f, 1.0f},
                               {1e30f, 1e-30f, 0.0f},       {from_bits(0x00800001u), from_bits(1u), 0.0f}};
  for (int k = 0; k < 48; ++k)  // every special vector in several lane positions, beside random ones
    for (int c = 0; c < 3; ++c) a[3 * (37 * k + 5) + c] = specials[k % 12][c];
  // Vectors 4000 .. 4959 (whole groups of 8 and 16 lanes, past the specials): every component 0 or at least
  // 2^-50 in magnitude, so that the lanes' pc_dot and pc_cross take their path without flushes. A third of
  // the components lie at that bound (products at 2^-100, sums that cancel to a few units of 2^-123), others
  // up to 2^127 (products that overflow). From 4480 on, one component of a and b in each vector is near
  // 2^-63 instead, so that their product is near FLT_MIN, which only the flushing path gets right.
  std::mt19937_64 rng(93);
  std::uniform_real_distribution<double> u(0, 1);
  for (size_t i = 4000; i < 4960; ++i) {
    int near_min = i < 4480 ? -1 : int(u(rng) * 3);
    for (std::vector<float>* v : {&a, &b})
      for (int c = 0; c < 3; ++c) {
        double pick = u(rng);
        float x = c == near_min ? float(std::ldexp(u(rng) + 1, -64 + int(u(rng) * 2)))
                  : pick < 0.1  ? 0.0f
                  : pick < 0.4  ? float(std::ldexp(1 + std::floor(u(rng) * 4) * 0x1p-23, -50))
                                : float(std::ldexp(u(rng) + 1, int(u(rng) * 177) - 50));
        (*v)[3 * i + c] = u(rng) < 0.5 ? -x : x;
      }
  }
  const size_t count = a.size() / 3;  // a multiple of 16
  ASSERT_EQ(count % 16, 0u);
  std::vector<float> dot = run_vector("pc_dot_3", a, &b, count, 1), cross = run_vector("pc_cross_3", a, &b, count, 3);
  std::vector<float> length = run_vector("pc_length_3", a, nullptr, count, 1);
  std::vector<float> normal = run_vector("pc_normalize_3", a, nullptr, count, 3);
  auto same = [](float x, float y) { return bits(x) == bits(y) || (std::isnan(x) && std::isnan(y)); };
  for (int width : {1, 8, 16}) {
    std::vector<float> lanes = run_vector("lane3_geometric_" + std::to_string(width), a, &b, count / width, 8 * width);
    size_t wrong = 0;
    for (size_t i = 0; i < count; ++i) {
      const float* r = &lanes[8 * i];
      const float expected[8] = {dot[i], cross[3 * i], cross[3 * i + 1], cross[3 * i + 2], length[i],
                                 normal[3 * i], normal[3 * i + 1], normal[3 * i + 2]};
      for (int k = 0; k < 8; ++k) {
        // length and normalize return the one NaN (exact_math.cl): bit for bit; dot and cross propagate
        // their inputs' NaNs, any NaN.
        const bool ok = k == 4 || k >= 5 ? bits(r[k]) == bits(expected[k]) : same(r[k], expected[k]);
        if (!ok && wrong++ < 5)
          ADD_FAILURE() << width << " lanes, vector " << i << vec_string(&a[3 * i], 3) << ", result " << k << ": "
                        << hex(r[k]) << ", float3 " << hex(expected[k]);
      }
    }
    EXPECT_EQ(wrong, 0u) << width << " lanes";
  }
}

// ---- denormal flushing ----------------------------------------------------------------------------------

// Built with -cl-denorms-are-zero (on PoCL the CPU then flushes denormal inputs and results), every function
// gives the same bits, on inputs whose intermediates or results come near FLT_MIN.
TEST(ExactMath, SameBitsWhereDenormalsAreFlushed) {
  // Released at the end of the test, not at exit: Oclgrind 21.10 aborts at exit when a second program of
  // this context is released then.
  KernelProgram flushing =
      build_kernel_program(test_device(), "tests_math.cl", math_options() + " -cl-denorms-are-zero");
  std::mt19937_64 rng(70);
  std::uniform_real_distribution<double> u(0, 1);
  auto near_min = [&] { return float(std::ldexp(u(rng) + 1, -126 + int(u(rng) * 40)) * (u(rng) < 0.5 ? -1 : 1)); };
  std::vector<float> x = edge_values(), y = edge_values();
  add_random_bits(x, 20000, 71);
  add_random_bits(y, 20000, 72);
  for (int i = 0; i < 20000; ++i) {
    x.push_back(near_min()), y.push_back(float(std::ldexp(u(rng) + 1, int(u(rng) * 60) - 20)));  // tiny ratios
    x.push_back(float(-88 - 16 * u(rng))), y.push_back(float(-120 - 32 * u(rng)));              // exp, exp2 near 0
    float base = float(0.5 + 0.5 * u(rng));  // powr(base, y) near FLT_MIN
    x.push_back(base), y.push_back(float(-126 / std::log2(double(base)) * (1 + (u(rng) - 0.5) * 0.05)));
  }
  std::vector<float> xy = x;
  xy.insert(xy.end(), y.begin(), y.end());
  for (const char* f : {"pc_sin", "pc_cos", "pc_acos", "pc_log", "pc_exp", "pc_exp2", "pc_erf"}) {
    std::vector<float> a = run_elementwise(f, {xy})[0], b = run_elementwise(f, {xy}, 1, flushing)[0];
    for (size_t i = 0; i < xy.size(); ++i)
      ASSERT_EQ(bits(a[i]), bits(b[i])) << f << "(" << hex(xy[i]) << ") = " << hex(a[i]) << ", flushing " << hex(b[i]);
  }
  for (const char* f : {"pc_atan2", "pc_powr"}) {
    std::vector<float> xs = x;
    if (std::string(f) == "pc_powr")
      for (float& v : xs) v = std::fabs(v);
    std::vector<float> a = run_elementwise(f, {xs, y})[0], b = run_elementwise(f, {xs, y}, 1, flushing)[0];
    for (size_t i = 0; i < x.size(); ++i)
      ASSERT_EQ(bits(a[i]), bits(b[i])) << f << "(" << hex(xs[i]) << ", " << hex(y[i]) << ") = " << hex(a[i])
                                        << ", flushing " << hex(b[i]);
  }
  for (int n : {2, 3, 4}) {
    std::vector<float> va = random_vectors(n, 20000, 80 + n), vb = random_vectors(n, 20000, 90 + n);
    for (size_t i = 0; i < va.size(); ++i)  // products near FLT_MIN
      if (i % 7 == 0) {
        va[i] = near_min() * float(std::ldexp(1.0, 20));
        vb[i] = float(std::ldexp(u(rng) + 1, -20 - int(u(rng) * 8)));
      }
    size_t count = va.size() / n;
    std::string suffix = "_" + std::to_string(n);
    std::vector<std::pair<std::string, size_t>> kernels = {{"pc_dot", 1}, {"pc_length", 1}, {"pc_normalize", n}};
    if (n > 2) kernels.push_back({"pc_cross", n});
    for (auto& [k, width] : kernels) {
      bool two = k == "pc_dot" || k == "pc_cross";
      std::vector<float> a = run_vector(k + suffix, va, two ? &vb : nullptr, count, width);
      std::vector<float> b = run_vector(k + suffix, va, two ? &vb : nullptr, count, width, flushing);
      for (size_t i = 0; i < a.size(); ++i)
        ASSERT_EQ(bits(a[i]), bits(b[i])) << k << suffix << " of " << vec_string(&va[i / width * n], n) << ": " << hex(a[i])
                                          << ", flushing " << hex(b[i]);
    }
  }
}

// ---- throughput ----------------------------------------------------------------------------------------

// 16M evaluations per kernel, exact and builtin alternately (A B A B ...), medians of 5 runs.
TEST(ExactMathBench, DISABLED_Throughput) {
  ClContext& cl = test_device();
  const cl_uint items = 1 << 16, count = 256;
  ClBuffer out(cl, CL_MEM_WRITE_ONLY, items * sizeof(float));
  std::printf("%s\n  %-12s %12s %12s %8s\n", cl.info.name.c_str(), "function", "exact Meval/s", "builtin", "ratio");
  for (const char* f : {"sin", "cos", "sincos", "atan2", "powr", "normalize"}) {
    std::vector<double> t[2];
    for (int rep = 0; rep < 5; ++rep)
      for (int exact = 1; exact >= 0; --exact) {
        ClKernel k(math_program().kernel((std::string("bench_") + (exact ? "pc_" : "") + f).c_str()));
        k.arg(0, count);
        k.arg(1, 1.0f / items);
        k.arg(2, out.mem);
        t[exact].push_back(run_kernel(cl, k.k, items));
      }
    for (auto& v : t) std::sort(v.begin(), v.end());
    double evals = double(items) * count;
    std::printf("  %-12s %12.1f %12.1f %8.2f\n", f, evals / t[1][2] / 1e3, evals / t[0][2] / 1e3, t[1][2] / t[0][2]);
  }
}
