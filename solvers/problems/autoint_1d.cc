// SPDX-License-Identifier: MIT
//
// AutoInt in one dimension: Φ is trained through its derivative, ∂Φ/∂x ≈ f, and then every
// integral ∫ₐᵇ f dx is read as Φ(b) − Φ(a) (integrators/segment_integrals.h).
//
//   problem: autoint_1d
//   domain: {lower: [-1], upper: [1]}
//   equation:                          # the integrand f, exactly one of:
//     integrand: "cos(10*x)"           #   an expression of x
//     samples: data/points.txt         #   lines "x f(x)", piecewise linear between them
//     audio: data/audio/clip.wav       #   a sound file, its samples spread over the domain
//     audio_seconds: [1.0, 1.5]        #   optional: that part of the clip
//     train_at: samples                # data: at the samples, or uniform over the domain
//     antiderivative: "sin(10*x)/10"   # optional: exact integrals for the metrics
//     intervals: 10000                 # random intervals the metrics integrate over
//
// The one loss term ("integrand") is the tangent stream along x minus f: at random points
// of the domain for an expression; for data at the samples, or (train_at: uniform) at random
// points against the joined samples. A field trained at the samples only is free between
// them: a high-frequency one (audio) then matches every sample and integrates to anything.
//
// Metrics (metrics.json): integral_rel_l2 = ‖Î − I‖ / ‖I‖ over the random intervals, Î from
// Φ's ends and I the reference (the antiderivative if given, else the exact integral of the
// piecewise-linear data, else adaptive Gauss–Kronrod of the expression to 1e-13 per interval); the fitted
// integrand's error on the data or a dense grid; and the cost of one integral from Φ
// beside batched adaptive Gauss–Kronrod of ∂Φ/∂x on the same field, its tolerance a tenth
// of the AutoInt error (so it is no less accurate). integrand.png plots f and ∂Φ/∂x (top:
// f grey, ∂Φ/∂x red) and Φ (bottom, blue); integrand.csv holds the same curves.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <fstream>
#include <numeric>
#include <optional>
#include <random>

#include "integrators/segment_integrals.h"
#include "io/atomic_write.h"
#include "io/audio.h"
#include "io/line_plot.h"
#include "io/text_numbers.h"
#include "solvers/problems/problems.h"

namespace nfield::solvers {
namespace {

// f as samples (x increasing) joined by straight lines.
struct PiecewiseLinear {
  Eigen::VectorXd x, f;
  Eigen::VectorXd cumulative;  // ∫ from x₀ to x_k

  PiecewiseLinear(Eigen::VectorXd xs, Eigen::VectorXd fs) : x(std::move(xs)), f(std::move(fs)) {
    cumulative = Eigen::VectorXd::Zero(x.size());
    for (Eigen::Index k = 1; k < x.size(); ++k)
      cumulative(k) = cumulative(k - 1) + 0.5 * (x(k) - x(k - 1)) * (f(k) + f(k - 1));
  }
  // The segment [x_k, x_{k+1}] holding t (clamped to the ends).
  Eigen::Index segment(double t) const {
    const auto it = std::upper_bound(x.data(), x.data() + x.size(), t);
    return std::clamp<Eigen::Index>(it - x.data() - 1, 0, x.size() - 2);
  }
  double value(double t) const {
    const Eigen::Index k = segment(t);
    const double w = (t - x(k)) / (x(k + 1) - x(k));
    return (1 - w) * f(k) + w * f(k + 1);
  }
  double integral_to(double t) const {
    const Eigen::Index k = segment(t);
    const double h = t - x(k), slope = (f(k + 1) - f(k)) / (x(k + 1) - x(k));
    return cumulative(k) + h * f(k) + 0.5 * slope * h * h;
  }
};

class AutoInt1d final : public Problem {
 public:
  static constexpr Eigen::Index kTimedIntervals = 1000;

