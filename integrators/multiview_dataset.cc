// SPDX-License-Identifier: MIT
#include "integrators/multiview_dataset.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iterator>
#include <numbers>
#include <optional>
#include <sstream>

#include <Eigen/LU>
#include <nlohmann/json.hpp>

#include "io/png_image.h"

namespace nfield::integrators {
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

std::string str(double v) {
  std::ostringstream out;
  out << v;
  return out.str();
}

// Reads one file's keys, each error naming the file and the key's JSON path.
class Reader {
 public:
  explicit Reader(std::string file) : file_(std::move(file)) {}

  DatasetError fail(const std::string& key, const std::string& what) const {
    return DatasetError(file_ + ": " + key + ": " + what);
  }
  DatasetError fail(const std::string& key, double value, const std::string& rule) const {
    return DatasetError(file_ + ": " + key + " = " + str(value) + ": " + rule);
  }

  // parent[key] as a finite number; nullopt when absent.
  std::optional<double> number(const json& parent, const std::string& key,
                               const std::string& path) const {
    const auto it = parent.find(key);
    if (it == parent.end()) return std::nullopt;
    return number(*it, path);
  }
  double number(const json& value, const std::string& path) const {
    if (!value.is_number())
      throw fail(path, std::string("expected a number, got ") + value.type_name());
    const double v = value.get<double>();
    if (!std::isfinite(v)) throw fail(path, "is not finite");
    return v;
  }
  std::optional<double> positive(const json& parent, const std::string& key) const {
    const auto v = number(parent, key, key);
    if (v && !(*v > 0)) throw fail(key, *v, "must be > 0");
    return v;
  }
  std::optional<int> size(const json& parent, const std::string& key) const {
    const auto v = number(parent, key, key);
    if (!v) return std::nullopt;
    if (*v < 1 || *v != std::floor(*v) || *v > 1 << 20)
      throw fail(key, *v, "must be a whole number of pixels, >= 1");
    return static_cast<int>(*v);
  }
  const json& member(const json& parent, const std::string& key, const std::string& path) const {
    const auto it = parent.find(key);
    if (it == parent.end()) throw fail(path, "missing");
    return *it;
  }

