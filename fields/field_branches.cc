// SPDX-License-Identifier: MIT
#include "fields/field_branches.h"

#include <memory>
#include <span>
#include <stdexcept>

#include "autodiff/on_columns.h"
#include "fields/activation_layer.h"
#include "fields/field_type.h"

namespace nfield::fields {
namespace {

// out = [in | in[:, columns]]: the branches' inputs appended to the field's. Linear, so the
// same on every stream; its adjoint adds each copied column's adjoint back to its source.
template <typename Scalar>
class AppendColumns final : public autodiff::Module<Scalar> {
 public:
  AppendColumns(Eigen::Index width, std::vector<int> columns) : width_(width), columns_(std::move(columns)) {}
  std::string name() const override { return "append_columns"; }
  Eigen::Index input_width() const override { return width_; }
  Eigen::Index output_width() const override { return width_ + static_cast<Eigen::Index>(columns_.size()); }

  void forward(const autodiff::StreamLayout&, const Scalar*, const autodiff::Streams<Scalar>& in,
               autodiff::Streams<Scalar>& out, autodiff::SavedTensors<Scalar>*) const override {
    out.resize(in.points, in.count, output_width());
    out.data.leftCols(width_) = in.data;
    for (std::size_t j = 0; j < columns_.size(); ++j)
      out.data.col(width_ + static_cast<Eigen::Index>(j)) = in.data.col(columns_[j]);
  }
  void backward(const autodiff::StreamLayout&, const Scalar*, const autodiff::Streams<Scalar>& in,
                const autodiff::SavedTensors<Scalar>&, autodiff::Streams<Scalar>& out_adjoint, Scalar*,
                autodiff::Streams<Scalar>* in_adjoint) const override {
    if (!in_adjoint) return;
    in_adjoint->resize(in.points, in.count, width_);
    in_adjoint->data = out_adjoint.data.leftCols(width_);
    for (std::size_t j = 0; j < columns_.size(); ++j)
      in_adjoint->data.col(columns_[j]) += out_adjoint.data.col(width_ + static_cast<Eigen::Index>(j));
  }