  explicit AutoInt1d(const ProblemContext& context)
      : domain_(Domain::from_config(context.root.child("domain"))) {
    const io::ConfigNode domain = context.root.child("domain");
    domain.require(domain_.input_dim() == 1 && !domain_.has_time(), "expected one coordinate (lower: [a], upper: [b])");
    const io::ConfigNode equation = context.root.child("equation");
    const int sources = equation.has("integrand") + equation.has("samples") + equation.has("audio");
    if (sources != 1)
      throw equation.error("expected exactly one of 'integrand', 'samples' and 'audio' (found " +
                           std::to_string(sources) + ")");
    const auto vars = domain_.expression_variables();
    if (equation.has("integrand"))
      integrand_ = std::make_shared<io::Expression>(equation.get_expression("integrand", vars));
    if (equation.has("samples")) read_samples(equation, context.config_dir);
    if (equation.has("audio")) read_audio(equation, context.config_dir);
    equation.require("audio_seconds", !equation.has("audio_seconds") || equation.has("audio"),
                     "only with 'audio'");
    uniform_points_ = equation.get_choice("train_at", {"samples", "uniform"}, "samples") == "uniform";
    equation.require("train_at", !uniform_points_ || samples_, "only with 'samples' or 'audio'");
    if (equation.has("antiderivative")) {
      equation.require("antiderivative", !equation.has("audio"), "not with 'audio' (its reference is the data)");
      antiderivative_ = std::make_shared<io::Expression>(equation.get_expression("antiderivative", vars));
    }
    const int intervals = equation.has("intervals") ? equation.get_in_range("intervals", 1, 10'000'000) : 10000;
    equation.reject_unknown_keys();

    // The metrics' intervals and their reference integrals, fixed for the run.
    std::mt19937_64 engine(20211);
    std::uniform_real_distribution<double> uniform(lower(), upper());
    interval_a_.resize(intervals, 1);
    interval_b_.resize(intervals, 1);
    for (int k = 0; k < intervals; ++k) {
      double a = uniform(engine), b = uniform(engine);
      while (a == b) b = uniform(engine);
      interval_a_(k) = std::min(a, b);
      interval_b_(k) = std::max(a, b);
    }
  }

  const Domain& domain() const override { return domain_; }
  std::vector<std::string> output_names() const override { return {"antiderivative"}; }

  std::vector<LossTerm> loss_terms() const override {
    LossTerm fit;
    fit.name = "integrand";
    fit.batch_key = "interior";
    fit.spec = autodiff::StreamSpec::gradient(1);
    fit.sample = [this](Random& rng, Eigen::Index n) -> TermPoints { return draw(rng, n); };
    fit.residual = [this, dphi_dx = autodiff::StreamLayout(fit.spec).tangent(0)](const TermPoints& points) {
      return std::make_unique<LinearResidual>(
          std::vector<LinearResidual::Term>{{0, dphi_dx, 0, Eigen::VectorXd::Ones(1)}}, integrand(points.x));
    };
    return {fit};
  }

  std::optional<double> reported_error(const OutputContext& context) const override {
    return relative_l2(autoint_integrals(context), reference());
  }

  void write_outputs(const OutputContext& context,
                     std::vector<std::pair<std::string, double>>& metrics) const override {
    const Eigen::VectorXd autoint = autoint_integrals(context);
    const double error = relative_l2(autoint, reference());
    metrics.emplace_back("integral_rel_l2", error);
    metrics.emplace_back("integral_max_abs_err", (autoint - reference()).cwiseAbs().maxCoeff<Eigen::PropagateNaN>());
    metrics.emplace_back("intervals", static_cast<double>(reference().size()));
    Eigen::MatrixXd whole_a(1, 1), whole_b(1, 1);
    whole_a << lower();
    whole_b << upper();
    const double whole = reference_integrals(whole_a, whole_b)(0);
    metrics.emplace_back("domain_integral", whole);
    metrics.emplace_back("domain_integral_abs_err",
                         std::abs(integrators::antiderivative_differences(phi(context), whole_a, whole_b)(0) - whole));

    // The fitted integrand where f is known best: the data, or a dense grid.
    const Eigen::MatrixXd x = samples_ ? Eigen::MatrixXd(samples_->x) : grid(4096);
    const Eigen::VectorXd f = integrand(x), fitted = derivative(context)(x);
    metrics.emplace_back("integrand_rel_l2", relative_l2(fitted, f));

    std::printf("integrals: rel. L2 error %.3e over %ld intervals\n", error,
                static_cast<long>(reference().size()));
    write_timing(context, autoint, metrics);
    write_curves(context);
  }

