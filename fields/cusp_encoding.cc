// SPDX-License-Identifier: MIT
#include "fields/cusp_encoding.h"

#include <algorithm>
#include <cmath>
#include <span>
#include <stdexcept>
#include <string>

#include "fields/encoding_type.h"

namespace nfield::fields {
namespace {

[[noreturn]] void reject(const std::string& option, const std::string& value,
                         const std::string& rule) {
  throw std::invalid_argument("encoding." + option + " = " + value + ": " + rule);
}

// |z|, with derivative sign(z) (0 at z = 0) and no higher ones.
template <typename Scalar>
class Abs final : public autodiff::ElementwiseFunction<Scalar> {
 public:
  void derivatives(const Eigen::Ref<const autodiff::Matrix<Scalar>>& z, int max_order,
                   std::vector<autodiff::Matrix<Scalar>>& tables) const override {
    tables.resize(max_order + 1);
    for (auto& table : tables) table.resize(z.rows(), z.cols());
    tables[0] = z.cwiseAbs();
    if (max_order >= 1)
      tables[1] = z.unaryExpr([](Scalar v) { return Scalar((v > 0) - (v < 0)); });
    for (int m = 2; m <= max_order; ++m) tables[m].setZero();
  }
};

std::vector<std::string> names_or_default(std::vector<std::string> names, int input_dim) {
  if (names.empty())
    for (int a = 0; a < input_dim; ++a) names.push_back(std::string(1, "xyzw"[a % 4]));
  return names;
}

}  // namespace

void CuspOptions::validate() const {
  if (at.empty()) throw std::invalid_argument("encoding.at = []: needs at least one plane");
  for (double c : at)
    if (!std::isfinite(c)) reject("at", std::to_string(c), "must be finite");
  if (axis < 0) reject("axis", std::to_string(axis), "must be >= 0");
  if (from_stage < 0) reject("from_stage", std::to_string(from_stage), "must be >= 0");
}

void CuspOptions::validate(int input_dim) const {
  validate();
  if (axis >= input_dim)
    reject("axis", std::to_string(axis), "must be < input_dim = " + std::to_string(input_dim));
}

namespace {

class CuspType final : public EncodingTypeOf<CuspType, CuspOptions> {
 public:
  int entry_stage(const EncodingOptions& o) const override { return own(o).from_stage; }
  void check_run(const io::ConfigNode& node, const EncodingOptions& o,
                 const EncodingRun& run) const override {
    const int stage = own(o).from_stage;
    if (stage > 0 && stage >= run.stages)
      throw node.error("from_stage", "expected a stage index below the number of training stages, " +
                                         std::to_string(run.stages) + ", or the features would never enter");
  }
  void validate(const EncodingOptions& o) const override { own(o).validate(); }
  void validate_inputs(const EncodingOptions& o, int input_dim) const override {
    own(o).validate(input_dim);
  }
  Eigen::MatrixXd matrix(const EncodingOptions& o, int input_dim) const override {
    const CuspOptions& c = own(o);
    if (c.axis >= input_dim)
      reject("axis", std::to_string(c.axis),
             "must be < the input dimension " + std::to_string(input_dim));
    Eigen::MatrixXd b = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(c.at.size()), input_dim);
    b.col(c.axis).setOnes();
    return b;
  }
  template <typename Scalar>
  static std::unique_ptr<autodiff::Module<Scalar>> make(const EncodingOptions& o, int input_dim) {
    const Eigen::MatrixXd b = CuspType().matrix(o, input_dim);
    return std::make_unique<FeatureEncoding<Scalar>>(
        b, -Eigen::Map<const Eigen::VectorXd>(own(o).at.data(), b.rows()),
        std::make_unique<Abs<Scalar>>(), true);
  }
  void read(const io::ConfigNode& e, const EncodingContext& context,
            EncodingOptions& o) const override {
    CuspOptions c;
    const std::vector<std::string> axes = names_or_default(context.input_names, context.input_dim);
    const std::string axis = e.get_choice("axis", axes);
    c.axis = static_cast<int>(std::find(axes.begin(), axes.end(), axis) - axes.begin());
    c.at = e.get<std::vector<double>>("at");
    e.require("at", !c.at.empty(), "expected a non-empty list of plane positions");
    for (double v : c.at) e.require("at", std::isfinite(v), "expected finite numbers");
    if (e.has("from_stage")) c.from_stage = e.get_in_range("from_stage", 0, 1000);
    o.own = c;
  }
  void write(const EncodingOptions& o, const EncodingContext& context,
             YAML::Node& n) const override {
    const CuspOptions& c = own(o);
    n["axis"] = names_or_default(context.input_names, context.input_dim).at(c.axis);
    n["at"] = c.at;
    if (c.from_stage > 0) n["from_stage"] = c.from_stage;
  }
  void save(io::H5Writer& file, const std::string& group,
            const EncodingOptions& o) const override {
    const CuspOptions& c = own(o);
    file.write_attribute(group, "encoding_axis", c.axis);
    file.write_attribute(group, "encoding_at", std::span<const double>(c.at));
    file.write_attribute(group, "encoding_from_stage", static_cast<std::int64_t>(c.from_stage));
  }
  void load(const io::H5Reader& file, const std::string& group,
            EncodingOptions& o) const override {
    CuspOptions c;
    if (file.has_attribute(group, "encoding_axis"))
      c.axis = static_cast<int>(file.read_attribute<std::int64_t>(group, "encoding_axis"));
    if (file.has_attribute(group, "encoding_at"))
      c.at = file.read_attribute<std::vector<double>>(group, "encoding_at");
    if (file.has_attribute(group, "encoding_from_stage"))
      c.from_stage = static_cast<int>(file.read_attribute<std::int64_t>(group, "encoding_from_stage"));
    o.own = c;
  }
};

}  // namespace

std::unique_ptr<const EncodingType> make_cusp_type() { return std::make_unique<CuspType>(); }

}  // namespace nfield::fields
