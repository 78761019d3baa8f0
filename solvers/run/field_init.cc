// SPDX-License-Identifier: MIT
#include "solvers/run/field_init.h"

#include <exception>

#include "fields/field.h"
#include "fields/field_io.h"
#include "io/hdf5_file.h"

namespace nfield::solvers {
namespace {

std::string shape_text(const fields::FieldOptions& o, Eigen::Index parameters) {
  std::string hidden;
  for (std::size_t i = 0; i < o.hidden.size(); ++i) hidden += (i ? ", " : "") + std::to_string(o.hidden[i]);
  return "a " + o.type + " field with hidden [" + hidden + "], " + std::to_string(o.input_dim) + " inputs, " +
         std::to_string(o.output_dim) + " outputs (" + std::to_string(parameters) + " parameters)";
}

}  // namespace

FieldInit read_field_init(const io::ConfigNode& field_node, const fields::FieldOptions& options,
                          const std::filesystem::path& data_dir) {
  FieldInit init;
  if (!field_node.has("init")) return init;
  init.text = field_node.get<std::string>("init");
  field_node.require("init", !init.text.empty(), "expected a checkpoint file, got an empty string");
  const std::filesystem::path path = data_dir / init.text;
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec))
    throw field_node.error("init", path.string() + ": no such checkpoint file");
  fields::FieldOptions saved_options;
  autodiff::Vector<double> saved;
  try {
    const io::H5Reader file(path);
    saved_options = fields::load_field_options(file);
    saved = fields::load_field<double>(file).parameters();
  } catch (const std::exception& e) {
    throw field_node.error("init", path.string() + ": cannot read its field: " + e.what());
  }
  const Eigen::Index wanted = fields::Field<double>(options).network_parameter_count();
  if (saved_options.type != options.type || saved_options.input_dim != options.input_dim ||
      saved_options.output_dim != options.output_dim || saved_options.hidden != options.hidden ||
      saved.size() != wanted)
    throw field_node.error("init", path.string() + " holds " + shape_text(saved_options, saved.size()) +
                                       "; this config's field is " + shape_text(options, wanted) +
                                       ": expected the same shape");
  init.parameters = saved;
  return init;
}

}  // namespace nfield::solvers