 private:
  double lower() const { return domain_.lower()[0]; }
  double upper() const { return domain_.upper()[0]; }

  void read_samples(const io::ConfigNode& equation, const std::filesystem::path& dir) {
    const std::filesystem::path path = dir / equation.get<std::string>("samples");
    std::ifstream in(path);
    if (!in) throw equation.error("samples", "cannot open " + path.string());
    std::vector<double> xs, fs, numbers;
    std::string line;
    for (int number = 1; std::getline(in, line); ++number) {
      if (!io::parse_numbers(line, numbers))
        throw equation.error("samples", path.string() + ":" + std::to_string(number) + ": expected numbers");
      if (numbers.empty()) continue;
      if (numbers.size() != 2 || !std::isfinite(numbers[0]) || !std::isfinite(numbers[1]))
        throw equation.error("samples", path.string() + ":" + std::to_string(number) +
                                            ": expected two finite numbers, x and f(x)");
      if (!xs.empty() && numbers[0] <= xs.back())
        throw equation.error("samples", path.string() + ":" + std::to_string(number) + ": x must increase");
      xs.push_back(numbers[0]);
      fs.push_back(numbers[1]);
    }
    if (xs.size() < 2) throw equation.error("samples", path.string() + ": expected at least two lines 'x f(x)'");
    if (xs.front() > lower() || xs.back() < upper())
      throw equation.error("samples", path.string() + ": the samples span [" + std::to_string(xs.front()) + ", " +
                                          std::to_string(xs.back()) + "], which does not cover the domain");
    samples_ = std::make_shared<PiecewiseLinear>(Eigen::Map<Eigen::VectorXd>(xs.data(), std::ssize(xs)),
                                                 Eigen::Map<Eigen::VectorXd>(fs.data(), std::ssize(fs)));
  }

  void read_audio(const io::ConfigNode& equation, const std::filesystem::path& dir) {
    io::AudioClip clip;
    try {
      clip = io::read_audio(dir / equation.get<std::string>("audio"));
    } catch (const std::runtime_error& e) {
      throw equation.error("audio", e.what());
    }
    Eigen::Index first = 0, count = clip.samples.size();
    if (equation.has("audio_seconds")) {
      const std::vector<double> span = equation.get_list<double>("audio_seconds", 2);
      equation.require("audio_seconds", 0 <= span[0] && span[0] < span[1] && span[1] <= clip.seconds(),
                       "expected [start, end] with 0 <= start < end <= " + std::to_string(clip.seconds()) +
                           " (the clip's length in seconds)");
      const io::SampleRange range = io::samples_between(clip, span[0], span[1]);
      first = range.first;
      count = range.count;
    }
    equation.require("audio", count >= 2, "the clip has fewer than two samples there");
    samples_ = std::make_shared<PiecewiseLinear>(Eigen::VectorXd::LinSpaced(count, lower(), upper()),
                                                 clip.samples.segment(first, count));
  }

  Eigen::VectorXd integrand(const Eigen::MatrixXd& x) const {
    if (integrand_) return integrand_->evaluate(x);
    Eigen::VectorXd f(x.rows());
    for (Eigen::Index i = 0; i < x.rows(); ++i) f(i) = samples_->value(x(i, 0));
    return f;
  }

  // Random points of the domain, or data points: all of them when n covers them, else n
  // distinct ones.
  Eigen::MatrixXd draw(Random& rng, Eigen::Index n) const {
    if (!samples_ || uniform_points_) return domain_.sample_interior(rng, n);
    const Eigen::Index count = samples_->x.size();
    if (n >= count) return samples_->x;
    std::vector<Eigen::Index> order(static_cast<size_t>(count));
    std::iota(order.begin(), order.end(), 0);
    Eigen::MatrixXd x(n, 1);
    for (Eigen::Index i = 0; i < n; ++i) {
      const Eigen::Index j = i + static_cast<Eigen::Index>(rng() % static_cast<Random::result_type>(count - i));
      std::swap(order[static_cast<size_t>(i)], order[static_cast<size_t>(j)]);
      x(i, 0) = samples_->x(order[static_cast<size_t>(i)]);
    }
    return x;
  }