 private:
  std::string file_;
};

// "LINE:COLUMN", both from 1, of the character at `offset` of `text`.
std::string line_column(const std::string& text, size_t offset) {
  offset = std::min(offset, text.size());
  const auto line = 1 + std::count(text.begin(), text.begin() + offset, '\n');
  const auto line_start = offset == 0 ? std::string::npos : text.rfind('\n', offset - 1);
  const size_t column = offset - (line_start == std::string::npos ? 0 : line_start + 1) + 1;
  return std::to_string(line) + ":" + std::to_string(column);
}

// nlohmann's message without its "[json.exception.…] " prefix and its own position
// ("parse error at line 4, column 23: "), which our FILE:LINE:COL prefix already gives.
std::string without_id(const std::string& what) {
  const auto bracket = what.find("] ");
  std::string why = bracket == std::string::npos ? what : what.substr(bracket + 2);
  if (why.starts_with("parse error at line "))
    if (const auto colon = why.find(": "); colon != std::string::npos) why = why.substr(colon + 2);
  return why;
}

std::string element(const std::string& path, size_t i) {
  return path + "[" + std::to_string(i) + "]";
}

Eigen::Matrix4d read_pose(const Reader& in, const json& value, const std::string& path) {
  if (!value.is_array())
    throw in.fail(path, std::string("expected a 4 x 4 array of numbers, got ") + value.type_name());
  if (value.size() != 4)
    throw in.fail(path, "expected 4 rows, got " + std::to_string(value.size()));
  Eigen::Matrix4d m;
  for (size_t r = 0; r < 4; ++r) {
    const json& row = value[r];
    if (!row.is_array() || row.size() != 4)
      throw in.fail(element(path, r),
                    row.is_array() ? "expected 4 numbers, got " + std::to_string(row.size())
                                   : std::string("expected an array of 4 numbers, got ") + row.type_name());
    for (size_t c = 0; c < 4; ++c) m(r, c) = in.number(row[c], element(element(path, r), c));
  }
  if ((m.row(3) - Eigen::RowVector4d(0, 0, 0, 1)).cwiseAbs().maxCoeff() > 1e-6)
    throw in.fail(element(path, 3), "must be [0, 0, 0, 1] (a rigid camera-to-world transform)");
  const Eigen::Matrix3d rotation = m.topLeftCorner<3, 3>();
  const double error = (rotation.transpose() * rotation - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
  if (error > 1e-4 || rotation.determinant() < 0)
    throw in.fail(path, "the upper-left 3 x 3 block must be a rotation (max |R^T R - I| = " +
                            str(error) + ", det R = " + str(rotation.determinant()) + ")");
  return m;
}

// rgb composited on `background` and alpha, from an io::Image of 1 to 4 channels.
void composite(const io::Image& image, const Eigen::Vector3d& background, PosedImage& out) {
  const Eigen::Index n = image.pixels.rows();
  const bool has_alpha = image.channels == 2 || image.channels == 4;
  const int colour = image.channels <= 2 ? 1 : 3;  // grey or RGB channels
  out.alpha = has_alpha ? Eigen::VectorXf(image.pixels.col(image.channels - 1))
                        : Eigen::VectorXf::Ones(n);
  out.rgb.resize(n, 3);
  for (int k = 0; k < 3; ++k) {
    const auto straight = image.pixels.col(colour == 1 ? 0 : k).array();
    out.rgb.col(k) = straight * out.alpha.array() +
                     static_cast<float>(background[k]) * (1.0f - out.alpha.array());
  }
}

}  // namespace

void DatasetOptions::validate() const {
  for (int k = 0; k < 3; ++k)
    if (!(background[k] >= 0 && background[k] <= 1))
      throw std::invalid_argument("dataset.background[" + std::to_string(k) + "] = " +
                                  str(background[k]) + ": must be in [0, 1]");
}

namespace {

// The file's JSON; a syntax error or an out-of-range number is reported at its line and column.
json parse_transforms(const fs::path& json_path) {
  const std::string file = json_path.string();
  if (!fs::is_regular_file(json_path)) throw DatasetError(file + ": cannot open: no such file");
  std::ifstream stream(json_path, std::ios::binary);
  const std::string text{std::istreambuf_iterator<char>(stream), std::istreambuf_iterator<char>()};
  if (!stream) throw DatasetError(file + ": cannot read the file");
  try {
    return json::parse(text);
  } catch (const json::parse_error& e) {
    // e.byte is the 1-based offset of the character where parsing stopped.
    throw DatasetError(file + ":" + line_column(text, e.byte > 0 ? e.byte - 1 : 0) +
                       ": malformed JSON: " + without_id(e.what()));
  } catch (const json::out_of_range& e) {
    // A number beyond double's range, the one way JSON text can hold a non-finite value. The
    // lexer gives no position but quotes the literal: point at its first occurrence.
    const std::string why = without_id(e.what());
    std::string where;
    const auto open = why.find('\''), close = why.rfind('\'');
    if (open != std::string::npos && close > open)
      if (const auto at = text.find(why.substr(open + 1, close - open - 1)); at != std::string::npos)
        where = ":" + line_column(text, at);
    throw DatasetError(file + where + ": malformed JSON: " + why + " (not a finite number)");
  }
}

// The camera keys of the file's root: focal lengths in pixels or view angles, the principal
// point and the image size, each optional; the size is known once the first image is read.
struct CameraKeys {
  std::optional<double> fl_x, fl_y, angle_x, angle_y, cx, cy;
  std::optional<int> w, h;

