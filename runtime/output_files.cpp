#include "runtime/output_files.h"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstring>
#include <filesystem>

#include <fcntl.h>
#include <unistd.h>

#include "runtime/errors.h"

namespace fs = std::filesystem;

namespace {

std::string lower_extension(const std::string& path) {
  std::string ext = fs::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  return ext;
}

void check_one(const OutputFile& f) {
  std::string where = f.option + " " + f.path + ": ";
  if (fs::is_directory(f.path) || f.path.back() == '/')
    throw UsageError(where + "is a directory; expected a file name" +
                     (f.image ? " ending in .exr or .png" : ""));
  if (f.image) image_format(f.option, f.path);
  fs::path parent = fs::path(f.path).parent_path();
  if (parent.empty()) parent = ".";
  std::error_code ec;
  fs::create_directories(parent, ec);
  if (ec) throw UsageError(where + "cannot make the directory " + parent.string() + ": " + ec.message());
  // Files are written beside their target and renamed over it (runtime/atomic_file.h): what must work is
  // creating a file in the directory, so that is tried (access(2) would say yes to root on /proc).
  std::string probe = f.path + ".partial." + std::to_string(::getpid()) + ".probe";
  int fd = ::open(probe.c_str(), O_WRONLY | O_CREAT | O_EXCL, 0644);
  if (fd < 0)
    throw UsageError(where + "cannot write into the directory " + parent.string() + ": " + std::strerror(errno));
  ::close(fd);
  ::unlink(probe.c_str());
}

}  // namespace

ImageFormat image_format(const std::string& option, const std::string& path) {
  std::string ext = lower_extension(path);
  if (ext == ".exr" && option != "--png") return ImageFormat::exr;
  if (ext == ".png") return ImageFormat::png;
  std::string expected = option == "--png" ? "a name ending in .png" : "a name ending in .exr (OpenEXR) or .png";
  throw UsageError(option + " " + path + ": " +
                   (ext.empty() ? "no file extension" : "pathcl does not write " + ext + " files") + "; expected " +
                   expected);
}

void check_output_files(const std::vector<OutputFile>& files) {
  std::vector<std::pair<fs::path, const OutputFile*>> seen;
  for (const OutputFile& f : files) {
    if (f.path.empty()) continue;
    check_one(f);
    std::error_code ec;
    fs::path canonical = fs::weakly_canonical(f.path, ec);
    if (ec) canonical = fs::absolute(f.path);
    for (const auto& [other, first] : seen)
      if (other == canonical)
        throw UsageError(f.option + " " + f.path + ": the same file as " + first->option + " " + first->path +
                         "; each output needs its own file");
    seen.emplace_back(canonical, &f);
  }
}

void write_image(const std::string& path, const Image& image) {
  if (image_format("-o", path) == ImageFormat::png)
    write_png(path, image);
  else
    write_exr(path, image);
}
