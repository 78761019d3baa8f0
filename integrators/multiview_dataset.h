// SPDX-License-Identifier: MIT
//
// Posed images in the NeRF-synthetic `transforms.json` layout (Mildenhall et al. 2020; the
// same keys Instant NGP reads):
//
//   {
//     "camera_angle_x": 0.69,            horizontal field of view, radians, and/or
//     "fl_x": 175.9, "fl_y": 175.9,      explicit intrinsics in pixels (fl_y defaults to fl_x,
//     "cx": 64, "cy": 64, "w": 128, "h": 128     cx, cy to the image centre, w, h to the
//                                                 first image's size)
//     "frames": [ { "file_path": "./train/r_000",
//                   "transform_matrix": [[…4…], […], […], [0, 0, 0, 1]] }, … ]
//   }
//
// fl_x, when present, wins over camera_angle_x (files written by Instant NGP's tools carry
// both); camera_angle_y, when present without fl_y, sets fy. file_path is relative to the
// folder of the json file, with ".png" appended when it has no extension (the NeRF-synthetic
// files name their images without one). transform_matrix is camera-to-world with OpenGL
// camera axes (camera.h); it must be 4 × 4 and finite, with last row (0, 0, 0, 1) and an
// orthonormal rotation (to 1e-4), since rays take ‖R d‖ = ‖d‖ for granted.
//
// Images are 8- or 16-bit PNGs of 1 to 4 channels (io/png_image.h: values in [0, 1]). PNG
// alpha is straight (not premultiplied), so a pixel is composited on the background as
// rgb·a + bg·(1 − a); alpha is kept (1 for images without it), and with it the colour on any
// other background b' is rgb_bg + (b' − bg)(1 − a) (ray_batch.h: composite_on). Every image
// must have the size w × h when the file gives them, else the size of the first image.
//
// Errors are strict: a missing file, malformed JSON (with line and column), a missing or
// mistyped key, a bad matrix, a wrong image size or no frames throws DatasetError whose
// message is "FILE: KEY: what", KEY the JSON path (e.g. frames[3].transform_matrix[1][2]).
#pragma once

#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "integrators/camera.h"

namespace nfield::integrators {

class DatasetError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct DatasetOptions {
  Eigen::Vector3d background = Eigen::Vector3d::Ones();  // NeRF-synthetic trains on white

  // Throws std::invalid_argument naming the field, its value and the rule (each in [0, 1]).
  void validate() const;
};

struct PosedImage {
  std::filesystem::path path;  // the image file
  Camera camera;
  Eigen::MatrixXf rgb;    // (height·width) × 3, composited on the dataset's background,
                          // row r·width + c for pixel (r, c) as in io::Image
  Eigen::VectorXf alpha;  // height·width
};

struct MultiviewDataset {
  std::filesystem::path source;  // the json file
  Intrinsics intrinsics;         // shared by all frames
  Eigen::Vector3d background = Eigen::Vector3d::Ones();
  std::vector<PosedImage> frames;

  Eigen::Index pixels_per_image() const {
    return Eigen::Index{intrinsics.width} * intrinsics.height;
  }
};

// Reads a transforms.json and its images. Throws DatasetError (see the top of this file).
MultiviewDataset read_transforms(const std::filesystem::path& json,
                                 const DatasetOptions& options = {});

}  // namespace nfield::integrators
