// SPDX-License-Identifier: MIT
#include "solvers/output/grid_output.h"
#include "solvers/core/problem_capabilities.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <cstdio>

#include "io/grid.h"
#include "io/png_image.h"
#include "io/pvd.h"
#include "io/vtk_image.h"
#include "solvers/output/domain_output.h"

namespace nfield::solvers {
namespace {

// Pads vectors of 2 components to 3 so ParaView's glyphs and stream tracers take them.
Eigen::MatrixXd as_vtk_vector(const Eigen::MatrixXd& v) {
  if (v.cols() != 2) return v;
  Eigen::MatrixXd out = Eigen::MatrixXd::Zero(v.rows(), 3);
  out.leftCols(2) = v;
  return out;
}

// The evaluation points of frame k: the space grid, at the frame's time when there is one,
// at the given parameter values (a parametric field).
Eigen::MatrixXd frame_points(const Domain& domain, const Eigen::MatrixXd& space, int k, int frames,
                             double* t, const Eigen::VectorXd& parameters) {
  Eigen::MatrixXd x(space.rows(), domain.input_dim());
  x.leftCols(domain.space_dim()) = space;
  for (int p = 0; p < domain.parameter_count(); ++p) x.col(domain.parameter_column(p)).setConstant(parameters(p));
  *t = 0;
  if (domain.has_time()) {
    const auto [t0, t1] = domain.time();
    *t = frames > 1 ? t0 + (t1 - t0) * k / (frames - 1) : t0;
    x.col(domain.time_column()).setConstant(*t);
  }
  return x;
}

// The larger of two errors, NaN when either is: a field that went non-finite somewhere must
// not report the largest of its finite errors (std::max drops a NaN second argument).
double max_or_nan(double a, double b) { return std::isnan(a) || std::isnan(b) ? std::numeric_limits<double>::quiet_NaN() : std::max(a, b); }

// u at a frame's points from a pass of values alone. The error after each stage (grid_error)
// and the final outputs read u from this one computation, so that the last stage's error is
// the run's final error to the bit: a pass that carries tangents too stacks them with the
// values into taller products, whose rounding may differ (it did under the sanitizer build).
Eigen::MatrixXd values_at(const StreamEvaluator& evaluate, const Domain& domain, const Eigen::MatrixXd& x) {
  return evaluate(autodiff::StreamLayout(autodiff::StreamSpec::values(domain.input_dim())), x).values();
}

// Sums of |u − u*|² and |u*|² over the points the problem's error mask keeps.
// Per output channel too (the _c vectors).
struct ErrorSums {
  double error_sq = 0, exact_sq = 0, max_abs = 0;
  Eigen::ArrayXd error_sq_c, exact_sq_c, max_abs_c;
  void add(const Eigen::MatrixXd& error, const Eigen::MatrixXd& exact,
           const Eigen::Array<bool, Eigen::Dynamic, 1>& mask) {
    resize(error.cols());
    for (Eigen::Index i = 0; i < error.rows(); ++i)
      if (mask(i)) {
        error_sq += error.row(i).squaredNorm();
        exact_sq += exact.row(i).squaredNorm();
        max_abs = max_or_nan(max_abs, error.row(i).cwiseAbs().maxCoeff<Eigen::PropagateNaN>());
        for (Eigen::Index c = 0; c < error.cols(); ++c) {
          error_sq_c(c) += error(i, c) * error(i, c);
          exact_sq_c(c) += exact(i, c) * exact(i, c);
          max_abs_c(c) = max_or_nan(max_abs_c(c), std::abs(error(i, c)));
        }
      }
  }
  void merge(const ErrorSums& other) {
    error_sq += other.error_sq;
    exact_sq += other.exact_sq;
    max_abs = max_or_nan(max_abs, other.max_abs);
    resize(other.error_sq_c.size());
    error_sq_c += other.error_sq_c;
    exact_sq_c += other.exact_sq_c;
    for (Eigen::Index c = 0; c < max_abs_c.size(); ++c) max_abs_c(c) = max_or_nan(max_abs_c(c), other.max_abs_c(c));
  }
  void resize(Eigen::Index channels) {
    if (error_sq_c.size() == channels) return;
    error_sq_c.setZero(channels);
    exact_sq_c.setZero(channels);
    max_abs_c.setZero(channels);
  }
  static double relative(double error_sq, double exact_sq) {
    return exact_sq > 0 ? std::sqrt(error_sq / exact_sq) : std::sqrt(error_sq);
  }
  double rel_l2() const { return relative(error_sq, exact_sq); }
  void report(GridMetrics& metrics) const {
    metrics.rel_l2 = rel_l2();
    metrics.max_abs_err = max_abs;
    metrics.output_rel_l2.clear();
    for (Eigen::Index c = 0; c < error_sq_c.size(); ++c)
      metrics.output_rel_l2.push_back(relative(error_sq_c(c), exact_sq_c(c)));
    metrics.output_max_abs_err.assign(max_abs_c.data(), max_abs_c.data() + max_abs_c.size());
  }
};

GridMetrics grid_error_at(const Problem& problem, const StreamEvaluator& evaluate, const OutputOptions& output,
                          const Eigen::VectorXd& parameters) {
  GridMetrics metrics;
  if (!problem.has_exact()) return metrics;
  const Domain& domain = problem.domain();
  const io::Grid grid = io::make_grid(domain.lower(), domain.upper(), output.grid);
  const Eigen::MatrixXd space = grid.points(domain.space_dim());
  const int frames = domain.has_time() ? output.frames : 1;
  ErrorSums sums;
  for (int k = 0; k < frames; ++k) {
    double t;
    const Eigen::MatrixXd x = frame_points(domain, space, k, frames, &t, parameters);
    const Eigen::MatrixXd exact = problem.exact(x);
    ErrorSums frame;
    frame.add(values_at(evaluate, domain, x) - exact, exact, error_mask(problem, x) && domain.contains_rows(x));
    sums.merge(frame);
    if (domain.has_time()) {
      metrics.frame_rel_l2.push_back(frame.rel_l2());
      metrics.frame_times.push_back(t);
    }
  }
  metrics.has_error = true;
  sums.report(metrics);
  return metrics;
}

// m with its rows outside a shaped domain set to NaN, which ParaView leaves blank.
Eigen::MatrixXd blank_outside(Eigen::MatrixXd m, const Eigen::Array<bool, Eigen::Dynamic, 1>& inside, bool shaped) {
  if (shaped)
    for (Eigen::Index i = 0; i < m.rows(); ++i)
      if (!inside(i)) m.row(i).setConstant(std::numeric_limits<double>::quiet_NaN());
  return m;
}

// Each output u, its gradient (grad_u, from the layout's d tangent streams), |u| of a complex
// pair and each scale's u of a multiscale field.
void add_solution_arrays(io::PointArrays& arrays, const Eigen::MatrixXd& u, const autodiff::StreamLayout& layout,
                         const autodiff::Streams<double>& streams,
                         const std::vector<std::string>& names, const Eigen::Array<bool, Eigen::Dynamic, 1>& inside,
                         bool shaped, const OutputContext* scales, const Eigen::MatrixXd& x) {
  const int channels = static_cast<int>(u.cols()), d = layout.tangents();
  for (int c = 0; c < channels; ++c) {
    arrays[names[c]] = u.col(c);
    Eigen::MatrixXd g(u.rows(), d);
    for (int a = 0; a < d; ++a) g.col(a) = streams.stream(layout.tangent(a)).col(c);
    arrays["grad_" + names[c]] = blank_outside(as_vtk_vector(g), inside, shaped);
  }
  if (channels == 2) arrays["abs_u"] = u.rowwise().norm();
  if (scales && scales->scales > 1 && scales->scale_values)
    for (int s = 0; s < scales->scales; ++s) {
      const Eigen::MatrixXd us = scales->scale_values(x, s);
      for (int c = 0; c < channels; ++c) arrays[names[c] + "_scale" + std::to_string(s)] = us.col(c);
    }
}

// The first output on the grid as a picture: row 0 is the top (largest y); in 3-D the middle
// z slice; outside a shaped domain (NaN) white, not the colormap's low end.
void write_solution_png(const std::filesystem::path& path, const io::Grid& grid, const Eigen::MatrixXd& u, int d) {
  const int nx = grid.dims[0], ny = grid.dims[1];
  const Eigen::Index slice = d == 3 ? static_cast<Eigen::Index>(grid.dims[2] / 2) * nx * ny : 0;
  Eigen::MatrixXd image(ny, nx);
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) image(ny - 1 - j, i) = u(slice + i + nx * j, 0);
  io::Image picture = io::colorize(image, {std::nullopt, io::Colormap::kViridis});
  for (int r = 0; r < ny; ++r)
    for (int c = 0; c < nx; ++c)
      if (!std::isfinite(image(r, c))) picture.pixels.row(r * nx + c).setOnes();
  io::write_png(path, picture);
}

// Everything written at a frame's points x (input rows), the grid's and domain.vtu's
// crossings alike: each output u, grad_u, |u| of a pair and each scale's u; the residual;
// exact_u and error_u; `inside` on a shaped domain; every array NaN outside.
class FrameArrays {
 public:
  FrameArrays(const Problem& problem, const StreamEvaluator& evaluate, const OutputContext* scales)
      : problem_(problem), evaluate_(evaluate), scales_(scales), terms_(problem.loss_terms()),
        residual_index_(problem.residual_term()), gradient_(space_gradient(problem.domain())) {}