  // The reference integrals over the metrics' intervals, computed on first use: by adaptive
  // quadrature they take a quarter second, which checking a config (nfield validate) skips.
  const Eigen::VectorXd& reference() const {
    if (!reference_) reference_ = reference_integrals(interval_a_, interval_b_);
    return *reference_;
  }

  Eigen::VectorXd reference_integrals(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) const {
    if (antiderivative_) return antiderivative_->evaluate(b) - antiderivative_->evaluate(a);
    if (!samples_) {
      const auto f = [this](const Eigen::MatrixXd& x) { return integrand_->evaluate(x); };
      integrators::AdaptiveQuadratureOptions options;
      options.tolerance = 1e-13;
      return integrators::adaptive_gauss_kronrod(f, a, b, options).integrals;
    }
    Eigen::VectorXd result(a.rows());
    for (Eigen::Index k = 0; k < a.rows(); ++k)
      result(k) = samples_->integral_to(b(k, 0)) - samples_->integral_to(a(k, 0));
    return result;
  }

  static integrators::PointFunction phi(const OutputContext& context) {
    const autodiff::StreamLayout values(autodiff::StreamSpec::values(1));
    return [&context, values](const Eigen::MatrixXd& x) -> Eigen::VectorXd {
      return context.streams(values, x).stream(values.value()).col(0);
    };
  }
  static integrators::PointFunction derivative(const OutputContext& context) {
    const autodiff::StreamLayout gradient(autodiff::StreamSpec::gradient(1));
    return [&context, gradient](const Eigen::MatrixXd& x) -> Eigen::VectorXd {
      return context.streams(gradient, x).stream(gradient.tangent(0)).col(0);
    };
  }
  Eigen::VectorXd autoint_integrals(const OutputContext& context) const {
    return integrators::antiderivative_differences(phi(context), interval_a_, interval_b_);
  }
  static double relative_l2(const Eigen::VectorXd& value, const Eigen::VectorXd& reference) {
    return (value - reference).norm() / reference.norm();
  }
  Eigen::MatrixXd grid(Eigen::Index n) const { return Eigen::VectorXd::LinSpaced(n, lower(), upper()); }

  // Seconds per call of `run`, repeated until 0.3 s have passed.
  template <typename Run>
  static double seconds_per_call(Run&& run) {
    using Clock = std::chrono::steady_clock;
    const auto started = Clock::now();
    long calls = 0;
    double elapsed = 0;
    do {
      run();
      ++calls;
      elapsed = std::chrono::duration<double>(Clock::now() - started).count();
    } while (elapsed < 0.3);
    return elapsed / static_cast<double>(calls);
  }

