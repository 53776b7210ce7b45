#include "runtime/kernel_program.h"

#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <deque>
#include <iterator>
#include <mutex>
#include <set>
#include <sstream>
#include <vector>

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include "runtime/atomic_file.h"
#include "runtime/hash.h"
#include "runtime/kernel_sources.h"
#include "scene/device_scene.h"

namespace fs = std::filesystem;

namespace {

// Sources registered at run time (register_kernel_source): a test's own technique.
std::mutex registered_mutex;
std::deque<std::pair<std::string, std::string>>& registered_sources() {  // a deque: texts never move
  static std::deque<std::pair<std::string, std::string>> sources;
  return sources;
}

const char* find_source(const std::string& name) {
  for (const KernelSourceFile& f : kernel_source_files())
    if (name == f.name) return f.text;
  std::lock_guard<std::mutex> lock(registered_mutex);
  for (const auto& [n, text] : registered_sources())
    if (n == name) return text.c_str();
  return nullptr;
}

// A file under templates/ is expanded at every #include (code written once over types that its includer
// defines before each include: the lane widths); any other file once.
bool is_template(const std::string& name) { return name.rfind("templates/", 0) == 0; }

void expand(const std::string& name, std::set<std::string>& seen, std::string& out) {
  const char* text = find_source(name);
  if (!text) throw RuntimeFailure("kernel source \"" + name + "\" is not embedded in this build");
  if (!is_template(name)) seen.insert(name);
  out += "#line 1 \"" + name + "\"\n";
  std::istringstream in(text);
  std::string line;
  for (int number = 1; std::getline(in, line); ++number) {
    size_t start = line.find("#include \"");
    if (start != std::string::npos && line.find_first_not_of(" \t") == start) {
      std::string included = line.substr(start + 10, line.find('"', start + 10) - start - 10);
      if (!seen.count(included)) expand(included, seen, out);
      out += "#line " + std::to_string(number + 1) + " \"" + name + "\"\n";
    } else {
      out += line + "\n";
    }
  }
}

fs::path cache_directory() {
  if (const char* dir = std::getenv("PATHCL_KERNEL_CACHE")) return dir;
  if (const char* xdg = std::getenv("XDG_CACHE_HOME"); xdg && *xdg) return fs::path(xdg) / "pathcl" / "kernels";
  if (const char* home = std::getenv("HOME"); home && *home) return fs::path(home) / ".cache" / "pathcl" / "kernels";
  return {};
}

std::string build_log(cl_program program, cl_device_id device) {
  size_t size = 0;
  clGetProgramBuildInfo(program, device, CL_PROGRAM_BUILD_LOG, 0, nullptr, &size);
  std::string log(size, '\0');
  clGetProgramBuildInfo(program, device, CL_PROGRAM_BUILD_LOG, size, log.data(), nullptr);
  while (!log.empty() && (log.back() == '\0' || log.back() == '\n')) log.pop_back();
  return log;
}

std::vector<unsigned char> program_binary(cl_program program) {
  size_t size = 0;
  CL_CHECK(clGetProgramInfo(program, CL_PROGRAM_BINARY_SIZES, sizeof(size), &size, nullptr));
  std::vector<unsigned char> binary(size);
  unsigned char* ptr = binary.data();
  CL_CHECK(clGetProgramInfo(program, CL_PROGRAM_BINARIES, sizeof(ptr), &ptr, nullptr));
  return binary;
}

// A cache file's contents; empty if there is none or it is damaged (the file ends with an FNV-1a checksum of
// the contents, checked before a driver ever sees the bytes).
std::vector<unsigned char> read_cached(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) return {};
  std::vector<unsigned char> binary((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (binary.size() <= sizeof(uint64_t)) return {};
  uint64_t stored;
  std::memcpy(&stored, binary.data() + binary.size() - sizeof stored, sizeof stored);
  binary.resize(binary.size() - sizeof stored);
  if (fnv1a(binary.data(), binary.size()) != stored) return {};
  return binary;
}

// Loads and builds a cached binary; nullptr if there is none, it is damaged or the driver rejects it.
cl_program load_cached(ClContext& cl, const fs::path& file, const std::string& options) {
  std::vector<unsigned char> binary = read_cached(file);
  if (binary.empty()) return nullptr;
  const unsigned char* ptr = binary.data();
  size_t size = binary.size();
  cl_int status = CL_SUCCESS, binary_status = CL_SUCCESS;
  cl_program program =
      clCreateProgramWithBinary(cl.context, 1, &cl.info.device, &size, &ptr, &binary_status, &status);
  if (status != CL_SUCCESS || binary_status != CL_SUCCESS) {
    if (program) clReleaseProgram(program);
    return nullptr;
  }
  if (clBuildProgram(program, 1, &cl.info.device, options.c_str(), nullptr, nullptr) != CL_SUCCESS) {
    clReleaseProgram(program);
    return nullptr;
  }
  return program;
}

// PoCL with its own cache on (POCL_KERNEL_CACHE=0 turns it off).
bool driver_caches_programs(const DeviceInfo& d) {
  const char* pocl_cache = std::getenv("POCL_KERNEL_CACHE");
  return is_pocl(d) && !(pocl_cache && std::string(pocl_cache) == "0");
}

// Written atomically (runtime/atomic_file.h), so concurrent processes never read half a binary.
void store_cached(const fs::path& file, const std::vector<unsigned char>& binary) {
  std::error_code ec;
  fs::create_directories(file.parent_path(), ec);
  std::vector<unsigned char> bytes = binary;
  uint64_t checksum = fnv1a(binary.data(), binary.size());
  bytes.insert(bytes.end(), reinterpret_cast<const unsigned char*>(&checksum),
               reinterpret_cast<const unsigned char*>(&checksum) + sizeof checksum);
  try {
    write_binary_file(file.string(), bytes.data(), bytes.size());
  } catch (const RuntimeFailure&) {
    // The cache is an optimisation: an unwritable directory only costs build time.
  }
}

// An exclusive lock on the cache entry `file` (flock on FILE.lock, held until destruction): one build of a
// program at a time, between the threads of one process (each device's worker) and between processes, so
// that a second build of the same program waits and then loads what the first stored, rather than compiling
// it at the same time (two identical devices, the ranks of an MPI job on one machine, tests run at once).
// Without a usable cache directory it locks nothing.
class CacheEntryLock {
 public:
  explicit CacheEntryLock(const fs::path& file) {
    if (file.empty()) return;
    std::error_code ec;
    fs::create_directories(file.parent_path(), ec);
    fd_ = ::open((file.string() + ".lock").c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
    if (fd_ >= 0 && ::flock(fd_, LOCK_EX) != 0) {
      ::close(fd_);
      fd_ = -1;
    }
  }
  ~CacheEntryLock() {
    if (fd_ >= 0) ::close(fd_);  // releases the lock
  }
  CacheEntryLock(const CacheEntryLock&) = delete;
  CacheEntryLock& operator=(const CacheEntryLock&) = delete;

 private:
  int fd_ = -1;
};

}  // namespace

void register_kernel_source(const std::string& name, const std::string& text) {
  if (find_source(name)) throw std::logic_error("kernel source \"" + name + "\" exists already");
  std::lock_guard<std::mutex> lock(registered_mutex);
  registered_sources().emplace_back(name, text);
}

std::string assemble_kernel_source(const std::string& main_file) {
  std::set<std::string> seen;
  // In force from the first line of every program: a fused multiply-add rounds once where the source
  // rounds twice, and drivers differ in where they fuse, so contraction would make the bits depend on
  // the OpenCL implementation (and let rays slip through shared triangle edges).
  // And clang's ABI notes (-Wpsabi) are off: compiled for a CPU without AVX-512 (PoCL on AVX2), every call
  // passing a float16 or uint16 draws one (the ray tracer's 16-wide packets: 136; 16 lanes: 1152), which
  // PoCL printed at each build (612 for the Cornell box's 8-lane program before the kernels' functions were
  // static: PoCL builds with -Dinline=, and compiled the 16-lane functions of the lane templates there too).
  // They say that such a call would differ from one compiled for AVX-512; a program's functions are
  // compiled together, for one target.
  std::string out = "#pragma OPENCL FP_CONTRACT OFF\n#ifdef __clang__\n#pragma clang diagnostic ignored \"-Wpsabi\"\n#endif\n";
  expand(main_file, seen, out);
  return out;
}

namespace {
// The -D flag of each feature bit of scene/device_scene.h, in bit order.
const char* const kFeatureFlags[] = {
    "PC_HAS_TRIANGLES",  "PC_HAS_SPHERES",         "PC_HAS_SMOOTH_NORMALS", "PC_HAS_AREA_LIGHTS",
    "PC_HAS_DIFFUSE",    "PC_HAS_OREN_NAYAR",      "PC_HAS_PHONG",          "PC_HAS_MIRROR",
    "PC_HAS_DIELECTRIC", "PC_HAS_ROUGH_CONDUCTOR", "PC_HAS_PLASTIC",        "PC_HAS_TEXTURES",
    "PC_HAS_POINT_LIGHTS", "PC_HAS_DIRECTIONAL_LIGHTS", "PC_HAS_ENVIRONMENT", "PC_HAS_ENVIRONMENT_MAP",
    "PC_HAS_CUTOUTS", "PC_HAS_INSTANCES", "PC_HAS_VERTEX_COLORS"};
constexpr uint32_t kFeatureCount = sizeof kFeatureFlags / sizeof kFeatureFlags[0];
static_assert(kFeatureCount == 19 && kFeatureAll == (1u << kFeatureCount) - 1, "one flag per feature bit");
}  // namespace

std::string kernel_options(uint32_t features) {
  // No fast-math options: they break the slab test's infinities and the watertight triangle test.
  std::string options = "-cl-std=CL1.2";
  for (uint32_t bit = 0; bit < kFeatureCount; ++bit)
    if (features & (1u << bit)) options += std::string(" -D") + kFeatureFlags[bit];
  return options;
}

KernelProgram::KernelProgram(KernelProgram&& o) noexcept
    : program(o.program), build_ms(o.build_ms), from_cache(o.from_cache), options(std::move(o.options)) {
  o.program = nullptr;
}

KernelProgram::~KernelProgram() {
  if (program) clReleaseProgram(program);
}

cl_kernel KernelProgram::kernel(const char* name) const { return CL_CHECKED(clCreateKernel, program, name); }

KernelProgram build_kernel_program(ClContext& cl, const std::string& main_file, const std::string& requested) {
  auto start = std::chrono::steady_clock::now();
  std::string source = assemble_kernel_source(main_file);
  KernelProgram result;
  // Correctly rounded division and sqrt where the device offers them (OpenCL's default allows 2.5 and
  // 3 ulp): with contraction off, every operation of the kernels is then exactly defined.
  std::string options = requested;
  if (cl.info.correctly_rounded_divide_sqrt) options += " -cl-fp32-correctly-rounded-divide-sqrt";
  // The device's BVH layout (runtime/device.h): PC_BVH_WIDE for the 8- and 16-wide ones, with leaf blocks.
  if (bvh_width(cl.info) != 4) options += " -DPC_BVH_WIDE=" + std::to_string(bvh_width(cl.info));
  // Oclgrind 21.10 cannot execute the llvm.bitreverse that clang's optimiser makes of sampler.cl's bit
  // reversal; unoptimised, the same source computes the same bits.
  if (is_oclgrind(cl.info)) options += " -cl-opt-disable";
  result.options = options;
  const DeviceInfo& d = cl.info;
  std::string identity = source + '\x1f' + options + '\x1f' + d.platform_name + '\x1f' + d.platform_version + '\x1f' +
                         d.name + '\x1f' + d.version + '\x1f' + d.driver_version;
  uint64_t key = fnv1a(identity.data(), identity.size());
  fs::path dir = cache_directory();
  char hex[17];
  std::snprintf(hex, sizeof hex, "%016llx", static_cast<unsigned long long>(key));
  // PoCL keeps what it compiles in a cache of its own (POCL_CACHE_DIR, else ~/.cache/pocl/kcache), the code
  // it generates for a kernel's work-group size at the first launch included. Asked for a binary, it
  // compiles a generic work-group function of every kernel besides, which no launch of ours uses: 2.8 of
  // the 7.9 s that the Cornell box's path program took cold. So for PoCL our cache holds a stamp saying
  // that the program was built, and the build from source finds PoCL's cached code (unless PoCL's cache is
  // off: POCL_KERNEL_CACHE=0, then the binary as for other drivers).
  const bool stamp_only = driver_caches_programs(d);
  fs::path file = dir.empty() ? fs::path()
                              : dir / (fs::path(main_file).stem().string() + "-" + hex + (stamp_only ? ".built" : ".bin"));
  auto elapsed_ms = [&] { return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count(); };

  if (cl.keep_programs) {
    std::lock_guard<std::mutex> lock(cl.kept_programs_mutex);
    for (const auto& [kept_key, program] : cl.kept_programs)
      if (kept_key == key) {
        CL_CHECK(clRetainProgram(program));
        result.program = program;
        result.from_cache = true;
        result.build_ms = elapsed_ms();
        return result;
      }
  }
  CacheEntryLock entry_lock(file);  // until the program is built and stored
  if (!file.empty() && stamp_only) result.from_cache = !read_cached(file).empty();
  if (!file.empty() && !stamp_only) result.from_cache = (result.program = load_cached(cl, file, options)) != nullptr;
  if (!result.program) {
    const char* text = source.c_str();
    size_t length = source.size();
    result.program = CL_CHECKED(clCreateProgramWithSource, cl.context, 1, &text, &length);
    cl_int status = clBuildProgram(result.program, 1, &d.device, options.c_str(), nullptr, nullptr);
    if (status != CL_SUCCESS)
      throw RuntimeFailure("kernel build of " + main_file + " failed (" + cl_error_name(status) + ") on " + d.name +
                           " with options \"" + options + "\":\n" + build_log(result.program, d.device));
    if (!file.empty() && !result.from_cache)
      store_cached(file, stamp_only ? std::vector<unsigned char>{'s', 't', 'a', 'm', 'p'} : program_binary(result.program));
  }
  if (cl.keep_programs) {
    std::lock_guard<std::mutex> lock(cl.kept_programs_mutex);
    if (cl.kept_programs.size() >= ClContext::kKeptPrograms) {
      clReleaseProgram(cl.kept_programs.front().second);
      cl.kept_programs.erase(cl.kept_programs.begin());
    }
    CL_CHECK(clRetainProgram(result.program));
    cl.kept_programs.emplace_back(key, result.program);
  }
  result.build_ms = elapsed_ms();
  return result;
}
