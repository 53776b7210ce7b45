// The files a command will write, checked before any work starts, so that a render is never lost at
// its end to a bad name: each names a file (not a directory) in a directory that exists or can be
// made and is writable, no two name the same file, and an image's extension names its format.
#pragma once
#include <string>
#include <vector>

#include "runtime/image_io.h"

enum class ImageFormat { exr, png };

struct OutputFile {
  std::string option;  // as the user wrote it: "-o", "--png", "--stats"
  std::string path;
  bool image = false;  // must end in .exr or .png (case-insensitive)
};

// UsageError "OPTION PATH: ..." for a bad or unsupported extension.
ImageFormat image_format(const std::string& option, const std::string& path);
// Checks all of them (UsageError naming the option and the path) and makes the missing parent
// directories. Empty paths are skipped.
void check_output_files(const std::vector<OutputFile>& files);
// Writes EXR or PNG by the extension of path.
void write_image(const std::string& path, const Image& image);
