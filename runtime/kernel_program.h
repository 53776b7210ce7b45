// Building kernel programs specialised to a scene's features, with an on-disk binary cache keyed by
// source, options, device and driver.
#pragma once
#include <cstdint>
#include <string>

#include "runtime/device.h"

// The -D flags that turn on the code for a feature mask (scene/device_scene.h).
std::string kernel_options(uint32_t features);

struct KernelProgram {
  cl_program program = nullptr;
  double build_ms = 0;     // source build, or loading the cached binary
  bool from_cache = false;
  std::string options;
  KernelProgram() = default;
  KernelProgram(KernelProgram&& o) noexcept;
  KernelProgram& operator=(KernelProgram&&) = delete;
  ~KernelProgram();
  cl_kernel kernel(const char* name) const;  // a new kernel object; the caller releases it
};

// The cache directory is $PATHCL_KERNEL_CACHE, else $XDG_CACHE_HOME/pathcl/kernels, else
// ~/.cache/pathcl/kernels; an empty PATHCL_KERNEL_CACHE turns caching off. A cached binary that the
// driver rejects is rebuilt from source. PoCL caches its compiled programs itself: for PoCL the cache holds
// only a stamp (from_cache: built before; kernel_program.cpp says why). A failed build throws RuntimeFailure
// with the build log.
// Where the device has correctly rounded divide and sqrt, -cl-fp32-correctly-rounded-divide-sqrt is
// added to the options (KernelProgram::options has it). With ClContext::keep_programs, a program built
// on the same context before for the same source and options is handed out again (from_cache is true).
KernelProgram build_kernel_program(ClContext& cl, const std::string& main_file, const std::string& options);

// A kernel object released with its owner.
struct ClKernel {
  cl_kernel k = nullptr;
  explicit ClKernel(cl_kernel kernel) : k(kernel) {}
  ~ClKernel() { if (k) clReleaseKernel(k); }
  ClKernel(const ClKernel&) = delete;
  template <class T>
  void arg(cl_uint index, const T& value) {
    CL_CHECK(clSetKernelArg(k, index, sizeof(T), &value));
  }
};
