// SPDX-License-Identifier: MIT
#pragma once
#include <filesystem>

#include "io/png_image.h"

namespace nfield::io {

// Reads a picture file, PNG or WebP, told apart by its first bytes (not its name): PNG
// through read_png (8 or 16 bits, 1 to 4 channels); WebP, lossy or lossless, through libwebp
// (8 bits, RGB, or RGBA when the file has alpha). The large pictures that Debian packages
// ship (gnome-backgrounds' 4096² wallpapers) are WebP. Throws std::runtime_error naming
// `path` when the file is missing, is neither format or does not decode.
Image read_image(const std::filesystem::path& path);

// True for the file names read_image is meant for (.png, .webp, any case): how a folder of
// pictures is listed.
bool is_image_file_name(const std::filesystem::path& path);

}  // namespace nfield::io
