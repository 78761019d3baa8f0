// SPDX-License-Identifier: MIT
//
// The activation, encoding and field-type registries: unknown names are rejected with a
// message listing every valid name, names match case-insensitively; option validation names
// the offending field.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <numbers>
#include <stdexcept>
#include <string>

#include "fields/activations.h"
#include "fields/cusp_encoding.h"
#include "fields/encoding_type.h"
#include "fields/encodings.h"
#include "fields/fourier_encoding.h"
#include "fields/field.h"
#include "fields/positional_encoding.h"
#include "io/config.h"
#include "io/registry.h"
#include "io/text.h"

namespace nfield::fields {
namespace {

std::string message_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  ADD_FAILURE() << "no std::invalid_argument thrown";
  return "";
}

void expect_lists(const std::string& message, const std::vector<std::string>& names) {
  ASSERT_FALSE(names.empty());
  for (const std::string& name : names)
    EXPECT_NE(message.find(name), std::string::npos) << "'" << message << "' lacks " << name;
}

TEST(ActivationRegistry, NamesAreSortedLowerCaseAndComplete) {
  const std::vector<std::string> names = activation_names();
  EXPECT_TRUE(std::is_sorted(names.begin(), names.end()));
  for (const std::string& name : names) EXPECT_EQ(name, io::to_lower(name));
  for (const char* documented : {"identity", "relu", "sine", "softplus", "tanh"})
    EXPECT_NE(std::find(names.begin(), names.end(), documented), names.end()) << documented;
}

TEST(ActivationRegistry, UnknownNameListsValidNames) {
  const std::string message = message_of([] { make_activation<double>({"swish", 1.0}); });
  EXPECT_NE(message.find("unknown activation 'swish'"), std::string::npos) << message;
  expect_lists(message, activation_names());
  EXPECT_THROW(make_activation<float>({"swish", 1.0}), UnknownNameError);
}

TEST(ActivationRegistry, NamesAreCaseInsensitive) {
  for (const char* name : {"SiNe", "SINE", "sine"}) {
    const auto f = make_activation<double>({name, 2.0});
    std::vector<Eigen::MatrixXd> tables;
    f->derivatives(Eigen::MatrixXd::Constant(1, 1, 0.3), 1, tables);
    EXPECT_DOUBLE_EQ(tables[0](0, 0), std::sin(0.6)) << name;
    EXPECT_DOUBLE_EQ(tables[1](0, 0), 2 * std::cos(0.6)) << name;
    EXPECT_NE(make_activation<float>({name, 2.0}), nullptr);
  }
  EXPECT_NE(make_activation<double>({"TanH", 1.0}), nullptr);
}

TEST(EncodingRegistry, UnknownNameListsValidNames) {
  EncodingOptions o;
  o.type = "hashgrid2";
  const std::string message = message_of([&] { o.validate(); });
  EXPECT_NE(message.find("unknown encoding 'hashgrid2'"), std::string::npos) << message;
  expect_lists(message, encoding_names());
  expect_lists(message_of([&] { encoding_matrix(o, 2); }), encoding_names());
}

TEST(EncodingRegistry, NamesAreCaseInsensitive) {
  EncodingOptions o = encoding_options(PositionalOptions{.frequencies = 2});
  o.type = "PosItional";
  EXPECT_NO_THROW(o.validate());
  const Eigen::MatrixXd b = encoding_matrix(o, 2);
  ASSERT_EQ(b.rows(), 4);
  EXPECT_DOUBLE_EQ(b(3, 1), 2 * std::numbers::pi);  // row l·d + i holds 2ˡ π eᵢ
  o = encoding_options(FourierOptions{.features = 5});
  o.type = "FOURIER";
  EXPECT_EQ(encoding_matrix(o, 3).rows(), 5);
  o.own.reset();
  o.type = "Identity";
  EXPECT_EQ(encoding_matrix(o, 3).rows(), 0);
}

TEST(EncodingOptions, ValidationNamesTheField) {
  EncodingOptions o = encoding_options(PositionalOptions{.frequencies = 0});
  EXPECT_NE(message_of([&] { o.validate(); }).find("encoding.frequencies = 0"), std::string::npos);
  o = encoding_options(FourierOptions{.features = 0});
  EXPECT_NE(message_of([&] { o.validate(); }).find("encoding.features"), std::string::npos);
  o = encoding_options(FourierOptions{.features = 4, .scale = 0});
  EXPECT_NE(message_of([&] { o.validate(); }).find("encoding.scale"), std::string::npos);
  o = {};
  o.type = "cusp";  // its defaults: no plane
  EXPECT_NE(message_of([&] { o.validate(); }).find("encoding.at = []"), std::string::npos);
  o = encoding_options(CuspOptions{.axis = 2, .at = {0.5}});
  EXPECT_NO_THROW(o.validate());
  EXPECT_NE(message_of([&] { encoding_matrix(o, 2); }).find("encoding.axis = 2"), std::string::npos);
  FieldOptions f;
  f.encoding = o;
  EXPECT_NE(message_of([&] { f.validate(); }).find("encoding.axis"), std::string::npos);
  o = encoding_options(CuspOptions{.axis = 1, .at = {0.5}, .from_stage = -1});
  EXPECT_NE(message_of([&] { o.validate(); }).find("encoding.from_stage = -1: must be >= 0"),
            std::string::npos);
  o = encoding_options(CuspOptions{.axis = 1, .at = {0.5}, .from_stage = 1});
  EXPECT_NO_THROW(o.validate());
  EXPECT_EQ(entry_stage(o), 1);
  // The holder keeps one type's struct: a type that finds another's refuses it by name.
  o.type = "fourier";
  const std::string message = message_of([&] { o.validate(); });
  EXPECT_NE(message.find("encoding.type = fourier: its options hold another encoding's"), std::string::npos)
      << message;
  EXPECT_EQ(entry_stage(encoding_options(FourierOptions{})), 0);
}

// What the run tells an encoding (fit_encoding): every type keeps the domain box; cusp
// refuses a from_stage the run does not reach, at the key; the others take any stage count.
TEST(EncodingOptions, FitToTheRunKeepsTheBoxAndChecksTheStages) {
  const io::ConfigNode node = io::parse_config(
      "type: cusp\naxis: y\nat: [0.5]\nfrom_stage: 2\n", "encoding.yaml");
  const EncodingRun run{.lower = {0, -1}, .upper = {1, 1}, .stages = 2};
  EncodingOptions cusp = encoding_options(CuspOptions{.axis = 1, .at = {0.5}, .from_stage = 2});
  std::string message;
  try {
    fit_encoding(node, run, cusp);
  } catch (const io::ConfigError& e) {
    message = e.what();
  }
  EXPECT_NE(message.find("encoding.yaml:4"), std::string::npos) << message;
  EXPECT_NE(message.find("from_stage"), std::string::npos) << message;
  EXPECT_NE(message.find("below the number of training stages, 2"), std::string::npos) << message;
  cusp = encoding_options(CuspOptions{.axis = 1, .at = {0.5}, .from_stage = 1});
  fit_encoding(node, run, cusp);
  EXPECT_EQ(cusp.lower, run.lower);
  EXPECT_EQ(cusp.upper, run.upper);
  EncodingOptions plain;  // identity
  fit_encoding(node, {.lower = {2}, .upper = {3}, .stages = 1}, plain);
  EXPECT_EQ(plain.lower, std::vector<double>{2});
}

// Fourier features in blocks (`scales`): one block at σ is the matrix of `scale: σ` (the same
// draws), each block's column a has the spread 2π σ_ga, and a block needs one σ or one per axis.
TEST(EncodingOptions, FourierScalesStackBlocksWithOneSigmaPerAxis) {
  const FourierOptions one{.features = 16, .scale = 3.0, .seed = 7};
  FourierOptions blocks = one;
  blocks.scales = {{3.0}};
  EXPECT_EQ(encoding_matrix(encoding_options(blocks), 2), encoding_matrix(encoding_options(one), 2));
  blocks.features = 4000;
  blocks.scales = {{1.0, 1.0}, {1.0, 10.0}};
  const Eigen::MatrixXd b = encoding_matrix(encoding_options(blocks), 2);
  ASSERT_EQ(b.rows(), 8000);
  const double sigma[2][2] = {{1, 1}, {1, 10}};
  for (int g = 0; g < 2; ++g)
    for (int a = 0; a < 2; ++a) {
      const Eigen::VectorXd column = b.block(g * 4000, a, 4000, 1);
      const double spread = std::sqrt(column.squaredNorm() / 4000);
      EXPECT_NEAR(spread / (2 * std::numbers::pi * sigma[g][a]), 1.0, 0.05) << g << " " << a;
    }
  blocks.scales = {{1.0, 2.0, 3.0}};
  EXPECT_NE(message_of([&] { encoding_options(blocks).validate(2); }).find("encoding.scales[0] = 3 values"),
            std::string::npos);
  blocks.scales = {{1.0, -2.0}};
  EXPECT_NE(message_of([&] { encoding_options(blocks).validate(); }).find("encoding.scales[0]"), std::string::npos);
}

// Cusp features: [x, |x_a − c_k|] with value, sign derivative and no curvature, by hand.
TEST(EncodingOptions, CuspFeaturesAreDistancesToThePlanes) {
  const EncodingOptions o = encoding_options(CuspOptions{.axis = 1, .at = {0.5, -0.25}});
  const auto encoding = make_encoding<double>(o, 2);
  ASSERT_NE(encoding, nullptr);
  ASSERT_EQ(encoding->output_width(), 4);
  const autodiff::StreamLayout layout(autodiff::StreamSpec::laplacian(2));
  autodiff::Streams<double> in, out;
  in.resize(2, layout.count(), 2);
  in.data.setZero();
  in.stream(0) << 0.3, 0.2, -0.7, 0.9;  // points (0.3, 0.2), (−0.7, 0.9)
  in.stream(layout.tangent(0))(0, 0) = in.stream(layout.tangent(0))(1, 0) = 1;
  in.stream(layout.tangent(1))(0, 1) = in.stream(layout.tangent(1))(1, 1) = 1;
  encoding->forward(layout, nullptr, in, out, nullptr);
  EXPECT_DOUBLE_EQ(out.stream(0)(0, 2), 0.3);   // |0.2 − 0.5|
  EXPECT_DOUBLE_EQ(out.stream(0)(0, 3), 0.45);  // |0.2 + 0.25|
  EXPECT_DOUBLE_EQ(out.stream(0)(1, 2), 0.4);
  EXPECT_DOUBLE_EQ(out.stream(0)(1, 0), -0.7);  // x itself first
  EXPECT_EQ(out.stream(layout.tangent(1))(0, 2), -1);  // below the plane y = 0.5
  EXPECT_EQ(out.stream(layout.tangent(1))(1, 2), 1);
  EXPECT_EQ(out.stream(layout.tangent(0))(0, 2), 0);
  for (int k = 0; k < layout.count(); ++k)
    if (k != 0 && k != layout.tangent(0) && k != layout.tangent(1))
      EXPECT_EQ(out.stream(k).rightCols(2).norm(), 0) << "stream " << k;
}

TEST(FieldRegistry, UnknownTypeAndActivationListValidNames) {
  FieldOptions o;
  o.type = "kan";
  std::string message = message_of([&] { o.validate(); });
  EXPECT_NE(message.find("unknown field type 'kan'"), std::string::npos) << message;
  expect_lists(message, field_type_names());

  o = {};
  o.type = "mlp";
  o.activation = "gelu";
  message = message_of([&] { Field<double> f(o); });
  EXPECT_NE(message.find("field.activation"), std::string::npos) << message;
  expect_lists(message, activation_names());
}

TEST(FieldRegistry, NamesAreCaseInsensitive) {
  FieldOptions o;
  o.type = "SIREN";
  o.hidden = {4};
  EXPECT_NO_THROW(Field<double>{o});
  o.type = "Mlp";
  o.activation = "SiNe";
  o.encoding = encoding_options(FourierOptions{.features = 3});
  o.encoding.type = "Fourier";
  const Field<double> f(o);
  EXPECT_EQ(f.encoding_matrix().rows(), 3);
}

TEST(FieldOptions, ValidationNamesTheField) {
  auto expect_field = [](const FieldOptions& o, const std::string& field) {
    const std::string message = message_of([&] { o.validate(); });
    EXPECT_NE(message.find(field), std::string::npos) << "'" << message << "' lacks " << field;
  };
  FieldOptions o;
  o.input_dim = 0;
  expect_field(o, "field.input_dim");
  o = {};
  o.type = "nerf";  // [x, d] → 4 outputs
  expect_field(o, "field.input_dim = 2: must be 6 for nerf");
  o = {};
  o.output_dim = 0;
  expect_field(o, "field.output_dim");
  o = {};
  o.hidden = {};
  expect_field(o, "field.hidden");
  o = {};
  o.hidden = {8, 0};
  expect_field(o, "field.hidden[1]");
  o = {};
  o.first_omega = 0;
  expect_field(o, "field.first_omega");
  o = {};
  o.hidden_omega = -1;
  expect_field(o, "field.hidden_omega");
  o = {};
  o.encoding = encoding_options(PositionalOptions{.frequencies = 30});
  expect_field(o, "encoding.frequencies");
}

TEST(Registry, RejectsDuplicatesAndMatchesCaseInsensitively) {
  Registry<int> r("widget");
  r.add("Alpha", 1);
  r.add("beta", 2);
  EXPECT_THROW(r.add("ALPHA", 3), std::logic_error);
  EXPECT_TRUE(r.contains("aLpHa"));
  EXPECT_EQ(r.at("BETA"), 2);
  EXPECT_EQ(r.names(), (std::vector<std::string>{"alpha", "beta"}));
  try {
    r.at("gamma");
    ADD_FAILURE() << "no exception";
  } catch (const UnknownNameError& e) {
    EXPECT_EQ(std::string(e.what()), "unknown widget 'gamma' (valid: alpha, beta)");
  }
}

}  // namespace
}  // namespace nfield::fields

namespace nfield::fields {
namespace {

// Fields take any number of inputs (a 5-D input: space, time and a parameter).
TEST(FieldOptions, AnyNumberOfInputs) {
  FieldOptions o;
  o.input_dim = 5;
  o.hidden = {8};
  const Field<double> field(o);
  EXPECT_EQ(field.values(Eigen::MatrixXd::Random(3, 5)).rows(), 3);
}

}  // namespace
}  // namespace nfield::fields

namespace nfield::fields {
namespace {

// One default per key: a field built without an activation and a config without the key
// get the same one.
TEST(FieldOptions, OneActivationDefaultPerType) {
  EXPECT_EQ(default_activation("siren"), "sine");
  EXPECT_EQ(default_activation("MLP"), "tanh");
  EXPECT_EQ(default_activation("nerf"), "relu");
  FieldOptions o;
  o.type = "mlp";
  o.hidden = {4};
  EXPECT_EQ(Field<double>(o).options().activation, "tanh");
  o.type = "nerf";
  o.input_dim = 6;
  o.output_dim = 4;
  EXPECT_EQ(Field<double>(o).options().activation, "relu");
}

}  // namespace
}  // namespace nfield::fields