 private:
  Eigen::Index width_;
  std::vector<int> columns_;
};

[[noreturn]] void reject(std::size_t b, const std::string& key, const std::string& value, const std::string& rule) {
  throw std::invalid_argument("field.branches[" + std::to_string(b) + "]." + key + " = " + value + ": " + rule);
}

bool coordinate_type(const std::string& type) { return type == "siren" || type == "mlp"; }

std::string key(std::size_t b, const char* name) { return "branch_" + std::to_string(b) + "_" + name; }

}  // namespace

FieldOptions main_options(const FieldOptions& options) {
  FieldOptions main = options;
  main.output_dim -= static_cast<int>(options.branches.size());
  main.branches.clear();
  return main;
}

void validate_branches(const FieldOptions& o) {
  if (o.branches.empty()) return;
  if (!coordinate_type(o.type))
    throw std::invalid_argument("field.type = " + o.type + ": a field with branches (unknown fields with a "
                                "network of their own) is a siren or an mlp");
  if (o.output_dim <= static_cast<int>(o.branches.size()))
    throw std::invalid_argument("field.output_dim = " + std::to_string(o.output_dim) + ": must exceed the " +
                                std::to_string(o.branches.size()) + " branches' outputs");
  for (std::size_t b = 0; b < o.branches.size(); ++b) {
    const FieldBranch& branch = o.branches[b];
    if (!coordinate_type(branch.options.type)) reject(b, "type", branch.options.type, "must be siren or mlp");
    if (branch.inputs.empty()) reject(b, "inputs", "[]", "needs at least one input column");
    for (std::size_t i = 0; i < branch.inputs.size(); ++i)
      if (branch.inputs[i] < 0 || branch.inputs[i] >= o.input_dim || (i > 0 && branch.inputs[i] <= branch.inputs[i - 1]))
        reject(b, "inputs[" + std::to_string(i) + "]", std::to_string(branch.inputs[i]),
               "must increase within [0, " + std::to_string(o.input_dim) + ")");
    if (branch.options.input_dim != static_cast<int>(branch.inputs.size()) || branch.options.output_dim != 1)
      reject(b, "options", "input_dim " + std::to_string(branch.options.input_dim), "must be inputs.size() with one output");
    try {
      branch.options.validate();
    } catch (const std::invalid_argument& e) {
      reject(b, "options", branch.options.type, e.what());
    }
  }
}

template <typename Scalar>
FeatureEncoding<Scalar>* append_branched_network(const FieldType& type, const FieldOptions& options,
                                                 autodiff::Sequential<Scalar>& network, std::vector<int>& parts) {
  std::vector<int> columns;
  for (const FieldBranch& branch : options.branches) columns.insert(columns.end(), branch.inputs.begin(), branch.inputs.end());
  const auto gathered = static_cast<Eigen::Index>(columns.size());
  network.add(std::make_unique<AppendColumns<Scalar>>(options.input_dim, std::move(columns)));
  parts.assign(1, 0);
  // g on columns [0, ·), the gathered columns carried past it.
  autodiff::Sequential<Scalar> part;
  FeatureEncoding<Scalar>* late = type.append_modules(main_options(options), part);
  for (auto& module : part.release_modules()) {
    const Eigen::Index width = module->input_width() + gathered;
    network.add(std::make_unique<autodiff::OnColumns<Scalar>>(std::move(module), 0, width));
    parts.push_back(0);
  }
  // Branch b reads the columns after g's outputs and the b outputs of the branches before it.
  Eigen::Index begin = options.output_dim - static_cast<Eigen::Index>(options.branches.size());
  Eigen::Index rest = gathered;  // gathered columns not yet consumed
  for (std::size_t b = 0; b < options.branches.size(); ++b, ++begin) {
    const FieldBranch& branch = options.branches[b];
    const auto own = static_cast<Eigen::Index>(branch.inputs.size());
    rest -= own;
    field_type(branch.options.type).append_modules(branch.options, part);
    for (auto& module : part.release_modules()) {
      const Eigen::Index width = begin + module->input_width() + rest;
      network.add(std::make_unique<autodiff::OnColumns<Scalar>>(std::move(module), begin, width));
      parts.push_back(static_cast<int>(b) + 1);
    }
    if (branch.positive) {
      network.add(std::make_unique<autodiff::OnColumns<Scalar>>(
          std::make_unique<ActivationLayer<Scalar>>(ActivationSpec{"softplus", 1.0}, 1), begin, begin + 1 + rest));
      parts.push_back(static_cast<int>(b) + 1);
    }
  }
  return late;
}

void save_branches(io::H5Writer& file, const std::string& group, const FieldOptions& o) {
  if (o.branches.empty()) return;
  file.write_attribute(group, "branches", static_cast<std::int64_t>(o.branches.size()));
  for (std::size_t b = 0; b < o.branches.size(); ++b) {
    const FieldBranch& branch = o.branches[b];
    const std::vector<std::int64_t> hidden(branch.options.hidden.begin(), branch.options.hidden.end());
    const std::vector<std::int64_t> inputs(branch.inputs.begin(), branch.inputs.end());
    file.write_attribute(group, key(b, "type"), branch.options.type);
    file.write_attribute(group, key(b, "hidden"), std::span<const std::int64_t>(hidden));
    file.write_attribute(group, key(b, "activation"), branch.options.activation);
    file.write_attribute(group, key(b, "first_omega"), branch.options.first_omega);
    file.write_attribute(group, key(b, "hidden_omega"), branch.options.hidden_omega);
    file.write_attribute(group, key(b, "inputs"), std::span<const std::int64_t>(inputs));
    file.write_attribute(group, key(b, "positive"), static_cast<std::int64_t>(branch.positive));
  }
}

void load_branches(const io::H5Reader& file, const std::string& group, FieldOptions& o) {
  if (!file.has_attribute(group, "branches")) return;
  const auto count = file.read_attribute<std::int64_t>(group, "branches");
  o.branches.clear();
  for (std::size_t b = 0; b < static_cast<std::size_t>(count); ++b) {
    FieldBranch branch;
    branch.options.type = file.read_attribute<std::string>(group, key(b, "type"));
    const auto hidden = file.read_attribute<std::vector<std::int64_t>>(group, key(b, "hidden"));
    branch.options.hidden.assign(hidden.begin(), hidden.end());
    branch.options.activation = file.read_attribute<std::string>(group, key(b, "activation"));
    branch.options.first_omega = file.read_attribute<double>(group, key(b, "first_omega"));
    branch.options.hidden_omega = file.read_attribute<double>(group, key(b, "hidden_omega"));
    const auto inputs = file.read_attribute<std::vector<std::int64_t>>(group, key(b, "inputs"));
    branch.inputs.assign(inputs.begin(), inputs.end());
    branch.positive = file.read_attribute<std::int64_t>(group, key(b, "positive")) != 0;
    branch.options.input_dim = static_cast<int>(branch.inputs.size());
    branch.options.output_dim = 1;
    branch.options.seed = o.seed;
    o.branches.push_back(std::move(branch));
  }
}

template FeatureEncoding<float>* append_branched_network(const FieldType&, const FieldOptions&,
                                                          autodiff::Sequential<float>&, std::vector<int>&);
template FeatureEncoding<double>* append_branched_network(const FieldType&, const FieldOptions&,
                                                           autodiff::Sequential<double>&, std::vector<int>&);

}  // namespace nfield::fields
