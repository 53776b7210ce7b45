#include "runtime/atomic_file.h"

#include <atomic>
#include <cerrno>
#include <climits>
#include <cstring>
#include <filesystem>
#include <fstream>

#include <unistd.h>

#include "runtime/errors.h"

namespace {

// The temporary files being written, in fixed slots that a signal handler can read without locks or
// allocation. A file that finds no free slot (more than kSlots written at once) is simply not removed
// by a hard exit.
constexpr int kSlots = 16;
char g_paths[kSlots][PATH_MAX];
std::atomic<bool> g_used[kSlots];  // slot taken by a writer
std::atomic<bool> g_live[kSlots];  // g_paths[i] holds a complete name

int register_partial(const std::string& tmp) {
  if (tmp.size() >= PATH_MAX) return -1;
  for (int i = 0; i < kSlots; ++i) {
    bool expected = false;
    if (!g_used[i].compare_exchange_strong(expected, true)) continue;
    std::memcpy(g_paths[i], tmp.c_str(), tmp.size() + 1);
    g_live[i].store(true);
    return i;
  }
  return -1;
}

void unregister_partial(int slot) {
  if (slot < 0) return;
  g_live[slot].store(false);
  g_used[slot].store(false);
}

}  // namespace

void remove_partial_files_now() {
  for (int i = 0; i < kSlots; ++i)
    if (g_live[i].load()) ::unlink(g_paths[i]);
}

void write_file_atomically(const std::string& path, const std::string& what,
                           const std::function<void(const std::string& tmp)>& write) {
  // Unique per process and call: several threads may write the same target (cached kernels).
  static std::atomic<unsigned> counter{0};
  std::string tmp = path + ".partial." + std::to_string(::getpid()) + "." + std::to_string(counter++);
  std::string prefix = path + ": cannot write" + (what.empty() ? "" : " " + what);
  int slot = register_partial(tmp);
  std::error_code ec;
  try {
    write(tmp);
  } catch (const std::exception& e) {
    std::filesystem::remove(tmp, ec);
    unregister_partial(slot);
    throw RuntimeFailure(prefix + ": " + e.what());
  }
  std::filesystem::rename(tmp, path, ec);
  if (ec) {
    std::error_code ignored;
    std::filesystem::remove(tmp, ignored);
  }
  unregister_partial(slot);
  if (ec) throw RuntimeFailure(prefix + ": " + ec.message());
}

void write_binary_file(const std::string& path, const void* data, size_t bytes) {
  write_file_atomically(path, "", [&](const std::string& tmp) {
    errno = 0;
    std::ofstream out(tmp, std::ios::binary);
    out.write(static_cast<const char*>(data), std::streamsize(bytes));
    out.flush();
    if (!out) throw std::runtime_error(errno ? std::strerror(errno) : "the write failed");
  });
}

void write_text_file(const std::string& path, const std::string& text) {
  write_binary_file(path, text.data(), text.size());
}
