// SPDX-License-Identifier: MIT
#include "fields/field_io.h"

#include <span>
#include <type_traits>

#include "fields/dense.h"
#include "fields/encoding_type.h"
#include "fields/field_branches.h"
#include "fields/field_type.h"
#include "fields/latent_code.h"

namespace nfield::fields {
namespace {

// Dense layers are saved as layers/K; a latent code as latent_code; the one other module with
// parameters, the encoding, as encoding_parameters.
template <typename Scalar>
bool is_dense(const autodiff::Module<Scalar>& module) {
  return dynamic_cast<const Dense<Scalar>*>(&module) != nullptr;
}
template <typename Scalar>
std::string vector_dataset(const autodiff::Module<Scalar>& module) {
  return dynamic_cast<const LatentCode<Scalar>*>(&module) ? "latent_code" : "encoding_parameters";
}

}  // namespace

template <typename Scalar>
void save_field(io::H5Writer& file, const Field<Scalar>& field, const std::string& group) {
  const FieldOptions& o = field.options();
  file.create_group(group);
  file.write_attribute(group, "type", o.type);
  file.write_attribute(group, "input_dim", o.input_dim);
  file.write_attribute(group, "output_dim", o.output_dim);
  std::vector<std::int64_t> hidden(o.hidden.begin(), o.hidden.end());
  file.write_attribute(group, "hidden", std::span<const std::int64_t>(hidden));
  file.write_attribute(group, "activation", o.activation);
  file.write_attribute(group, "first_omega", o.first_omega);
  file.write_attribute(group, "hidden_omega", o.hidden_omega);
  file.write_attribute(group, "seed", static_cast<std::int64_t>(o.seed));
  if (o.latent_size > 0) file.write_attribute(group, "latent_size", static_cast<std::int64_t>(o.latent_size));
  file.write_attribute(group, "precision", std::is_same_v<Scalar, float> ? "float" : "double");
  file.write_attribute(group, "encoding_type", o.encoding.type);
  if (!o.encoding.lower.empty()) {
    file.write_attribute(group, "encoding_lower", std::span<const double>(o.encoding.lower));
    file.write_attribute(group, "encoding_upper", std::span<const double>(o.encoding.upper));
  }
  field_type(o.type).save(file, group, o);
  save_branches(file, group, o);
  encoding_type(o.encoding.type).save(file, group, o.encoding);
  if (field.encoding_matrix().rows() > 0) file.write(group + "/encoding", field.encoding_matrix());
  const auto& modules = field.network().modules();
  int layer = 0;
  for (size_t m = 0; m < modules.size(); ++m) {
    const auto& owner = parameter_owner(*modules[m]);
    const Eigen::Index in = owner.input_width(), out = owner.output_width();
    const Eigen::Index count = owner.parameter_count();
    if (count == 0) continue;
    const Scalar* p = field.parameters().data() + field.network().parameter_offset(m);
    if (!is_dense(owner)) {
      file.write(group + "/" + vector_dataset(owner), Eigen::Map<const autodiff::Vector<Scalar>>(p, count));
      continue;
    }
    const std::string prefix = group + "/layers/" + std::to_string(layer++);
    file.write(prefix + "/weight", Eigen::Map<const autodiff::Matrix<Scalar>>(p, out, in));
    file.write(prefix + "/bias", Eigen::Map<const autodiff::Vector<Scalar>>(p + out * in, out));
  }
}

FieldOptions load_field_options(const io::H5Reader& file, const std::string& group) {
  FieldOptions o;
  o.type = file.read_attribute<std::string>(group, "type");
  o.input_dim = static_cast<int>(file.read_attribute<std::int64_t>(group, "input_dim"));
  o.output_dim = static_cast<int>(file.read_attribute<std::int64_t>(group, "output_dim"));
  const auto hidden = file.read_attribute<std::vector<std::int64_t>>(group, "hidden");
  o.hidden.assign(hidden.begin(), hidden.end());
  o.activation = file.read_attribute<std::string>(group, "activation");
  o.first_omega = file.read_attribute<double>(group, "first_omega");
  o.hidden_omega = file.read_attribute<double>(group, "hidden_omega");
  o.seed = static_cast<std::uint64_t>(file.read_attribute<std::int64_t>(group, "seed"));
  if (file.has_attribute(group, "latent_size"))
    o.latent_size = static_cast<int>(file.read_attribute<std::int64_t>(group, "latent_size"));
  o.encoding.type = file.read_attribute<std::string>(group, "encoding_type");
  if (file.has_attribute(group, "encoding_lower")) {
    o.encoding.lower = file.read_attribute<std::vector<double>>(group, "encoding_lower");
    o.encoding.upper = file.read_attribute<std::vector<double>>(group, "encoding_upper");
  }
  encoding_type(o.encoding.type).load(file, group, o.encoding);
  field_type(o.type).load(file, group, o);
  load_branches(file, group, o);
  return o;
}

template <typename Scalar>
Field<Scalar> load_field(const io::H5Reader& file, const std::string& group) {
  Field<Scalar> field(load_field_options(file, group));
  const auto& modules = field.network().modules();
  int layer = 0;
  for (size_t m = 0; m < modules.size(); ++m) {
    const auto& owner = parameter_owner(*modules[m]);
    const Eigen::Index in = owner.input_width(), out = owner.output_width();
    const Eigen::Index count = owner.parameter_count();
    if (count == 0) continue;
    Scalar* p = field.parameters().data() + field.network().parameter_offset(m);
    if (!is_dense(owner)) {
      const std::string dataset = group + "/" + vector_dataset(owner);
      const auto values = file.read_vector<Scalar>(dataset);
      if (values.size() != count)
        throw io::H5Error(file.path().string() + ": " + dataset + " has " +
                          std::to_string(values.size()) + " values, the field needs " +
                          std::to_string(count));
      Eigen::Map<autodiff::Vector<Scalar>>(p, count) = values;
      continue;
    }
    const std::string prefix = group + "/layers/" + std::to_string(layer++);
    const auto weight = file.read_matrix<Scalar>(prefix + "/weight");
    const auto bias = file.read_vector<Scalar>(prefix + "/bias");
    if (weight.rows() != out || weight.cols() != in || bias.size() != out)
      throw io::H5Error(file.path().string() + ": " + prefix + " has the wrong shape for " +
                        std::to_string(out) + " x " + std::to_string(in));
    Eigen::Map<autodiff::Matrix<Scalar>>(p, out, in) = weight;
    Eigen::Map<autodiff::Vector<Scalar>>(p + out * in, out) = bias;
  }
  return field;
}

template void save_field<float>(io::H5Writer&, const Field<float>&, const std::string&);
template void save_field<double>(io::H5Writer&, const Field<double>&, const std::string&);
template Field<float> load_field<float>(const io::H5Reader&, const std::string&);
template Field<double> load_field<double>(const io::H5Reader&, const std::string&);

}  // namespace nfield::fields
