// SPDX-License-Identifier: MIT
//
// A family of pictures for `problem: fit` (issue 28, item 5): many images of one size, fitted
// one at a time by the instances of a meta-learning run (training.meta,
// solvers/training/reptile.h), some held out to measure how fast a new picture is fitted.
//
//   equation:
//     signal: image
//     channels: grey                    # auto | grey | rgb, as for one picture (auto: the
//                                       #   first picture's: RGB if it has colour)
//     family:
//       images: ../data/images/family   # a folder (its *.png in name order) or a list of files
//       crop: 64                        # n or [width, height]: each picture's central crop
//       held_out: 4                     # the last n pictures, or a list of file names
//
// Without `crop`, every picture must have the first one's size; with it, every picture must
// be at least the crop in each direction. Either mismatch is a located error at `images`
// naming the file and both sizes: a family whose members differ in size has no one field
// shape (nor one coordinate grid) to learn an initialisation for. At least one picture must
// stay for training; held-out names must be among the pictures.
#pragma once

#include <cstddef>
#include <filesystem>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "io/config.h"
#include "io/png_image.h"

namespace nfield::solvers {

struct ImageFamily {
  std::vector<io::Image> images;   // the training pictures first, then the held-out ones
  std::vector<std::string> names;  // their file names
  std::size_t training = 0;        // how many are for training
};

// The order of a family's files (equation.family.held_out, of pictures or meshes): training
// ones first, in file order, then the held-out ones in the order held_out gives (a list of file
// names) or the last n (a count); `training` is set to how many are for training. Errors are
// located at held_out and name the family's `noun` ("pictures").
std::vector<std::size_t> held_out_last(const io::ConfigNode& family, const std::vector<std::filesystem::path>& files,
                                       std::size_t& training, const std::string& noun);

// The `crop` key of `node` (equation, or equation.family): n or [width, height], each in
// [1, 65536]; nullopt when absent.
std::optional<std::pair<int, int>> read_crop_size(const io::ConfigNode& node);

// Reads `family` (the node of equation.family); paths relative to `config_dir`; `channels`
// is auto, grey or rgb. Throws io::ConfigError located at the key at fault.
ImageFamily read_image_family(const io::ConfigNode& family, const std::filesystem::path& config_dir,
                              const std::string& channels);

}  // namespace nfield::solvers
