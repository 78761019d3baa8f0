// SPDX-License-Identifier: MIT
#pragma once
#include <filesystem>
#include <functional>

namespace nfield::io {

// Writes `path` all at once or not at all: calls write(temporary) with a hidden temporary
// path in the same folder (same extension), then renames the temporary onto `path`. If the
// folder is missing, `write` throws, or the temporary was not created or cannot be renamed,
// the temporary is removed and std::runtime_error("cannot write '<path>': <reason>") is thrown;
// an existing `path` is then left as it was.
void write_atomically(const std::filesystem::path& path,
                      const std::function<void(const std::filesystem::path&)>& write);

}  // namespace nfield::io