  // AutoInt against adaptive quadrature of the fitted integrand, both on the first
  // kTimedIntervals intervals in one batch each.
  void write_timing(const OutputContext& context, const Eigen::VectorXd& autoint,
                    std::vector<std::pair<std::string, double>>& metrics) const {
    const Eigen::Index m = std::min<Eigen::Index>(kTimedIntervals, reference().size());
    const Eigen::MatrixXd a = interval_a_.topRows(m), b = interval_b_.topRows(m);
    const Eigen::VectorXd reference = this->reference().head(m), from_ends = autoint.head(m);
    const double rms_error = (from_ends - reference).norm() / std::sqrt(static_cast<double>(m));
    integrators::AdaptiveQuadratureOptions options;
    options.tolerance = std::max(0.1 * rms_error, 1e-15 * reference.cwiseAbs().maxCoeff());
    options.epsilon = context.epsilon;
    auto shown = std::chrono::steady_clock::now();
    options.on_round = [&shown, m](const integrators::AdaptiveQuadratureResult& so_far, long open) {
      if (std::chrono::steady_clock::now() - shown < std::chrono::seconds(3)) return;
      shown = std::chrono::steady_clock::now();
      std::printf("adaptive quadrature of %ld integrals: round %d, %ld pieces open, %.0f evaluations per integral\n",
                  static_cast<long>(m), so_far.rounds, open, static_cast<double>(so_far.evaluations) / m);
      std::fflush(stdout);
    };
    const integrators::PointFunction fitted = derivative(context);
    const auto quadrature = integrators::adaptive_gauss_kronrod(fitted, a, b, options);
    const double per_integral = static_cast<double>(quadrature.evaluations) / static_cast<double>(m);
    metrics.emplace_back("timed_intervals", static_cast<double>(m));
    metrics.emplace_back("quadrature_tolerance", options.tolerance);
    metrics.emplace_back("quadrature_rel_l2", relative_l2(quadrature.integrals, reference));
    metrics.emplace_back("quadrature_minus_autoint_rel_l2", (quadrature.integrals - from_ends).norm() / reference.norm());
    metrics.emplace_back("quadrature_evaluations_per_integral", per_integral);
    metrics.emplace_back("quadrature_unconverged_pieces", static_cast<double>(quadrature.unconverged));

    options.on_round = nullptr;
    const integrators::PointFunction values = phi(context);
    const double autoint_seconds =
        seconds_per_call([&] { integrators::antiderivative_differences(values, a, b); }) / static_cast<double>(m);
    const double quadrature_seconds =
        seconds_per_call([&] { integrators::adaptive_gauss_kronrod(fitted, a, b, options); }) / static_cast<double>(m);
    metrics.emplace_back("autoint_us_per_integral", 1e6 * autoint_seconds);
    metrics.emplace_back("quadrature_us_per_integral", 1e6 * quadrature_seconds);
    metrics.emplace_back("autoint_speedup_over_quadrature", quadrature_seconds / autoint_seconds);
    std::printf("integrals: %.2f us each from the antiderivative, %.2f us by adaptive quadrature of the fitted "
                "integrand (%.1f evaluations each, rel. L2 error %.3e): %.1fx (%ld intervals)\n",
                1e6 * autoint_seconds, 1e6 * quadrature_seconds, per_integral,
                relative_l2(quadrature.integrals, reference), quadrature_seconds / autoint_seconds, static_cast<long>(m));
  }

  void write_curves(const OutputContext& context) const {
    // At least two points per pixel column, and every data point when there are more.
    const Eigen::MatrixXd x = samples_ && samples_->x.size() > 2048 ? Eigen::MatrixXd(samples_->x) : grid(2048);
    const Eigen::VectorXd f = integrand(x), fitted = derivative(context)(x), antiderivative = phi(context)(x);
    io::Image plot = io::plot_curves(
        {io::PlotPanel{{io::Curve{x.col(0), f, {0.55f, 0.55f, 0.55f}}, io::Curve{x.col(0), fitted, {0.85f, 0.1f, 0.1f}}}},
         io::PlotPanel{{io::Curve{x.col(0), antiderivative, {0.1f, 0.25f, 0.8f}}}}},
        1200, 700);
    io::write_png(context.dir / "integrand.png", plot);
    io::write_atomically(context.dir / "integrand.csv", [&](const std::filesystem::path& path) {
      std::ofstream out(path);
      out << "x,f,fitted_integrand,antiderivative\n";
      out.precision(12);
      for (Eigen::Index i = 0; i < x.rows(); ++i)
        out << x(i, 0) << ',' << f(i) << ',' << fitted(i) << ',' << antiderivative(i) << '\n';
    });
  }

  Domain domain_;
  std::shared_ptr<io::Expression> integrand_, antiderivative_;
  std::shared_ptr<const PiecewiseLinear> samples_;
  bool uniform_points_ = false;  // data integrands trained between their samples too
  Eigen::MatrixXd interval_a_, interval_b_;
  mutable std::optional<Eigen::VectorXd> reference_;
};

}  // namespace

std::unique_ptr<Problem> make_autoint_1d(const ProblemContext& context) {
  return std::make_unique<AutoInt1d>(context);
}

}  // namespace nfield::solvers
