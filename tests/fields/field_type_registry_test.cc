// SPDX-License-Identifier: MIT
//
// The field-type registry from outside the library: a type registered here (one hidden layer
// whose width is its own key) is built from a config, its key read strictly and written back,
// kept through a checkpoint; taken names are refused and an unknown type lists the valid ones.
#include <gtest/gtest.h>

#include <any>
#include <stdexcept>
#include <string>

#include "fields/activation_layer.h"
#include "fields/dense.h"
#include "fields/field.h"
#include "fields/field_config.h"
#include "fields/field_io.h"
#include "fields/field_type.h"
#include "io/config.h"
#include "io/registry.h"
#include "tests/testing/scratch.h"

namespace nfield::fields {
namespace {

// The type's own options, beside FieldOptions (FieldOptions::extension).
struct ShallowOptions {
  double gain = 1;  // scales the initial weights of the output layer
};

const ShallowOptions& shallow_options(const FieldOptions& o) {
  static const ShallowOptions defaults;
  const auto* own = std::any_cast<ShallowOptions>(&o.extension);
  return own ? *own : defaults;
}

// x → Dense → σ → Dense with σ softplus by default, the width given as `width` and the output
// layer's initial weights scaled by its own key `gain`.
class ShallowType final : public FieldTypeOf<ShallowType> {
 public:
  std::string default_activation() const override { return "softplus"; }
  void validate(const FieldOptions& o) const override {
    if (o.hidden.size() != 1)
      throw std::invalid_argument("field.hidden: shallow has one hidden layer, not " +
                                  std::to_string(o.hidden.size()));
  }
  template <typename Scalar>
  static FeatureEncoding<Scalar>* append(const FieldOptions& o, autodiff::Sequential<Scalar>& network) {
    network.add(std::make_unique<Dense<Scalar>>(o.input_dim, o.hidden[0]));
    network.add(std::make_unique<ActivationLayer<Scalar>>(ActivationSpec{o.activation, o.hidden_omega},
                                                          o.hidden[0]));
    network.add(std::make_unique<Dense<Scalar>>(o.hidden[0], o.output_dim));
    return nullptr;
  }
  InitialBounds initial_bounds(const FieldOptions& o, int index, Eigen::Index in, Eigen::Index out) const override {
    InitialBounds bounds = FieldType::initial_bounds(o, index, in, out);
    if (index == 1) bounds.weight *= shallow_options(o).gain;
    return bounds;
  }
  void read(const io::ConfigNode& node, FieldOptions& o) const override {
    o.hidden = {node.get_in_range("width", 1, 4096)};
    ShallowOptions own;
    own.gain = node.get_or("gain", own.gain);
    node.require("gain", own.gain >= 0, "expected a gain >= 0");
    o.extension = own;
  }
  void write(const FieldOptions& o, YAML::Node& n) const override {
    n["width"] = o.hidden[0];
    n["gain"] = shallow_options(o).gain;
  }
  void save(io::H5Writer& file, const std::string& group, const FieldOptions& o) const override {
    file.write_attribute(group, "shallow_width", static_cast<std::int64_t>(o.hidden[0]));
    file.write_attribute(group, "shallow_gain", shallow_options(o).gain);
  }
  void load(const io::H5Reader& file, const std::string& group, FieldOptions& o) const override {
    EXPECT_EQ(file.read_attribute<std::int64_t>(group, "shallow_width"), o.hidden[0]);
    o.extension = ShallowOptions{file.read_attribute<double>(group, "shallow_gain")};
  }
};

void register_shallow() {
  static const bool registered = [] {
    register_field_type("shallow", std::make_unique<ShallowType>());
    return true;
  }();
  (void)registered;
}

FieldOptions from_text(const std::string& field) {
  const io::ConfigNode root = io::parse_config("field: " + field + "\n", "field.yaml");
  return field_options_from_config(root.child("field"), 2, 1, 11);
}

TEST(FieldTypeRegistry, TypeFromOutsideIsBuiltFromAConfig) {
  register_shallow();
  const FieldOptions options = from_text("{type: shallow, width: 12}");
  EXPECT_EQ(options.hidden, std::vector<int>{12});
  const Field<double> field(options);
  EXPECT_EQ(field.options().activation, "softplus");
  ASSERT_EQ(field.network().modules().size(), 3u);
  EXPECT_EQ(field.parameter_count(), (2 * 12 + 12) + (12 + 1));

  // The same chain as a one-layer mlp: same default initialization, same values.
  FieldOptions mlp = options;
  mlp.type = "mlp";
  const Field<double> reference(mlp);
  EXPECT_EQ(field.parameters(), reference.parameters());
  const Eigen::MatrixXd x = Eigen::MatrixXd::Random(7, 2);
  EXPECT_EQ(field.values(x), reference.values(x));

  const YAML::Node written = to_yaml(options, {"x", "y"});
  EXPECT_EQ(written["type"].as<std::string>(), "shallow");
  EXPECT_EQ(written["width"].as<int>(), 12);
  EXPECT_EQ(written["gain"].as<double>(), 1.0);
  EXPECT_EQ(written["activation"].as<std::string>(), "softplus");
  EXPECT_FALSE(written["color_hidden"]);
}

// A key of the type's own (`gain`, in FieldOptions::extension) reaches the network: gain 0
// zeroes the output layer's initial weights, so the field starts at its bias, 0.
TEST(FieldTypeRegistry, TypeOwnKeyReachesTheNetwork) {
  register_shallow();
  const FieldOptions options = from_text("{type: shallow, width: 6, gain: 0}");
  EXPECT_EQ(shallow_options(options).gain, 0.0);
  const Field<double> field(options);
  EXPECT_EQ(field.values(Eigen::MatrixXd::Random(5, 2)).cwiseAbs().maxCoeff(), 0.0);
  const Field<double> half(from_text("{type: shallow, width: 6, gain: 0.5}"));
  const Field<double> full(from_text("{type: shallow, width: 6}"));
  const Eigen::MatrixXd x = Eigen::MatrixXd::Random(5, 2);
  EXPECT_NEAR((half.values(x) - 0.5 * full.values(x)).cwiseAbs().maxCoeff(), 0.0, 1e-12);
  try {
    from_text("{type: shallow, width: 6, gain: -1}");
    ADD_FAILURE() << "no error";
  } catch (const io::ConfigError& e) {
    EXPECT_EQ(e.key_path(), "field.gain") << e.what();
  }
}

TEST(FieldTypeRegistry, TypeKeysAreReadStrictly) {
  register_shallow();
  try {
    from_text("{type: shallow, width: 12, color_hidden: [8]}");
    ADD_FAILURE() << "no error";
  } catch (const io::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("unknown key 'color_hidden'"), std::string::npos) << e.what();
  }
  try {
    from_text("{type: shallow, width: 0}");
    ADD_FAILURE() << "no error";
  } catch (const io::ConfigError& e) {
    EXPECT_EQ(e.key_path(), "field.width") << e.what();
  }
}

TEST(FieldTypeRegistry, CheckpointKeepsTheType) {
  register_shallow();
  const Field<float> field(from_text("{type: shallow, width: 5, activation: tanh, gain: 0.25}"));
  const auto path = testutil::scratch_dir("field_type_registry") / "shallow.h5";
  {
    io::H5Writer file(path);
    save_field(file, field, "field");
    file.commit();
  }
  const io::H5Reader file(path);
  const Field<float> loaded = load_field<float>(file, "field");
  EXPECT_EQ(loaded.options().type, "shallow");
  EXPECT_EQ(loaded.options().activation, "tanh");
  EXPECT_EQ(shallow_options(loaded.options()).gain, 0.25);
  EXPECT_EQ(loaded.parameters(), field.parameters());
}

TEST(FieldTypeRegistry, TakenAndUnknownNames) {
  register_shallow();
  EXPECT_THROW(register_field_type("MLP", std::make_unique<ShallowType>()), std::logic_error);
  EXPECT_THROW(register_field_type("shallow", std::make_unique<ShallowType>()), std::logic_error);
  try {
    field_type("kan");
    ADD_FAILURE() << "no error";
  } catch (const UnknownNameError& e) {
    EXPECT_EQ(std::string(e.what()), "unknown field type 'kan' (valid: acorn, bacon, mlp, nerf, shallow, siren)");
  }
  EXPECT_EQ(default_activation("Shallow"), "softplus");
}

}  // namespace
}  // namespace nfield::fields
