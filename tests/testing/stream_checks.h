// SPDX-License-Identifier: MIT
//
// Helpers for checking derivative streams: the expected streams of a field from nested
// ceres::Jet, Ridders-extrapolated central differences, per-stream relative errors, the
// network cases (every registered activation × encoding), and a report of the worst error
// seen per check, printed when a test program ends.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <functional>
#include <iomanip>
#include <iostream>
#include <limits>
#include <map>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "autodiff/streams.h"
#include "fields/acorn.h"
#include "fields/activations.h"
#include "fields/bacon.h"
#include "fields/encoding_type.h"
#include "fields/encodings.h"
#include "fields/field.h"
#include "io/text.h"
#include "tests/testing/reference_field.h"
#include "tests/testing/small_acorn.h"

namespace nfield::testutil {

using autodiff::StreamLayout;
using autodiff::Streams;
using autodiff::StreamSpec;

// ---------------------------------------------------------------------------------------
// Worst errors per check, printed at the end of the program.

class WorstErrors {
 public:
  static WorstErrors& get() {
    static WorstErrors instance;
    return instance;
  }
  void record(const std::string& check, double error, const std::string& where = "") {
    auto& [worst, at] = worst_[check];
    if (error >= worst) {
      worst = error;
      at = where;
    }
  }
  void print(std::ostream& os) const {
    if (worst_.empty()) return;
    os << "worst relative errors observed:\n";
    for (const auto& [check, entry] : worst_)
      os << "  " << std::left << std::setw(48) << check << std::scientific << std::setprecision(2)
         << entry.first << "  " << entry.second << "\n";
    os << std::defaultfloat;
  }

