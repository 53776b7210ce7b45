// Kernel sources embedded at build time (cmake/embed_kernels.cmake) and assembled for the compiler.
#pragma once
#include <string>
#include <vector>

struct KernelSourceFile {
  const char* name;  // path relative to kernels/, e.g. "intersect.cl", "shared/types.h"
  const char* text;
};

const std::vector<KernelSourceFile>& kernel_source_files();

// Adds a source file under `name` beside the embedded ones (a technique that a test registers with its
// own kernel); names are never reused or removed.
void register_kernel_source(const std::string& name, const std::string& text);

// The main file with every `#include "..."` expanded once, each piece preceded by a #line marker so
// that compiler messages name the real file and line (e.g. "intersect.cl:87").
std::string assemble_kernel_source(const std::string& main_file);