  struct At {
    io::PointArrays arrays;
    Eigen::MatrixXd u, exact, residual;  // exact, residual: empty when there are none
  };
  At at(const Eigen::MatrixXd& x, const Eigen::Array<bool, Eigen::Dynamic, 1>& inside) const {
    const Domain& domain = problem_.domain();
    const bool shaped = domain.geometry() != nullptr;
    const auto blank = [&](Eigen::MatrixXd m) { return blank_outside(std::move(m), inside, shaped); };
    const std::vector<std::string> names = problem_.output_names();
    At out;
    if (shaped) out.arrays["inside"] = inside.cast<double>().matrix();
    out.u = blank(values_at(evaluate_, domain, x));
    add_solution_arrays(out.arrays, out.u, gradient_, evaluate_(gradient_, x), names, inside, shaped, scales_, x);
    if (residual_index_ >= 0) {
      const LossTerm& term = terms_[static_cast<size_t>(residual_index_)];
      const autodiff::StreamLayout layout(term.spec);
      term.residual(x)->evaluate(0, layout, evaluate_(layout, x), out.residual);
      out.arrays["residual"] = blank(out.residual);
    }
    if (problem_.has_exact()) {
      out.exact = problem_.exact(x);
      const Eigen::MatrixXd error = out.u - out.exact;  // NaN outside a shaped domain
      for (size_t c = 0; c < names.size(); ++c) {
        out.arrays["exact_" + names[c]] = blank(out.exact.col(static_cast<Eigen::Index>(c)));
        out.arrays["error_" + names[c]] = error.col(static_cast<Eigen::Index>(c));
      }
    }
    return out;
  }

