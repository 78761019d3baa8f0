// SPDX-License-Identifier: MIT
#include "solvers/problems/image_family.h"

#include <algorithm>
#include <optional>
#include <utility>

#include "io/image_file.h"
#include "io/text.h"

namespace nfield::solvers {
namespace {

namespace fs = std::filesystem;

std::vector<fs::path> family_files(const io::ConfigNode& family, const fs::path& config_dir) {
  std::vector<fs::path> files;
  if (family.has_list("images")) {
    const io::ConfigNode list = family.child("images");
    family.require("images", list.size() >= 2, "expected at least two pictures");
    for (std::size_t i = 0; i < list.size(); ++i) files.push_back(config_dir / list.at(i).as<std::string>());
    return files;
  }
  const fs::path folder = config_dir / family.get<std::string>("images");
  std::error_code ec;
  if (!fs::is_directory(folder, ec))
    throw family.error("images", folder.string() + ": expected a folder of PNG or WebP pictures or a list of files");
  for (const auto& entry : fs::directory_iterator(folder, ec))
    if (entry.is_regular_file() && io::is_image_file_name(entry.path()))
      files.push_back(entry.path());
  if (ec) throw family.error("images", folder.string() + ": cannot list the folder: " + ec.message());
  std::sort(files.begin(), files.end());
  family.require("images", files.size() >= 2, folder.string() + ": expected at least two pictures (*.png, *.webp)");
  return files;
}

std::string size_text(int width, int height) { return std::to_string(width) + " x " + std::to_string(height); }

}  // namespace

std::vector<std::size_t> held_out_last(const io::ConfigNode& family, const std::vector<fs::path>& files,
                                       std::size_t& training, const std::string& noun) {
  std::vector<std::size_t> held;
  const int count = static_cast<int>(files.size());
  if (family.has_list("held_out")) {
    const io::ConfigNode list = family.child("held_out");
    for (std::size_t i = 0; i < list.size(); ++i) {
      const std::string name = list.at(i).as<std::string>();
      const auto it = std::find_if(files.begin(), files.end(), [&](const fs::path& f) {
        return f.filename().string() == name || f.string() == name;
      });
      if (it == files.end())
        throw list.at(i).error("'" + name + "' is none of the family's " + noun + " (expected a file name such as " +
                               files.front().filename().string() + ")");
      const auto k = static_cast<std::size_t>(it - files.begin());
      if (std::find(held.begin(), held.end(), k) != held.end()) throw list.at(i).error("'" + name + "' is held out twice");
      held.push_back(k);
    }
    family.require("held_out", static_cast<int>(held.size()) < count, "expected at least one of the " + noun + " left for training");
  } else if (family.has("held_out")) {
    const int n = family.get_in_range("held_out", 0, count - 1);
    for (int k = count - n; k < count; ++k) held.push_back(static_cast<std::size_t>(k));
  }
  std::vector<std::size_t> order;
  for (std::size_t k = 0; k < files.size(); ++k)
    if (std::find(held.begin(), held.end(), k) == held.end()) order.push_back(k);
  training = order.size();
  order.insert(order.end(), held.begin(), held.end());
  return order;
}


std::optional<std::pair<int, int>> read_crop_size(const io::ConfigNode& node) {
  if (!node.has("crop")) return std::nullopt;
  if (node.has_list("crop")) {
    const std::vector<int> size = node.get_list<int>("crop", 2);
    node.require("crop", size[0] >= 1 && size[1] >= 1 && size[0] <= 65536 && size[1] <= 65536,
                 "expected [width, height], each in [1, 65536]");
    return std::pair{size[0], size[1]};
  }
  const int size = node.get_in_range("crop", 1, 65536);
  return std::pair{size, size};
}

ImageFamily read_image_family(const io::ConfigNode& family, const fs::path& config_dir, const std::string& channels) {
  family.require(family.is_map(), "expected a mapping {images: FOLDER or [FILE, ...], crop: 64, held_out: 4}");
  const std::vector<fs::path> files = family_files(family, config_dir);
  const std::optional<std::pair<int, int>> crop = read_crop_size(family);
  ImageFamily out;
  const std::vector<std::size_t> order = held_out_last(family, files, out.training, "pictures");
  int first_width = 0, first_height = 0, chosen_channels = 0;
  for (std::size_t k = 0; k < files.size(); ++k) {
    const fs::path& file = files[k];
    io::Image image;
    try {
      image = io::read_image(file);
    } catch (const std::exception& e) {
      throw family.error("images", e.what());
    }
    if (k == 0) {
      first_width = image.width;
      first_height = image.height;
      chosen_channels = channels == "grey" ? 1 : channels == "rgb" ? 3 : image.channels >= 3 ? 3 : 1;
    }
    if (crop && (image.width < crop->first || image.height < crop->second))
      throw family.error("images", file.string() + ": a picture of " + size_text(image.width, image.height) +
                                       " pixels, smaller than the crop of " + size_text(crop->first, crop->second));
    if (!crop && (image.width != first_width || image.height != first_height))
      throw family.error("images", file.string() + ": a picture of " + size_text(image.width, image.height) +
                                       " pixels; the first, " + files.front().filename().string() + ", has " +
                                       size_text(first_width, first_height) +
                                       " (pictures of mixed sizes: give family.crop, or make them one size)");
    const int width = crop ? crop->first : image.width, height = crop ? crop->second : image.height;
    out.images.push_back(io::with_channels(io::central_crop(image, width, height), chosen_channels));
    out.names.push_back(file.filename().string());
  }
  ImageFamily ordered{{}, {}, out.training};
  for (std::size_t k : order) {
    ordered.images.push_back(std::move(out.images[k]));
    ordered.names.push_back(std::move(out.names[k]));
  }
  return ordered;
}

}  // namespace nfield::solvers
