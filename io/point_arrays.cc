// SPDX-License-Identifier: MIT
#include "io/point_arrays.h"

#include <stdexcept>

namespace nfield::io {

const Eigen::MatrixXd& require_array(const PointArrays& arrays, std::string_view name,
                                     const std::filesystem::path& file) {
  if (auto it = arrays.find(name); it != arrays.end()) return it->second;
  std::string present;
  for (const auto& [n, a] : arrays) present += (present.empty() ? "" : ", ") + n;
  throw std::runtime_error("'" + file.string() + "' has no point array '" + std::string(name) +
                           "' (present: " + (present.empty() ? "none" : present) + ")");
}

}  // namespace nfield::io