 private:
  const Problem& problem_;
  const StreamEvaluator& evaluate_;
  const OutputContext* scales_;
  std::vector<LossTerm> terms_;
  int residual_index_;
  autodiff::StreamLayout gradient_;  // values and the d spatial tangents

  static autodiff::StreamLayout space_gradient(const Domain& domain) {
    autodiff::StreamSpec spec = autodiff::StreamSpec::values(domain.input_dim());
    spec.tangents = Eigen::MatrixXd::Identity(domain.input_dim(), domain.space_dim());
    return autodiff::StreamLayout(spec);
  }
};

GridMetrics write_grid_at(const Problem& problem, const StreamEvaluator& evaluate, const OutputOptions& output,
                          const OutputContext* scales, const Eigen::VectorXd& parameters) {
  const Domain& domain = problem.domain();
  const int d = domain.space_dim();
  const io::Grid grid = io::make_grid(domain.lower(), domain.upper(), output.grid);
  const Eigen::MatrixXd space = grid.points(d);
  const int frames = domain.has_time() ? output.frames : 1;
  const FrameArrays arrays_at(problem, evaluate, scales);

  GridMetrics metrics;
  ErrorSums sums;
  double residual_sq = 0;
  Eigen::Index residual_count = 0;
  io::PvdCollection pvd(output.dir / "solution.pvd");
  DomainOutput on_domain(domain, grid, output.dir, domain.has_time());
  Eigen::MatrixXd xt_image(frames, grid.dims[0]);  // 1D + time preview
  for (int k = 0; k < frames; ++k) {
    double t;
    const Eigen::MatrixXd x = frame_points(domain, space, k, frames, &t, parameters);
    // A shaped domain: the grid covers its bounding box; points outside are masked (`inside`
    // = 0) and every array there is NaN, which ParaView leaves blank (threshold on `inside`).
    const Eigen::Array<bool, Eigen::Dynamic, 1> inside = domain.contains_rows(x);
    const FrameArrays::At frame_at = arrays_at.at(x, inside);
    const io::PointArrays& arrays = frame_at.arrays;
    const Eigen::MatrixXd& u = frame_at.u;
    for (Eigen::Index i = 0; i < frame_at.residual.rows(); ++i)
      if (inside(i)) {
        residual_sq += frame_at.residual.row(i).squaredNorm();
        ++residual_count;
      }
    std::map<std::string, double, std::less<>> field_data;
    if (problem.has_exact()) {
      ErrorSums frame;
      frame.add(u - frame_at.exact, frame_at.exact, error_mask(problem, x) && inside);
      sums.merge(frame);
      if (domain.has_time()) {
        metrics.frame_rel_l2.push_back(frame.rel_l2());
        metrics.frame_times.push_back(t);
        field_data["rel_l2"] = frame.rel_l2();
      }
      metrics.has_error = true;
    }
    if (domain.has_time()) {
      char file[64];
      std::snprintf(file, sizeof file, "frame_%04d.vti", k);
      io::write_vti(output.dir / file, grid, arrays, io::Precision::kFloat64, field_data);
      pvd.add(t, file);
      if (d == 1) xt_image.row(frames - 1 - k) = u.col(0).transpose();
    } else {
      io::write_vti(output.dir / "solution.vti", grid, arrays);
    }
    on_domain.write(k, t, arrays, inside, [&](const Eigen::MatrixXd& s) {
      double frame_t;
      const Eigen::MatrixXd xs = frame_points(domain, s, k, frames, &frame_t, parameters);
      return arrays_at.at(xs, Eigen::Array<bool, Eigen::Dynamic, 1>::Ones(xs.rows())).arrays;
    });
    if (output.png && k == 0 && d >= 2) write_solution_png(output.dir / "solution.png", grid, u, d);
  }
  if (domain.has_time()) pvd.write();
  on_domain.finish();
  if (output.png && domain.has_time() && d == 1)
    io::write_scalar_png(output.dir / "solution.png", xt_image, {std::nullopt, io::Colormap::kViridis});
  if (metrics.has_error) sums.report(metrics);
  if (residual_count > 0) metrics.residual_rms = std::sqrt(residual_sq / residual_count);
  return metrics;
}

// The folder of a held-out value: held_out_nu_0.01 (names and values, %g).
std::string held_out_folder(const Domain& domain, const Eigen::VectorXd& parameters) {
  std::string name = "held_out";
  for (int p = 0; p < domain.parameter_count(); ++p) {
    char value[40];
    std::snprintf(value, sizeof value, "_%s_%g", domain.parameters()[static_cast<std::size_t>(p)].name.c_str(),
                  parameters(p));
    name += value;
  }
  return name;
}

// The held-out values' figures gathered: the worst of each, residual_rms over all.
GridMetrics gather_held_out(const Domain& domain, const std::vector<Eigen::VectorXd>& values,
                            const std::vector<GridMetrics>& each) {
  GridMetrics all;
  double residual_sq = 0;
  for (std::size_t i = 0; i < each.size(); ++i) {
    const GridMetrics& m = each[i];
    HeldOutMetrics h;
    for (int p = 0; p < domain.parameter_count(); ++p)
      h.parameters.emplace_back(domain.parameters()[static_cast<std::size_t>(p)].name, values[i](p));
    h.dir = held_out_folder(domain, values[i]);
    h.rel_l2 = m.rel_l2;
    h.max_abs_err = m.max_abs_err;
    for (const double f : m.frame_rel_l2) h.max_frame_rel_l2 = max_or_nan(h.max_frame_rel_l2, f);
    all.held_out.push_back(h);
    all.has_error = m.has_error;
    all.rel_l2 = i == 0 ? m.rel_l2 : max_or_nan(all.rel_l2, m.rel_l2);
    all.max_abs_err = i == 0 ? m.max_abs_err : max_or_nan(all.max_abs_err, m.max_abs_err);
    all.output_rel_l2.resize(m.output_rel_l2.size());
    all.output_max_abs_err.resize(m.output_max_abs_err.size());
    for (std::size_t c = 0; c < m.output_rel_l2.size(); ++c) {
      all.output_rel_l2[c] = i == 0 ? m.output_rel_l2[c] : max_or_nan(all.output_rel_l2[c], m.output_rel_l2[c]);
      all.output_max_abs_err[c] =
          i == 0 ? m.output_max_abs_err[c] : max_or_nan(all.output_max_abs_err[c], m.output_max_abs_err[c]);
    }
    residual_sq += m.residual_rms * m.residual_rms;
  }
  if (!each.empty()) all.residual_rms = std::sqrt(residual_sq / static_cast<double>(each.size()));
  return all;
}

}  // namespace

GridMetrics grid_error(const Problem& problem, const StreamEvaluator& evaluate, const OutputOptions& output) {
  const std::vector<Eigen::VectorXd> values = problem.held_out_parameters();
  if (problem.domain().parameter_count() == 0) return grid_error_at(problem, evaluate, output, {});
  std::vector<GridMetrics> each;
  for (const Eigen::VectorXd& v : values) each.push_back(grid_error_at(problem, evaluate, output, v));
  return gather_held_out(problem.domain(), values, each);
}

GridMetrics write_grid_outputs(const Problem& problem, const StreamEvaluator& evaluate,
                               const OutputOptions& output, const OutputContext* scales) {
  const Domain& domain = problem.domain();
  if (domain.parameter_count() == 0) return write_grid_at(problem, evaluate, output, scales, {});
  const std::vector<Eigen::VectorXd> values = problem.held_out_parameters();
  std::vector<GridMetrics> each;
  for (const Eigen::VectorXd& v : values) {
    OutputOptions own = output;
    own.dir = output.dir / held_out_folder(domain, v);
    std::filesystem::create_directories(own.dir);
    each.push_back(write_grid_at(problem, evaluate, own, scales, v));
  }
  return gather_held_out(domain, values, each);
}

}  // namespace nfield::solvers