 private:
  std::map<std::string, std::pair<double, std::string>> worst_;
};

class WorstErrorReport : public ::testing::Environment {
 public:
  void TearDown() override { WorstErrors::get().print(std::cout); }
};
inline ::testing::Environment* const kWorstErrorReport =
    ::testing::AddGlobalTestEnvironment(new WorstErrorReport);

// ---------------------------------------------------------------------------------------
// Random numbers from the raw engine only, so the draws do not depend on the standard
// library's distributions.

inline double uniform(std::mt19937_64& rng, double lo = -1, double hi = 1) {
  return lo + (hi - lo) * static_cast<double>(rng() >> 11) * 0x1.0p-53;
}
inline Eigen::MatrixXd random_matrix(Eigen::Index rows, Eigen::Index cols, std::mt19937_64& rng,
                                     double lo = -1, double hi = 1) {
  Eigen::MatrixXd m(rows, cols);
  for (Eigen::Index j = 0; j < cols; ++j)
    for (Eigen::Index i = 0; i < rows; ++i) m(i, j) = uniform(rng, lo, hi);
  return m;
}
inline Eigen::MatrixXd random_symmetric(Eigen::Index n, std::mt19937_64& rng) {
  const Eigen::MatrixXd a = random_matrix(n, n, rng);
  return a + a.transpose();
}
inline std::uint64_t fnv1a(const std::string& s) {
  std::uint64_t h = 1469598103934665603ull;
  for (unsigned char c : s) h = (h ^ c) * 1099511628211ull;
  return h;
}

// ---------------------------------------------------------------------------------------
// Stream names and orders.

inline int stream_order(const StreamLayout& l, int s) {
  if (s == 0) return 0;
  if (s <= l.tangents()) return 1;
  if (s <= l.tangents() + l.operators()) return 2;
  return (s - 1 - l.tangents() - l.operators()) % l.taylor_order() + 1;
}

inline std::string stream_name(const StreamLayout& l, int s) {
  if (s == 0) return "value";
  if (s <= l.tangents()) return "tangent " + std::to_string(s - 1);
  if (s <= l.tangents() + l.operators())
    return "operator " + std::to_string(s - 1 - l.tangents());
  const int t = s - 1 - l.tangents() - l.operators();
  return "taylor dir " + std::to_string(t / l.taylor_order()) + " order " +
         std::to_string(t % l.taylor_order() + 1);
}

// Kind of a stream for the error report: value, tangent, operator, taylor k.
inline std::string stream_kind(const StreamLayout& l, int s) {
  if (s == 0) return "value";
  if (s <= l.tangents()) return "tangent";
  if (s <= l.tangents() + l.operators()) return "operator";
  return "taylor order " + std::to_string(stream_order(l, s));
}

// ---------------------------------------------------------------------------------------
// Errors.

// max over columns of  max_n |actual − expected| / max(max_n |expected|, max_n |actual|, floor).
// Exactly equal columns (both zero, say) have error 0.
inline double relative_error(const Eigen::Ref<const Eigen::MatrixXd>& actual,
                             const Eigen::Ref<const Eigen::MatrixXd>& expected, double floor) {
  double worst = 0;
  for (Eigen::Index c = 0; c < actual.cols(); ++c) {
    const double diff = (actual.col(c) - expected.col(c)).cwiseAbs().maxCoeff();
    if (diff == 0) continue;
    if (!std::isfinite(diff)) return std::numeric_limits<double>::infinity();
    const double scale = std::max({expected.col(c).cwiseAbs().maxCoeff(),
                                   actual.col(c).cwiseAbs().maxCoeff(), floor});
    worst = std::max(worst, diff / scale);
  }
  return worst;
}

// Per derivative order of a layout, the largest magnitude of any stream of that order.
inline std::vector<double> order_scales(const StreamLayout& l, const Eigen::MatrixXd& data,
                                        Eigen::Index points) {
  std::vector<double> scale(std::max(2, l.taylor_order()) + 1, 0.0);
  for (int s = 0; s < l.count(); ++s) {
    const int k = stream_order(l, s);
    scale[k] = std::max(scale[k], data.middleRows(s * points, points).cwiseAbs().maxCoeff());
  }
  return scale;
}

// ---------------------------------------------------------------------------------------
// Ridders' extrapolation of central differences (Numerical Recipes, 3rd ed., §5.7),
// componentwise: differences at h, h/c, h/c², … form a Neville tableau in h²; per component
// the entry with the smallest error estimate wins. order 1: (F(h) − F(−h)) / 2h,
// order 2: (F(h) − 2F(0) + F(−h)) / h². Both have error expansions in even powers of h.
struct RiddersResult {
  Eigen::VectorXd value, error;
};

inline RiddersResult ridders(const std::function<Eigen::VectorXd(double)>& f, double h,
                             int order = 1, int levels = 10, double shrink = 1.4) {
  Eigen::VectorXd f0;
  if (order == 2) f0 = f(0.0);
  auto difference = [&](double hh) -> Eigen::VectorXd {
    const Eigen::VectorXd plus = f(hh), minus = f(-hh);
    if (order == 1) return (plus - minus) / (2 * hh);
    return (plus - 2 * f0 + minus) / (hh * hh);
  };
  std::vector<std::vector<Eigen::VectorXd>> a(levels, std::vector<Eigen::VectorXd>(levels));
  a[0][0] = difference(h);
  RiddersResult out{a[0][0], Eigen::VectorXd::Constant(a[0][0].size(),
                                                       std::numeric_limits<double>::infinity())};
  const double c2 = shrink * shrink;
  for (int i = 1; i < levels; ++i) {
    h /= shrink;
    a[i][0] = difference(h);
    double fac = c2;
    for (int j = 1; j <= i; ++j) {
      a[i][j] = (a[i][j - 1] * fac - a[i - 1][j - 1]) / (fac - 1);
      fac *= c2;
      const Eigen::ArrayXd e = (a[i][j] - a[i][j - 1])
                                   .cwiseAbs()
                                   .array()
                                   .max((a[i][j] - a[i - 1][j - 1]).cwiseAbs().array());
      for (Eigen::Index k = 0; k < e.size(); ++k)
        if (e[k] <= out.error[k]) {
          out.error[k] = e[k];
          out.value[k] = a[i][j][k];
        }
    }
  }
  return out;
}

// ---------------------------------------------------------------------------------------
// Expected streams from nested jets: value, gradient g and Hessian H from
// Jet<Jet<double, 4>, 4>; tangents gᵀvᵢ; operators Σᵢⱼ Cᵢⱼ vᵢᵀ H vⱼ; Taylor coefficients
// (1/k!) dᵏ/dτᵏ f(x + τ w) from a jet nested four deep in one variable (K ≤ 4).
// Returns the same (count · N) × m layout as autodiff::Streams::data.
inline Eigen::MatrixXd reference_streams(const ReferenceField& ref, const StreamLayout& layout,
                                         const Eigen::MatrixXd& x) {
  using J1 = ceres::Jet<double, 4>;
  using J2 = ceres::Jet<J1, 4>;
  using T1 = ceres::Jet<double, 1>;
  using T2 = ceres::Jet<T1, 1>;
  using T3 = ceres::Jet<T2, 1>;
  using T4 = ceres::Jet<T3, 1>;
  const int d = layout.input_dim(), m = ref.output_dim();
  const Eigen::Index n = x.rows();
  if (d > 4 || layout.taylor_order() > 4)
    throw std::logic_error("reference_streams: at most 4 inputs and Taylor order 4");
  const StreamSpec& spec = layout.spec();
  Eigen::MatrixXd out = Eigen::MatrixXd::Zero(layout.count() * n, m);
  for (Eigen::Index p = 0; p < n; ++p) {
    std::vector<J2> xj(d);
    for (int i = 0; i < d; ++i) {
      xj[i] = constant<J2>(x(p, i));
      xj[i].a.v[i] = 1.0;
      xj[i].v[i] = constant<J1>(1.0);
    }
    const std::vector<J2> y = ref.evaluate(xj);
    for (int o = 0; o < m; ++o) {
      Eigen::VectorXd g(d);
      Eigen::MatrixXd h(d, d);
      for (int i = 0; i < d; ++i) {
        g[i] = y[o].a.v[i];
        for (int j = 0; j < d; ++j) h(i, j) = y[o].v[i].v[j];
      }
      out(p, o) = y[o].a.a;
      const Eigen::MatrixXd vhv = spec.tangents.transpose() * h * spec.tangents;
      for (int t = 0; t < layout.tangents(); ++t)
        out(layout.tangent(t) * n + p, o) = g.dot(spec.tangents.col(t));
      for (int q = 0; q < layout.operators(); ++q)
        out(layout.op(q) * n + p, o) = spec.operators[q].cwiseProduct(vhv).sum();
    }
    for (int dir = 0; dir < layout.taylor_dirs(); ++dir) {
      const T4 tau = taylor_variable<T4>(0.0);
      std::vector<T4> xt(d);
      for (int i = 0; i < d; ++i)
        xt[i] = constant<T4>(x(p, i)) + constant<T4>(spec.taylor_directions(i, dir)) * tau;
      const std::vector<T4> y = ref.evaluate(xt);
      double factorial = 1;
      for (int k = 1; k <= layout.taylor_order(); ++k) {
        factorial *= k;
        for (int o = 0; o < m; ++o)
          out(layout.taylor(dir, k) * n + p, o) = taylor_derivative(y[o], k) / factorial;
      }
    }
  }
  return out;
}

// ---------------------------------------------------------------------------------------
// Network cases: every registered activation (as an mlp) and SIREN, each with every
// registered encoding, and with each variant of an encoding that has some (hash_grid's
// interpolations beyond the default case's smoothstep). A newly registered activation or
// encoding becomes a case by itself.
// BACON and ACORN (their own modules) are cases too; ACORN gives the value and tangent
// streams only, and the tests check those and that it refuses the others
// (unsupported_streams below).

struct NetworkCase {
  std::string type;        // siren | mlp | bacon | acorn
  std::string activation;  // mlp's activation ("sine" for siren)
  std::string encoding;
  std::string variant = {};  // hash_grid: the interpolation, empty for smoothstep
  bool latent = false;       // a latent code of 3 joins the first hidden layer (fields/latent_code.h)
  std::string name() const {
    std::string s = type == "siren" ? "siren_" + encoding : type + "_" + activation + "_" + encoding;
    if (!variant.empty()) s += "_" + variant;
    if (latent) s += "_latent";
    for (char& c : s)
      if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
    return s;
  }
};

inline std::vector<NetworkCase> registered_network_cases() {
  std::vector<NetworkCase> cases;
  for (const std::string& encoding : fields::encoding_names()) {
    std::vector<std::string> variants{""};
    if (encoding == "hash_grid") variants.push_back("cubic");
    for (const std::string& variant : variants) {
      cases.push_back({"siren", "sine", encoding, variant});
      for (const std::string& activation : fields::activation_names())
        cases.push_back({"mlp", activation, encoding, variant});
    }
  }
  // Latent codes, on a plain SIREN and behind two kinds of encoding.
  cases.push_back({"siren", "sine", "identity", "", true});
  cases.push_back({"mlp", "tanh", "positional", "", true});
  cases.push_back({"mlp", "relu", "hash_grid", "", true});
  // BACON reads the coordinates itself: identity only; its finest head, and its coarse one.
  cases.push_back({"bacon", "sine", "identity"});
  cases.push_back({"bacon", "sine", "identity", "coarse"});
  // ACORN: its own encoder and feature grids, then a decoder (smooth, and with kinks).
  cases.push_back({"acorn", "tanh", "identity"});
  cases.push_back({"acorn", "relu", "identity"});
  return cases;
}

// The streams a case's field does not give, with the reason (empty when it gives all):
// ACORN's multilinear feature grids have value and gradient streams only (fields/acorn.h).
inline std::string unsupported_streams(const NetworkCase& c) {
  if (c.type == "acorn")
    return "acorn gives the value and tangent streams only: its feature grids are multilinear "
           "per cell and not continuous across block faces, so operator and Taylor streams are "
           "refused (fields/acorn.h)";
  return {};
}
inline bool supports(const NetworkCase& c, const StreamLayout& layout) {
  return unsupported_streams(c).empty() || (layout.operators() == 0 && layout.taylor_dirs() == 0);
}

// Whether the case's field takes d inputs: an encoding that reads variances takes k means and
// k variances (fields/integrated_positional.h), so an even number.
inline bool takes_input_dim(const NetworkCase& c, int d) {
  if (c.type == "acorn") return d <= 3;  // a quadtree/octree of at most three axes
  return !fields::encoding_type(c.encoding).reads_variances() || d % 2 == 0;
}

inline std::string case_name(const ::testing::TestParamInfo<NetworkCase>& info) {
  return info.param.name();
}

// A small random network: hidden [8, 8], moderate encodings (positional L = 3, Fourier
// features 8 with σ = 1, hash grid of 3 smoothstep (or the case's variant) levels N = 2, 3, 6 over the points' box
// [−1, 1]^d with 2^10 rows, hashed for d = 4, tables U(−0.5, 0.5)), SIREN with its defaults ω₀ = 30, an mlp sine
// with frequency 2.
inline fields::FieldOptions small_options(const NetworkCase& c, int input_dim, int output_dim,
                                          std::uint64_t seed, std::vector<int> hidden = {8, 8}) {
  fields::FieldOptions o;
  o.type = c.type;
  o.activation = c.activation;
  o.input_dim = input_dim;
  o.output_dim = output_dim;
  o.hidden = std::move(hidden);
  if (c.type != "siren") o.hidden_omega = 2.0;
  o.encoding = encoding_of(c.encoding, {.frequencies = 3,
                                         .features = 8,
                                         .scale = 1.0,
                                         .seed = seed + 17,
                                         .axis = input_dim - 1,
                                         .at = {-0.3, 0.45},
                                         .levels = 3,
                                         .features_per_level = 2,
                                         .log2_table_size = 10,
                                         .base_resolution = 2,
                                         .finest_resolution = 6,
                                         .interpolation = c.variant.empty() ? "smoothstep" : c.variant,
                                         // features of order 1, as after training
                                         .init_scale = 0.5});
  // One bound per coordinate: an encoding that reads variances has input_dim / 2 of them.
  const int coordinates = fields::encoding_type(c.encoding).reads_variances() ? input_dim / 2 : input_dim;
  o.encoding.lower.assign(coordinates, -1.0);
  o.encoding.upper.assign(coordinates, 1.0);
  o.seed = seed;
  if (c.latent) o.latent_size = 3;
  if (c.type == "bacon") {
    // Two scales on the box [−1, 1]^d (D = 2): 2 and 5 lattice steps, |ω| ≤ 5π per axis.
    fields::BaconOptions b;
    b.max_frequency = {1.0, 2.5};
    b.output_scale = c.variant == "coarse" ? 0 : -1;
    o.extension = b;
  }
  if (c.type == "acorn") {
    o.extension = small_acorn_options();
    fields::acorn_tree(o)->set_blocks(split_corner(input_dim));  // two levels of blocks
  }
  return o;
}

// Whether the network has kinks (ReLU, cusp features, hash-grid cell faces) that finite
// differences must not straddle.
inline bool has_kinks(const fields::FieldOptions& o) {
  return (io::to_lower(o.type) != "siren" && io::to_lower(o.activation) == "relu") ||
         io::to_lower(o.encoding.type) == "cusp" || io::to_lower(o.type) == "acorn" ||
         io::to_lower(o.encoding.type) == "hash_grid";
}

// Signs of ReferenceField::preactivations at every point.
inline std::vector<bool> kink_pattern(const ReferenceField& ref, const Eigen::MatrixXd& x) {
  std::vector<bool> pattern;
  for (Eigen::Index p = 0; p < x.rows(); ++p) {
    std::vector<double> xp(x.cols());
    for (Eigen::Index i = 0; i < x.cols(); ++i) xp[i] = x(p, i);
    for (double z : ref.preactivations(xp)) pattern.push_back(z > 0);
  }
  return pattern;
}

// Variances drawn for inputs that are variances (ReferenceField::variance_begin): with the
// harness's frequencies up to 4π, e^{−ω²σ²/2} then lies in [e^{−4}, 1] for the top octave.
inline constexpr double kLowestVariance = 0.0, kHighestVariance = 0.05;

// n points uniform in [−1, 1]^d (variances uniform in [kLowestVariance, kHighestVariance]);
// for networks with kinks, only points whose pre-activations all stay at least `margin` away
// from 0.
inline Eigen::MatrixXd sample_points(const ReferenceField& ref, bool kinks, Eigen::Index n,
                                     std::mt19937_64& rng, double margin = 0.05) {
  const int d = ref.input_dim();
  Eigen::MatrixXd x(n, d);
  for (Eigen::Index p = 0; p < n; ++p) {
    for (int tries = 0;; ++tries) {
      std::vector<double> xp(d);
      for (int i = 0; i < d; ++i)
        xp[i] = i < ref.variance_begin() ? uniform(rng) : uniform(rng, kLowestVariance, kHighestVariance);
      bool ok = true;
      if (kinks)
        for (double z : ref.preactivations(xp)) ok = ok && std::abs(z) >= margin;
      if (ok || tries > 100000) {
        for (int i = 0; i < d; ++i) x(p, i) = xp[i];
        break;
      }
    }
  }
  return x;
}

// ---------------------------------------------------------------------------------------
// Stream specs covering every rule and every forward order.

struct NamedSpec {
  std::string name;
  StreamSpec spec;
};

inline Eigen::MatrixXd wave_operator(int d, double c) {
  Eigen::MatrixXd a = Eigen::MatrixXd::Identity(d, d) * (-c * c);
  a(d - 1, d - 1) = 1;
  return a;
}

// Tangents along the axes with the Laplacian, the wave operator, a single ∂xx and a general
// symmetric C (off-diagonal terms); Taylor order 4 along two arbitrary directions.
inline StreamSpec axes_spec(int d, std::mt19937_64& rng, int taylor_order = 4) {
  StreamSpec s = StreamSpec::gradient(d);
  s.add_operator(Eigen::MatrixXd::Identity(d, d));
  s.add_operator(wave_operator(d, 1.3));
  Eigen::MatrixXd xx = Eigen::MatrixXd::Zero(d, d);
  xx(0, 0) = 1;
  s.add_operator(xx);
  s.add_operator(random_symmetric(d, rng));
  if (taylor_order > 0) s.set_taylor(random_matrix(d, 2, rng), taylor_order);
  return s;
}

// Tangents along d + 1 arbitrary directions, a general C and the identity over them;
// Taylor order 1 along three directions.
inline StreamSpec directions_spec(int d, std::mt19937_64& rng) {
  StreamSpec s = StreamSpec::values(d);
  s.tangents = random_matrix(d, d + 1, rng);
  s.add_operator(random_symmetric(d + 1, rng));
  s.add_operator(Eigen::MatrixXd::Identity(d + 1, d + 1));
  s.set_taylor(random_matrix(d, 3, rng), 1);
  return s;
}

// The richest spec a case's field gives: axes_spec with Taylor order 4, or the gradient
// for a field without operator and Taylor streams.
inline StreamSpec richest_spec(const NetworkCase& c, int d, std::mt19937_64& rng) {
  if (!unsupported_streams(c).empty()) return StreamSpec::gradient(d);
  return axes_spec(d, rng, 4);
}

inline std::vector<NamedSpec> all_specs(int d, std::mt19937_64& rng) {
  std::vector<NamedSpec> specs;
  specs.push_back({"values", StreamSpec::values(d)});
  specs.push_back({"gradient", StreamSpec::gradient(d)});
  StreamSpec lap = StreamSpec::laplacian(d);
  lap.add_operator(Eigen::MatrixXd::Zero(d, d));  // an operator with no quadratic terms
  specs.push_back({"laplacian", lap});
  specs.push_back({"axes operators + taylor 4", axes_spec(d, rng, 4)});
  specs.push_back({"axes operators + taylor 3", axes_spec(d, rng, 3)});
  specs.push_back({"directions + taylor 1", directions_spec(d, rng)});
  for (int k = 1; k <= 4; ++k) {
    StreamSpec t = StreamSpec::values(d);
    t.set_taylor(random_matrix(d, 2, rng), k);
    specs.push_back({"taylor " + std::to_string(k) + " only", t});
  }
  StreamSpec tk = StreamSpec::gradient(d);
  tk.set_taylor(random_matrix(d, 1, rng), 2);
  specs.push_back({"gradient + taylor 2", tk});
  return specs;
}

// Streams of `field` at x as one matrix.
inline Eigen::MatrixXd field_streams(const fields::Field<double>& field, const StreamLayout& layout,
                                     const Eigen::MatrixXd& x) {
  Streams<double> out;
  field.evaluate(layout, x, out);
  return out.data;
}

}  // namespace nfield::testutil
