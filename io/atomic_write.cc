// SPDX-License-Identifier: MIT
#include "io/atomic_write.h"

#include <unistd.h>

#include <atomic>
#include <stdexcept>
#include <string>
#include <system_error>

namespace nfield::io {
namespace fs = std::filesystem;

namespace {
fs::path temporary_for(const fs::path& path) {
  static std::atomic<unsigned long> counter{0};
  std::string name = ".";  // (appending avoids a GCC 12 -Wrestrict false positive)
  name += path.stem().string();
  name += ".tmp-" + std::to_string(::getpid()) + "-" + std::to_string(counter++);
  name += path.extension().string();
  return path.parent_path() / name;
}
}  // namespace

void write_atomically(const fs::path& path, const std::function<void(const fs::path&)>& write) {
  const auto fail = [&](const std::string& why) {
    return std::runtime_error("cannot write '" + path.string() + "': " + why);
  };
  if (path.filename().empty()) throw fail("not a file name");
  const fs::path dir = path.parent_path().empty() ? fs::path(".") : path.parent_path();
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) throw fail("folder '" + dir.string() + "' does not exist");
  const fs::path tmp = temporary_for(path);
  try {
    write(tmp);
    if (!fs::is_regular_file(tmp, ec)) throw std::runtime_error("no file was written");
    fs::rename(tmp, path, ec);
    if (ec) throw std::runtime_error("rename failed: " + ec.message());
  } catch (const std::exception& e) {
    fs::remove(tmp, ec);
    throw fail(e.what());
  }
}

}  // namespace nfield::io
