// SPDX-License-Identifier: MIT
//
// BACON (fields/bacon.h): the band limit of every scale by FFT on a fine periodic grid, for
// random networks and after training; the lattice budget; the multiscale loss as the sum of
// the per-scale losses, each asked for with its scale (a target per scale); the scales after
// a fit ordered coarse ≤ fine and each close to the signal's own low-pass; located config
// errors for every key; a checkpoint round trip.
// (The derivative streams go through the stream harness: tests/testing/stream_checks.h's
// bacon cases.)
#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <numbers>
#include <random>
#include <string>
#include <unsupported/Eigen/FFT>
#include <vector>

#include "autodiff/stream_loss.h"
#include "fields/bacon.h"
#include "fields/field.h"
#include "fields/field_config.h"
#include "fields/field_io.h"
#include "io/config.h"
#include "solvers/training/adam.h"
#include "tests/testing/scratch.h"

namespace nfield::fields {
namespace {

using autodiff::Streams;

FieldOptions bacon(int d, std::vector<int> hidden, std::vector<double> max_frequency, std::uint64_t seed,
                   double lower = -1, double upper = 1) {
  FieldOptions o;
  o.type = "bacon";
  o.input_dim = d;
  o.output_dim = 1;
  o.hidden = std::move(hidden);
  o.seed = seed;
  o.encoding.type = "identity";
  o.encoding.lower.assign(d, lower);
  o.encoding.upper.assign(d, upper);
  BaconOptions b;
  b.max_frequency = std::move(max_frequency);
  o.extension = b;
  return o;
}

// Points of a periodic grid of g per axis over the box, axis 0 fastest.
Eigen::MatrixXd periodic_grid(int d, int g, double lower, double upper) {
  Eigen::Index n = 1;
  for (int k = 0; k < d; ++k) n *= g;
  Eigen::MatrixXd x(n, d);
  for (Eigen::Index i = 0; i < n; ++i)
    for (int k = 0, rest = static_cast<int>(i); k < d; ++k, rest /= g)
      x(i, k) = lower + (upper - lower) * (rest % g) / g;
  return x;
}

// Fraction of the energy of samples f (grid of g per axis, d ≤ 2) at frequencies above
// `cutoff` lattice steps along some axis (index q in [−g/2, g/2) cycles per period).
double energy_above(const Eigen::VectorXd& f, int d, int g, const Eigen::VectorXi& cutoff) {
  Eigen::FFT<double> fft;
  const Eigen::Index rows = g, cols = d == 2 ? g : 1;
  Eigen::MatrixXcd spectrum(rows, cols);  // (axis 0, axis 1)
  for (Eigen::Index c = 0; c < cols; ++c) {
    std::vector<double> line(f.data() + c * rows, f.data() + (c + 1) * rows);
    std::vector<std::complex<double>> out;
    fft.fwd(out, line);
    for (Eigen::Index r = 0; r < rows; ++r) spectrum(r, c) = out[static_cast<size_t>(r)];
  }
  if (d == 2)
    for (Eigen::Index r = 0; r < rows; ++r) {
      std::vector<std::complex<double>> line(static_cast<size_t>(cols)), out;
      for (Eigen::Index c = 0; c < cols; ++c) line[static_cast<size_t>(c)] = spectrum(r, c);
      fft.fwd(out, line);
      for (Eigen::Index c = 0; c < cols; ++c) spectrum(r, c) = out[static_cast<size_t>(c)];
    }
  auto q = [g](Eigen::Index i) { return static_cast<int>(i < g / 2 ? i : i - g); };
  double total = 0, above = 0;
  for (Eigen::Index r = 0; r < rows; ++r)
    for (Eigen::Index c = 0; c < cols; ++c) {
      const double e = std::norm(spectrum(r, c));
      total += e;
      if (std::abs(q(r)) > cutoff(0) || (d == 2 && std::abs(q(c)) > cutoff(1))) above += e;
    }
  return above / total;
}

// Worst fraction over the scales; expects every scale to have energy above its cut-off ≤ 1e-12
// and, as a check that the test can fail, a scale's output to have energy above the next
// coarser scale's cut-off.
void expect_band_limited(const Field<double>& field, int g, double lower, double upper, const std::string& where) {
  const int d = field.input_dim();
  const Eigen::MatrixXi steps = bacon_cutoff_steps(field.options());
  const Eigen::MatrixXd x = periodic_grid(d, g, lower, upper);
  for (int s = 0; s < field.scales(); ++s) {
    ASSERT_GT(g / 2, 2 * steps.row(s).maxCoeff()) << "grid too coarse to see a broken band limit";
    const Eigen::VectorXd f = field.values(x, s).col(0);
    const double above = energy_above(f, d, g, steps.row(s).transpose());
    EXPECT_LE(above, 1e-12) << where << " scale " << s;
    if (s > 0) EXPECT_GT(energy_above(f, d, g, steps.row(s - 1).transpose()), 1e-6) << where << " scale " << s;
  }
}

TEST(Bacon, LayerBoundsSumToEachScalesCutoff) {
  FieldOptions o = bacon(2, {8, 8, 8, 8, 8}, {3.0, 8.0, 16.0}, 1, 0.0, 2.0);  // D = 2: K = 6, 16, 32
  BaconOptions b = bacon_options(o);
  b.output_layers = {2, 3, 4};
  o.extension = b;
  const Eigen::MatrixXi bounds = bacon_layer_bounds(o);
  EXPECT_EQ(bounds.col(0).transpose(), Eigen::RowVectorXi::Map(std::vector<int>{2, 2, 2, 10, 16}.data(), 5));
  const Eigen::MatrixXi steps = bacon_cutoff_steps(o);
  EXPECT_EQ(steps.col(1).transpose(), Eigen::RowVectorXi::Map(std::vector<int>{6, 16, 32}.data(), 3));
  // Resolution N: the Nyquist limit, N/2 steps whatever the box.
  b.max_frequency.clear();
  b.resolution = {4, 16, 64};
  o.extension = b;
  EXPECT_EQ(bacon_cutoff_steps(o).col(0).transpose(), Eigen::RowVectorXi::Map(std::vector<int>{2, 8, 32}.data(), 3));
  // The drawn frequencies stay within each layer's bound and reach it.
  const std::vector<Eigen::MatrixXd> omega = bacon_filter_frequencies(o);
  const Eigen::MatrixXi m = bacon_layer_bounds(o);
  for (size_t i = 0; i < omega.size(); ++i) {
    const Eigen::ArrayXXd n = omega[i].array() / (std::numbers::pi);  // 2π n / D with D = 2
    EXPECT_LE((n - n.round()).abs().maxCoeff(), 1e-12);
    for (int k = 0; k < 2; ++k) EXPECT_LE(n.col(k).abs().maxCoeff(), m(static_cast<Eigen::Index>(i), k) + 1e-9);
  }
}

TEST(Bacon, RandomNetworksAreBandLimited) {
  for (std::uint64_t seed : {1u, 2u, 3u}) {
    const Field<double> field1(bacon(1, {32, 32, 32, 32}, {3.0, 6.0, 12.0}, seed, 0.0, 3.0));
    expect_band_limited(field1, 512, 0.0, 3.0, "1-D seed " + std::to_string(seed));
    const Field<double> field2(bacon(2, {16, 16, 16}, {1.5, 3.0, 6.0}, seed));
    expect_band_limited(field2, 64, -1.0, 1.0, "2-D seed " + std::to_string(seed));
    // period: 2 box widths; the grid covers the whole period [0, 2).
    FieldOptions o = bacon(1, {16, 16}, {2.0, 5.0}, seed, 0.0, 1.0);
    BaconOptions b = bacon_options(o);
    b.period = 2;
    o.extension = b;
    EXPECT_EQ(bacon_cutoff_steps(o)(1, 0), 10);
    expect_band_limited(Field<double>(o), 256, 0.0, 2.0, "1-D period 2 seed " + std::to_string(seed));
  }
}

// Mean squared error to `target` on every scale (or only the chosen one), with Adam.
void train(Field<double>& field, const Eigen::MatrixXd& x, const Eigen::VectorXd& target, int steps, double lr) {
  const autodiff::StreamLayout layout(autodiff::StreamSpec::values(field.input_dim()));
  const autodiff::LambdaLoss<double> loss([&](Eigen::Index first, const autodiff::StreamLayout&,
                                              const Streams<double>& out, Streams<double>& adjoint) {
    const Eigen::VectorXd r = out.stream(0).col(0) - target.segment(first, out.points);
    adjoint.stream(0).col(0) = 2.0 * r / static_cast<double>(target.size());
    return r.squaredNorm() / static_cast<double>(target.size());
  });
  solvers::Adam<double> adam(field.parameter_count());
  Eigen::VectorXd gradient(field.parameter_count());
  for (int step = 0; step < steps; ++step) {
    gradient.setZero();
    field.value_and_gradient(field.parameters().data(), layout, autodiff::Batch<double>{x}, loss, gradient.data());
    adam.step(field.parameters().data(), gradient.data(), lr);
  }
}

// A periodic signal on [0, 1) with energy at every frequency up to 40 cycles.
Eigen::VectorXd rich_signal(const Eigen::VectorXd& x) {
  Eigen::VectorXd f = Eigen::VectorXd::Zero(x.size());
  for (int q = 1; q <= 40; ++q) f.array() += (1.0 / q) * (2 * std::numbers::pi * q * x.array() + 0.7 * q).sin();
  return f;
}

// The signal's own low-pass at `cutoff` cycles: its DFT truncated.
Eigen::VectorXd low_pass(const Eigen::VectorXd& f, int cutoff) {
  Eigen::FFT<double> fft;
  std::vector<double> in(f.data(), f.data() + f.size());
  std::vector<std::complex<double>> spectrum;
  fft.fwd(spectrum, in);
  const int g = static_cast<int>(f.size());
  for (int i = 0; i < g; ++i)
    if (std::abs(i < g / 2 ? i : i - g) > cutoff) spectrum[static_cast<size_t>(i)] = 0;
  std::vector<double> out;
  fft.inv(out, spectrum);
  return Eigen::VectorXd::Map(out.data(), g);
}

TEST(Bacon, TrainedScalesStayBandLimitedAndApproachTheirLowPass) {
  FieldOptions o = bacon(1, {48, 48, 48}, {5.0, 10.0, 20.0}, 7, 0.0, 1.0);
  Field<double> field(o, {.block_points = 128, .threads = 1});
  const Eigen::MatrixXd x = periodic_grid(1, 256, 0.0, 1.0);
  const Eigen::VectorXd target = rich_signal(x.col(0));
  train(field, x, target, 300, 5e-3);
  expect_band_limited(field, 256, 0.0, 1.0, "after training");
  double previous = INFINITY;
  for (int s = 0; s < 3; ++s) {
    const Eigen::VectorXd u = field.values(x, s).col(0);
    const double error = (u - target).norm() / target.norm();
    const int cutoff = bacon_cutoff_steps(o)(s, 0);
    const double to_low_pass = (u - low_pass(target, cutoff)).norm() / target.norm();
    EXPECT_LT(error, previous) << "scale " << s;  // coarse ≤ fine
    // The best a scale can do is its low-pass (everything above is out of its reach).
    EXPECT_GE(error, (low_pass(target, cutoff) - target).norm() / target.norm() - 1e-9) << "scale " << s;
    EXPECT_LT(to_low_pass, 0.1) << "scale " << s << ": far from the signal's low-pass";
    previous = error;
  }
}

// `o` with the loss and outputs of scale s alone.
FieldOptions one_scale(const FieldOptions& o, int s) {
  BaconOptions b = bacon_options(o);
  b.train_all_scales = false;
  b.output_scale = s;
  FieldOptions one = o;
  one.extension = b;
  return one;
}

TEST(Bacon, AllScalesLossIsTheSumOfTheScalesLosses) {
  FieldOptions o = bacon(2, {6, 5, 4}, {1.0, 2.0, 3.0}, 3);
  const Field<double> all(o);
  const Eigen::MatrixXd x = Eigen::MatrixXd::Random(9, 2);
  const autodiff::StreamLayout layout(autodiff::StreamSpec::laplacian(2));
  // A loss reading the value and the Laplacian streams.
  const autodiff::LambdaLoss<double> loss([&](Eigen::Index, const autodiff::StreamLayout& l,
                                              const Streams<double>& out, Streams<double>& adjoint) {
    const auto u = out.stream(0).col(0), lap = out.stream(l.op(0)).col(0);
    adjoint.stream(0).col(0) = 2 * u;
    adjoint.stream(l.op(0)).col(0) = 2 * lap;
    return u.squaredNorm() + lap.squaredNorm();
  });
  EXPECT_TRUE(all.trains_all_scales());
  Eigen::VectorXd g_all = Eigen::VectorXd::Zero(all.parameter_count());
  const double l_all = all.value_and_gradient(all.parameters().data(), layout, {x}, loss, g_all.data());
  Eigen::VectorXd g_sum = Eigen::VectorXd::Zero(all.parameter_count());
  double l_sum = 0;
  for (int s = 0; s < 3; ++s) {
    Field<double> field(one_scale(o, s));
    field.parameters() = all.parameters();
    EXPECT_FALSE(field.trains_all_scales());
    l_sum += field.value_and_gradient(field.parameters().data(), layout, {x}, loss, g_sum.data());
  }
  EXPECT_NEAR(l_all, l_sum, 1e-12 * l_sum);
  EXPECT_LE((g_all - g_sum).cwiseAbs().maxCoeff(), 1e-12 * g_sum.cwiseAbs().maxCoeff());
  // The default output is the finest scale.
  EXPECT_EQ(all.values(x), all.values(x, 2));
  EXPECT_NE(all.values(x), all.values(x, 1));
}

// A loss with a target per scale: scale s's outputs against s + 1 (value stream only).
class PerScaleLoss final : public autodiff::StreamLoss<double> {
 public:
  double evaluate(Eigen::Index, const autodiff::StreamLayout&, const Streams<double>&, Streams<double>&) const override {
    ADD_FAILURE() << "a multiscale field asks each scale's loss by evaluate_scale";
    return 0;
  }
  double evaluate_scale(int scale, Eigen::Index, const autodiff::StreamLayout&, const Streams<double>& out,
                        Streams<double>& adjoint) const override {
    const Eigen::ArrayXd r = out.stream(0).col(0).array() - (scale + 1.0);
    adjoint.stream(0).col(0) = 2 * r.matrix();
    return r.square().sum();
  }
};

TEST(Bacon, EachScalesLossIsAskedForWithItsScale) {
  FieldOptions o = bacon(2, {6, 5, 4}, {1.0, 2.0, 3.0}, 3);
  const Field<double> all(o);
  const Eigen::MatrixXd x = Eigen::MatrixXd::Random(9, 2);
  const autodiff::StreamLayout layout(autodiff::StreamSpec::values(2));
  double expected = 0;
  for (int s = 0; s < 3; ++s) expected += (all.values(x, s).col(0).array() - (s + 1.0)).square().sum();
  Eigen::VectorXd g_all = Eigen::VectorXd::Zero(all.parameter_count());
  EXPECT_NEAR(all.value_and_gradient(all.parameters().data(), layout, {x}, PerScaleLoss(), g_all.data()), expected,
              1e-12 * expected);
  // The gradient: the sum of the one-scale fields' (each asks its own scale).
  Eigen::VectorXd g_sum = Eigen::VectorXd::Zero(all.parameter_count());
  for (int s = 0; s < 3; ++s) {
    const Field<double> field(one_scale(o, s));
    field.value_and_gradient(all.parameters().data(), layout, {x}, PerScaleLoss(), g_sum.data());
  }
  EXPECT_LE((g_all - g_sum).cwiseAbs().maxCoeff(), 1e-12 * g_sum.cwiseAbs().maxCoeff());
}

FieldOptions from_text(const std::string& field) {
  const io::ConfigNode root = io::parse_config("field: " + field + "\n", "field.yaml");
  return field_options_from_config(root.child("field"), 2, 1, 11);
}

void expect_error_at(const std::string& text, const std::string& key) {
  try {
    from_text(text);
    ADD_FAILURE() << "no error for " << text;
  } catch (const io::ConfigError& e) {
    EXPECT_EQ(e.key_path(), key) << text << ": " << e.what();
    EXPECT_NE(std::string(e.what()).find("field.yaml:"), std::string::npos) << e.what();
  }
}

TEST(Bacon, ConfigKeysAndLocatedErrors) {
  const FieldOptions o = from_text("{type: bacon, hidden: [8, 8, 8, 8], resolution: [16, 32], train_scales: output}");
  const BaconOptions& b = bacon_options(o);
  EXPECT_EQ(b.resolution, (std::vector<int>{16, 32}));
  EXPECT_FALSE(b.train_all_scales);
  EXPECT_EQ(b.head_layers(4), (std::vector<int>{2, 3}));
  const YAML::Node written = to_yaml(o, {"x", "y"});
  EXPECT_EQ(written["output_layers"].as<std::vector<int>>(), (std::vector<int>{2, 3}));
  EXPECT_EQ(written["train_scales"].as<std::string>(), "output");

  expect_error_at("{type: bacon, hidden: [8, 8], resolution: [32, 16]}", "field.resolution");
  expect_error_at("{type: bacon, hidden: [8, 8], resolution: [1, 16]}", "field.resolution");
  expect_error_at("{type: bacon, hidden: [8, 8], max_frequency: [0, 2]}", "field.max_frequency");
  expect_error_at("{type: bacon, hidden: [8, 8], max_frequency: [3, 2]}", "field.max_frequency");
  expect_error_at("{type: bacon, hidden: [8, 8], max_frequency: [1, 2], resolution: [4, 8]}", "field.max_frequency");
  expect_error_at("{type: bacon, hidden: [8], resolution: [4, 8]}", "field.hidden");
  expect_error_at("{type: bacon, hidden: [8, 8, 8], resolution: [4, 8], output_layers: [0, 1]}", "field.output_layers");
  expect_error_at("{type: bacon, hidden: [8, 8, 8], resolution: [4, 8], output_layers: [2, 2]}", "field.output_layers");
  expect_error_at("{type: bacon, hidden: [8, 8, 8], resolution: [4, 8], output_layers: [1]}", "field.output_layers");
  expect_error_at("{type: bacon, hidden: [8, 8], resolution: [4, 8], train_scales: some}", "field.train_scales");
  expect_error_at("{type: bacon, hidden: [8, 8], resolution: [4, 8], output_scale: 2}", "field.output_scale");
  expect_error_at("{type: bacon, hidden: [8, 8], resolution: [4, 8], period: 0}", "field.period");
  expect_error_at("{type: bacon, hidden: [8, 8], resolution: [4, 8], output_sclae: 1}", "field.output_sclae");
  expect_error_at("{type: bacon, hidden: [8, 8], resolution: [4, 8], activation: relu}", "field.activation");
  expect_error_at("{type: bacon, hidden: [8, 8], resolution: [4, 8], encoding: {type: fourier}}", "field");
}

TEST(Bacon, CheckpointRoundTrip) {
  FieldOptions o = from_text("{type: bacon, hidden: [8, 6, 4], max_frequency: [1.5, 3], output_scale: 0, period: 3}");
  o.encoding.lower = {0.0, -1.0};
  o.encoding.upper = {2.0, 3.0};
  Field<float> field(o);
  field.parameters().array() += 0.25f;
  const auto path = testutil::scratch_dir("bacon") / "bacon.h5";
  {
    io::H5Writer file(path);
    save_field(file, field, "field");
    file.commit();
  }
  const io::H5Reader file(path);
  const Field<float> loaded = load_field<float>(file, "field");
  EXPECT_EQ(loaded.parameters(), field.parameters());
  EXPECT_EQ(loaded.scales(), 2);
  EXPECT_EQ(loaded.output_scale(), 0);
  EXPECT_EQ(bacon_options(loaded.options()).period, 3);
  const Eigen::MatrixXf x = Eigen::MatrixXf::Random(5, 2);
  for (int s = 0; s < 2; ++s) EXPECT_EQ(loaded.values(x, s), field.values(x, s));
}

}  // namespace
}  // namespace nfield::fields