  CameraKeys(const Reader& in, const json& root)
      : fl_x(in.positive(root, "fl_x")),
        fl_y(in.positive(root, "fl_y")),
        angle_x(in.number(root, "camera_angle_x", "camera_angle_x")),
        angle_y(in.number(root, "camera_angle_y", "camera_angle_y")),
        cx(in.number(root, "cx", "cx")),
        cy(in.number(root, "cy", "cy")),
        w(in.size(root, "w")),
        h(in.size(root, "h")) {
    for (const auto& [key, angle] : {std::pair{"camera_angle_x", angle_x}, std::pair{"camera_angle_y", angle_y}})
      if (angle && !(*angle > 0 && *angle < std::numbers::pi)) throw in.fail(key, *angle, "must be in (0, pi) radians");
    if (!fl_x && !angle_x) throw in.fail("camera_angle_x", "missing (and no fl_x either)");
  }

  // The size every image must have: w and h when given, else the first image's.
  Intrinsics intrinsics(const io::Image& first) const {
    Intrinsics k;
    k.width = w.value_or(first.width);
    k.height = h.value_or(first.height);
    k.fx = fl_x ? *fl_x : 0.5 * k.width / std::tan(0.5 * *angle_x);
    k.fy = fl_y ? *fl_y : fl_x ? *fl_x : angle_y ? 0.5 * k.height / std::tan(0.5 * *angle_y) : k.fx;
    k.cx = cx.value_or(0.5 * k.width);
    k.cy = cy.value_or(0.5 * k.height);
    return k;
  }
};

// frames[i]: its pose and image path, the image read.
PosedImage read_frame(const Reader& in, const json& frame, const std::string& key, const fs::path& folder,
                      io::Image& image) {
  if (!frame.is_object()) throw in.fail(key, std::string("expected an object, got ") + frame.type_name());
  const json& file_path = in.member(frame, "file_path", key + ".file_path");
  if (!file_path.is_string())
    throw in.fail(key + ".file_path", std::string("expected a string, got ") + file_path.type_name());
  PosedImage posed;
  posed.camera.camera_to_world =
      read_pose(in, in.member(frame, "transform_matrix", key + ".transform_matrix"), key + ".transform_matrix");
  posed.path = folder / file_path.get<std::string>();
  if (!posed.path.has_extension()) posed.path += ".png";
  if (!fs::is_regular_file(posed.path))
    throw in.fail(key + ".file_path", "'" + posed.path.string() + "': no such file");
  try {
    image = io::read_png(posed.path);
  } catch (const std::exception& e) {
    throw in.fail(key + ".file_path", e.what());
  }
  return posed;
}

}  // namespace

MultiviewDataset read_transforms(const fs::path& json_path, const DatasetOptions& options) {
  options.validate();
  const Reader in(json_path.string());
  const json root = parse_transforms(json_path);
  if (!root.is_object()) throw in.fail("(root)", std::string("expected an object, got ") + root.type_name());
  const CameraKeys camera(in, root);
  const json& frames = in.member(root, "frames", "frames");
  if (!frames.is_array()) throw in.fail("frames", std::string("expected an array, got ") + frames.type_name());
  if (frames.empty()) throw in.fail("frames", "no frames");

  MultiviewDataset data;
  data.source = json_path;
  data.background = options.background;
  for (size_t i = 0; i < frames.size(); ++i) {
    const std::string key = element("frames", i);
    io::Image image;
    PosedImage posed = read_frame(in, frames[i], key, json_path.parent_path(), image);
    if (i == 0) data.intrinsics = camera.intrinsics(image);
    const Intrinsics& k = data.intrinsics;
    if (image.width != k.width || image.height != k.height)
      throw in.fail(key + ".file_path",
                    "'" + posed.path.string() + "' is " + std::to_string(image.width) + "x" +
                        std::to_string(image.height) + " pixels, expected " + std::to_string(k.width) + "x" +
                        std::to_string(k.height) + (camera.w || camera.h ? " (w and h of the file)" : " (the size of frames[0])"));
    posed.camera.intrinsics = k;
    composite(image, options.background, posed);
    data.frames.push_back(std::move(posed));
  }
  return data;
}

}  // namespace nfield::integrators
