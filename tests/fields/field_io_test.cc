// SPDX-License-Identifier: MIT
// Fields saved in HDF5 and loaded back are bit-identical, in both precisions, for every
// encoding; the layout is the documented one (one dataset per weight and bias).
#include <gtest/gtest.h>

#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "fields/encoding_type.h"
#include "fields/field_io.h"
#include "tests/testing/encoding_options.h"
#include "tests/testing/scratch.h"

namespace nfield::fields {
namespace {

std::filesystem::path temp_file(const std::string& name) {
  return testutil::test_folder("field_io") / name;
}

template <typename Scalar>
void expect_round_trip(const FieldOptions& options, const std::string& name) {
  Field<Scalar> field(options);
  field.parameters().setRandom();  // not the initialization: any bits must survive
  const auto path = temp_file(name);
  {
    io::H5Writer file(path);
    save_field(file, field);
    file.commit();
  }
  const io::H5Reader file(path);
  const Field<Scalar> loaded = load_field<Scalar>(file);
  ASSERT_EQ(loaded.parameter_count(), field.parameter_count());
  EXPECT_EQ(std::memcmp(loaded.parameters().data(), field.parameters().data(),
                        sizeof(Scalar) * field.parameter_count()), 0);
  EXPECT_EQ(loaded.encoding_matrix(), field.encoding_matrix());
  const FieldOptions o = load_field_options(file);
  EXPECT_EQ(o.hidden, options.hidden);
  EXPECT_EQ(o.encoding.type, options.encoding.type);
  // Every key of the encoding's own options comes back.
  EXPECT_TRUE(testutil::any_encoding(o.encoding) == testutil::any_encoding(options.encoding))
      << options.encoding.type;
  EXPECT_EQ(o.encoding.lower, options.encoding.lower);
  EXPECT_EQ(o.encoding.upper, options.encoding.upper);
  // Layout: layer 0 weight is (hidden[0], encoded input width).
  const auto shape = file.shape("field/layers/0/weight");
  ASSERT_EQ(shape.size(), 2u);
  EXPECT_EQ(shape[0], static_cast<std::uint64_t>(options.hidden[0]));
  EXPECT_EQ(file.shape("field/layers/" + std::to_string(options.hidden.size()) + "/bias")[0],
            static_cast<std::uint64_t>(options.output_dim));
  autodiff::Matrix<Scalar> x = autodiff::Matrix<Scalar>::Random(7, options.input_dim);
  if (reads_variances(options.encoding)) {  // [μ, σ²] with σ² ≥ 0
    const Eigen::Index k = options.input_dim / 2;
    x.rightCols(k) = x.rightCols(k).cwiseAbs() * Scalar(0.01);
  }
  EXPECT_EQ(loaded.values(x), field.values(x));
}

TEST(FieldIo, RoundTripIsBitExactForEveryEncodingAndPrecision) {
  for (const std::string& encoding : encoding_names()) {
    FieldOptions options;
    options.input_dim = reads_variances(EncodingOptions{.type = encoding}) ? 4 : 3;  // [μ, σ²]
    options.output_dim = 2;
    options.hidden = {8, 6};
    // Values other than the defaults, so that a key that does not come back shows.
    options.encoding = testutil::encoding_of(encoding, {.frequencies = 3,
                                                        .include_input = false,
                                                        .features = 5,
                                                        .scale = 2.5,
                                                        .seed = 9,
                                                        .axis = 1,
                                                        .at = {-0.25, 0.5},
                                                        .from_stage = encoding == "cusp" ? 2 : 0,
                                                        .levels = 4,  // hash_grid: small tables
                                                        .log2_table_size = 10,
                                                        .finest_resolution = 64,
                                                        .interpolation = "cubic",
                                                        .init_scale = 0.25});
    if (encoding == "hash_grid") options.encoding.lower = {-1, 0, 2}, options.encoding.upper = {1, 3, 4};
    expect_round_trip<float>(options, encoding + "_float.h5");
    expect_round_trip<double>(options, encoding + "_double.h5");
  }
  FieldOptions mlp;
  mlp.type = "mlp";
  mlp.activation = "softplus";
  mlp.hidden = {4};
  expect_round_trip<double>(mlp, "mlp.h5");
  FieldOptions normalized;
  normalized.input_dim = 3;
  normalized.hidden = {4};
  normalized.encoding = encoding_options(PositionalOptions{.normalize = true});
  expect_round_trip<double>(normalized, "positional_normalized.h5");
  FieldOptions scales;  // Fourier features in blocks of several scales
  scales.input_dim = 2;
  scales.hidden = {4};
  scales.encoding = encoding_options(FourierOptions{.features = 3, .scales = {{1.0, 2.0}, {0.5}}});
  expect_round_trip<double>(scales, "fourier_scales.h5");
}

// Files written before each encoding saved its own keys carry encoding_frequencies,
// encoding_include_input, encoding_features, encoding_scale and encoding_seed for every type,
// and hash_grid's include_input only among them: each type reads its own from there.
TEST(FieldIo, ReadsFilesWithTheFormerCommonEncodingAttributes) {
  for (const std::string& type : {"positional", "fourier", "hash_grid", "identity"}) {
    FieldOptions options;
    options.hidden = {4};
    options.encoding = testutil::encoding_of(type, {.levels = 2, .log2_table_size = 10, .finest_resolution = 32});
    const auto path = temp_file("former_" + type + ".h5");
    {
      io::H5Writer file(path);
      save_field(file, Field<double>(options));
      file.write_attribute("field", "encoding_frequencies", 3);
      file.write_attribute("field", "encoding_include_input", std::int64_t{0});
      file.write_attribute("field", "encoding_features", 7);
      file.write_attribute("field", "encoding_scale", 0.5);
      file.write_attribute("field", "encoding_seed", std::int64_t{12});
      file.commit();
    }
    const FieldOptions o = load_field_options(io::H5Reader(path));
    const testutil::AnyEncoding a = testutil::any_encoding(o.encoding);
    ASSERT_EQ(o.encoding.type, type);
    if (type == "positional") EXPECT_EQ(a.frequencies, 3);
    if (type == "positional" || type == "hash_grid") EXPECT_FALSE(a.include_input) << type;
    if (type == "fourier") {
      EXPECT_EQ(a.features, 7);
      EXPECT_EQ(a.scale, 0.5);
      EXPECT_EQ(a.seed, 12u);
    }
    if (type == "hash_grid") EXPECT_EQ(a.levels, 2);
  }
}

TEST(FieldIo, H5pyReadsTheLayout) {
  if (std::system("/usr/bin/python3 -c 'import h5py' >/dev/null 2>&1") != 0) GTEST_SKIP() << "no h5py";
  FieldOptions options;
  options.hidden = {5, 4};
  Field<float> field(options);
  const auto path = temp_file("h5py.h5");
  {
    io::H5Writer file(path);
    save_field(file, field);
    file.commit();
  }
  const float w = field.parameters()(1);  // W(1, 0) of layer 0, column-major out × in
  const std::string script = "import h5py,sys; f=h5py.File('" + path.string() +
                             "','r'); w=f['field/layers/0/weight']; "
                             "sys.exit(0 if w.shape==(5,2) and abs(w[1,0]-(" + std::to_string(w) +
                             "))<1e-6 and f['field'].attrs['type']=='siren' else 1)";
  EXPECT_EQ(std::system(("/usr/bin/python3 -c \"" + script + "\"").c_str()), 0);
}

}  // namespace
}  // namespace nfield::fields
