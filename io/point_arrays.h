// SPDX-License-Identifier: MIT
#pragma once
#include <filesystem>
#include <functional>
#include <map>
#include <string>
#include <string_view>

#include <Eigen/Core>

namespace nfield::io {

// Named per-point data: each matrix has one row per point and one column per component
// (1: scalar, 2 or 3: vector, more: anything else).
using PointArrays = std::map<std::string, Eigen::MatrixXd, std::less<>>;

// How real numbers are stored in a VTK file. Reading always gives double.
enum class Precision { kFloat64, kFloat32 };

// arrays[name], or std::runtime_error naming `file`, the missing array and those present.
const Eigen::MatrixXd& require_array(const PointArrays& arrays, std::string_view name,
                                     const std::filesystem::path& file);

}  // namespace nfield::io
