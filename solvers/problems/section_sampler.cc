// SPDX-License-Identifier: MIT
#include "solvers/problems/section_sampler.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "autodiff/stream_loss.h"
#include "fields/field_io.h"
#include "fields/positional_encoding.h"
#include "integrators/volume_rendering.h"
#include "io/hdf5_file.h"

namespace nfield::solvers {
namespace {

fields::FieldOptions network_options(int sections, const SectionSamplerOptions& options) {
  fields::FieldOptions f;
  f.type = "mlp";
  f.activation = "relu";
  f.input_dim = 6;
  f.output_dim = sections;
  f.hidden = options.hidden;
  if (options.frequencies > 0)
    f.encoding = fields::encoding_options(fields::PositionalOptions{.frequencies = options.frequencies});
  f.seed = options.seed;
  return f;
}

std::string rule(const std::string& field, const std::string& value, const std::string& what) {
  return "SectionSamplerOptions." + field + " = " + value + ": " + what;
}

}  // namespace

void SectionSamplerOptions::validate() const {
  if (hidden.empty()) throw std::invalid_argument(rule("hidden", "[]", "needs at least one layer"));
  for (int width : hidden)
    if (width < 1) throw std::invalid_argument(rule("hidden", std::to_string(width), "widths must be >= 1"));
  if (frequencies < 0 || frequencies > 16)
    throw std::invalid_argument(rule("frequencies", std::to_string(frequencies), "must be in [0, 16]"));
  if (!(learning_rate > 0) || !std::isfinite(learning_rate))
    throw std::invalid_argument(rule("learning_rate", std::to_string(learning_rate), "must be > 0"));
  if (!(min_share >= 0 && min_share < 1))
    throw std::invalid_argument(rule("min_share", std::to_string(min_share), "must be in [0, 1)"));
  if (every < 1) throw std::invalid_argument(rule("every", std::to_string(every), "must be >= 1"));
  if (rays < 1) throw std::invalid_argument(rule("rays", std::to_string(rays), "must be >= 1"));
}

SectionSamplerOptions SectionSamplerOptions::from_config(const io::ConfigNode& node) {
  SectionSamplerOptions o;
  if (node.has("hidden")) {
    o.hidden = node.get<std::vector<int>>("hidden");
    node.require("hidden", !o.hidden.empty(), "expected a list of at least one layer width");
    for (int width : o.hidden) node.require("hidden", width >= 1, "expected layer widths >= 1");
  }
  if (node.has("frequencies")) o.frequencies = node.get_in_range("frequencies", 0, 16);
  o.learning_rate = node.get_or("lr", o.learning_rate);
  node.require("lr", o.learning_rate > 0 && std::isfinite(o.learning_rate), "expected a number > 0");
  o.min_share = node.get_or("min_share", o.min_share);
  node.require("min_share", o.min_share >= 0 && o.min_share < 1, "expected a number in [0, 1)");
  if (node.has("every")) o.every = node.get_in_range("every", 1, 1000000);
  if (node.has("rays")) o.rays = node.get_in_range("rays", 1, 1 << 24);
  if (node.has("seed")) o.seed = static_cast<std::uint64_t>(node.get_in_range("seed", 0, 1 << 30));
  node.reject_unknown_keys();
  return o;
}

SectionSampler::SectionSampler(int sections, SectionSamplerOptions options)
    : sections_(sections),
      options_((options.validate(), std::move(options))),
      network_(network_options(sections, options_)),
      adam_(network_.parameter_count(), AdamOptions{options_.learning_rate}) {
  if (sections < 1) throw std::invalid_argument("SectionSampler: sections = " + std::to_string(sections) + ": must be >= 1");
  // The output layer starts at zero: equal sections, the baseline S has to improve on, and
  // a gradient that reaches that layer's weights from the first step.
  const auto& modules = network_.network().modules();
  const Eigen::Index last = network_.network().parameter_offset(modules.size() - 1);
  network_.parameters().tail(network_.parameter_count() - last).setZero();
}

Eigen::MatrixXd SectionSampler::features(const integrators::Rays<double>& rays) const {
  Eigen::MatrixXd x(rays.size(), 6);
  Eigen::Index k = 0;
  for (Eigen::Index r = 0; r < rays.size(); ++r) {
    if (!(rays.far(r) > rays.near(r))) continue;
    x.row(k).head(3) = rays.origins.row(r) + rays.near(r) * rays.directions.row(r);
    x.row(k).tail(3) = rays.directions.row(r);
    ++k;
  }
  return x.topRows(k);
}

namespace {

// Row-wise softmax of logits, stabilised by the row maximum.
Eigen::MatrixXd softmax(const Eigen::MatrixXd& z) {
  Eigen::MatrixXd w = (z.colwise() - z.rowwise().maxCoeff()).array().exp().matrix();
  return w.array().colwise() / w.rowwise().sum().array();
}

// Lengths Δ (rows: rays with sections) from the softmax weights w and the rays' lengths.
Eigen::MatrixXd boundaries_from(const integrators::Rays<double>& rays, const Eigen::MatrixXd& w,
                                double min_share) {
  const Eigen::Index sections = w.cols();
  Eigen::MatrixXd t(w.rows(), sections + 1);
  Eigen::Index k = 0;
  for (Eigen::Index r = 0; r < rays.size(); ++r) {
    const double near = rays.near(r), far = rays.far(r);
    if (!(far > near)) continue;
    const double length = far - near;
    t(k, 0) = near;
    for (Eigen::Index i = 0; i < sections; ++i)
      t(k, i + 1) = t(k, i) + length * (min_share / sections + (1 - min_share) * w(k, i));
    t(k, sections) = far;  // the sum of the shares is 1 up to rounding: end exactly at far
    ++k;
  }
  return t;
}

}  // namespace

Eigen::MatrixXd SectionSampler::boundaries(const integrators::Rays<double>& rays) const {
  const Eigen::MatrixXd x = features(rays);
  if (x.rows() == 0) return Eigen::MatrixXd(0, sections_ + 1);
  return boundaries_from(rays, softmax(network_.values(x)), options_.min_share);
}

integrators::RaySamples<double> SectionSampler::sections(const integrators::Rays<double>& rays) const {
  const Eigen::MatrixXd t = boundaries(rays);
  integrators::RaySamples<double> out;
  out.offsets.assign(rays.size() + 1, 0);
  for (Eigen::Index r = 0; r < rays.size(); ++r)
    out.offsets[r + 1] = out.offsets[r] + (rays.far(r) > rays.near(r) ? sections_ : 0);
  out.t.resize(out.offsets.back());
  out.delta.resize(out.offsets.back());
  for (Eigen::Index k = 0; k < t.rows(); ++k)
    for (int i = 0; i < sections_; ++i) {
      out.t(k * sections_ + i) = 0.5 * (t(k, i) + t(k, i + 1));
      out.delta(k * sections_ + i) = t(k, i + 1) - t(k, i);
    }
  return out;
}

Eigen::MatrixXd SectionSampler::end_points(const integrators::Rays<double>& rays,
                                           const Eigen::MatrixXd& boundaries) {
  const Eigen::Index ends = boundaries.cols();
  Eigen::MatrixXd x(boundaries.rows() * ends, 6);
  Eigen::Index k = 0;
  for (Eigen::Index r = 0; r < rays.size(); ++r) {
    if (!(rays.far(r) > rays.near(r))) continue;
    for (Eigen::Index e = 0; e < ends; ++e) {
      x.row(k * ends + e).head(3) = rays.origins.row(r) + boundaries(k, e) * rays.directions.row(r);
      x.row(k * ends + e).tail(3) = rays.directions.row(r);
    }
    ++k;
  }
  return x;
}

SamplerUpdate SectionSampler::update(const integrators::Rays<double>& rays, const Eigen::MatrixXd& target,
                                     const Eigen::MatrixXd& background, const FieldStreams& field,
                                     const DensityActivation& density, double density_scale) {
  const Eigen::Index n = std::min<Eigen::Index>(rays.size(), options_.rays);
  const integrators::Rays<double> read = rays.subset(Eigen::seqN(0, n));
  const Eigen::MatrixXd read_background = background.rows() == 1 ? background : background.topRows(n);
  Eigen::VectorXd gradient;
  const SamplerUpdate result =
      loss_and_gradient(read, target.topRows(n), read_background, field, density, density_scale, gradient);
  adam_.step(network_.parameters().data(), gradient.data());
  return result;
}

namespace {

// φ = ∇ₓΦ · d at each section end (row k(K + 1) + e for end e of the k-th ray with sections),
// from the tangent streams of Φ along the three axes.
Eigen::MatrixXd end_rates(const integrators::Rays<double>& rays, const autodiff::StreamLayout& layout,
                          const autodiff::Streams<double>& phi_streams, Eigen::Index hit, Eigen::Index ends) {
  Eigen::MatrixXd rate(hit * ends, 4);
  Eigen::Index k = 0;
  for (Eigen::Index r = 0; r < rays.size(); ++r) {
    if (!(rays.far(r) > rays.near(r))) continue;
    for (Eigen::Index e = 0; e < ends; ++e) {
      const Eigen::Index row = k * ends + e;
      rate.row(row).setZero();
      for (int a = 0; a < 3; ++a)
        rate.row(row) += rays.directions(r, a) * phi_streams.stream(layout.tangent(a)).row(row);
    }
    ++k;
  }
  return rate;
}

// The hit rays' rendering as at render time: the sections as samples, the section means
// s̄ᵢ = (Φ(tᵢ₊₁) − Φ(tᵢ))/Δᵢ (row k·K + i), each hit ray's pixel and background; then the
// means shaded (density column scaled) and the rendering's adjoints σ̄ and rgb̄ at them.
struct SectionRendering {
  integrators::RaySamples<double> samples;
  Eigen::MatrixXd means, pixels, backgrounds;
  Eigen::MatrixXd scaled;
  Shading shading;
  Eigen::VectorXd sigma_bar;
  Eigen::MatrixXd rgb_bar;
};

template <typename Phi>
SectionRendering section_rendering(const integrators::Rays<double>& rays, const Eigen::MatrixXd& t, const Phi& phi,
                                   const Eigen::MatrixXd& target, const Eigen::MatrixXd& background) {
  const Eigen::Index hit = t.rows(), K = t.cols() - 1, ends = K + 1;
  SectionRendering out;
  integrators::RaySamples<double>& samples = out.samples;
  samples.offsets.resize(hit + 1);
  for (Eigen::Index k = 0; k <= hit; ++k) samples.offsets[k] = k * K;
  samples.t.resize(hit * K);
  samples.delta.resize(hit * K);
  out.means.resize(hit * K, 4);
  out.pixels.resize(hit, 3);
  out.backgrounds.resize(background.rows() == 1 ? 1 : hit, 3);
  if (background.rows() == 1) out.backgrounds = background;
  Eigen::Index k = 0;
  for (Eigen::Index r = 0; r < rays.size(); ++r) {
    if (!(rays.far(r) > rays.near(r))) continue;
    out.pixels.row(k) = target.row(r);
    if (background.rows() != 1) out.backgrounds.row(k) = background.row(r);
    for (int i = 0; i < K; ++i) {
      const double delta = t(k, i + 1) - t(k, i);
      samples.t(k * K + i) = 0.5 * (t(k, i) + t(k, i + 1));
      samples.delta(k * K + i) = delta;
      out.means.row(k * K + i) = (phi.row(k * ends + i + 1) - phi.row(k * ends + i)) / delta;
    }
    ++k;
  }
  return out;
}

// Boundary adjoints t̄, then Δ̄, w̄ and the logits' z̄ (top of section_sampler.h), for the
// boundaries t, the softmax weights w and the rates φ at the ends.
Eigen::MatrixXd logit_adjoints(const Eigen::MatrixXd& t, const Eigen::MatrixXd& w, double min_share,
                               const SectionRendering& sections, const Eigen::MatrixXd& rate,
                               const DensityActivation& density, double density_scale) {
  const Eigen::Index hit = t.rows(), K = t.cols() - 1, ends = K + 1;
  const Shading& shading = sections.shading;
  Eigen::MatrixXd z_bar(hit, K);
  for (Eigen::Index k = 0; k < hit; ++k) {
    Eigen::VectorXd t_bar = Eigen::VectorXd::Zero(ends);
    for (int i = 0; i < K; ++i) {
      const Eigen::Index s = k * K + i;
      const double delta = sections.samples.delta(s);
      Eigen::Vector4d mean_bar;
      mean_bar(0) = sections.sigma_bar(s) * density.derivative(sections.scaled(s, 0)) * density_scale;
      for (int c = 0; c < 3; ++c)
        mean_bar(1 + c) = sections.rgb_bar(s, c) * shading.rgb(s, c) * (1 - shading.rgb(s, c));
      const Eigen::RowVector4d m = sections.means.row(s);
      t_bar(i + 1) += mean_bar.dot((rate.row(k * ends + i + 1) - m).transpose()) / delta;
      t_bar(i) += mean_bar.dot((m - rate.row(k * ends + i)).transpose()) / delta;
      const double delta_bar = sections.sigma_bar(s) * shading.sigma(s) / delta;  // through τ = σδ
      t_bar(i + 1) += delta_bar;
      t_bar(i) -= delta_bar;
    }
    const double length = t(k, K) - t(k, 0);
    Eigen::VectorXd w_bar(K);
    double suffix = 0;
    for (Eigen::Index i = K - 1; i >= 0; --i) {
      suffix += t_bar(i + 1);  // Δ̄ᵢ = Σ_{j>i} t̄ⱼ
      w_bar(i) = length * (1 - min_share) * suffix;
    }
    const double dot = w.row(k).dot(w_bar);
    z_bar.row(k) = w.row(k).array() * (w_bar.transpose().array() - dot);
  }
  return z_bar;
}

}  // namespace

SamplerUpdate SectionSampler::loss_and_gradient(const integrators::Rays<double>& rays,
                                                const Eigen::MatrixXd& target,
                                                const Eigen::MatrixXd& background,
                                                const FieldStreams& field,
                                                const DensityActivation& density,
                                                double density_scale,
                                                Eigen::VectorXd& gradient) const {
  gradient.setZero(network_.parameter_count());
  if (target.rows() != rays.size() || target.cols() != 3)
    throw std::invalid_argument("SectionSampler: target is " + std::to_string(target.rows()) + " x " +
                                std::to_string(target.cols()) + ", expected one RGB row per ray (" +
                                std::to_string(rays.size()) + ")");
  const Eigen::MatrixXd x = features(rays);
  const Eigen::Index hit = x.rows();
  const int K = sections_;
  if (hit == 0) return {};
  const Eigen::MatrixXd w = softmax(network_.values(x));
  const Eigen::MatrixXd t = boundaries_from(rays, w, options_.min_share);

  // Φ and ∇ₓΦ at the section ends; φ = ∇ₓΦ · d.
  autodiff::StreamSpec spec = autodiff::StreamSpec::values(6);
  spec.tangents = Eigen::MatrixXd::Zero(6, 3);
  spec.tangents.topRows(3).setIdentity();
  const autodiff::StreamLayout layout(spec);
  const autodiff::Streams<double> phi_streams = field(layout, end_points(rays, t));
  const Eigen::MatrixXd rate = end_rates(rays, layout, phi_streams, hit, K + 1);

  SectionRendering sections =
      section_rendering(rays, t, phi_streams.stream(autodiff::StreamLayout::value()), target, background);
  sections.scaled = sections.means;
  sections.scaled.col(0) *= density_scale;
  sections.shading = shade(sections.scaled, density);
  const Shading& shading = sections.shading;
  const auto rendered =
      integrators::render<double>(sections.samples, shading.sigma, shading.rgb, sections.backgrounds);
  const Eigen::MatrixXd error = rendered.color - sections.pixels;
  SamplerUpdate result;
  result.loss = error.squaredNorm() / static_cast<double>(hit);
  result.max_section_share = (t.rightCols(K) - t.leftCols(K)).rowwise().maxCoeff().cwiseQuotient(
                                 (t.col(K) - t.col(0)) / K).mean();

  integrators::RenderAdjoint<double> bar;
  bar.color = 2 * error / static_cast<double>(hit);
  sections.sigma_bar.resize(hit * K);
  sections.rgb_bar.resize(hit * K, 3);
  integrators::render_backward<double>(sections.samples, shading.sigma, shading.rgb, sections.backgrounds, bar,
                                       sections.sigma_bar, sections.rgb_bar);
  const Eigen::MatrixXd z_bar =
      logit_adjoints(t, w, options_.min_share, sections, rate, density, density_scale);

  // S's reverse pass with z̄ as the adjoint of its outputs.
  const autodiff::StreamLayout values_layout(autodiff::StreamSpec::values(6));
  const autodiff::LambdaLoss<double> loss([&z_bar](Eigen::Index first, const autodiff::StreamLayout& l,
                                                   const autodiff::Streams<double>& out,
                                                   autodiff::Streams<double>& adjoint) {
    adjoint.stream(l.value()) = z_bar.middleRows(first, out.points);
    return 0.0;
  });
  network_.value_and_gradient(network_.parameters().data(), values_layout, autodiff::Batch<double>{x}, loss,
                              gradient.data());
  return result;
}

void SectionSampler::save(io::H5Writer& file, const std::string& group) const {
  fields::save_field(file, network_, group + "/network");
  file.write(group + "/adam_m", adam_.first_moment());
  file.write(group + "/adam_v", adam_.second_moment());
  file.write_attribute(group, "adam_steps", static_cast<std::int64_t>(adam_.steps()));
}

void SectionSampler::load(const io::H5Reader& file, const std::string& group) {
  fields::Field<double> saved = fields::load_field<double>(file, group + "/network");
  if (saved.parameter_count() != network_.parameter_count() || saved.output_dim() != sections_)
    throw std::runtime_error(file.path().string() + ": its sampling network has " +
                             std::to_string(saved.parameter_count()) + " parameters and " +
                             std::to_string(saved.output_dim()) + " sections, the config's " +
                             std::to_string(network_.parameter_count()) + " and " + std::to_string(sections_));
  network_.parameters() = saved.parameters();
  adam_.first_moment() = file.read_vector<double>(group + "/adam_m");
  adam_.second_moment() = file.read_vector<double>(group + "/adam_v");
  adam_.set_steps(file.read_attribute<std::int64_t>(group, "adam_steps"));
}

}  // namespace nfield::solvers
