// SPDX-License-Identifier: MIT
//
// Signal fitting (SIREN, Sitzmann et al. 2020, Sec. 3; Instant NGP, Müller et al. 2022,
// Sec. 5.1): a field over coordinates is fitted to the samples of an image, a sound clip or
// a video, and compared with them after training.
//
//   problem: fit
//   equation:
//     signal: image                   # image | audio | video
//     path: ../data/images/camera.png # relative to the config file: a PNG or WebP (image), a sound
//                                     # file read by libsndfile (audio), or a folder of
//                                     # same-sized PNG/WebP frames in file-name order (video)
//     channels: auto                  # image, video: auto | grey | rgb (auto: grey for a
//                                     #   grey picture, else RGB; alpha is dropped)
//     crop: 256                       # image, video: the central crop, n or [width, height]
//     frames: 32                      # video: the first n frames of the folder
//     seconds: [0.5, 2.5]             # audio: that part of the clip
//     time_scale: 1                   # audio, video: t runs over [-s, s] instead of [-1, 1]
//     scale_targets: band_limited     # a multiscale field's coarser scales: band_limited | signal
//     draws: epochs                   # the batches' samples: epochs | independent
//
// Coordinates: the sample centres spread evenly over [-1, 1] on each axis, so that sample k
// of n lies at -1 + (2k + 1)/n (the centre of its n-th of the interval): (x, y) for an image,
// x right and y up; t for audio (the field's one input, named x in `field:` keys); (x, y, t)
// for a video, t over the frames. The values are the pixels' channels in [0, 1], or the
// clip's samples in [-1, 1] (channels averaged). `domain` and `conditions` are not read.
// A hash grid (fields/hash_grid.h) over this box with N cells across an axis of N samples
// has its vertices on the samples: p = N (u + 1)/2 + 1/2 = k + 1 at u = -1 + (2k + 1)/N.
//
// Training: one loss term `signal` (batch `interior`): random samples (all of them, in order,
// when the batch is at least their count), and the residual value − target per channel (a
// LinearResidual on the value stream), so the loss is the mean squared error over the batch.
// With `draws: epochs` (the default) the samples are drawn in epochs: each batch takes the
// next ones of a shuffled order of all of them, reshuffled when used up
// (solvers/sampling/epoch_order.h, seeded by training.seed, indexed by the step, so a resumed
// run draws the same); `independent` draws each with replacement. Epochs were ahead on every
// shipped fit (docs/experiments.md, 2026-11-28 session 31). A family's pictures are fitted on
// all their pixels and have no `draws`. Every optimizer and checkpoints work as for any
// problem. The progress line adds the PSNR (audio: SNR) on at most 65,536 evenly spread
// samples, refreshed every 10 s.
//
// After training the field is evaluated at every sample. metrics.json: `rel_l2` (also per
// stage) and `max_abs_err` over all samples and channels; image: `psnr_db`, `ssim`;
// audio: `snr_db` = 10 log₁₀(Σ s² / Σ (ŝ − s)²) and `psnr_db` = 10 log₁₀(1 / MSE) (full
// scale 1); video: `psnr_mean` (the mean of the frames' PSNRs), `psnr_frame_NNN` per frame,
// `psnr_min`, `ssim_mean`, and `psnr_db` over all frames. PSNR and SSIM are those of
// io/image_metrics.h, on the reconstruction clamped to [0, 1] (audio: [-1, 1]) as written.
// Files: image: reconstruction.png, error.png (|error|, mean over channels, viridis from 0
// to max_abs_err); audio: reconstruction.wav (16-bit PCM at the clip's rate) and
// waveform.png (top: the clip in grey and the reconstruction in red; bottom: the error in
// blue); video: frames/reconstruction_NNN.png and frames/error_NNN.png (one viridis range,
// 0 to max_abs_err, for all frames). Every file is written atomically.
// A field with several scales (field.type: bacon) is fitted as any field, its loss the sum
// of the scales' losses (fields/field.h). Scale s's target is the signal's band-limited part
// P_K s (solvers/problems/periodic_lowpass.h), K = ⌊F_s D⌋ cycles over the box per axis (F_s
// the scale's cut-off in cycles per unit, D the box's width), with `scale_targets:
// band_limited` (the default); the signal itself for every scale with `signal` (BACON's own
// loss). On the full grid (field.period 1) the two have the same minimiser (s − P_K s is
// orthogonal to all a head band-limited to K can hold), but on a batch of random samples the
// part of s above a coarse head's band is a residual it can never reduce, and its gradient
// is noise in the layers the scales share (docs/experiments.md, 2026-11-28). A family's
// pictures keep the signal as every scale's target. An image fit then also writes each scale:
// reconstruction_scaleS.png, psnr_full_scaleS and, at the scale's own resolution,
// psnr_scaleS against the picture averaged to it (write_scale_outputs below).
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "io/audio.h"
#include "io/image_file.h"
#include "io/image_metrics.h"
#include "io/line_plot.h"
#include "io/png_image.h"
#include "io/text.h"
#include "solvers/core/problem_capabilities.h"
#include "solvers/core/slice_progress.h"
#include "solvers/problems/image_family.h"
#include "solvers/problems/periodic_lowpass.h"
#include "solvers/problems/problems.h"
#include "solvers/sampling/epoch_order.h"

namespace nfield::solvers {
namespace {

namespace fs = std::filesystem;

// Samples on a regular lattice: index (f·height + r)·width + c, with c the fastest axis
// (audio: c the sample, height = frames = 1).
enum class Kind { kImage, kAudio, kVideo };

struct Signal {
  Kind kind = Kind::kImage;
  int width = 1, height = 1, frames = 1;
  int channels = 1;
  double sample_rate = 0;       // audio
  Eigen::MatrixXf values;       // samples × channels
  Eigen::Index size() const { return values.rows(); }
};

// 10 log₁₀(Σ s² / Σ (ŝ − s)²) over every sample and channel.
double snr_db(const Eigen::MatrixXd& fitted, const Eigen::MatrixXd& target) {
  return 10.0 * std::log10(target.squaredNorm() / std::max((fitted - target).squaredNorm(), 1e-300));
}

class Fit final : public Problem,
                  public ReportsProgress,
                  public HasInstances,
                  public HasScaleTargets,
                  public SamplesWithSolution {
 public:
  explicit Fit(const ProblemContext& context) : domain_({-1.0}, {1.0}) {
    const io::ConfigNode equation = context.root.child("equation");
    const std::string kind = equation.get_choice("signal", {"image", "audio", "video"});
    signal_.kind = kind == "audio" ? Kind::kAudio : kind == "video" ? Kind::kVideo : Kind::kImage;
    if (equation.has("family")) {
      equation.require("family", signal_.kind == Kind::kImage, "expected signal: image (a family holds pictures)");
      equation.require("family", !equation.has("path"), "a family names its pictures itself: drop equation.path");
      read_family(equation, context.config_dir);
      scale_targets_ = false;
    } else {
      const fs::path path = context.config_dir / equation.get<std::string>("path");
      if (signal_.kind == Kind::kAudio)
        read_audio(equation, path);
      else
        read_pictures(equation, path);
      scale_targets_ =
          equation.get_choice("scale_targets", {"band_limited", "signal"}, "band_limited") == "band_limited";
      if (equation.get_choice("draws", {"epochs", "independent"}, "epochs") == "epochs") {
        std::int64_t seed = 0;  // training.seed's default (solvers/training/training_options.h)
        if (context.root.has("training") && context.root.child("training").has("seed"))
          seed = context.root.child("training").get_nonnegative<std::int64_t>("seed");
        epochs_.emplace(signal_.size(), static_cast<std::uint64_t>(seed));
      }
    }
    equation.reject_unknown_keys();
    finish();
  }

  // One instance of a family: a problem of that one picture.
  explicit Fit(Signal signal) : domain_({-1.0}, {1.0}), signal_(std::move(signal)) { finish(); }

  std::vector<ProblemInstance> instances(bool held_out) const override {
    std::vector<ProblemInstance> out;
    const std::size_t first = held_out ? training_count_ : 0, end = held_out ? family_.size() : training_count_;
    for (std::size_t k = first; k < end; ++k) out.push_back({family_names_[k], std::make_unique<Fit>(family_[k])});
    return out;
  }

  const Domain& domain() const override { return domain_; }
  int output_dim() const override { return signal_.channels; }
  std::vector<std::string> output_names() const override {
    if (signal_.channels == 3) return {"red", "green", "blue"};
    return {signal_.kind == Kind::kAudio ? "amplitude" : "grey"};
  }
  int residual_term() const override { return -1; }
  bool writes_grid_outputs() const override { return false; }

  std::vector<LossTerm> loss_terms() const override {
    LossTerm term;
    term.name = "signal";
    term.batch_key = "interior";
    term.spec = autodiff::StreamSpec::values(domain_.input_dim());
    term.sample = [this](Random& rng, Eigen::Index n) {
      const Eigen::Index count = signal_.size();
      if (n >= count) return TermPoints(coordinates(Eigen::VectorXi::LinSpaced(count, 0, static_cast<int>(count - 1))));
      if (epochs_ && step_ >= 0) return TermPoints(coordinates(epochs_->at(step_ * n, n)));
      Eigen::VectorXi index(n);
      for (Eigen::Index i = 0; i < n; ++i)
        index(i) = static_cast<int>(rng() % static_cast<Random::result_type>(count));
      return TermPoints(coordinates(index));
    };
    term.residual = [this](const TermPoints& points) -> std::unique_ptr<Residual> {
      Eigen::VectorXi index(points.x.rows());
      for (Eigen::Index i = 0; i < index.size(); ++i) index(i) = static_cast<int>(index_of(points.x.row(i)));
      if (scale_cutoffs_.rows() == 0) return value_residual(index, signal_.values);
      std::vector<std::unique_ptr<Residual>> scales;
      for (const Eigen::MatrixXf& values : scale_values())
        scales.push_back(value_residual(index, values.size() > 0 ? values : signal_.values));
      return std::make_unique<ScaleTargetResidual>(std::move(scales), output_scale_);
    };
    return {term};
  }

  // The step indexes the epochs' order. Until a trainer has said it (a draw outside training),
  // samples are drawn independently.
  void before_step(long step, const Solution&, Random&) override { step_ = step; }

  // Only kept: the targets are filtered at the first residual (scale_values), so that
  // `nfield eval` and a config's validation spend no FFTs on them.
  void set_scale_cutoffs(const Eigen::MatrixXd& cutoffs, int output_scale) override {
    if (!scale_targets_ || cutoffs.cols() != domain_.input_dim()) return;
    scale_cutoffs_ = cutoffs;
    output_scale_ = output_scale;
  }

  // Scale s's target (scale_targets: band_limited): the signal's band-limited part, kept
  // where the scale's band is narrower than the grid's (an empty matrix: the signal itself).
  const std::vector<Eigen::MatrixXf>& scale_values() const {
    std::call_once(scale_values_once_, [this] {
      const Eigen::VectorXd width = domain_.input_upper() - domain_.input_lower();
      const std::array<Eigen::Index, 3> dims{signal_.width, signal_.height, signal_.frames};
      // The grid axes' inputs: x, y, t for a picture or video; t alone for audio.
      const std::array<int, 3> input = signal_.kind == Kind::kAudio ? std::array<int, 3>{0, -1, -1}
                                       : signal_.kind == Kind::kImage ? std::array<int, 3>{0, 1, -1}
                                                                      : std::array<int, 3>{0, 1, 2};
      scale_values_.assign(static_cast<size_t>(scale_cutoffs_.rows()), Eigen::MatrixXf());
      for (Eigen::Index s = 0; s < scale_cutoffs_.rows(); ++s) {
        std::array<Eigen::Index, 3> cycles{};
        bool narrower = false;
        for (size_t axis = 0; axis < 3; ++axis) {
          const int k = input[axis];
          cycles[axis] = k < 0 ? dims[axis]
                               : static_cast<Eigen::Index>(std::floor(scale_cutoffs_(s, k) * width(k) + 1e-9));
          narrower = narrower || !keeps_every_mode(dims[axis], cycles[axis]);
        }
        if (!narrower) continue;
        Eigen::MatrixXd values = signal_.values.cast<double>();
        periodic_lowpass(values, dims, cycles);
        scale_values_[static_cast<size_t>(s)] = values.cast<float>();
      }
    });
    return scale_values_;
  }

  // rel_l2 over every sample, after each stage. The evaluation is kept for write_outputs,
  // which reuses it when the field has not changed since (OutputContext::field_as_last_reported):
  // one pass over every sample after training instead of two. Until then it holds n × channels
  // doubles.
  std::optional<double> reported_error(const OutputContext& context) const override {
    last_evaluation_ = evaluate_all(context);
    return (*last_evaluation_ - signal_.values.cast<double>()).norm() / signal_.values.cast<double>().norm();
  }

  std::vector<std::pair<std::string, double>> progress_metrics(const OutputContext& context,
                                                               const TrainingRate&) const override {
    const Eigen::MatrixXf fitted = context.values(coordinates(progress_samples_)).cast<float>();
    Eigen::MatrixXf target(fitted.rows(), fitted.cols());
    for (Eigen::Index k = 0; k < progress_samples_.size(); ++k) target.row(k) = signal_.values.row(progress_samples_(k));
    if (signal_.kind == Kind::kAudio) return {{"SNR dB", snr_db(fitted.cast<double>(), target.cast<double>())}};
    return {{"PSNR", io::psnr(fitted, target)}};
  }

  void write_outputs(const OutputContext& context,
                     std::vector<std::pair<std::string, double>>& metrics) const override {
    Eigen::MatrixXd fitted =
        context.field_as_last_reported && last_evaluation_ ? std::move(*last_evaluation_) : evaluate_all(context);
    last_evaluation_.reset();
    const Eigen::MatrixXd target = signal_.values.cast<double>();
    metrics.emplace_back("rel_l2", (fitted - target).norm() / target.norm());
    const double low = signal_.kind == Kind::kAudio ? -1.0 : 0.0;
    fitted = fitted.cwiseMax(low).cwiseMin(1.0);
    const Eigen::MatrixXd error = fitted - target;
    const double max_abs = error.cwiseAbs().maxCoeff<Eigen::PropagateNaN>();
    metrics.emplace_back("max_abs_err", max_abs);
    if (signal_.kind == Kind::kAudio) {
      write_audio_outputs(context, fitted.col(0), metrics);
      return;
    }
    const Eigen::MatrixXf reconstruction = fitted.cast<float>();
    const double psnr = io::psnr(reconstruction, signal_.values);
    metrics.emplace_back("psnr_db", psnr);
    const Eigen::Index frame = static_cast<Eigen::Index>(signal_.width) * signal_.height;
    const io::ScalarImageOptions error_colours{std::pair{0.0, std::max(max_abs, 1e-12)}, io::Colormap::kViridis};
    const auto picture = [&](Eigen::Index f) {
      return io::Image{signal_.width, signal_.height, signal_.channels, reconstruction.middleRows(f * frame, frame)};
    };
    const auto error_map = [&](Eigen::Index f) {
      const Eigen::VectorXd e = error.middleRows(f * frame, frame).cwiseAbs().rowwise().mean();
      return Eigen::MatrixXd(Eigen::Map<const Eigen::Matrix<double, -1, -1, Eigen::RowMajor>>(
          e.data(), signal_.height, signal_.width));
    };
    const bool ssim_possible = signal_.width >= 11 && signal_.height >= 11;
    if (signal_.kind == Kind::kImage) {
      // SSIM and the two pictures take about 20 s at 4096²: say so rather than look hung.
      const bool large = frame > (Eigen::Index{1} << 22);
      if (large) {
        std::printf("fit: SSIM and reconstruction.png, error.png of %ld pixels\n", static_cast<long>(frame));
        std::fflush(stdout);
      }
      if (ssim_possible) metrics.emplace_back("ssim", io::ssim(reconstruction, signal_.values, signal_.width, signal_.height));
      io::write_png(context.dir / "reconstruction.png", picture(0));
      io::write_scalar_png(context.dir / "error.png", error_map(0), error_colours);
      std::printf("PSNR %.2f dB\n", psnr);
      if (context.scales > 1) write_scale_outputs(context, metrics);
      return;
    }
    const fs::path dir = context.dir / "frames";
    fs::create_directories(dir);
    double sum = 0, least = std::numeric_limits<double>::infinity(), ssim_sum = 0;
    char name[64];
    for (int f = 0; f < signal_.frames; ++f) {
      const io::Image image = picture(f);
      const auto truth = signal_.values.middleRows(f * frame, frame);
      const double frame_psnr = io::psnr(image.pixels, truth);
      std::snprintf(name, sizeof name, "psnr_frame_%03d", f);
      metrics.emplace_back(name, frame_psnr);
      sum += frame_psnr;
      least = std::min(least, frame_psnr);
      if (ssim_possible) ssim_sum += io::ssim(image.pixels, truth, signal_.width, signal_.height);
      std::snprintf(name, sizeof name, "reconstruction_%03d.png", f);
      io::write_png(dir / name, image);
      std::snprintf(name, sizeof name, "error_%03d.png", f);
      io::write_scalar_png(dir / name, error_map(f), error_colours);
    }
    metrics.emplace_back("psnr_mean", sum / signal_.frames);
    metrics.emplace_back("psnr_min", least);
    if (ssim_possible) metrics.emplace_back("ssim_mean", ssim_sum / signal_.frames);
    std::printf("mean PSNR over %d frames %.2f dB (lowest %.2f dB)\n", signal_.frames, sum / signal_.frames, least);
  }

 private:
  void finish() {
    if (signal_.kind == Kind::kImage)
      domain_ = Domain({-1.0, -1.0}, {1.0, 1.0});
    else if (signal_.kind == Kind::kAudio)
      domain_ = Domain({-time_scale_}, {time_scale_});
    else
      domain_ = Domain({-1.0, -1.0}, {1.0, 1.0}, std::pair{-time_scale_, time_scale_});
    // Evenly spread samples for the progress line's figure.
    const Eigen::Index n = signal_.size(), shown = std::min<Eigen::Index>(n, 65536);
    progress_samples_.resize(shown);
    for (Eigen::Index k = 0; k < shown; ++k) progress_samples_(k) = k * n / shown;
  }

  // equation.family: {images: FOLDER | [FILE, …], crop: n | [w, h], held_out: n | [FILE, …]}
  // (solvers/problems/image_family.h). The family problem stands for its first training picture.
  void read_family(const io::ConfigNode& equation, const fs::path& config_dir) {
    const std::string channels = equation.get_choice("channels", {"auto", "grey", "rgb"}, "auto");
    const io::ConfigNode family = equation.child("family");
    const ImageFamily pictures = read_image_family(family, config_dir, channels);
    family.reject_unknown_keys();
    for (std::size_t k = 0; k < pictures.images.size(); ++k) {
      const io::Image& image = pictures.images[k];
      Signal signal;
      signal.width = image.width;
      signal.height = image.height;
      signal.channels = image.channels;
      signal.values = image.pixels;
      family_.push_back(std::move(signal));
      family_names_.push_back(pictures.names[k]);
    }
    training_count_ = pictures.training;
    signal_ = family_.front();
  }

  void read_audio(const io::ConfigNode& equation, const fs::path& path) {
    io::AudioClip clip;
    try {
      clip = io::read_audio(path);
    } catch (const std::exception& e) {
      throw equation.error("path", e.what());
    }
    Eigen::Index first = 0, count = clip.samples.size();
    if (equation.has("seconds")) {
      const std::vector<double> span = equation.get_list<double>("seconds", 2);
      equation.require("seconds", 0 <= span[0] && span[0] < span[1] && span[1] <= clip.seconds(),
                       "expected [start, end] with 0 <= start < end <= " + std::to_string(clip.seconds()) +
                           " (the clip's length in seconds)");
      const io::SampleRange range = io::samples_between(clip, span[0], span[1]);
      first = range.first;
      count = range.count;
    }
    equation.require(equation.has("seconds") ? "seconds" : "path", count >= 2,
                     "the clip has fewer than two samples there");
    read_time_scale(equation);
    signal_.width = static_cast<int>(count);
    signal_.sample_rate = clip.sample_rate;
    signal_.values = clip.samples.segment(first, count).cast<float>();
  }

  void read_time_scale(const io::ConfigNode& equation) {
    time_scale_ = equation.get_or("time_scale", 1.0);
    equation.require("time_scale", time_scale_ > 0 && time_scale_ <= 1e6, "expected a number in (0, 1e6]");
  }

  // An image, or a video's frames: the PNG or WebP files of a folder in name order.
  void read_pictures(const io::ConfigNode& equation, const fs::path& path) {
    const bool video = signal_.kind == Kind::kVideo;
    const std::string channels = equation.get_choice("channels", {"auto", "grey", "rgb"}, "auto");
    const std::optional<std::pair<int, int>> crop = read_crop_size(equation);
    int frames = 0;
    if (video) {
      if (equation.has("frames")) frames = equation.get_in_range("frames", 1, 100000);
      read_time_scale(equation);
    }
    std::vector<fs::path> files;
    if (!video) {
      files.push_back(path);
    } else {
      std::error_code ec;
      if (!fs::is_directory(path, ec))
        throw equation.error("path", path.string() + ": expected a folder of PNG or WebP frames");
      for (const auto& entry : fs::directory_iterator(path, ec)) {
        if (entry.is_regular_file() && io::is_image_file_name(entry.path())) files.push_back(entry.path());
      }
      if (ec) throw equation.error("path", path.string() + ": cannot list the folder: " + ec.message());
      if (files.empty()) throw equation.error("path", path.string() + ": no frames (*.png, *.webp) in the folder");
      std::sort(files.begin(), files.end());
      if (frames > 0) {
        equation.require("frames", frames <= static_cast<int>(files.size()),
                         "expected at most " + std::to_string(files.size()) + " (the frames in " +
                             path.string() + ")");
        files.resize(static_cast<size_t>(frames));
      }
    }
    std::vector<Eigen::MatrixXf> pictures;
    int width = 0, height = 0, source_width = 0, source_height = 0;
    for (const fs::path& file : files) {
      io::Image image;
      try {
        image = io::read_image(file);
      } catch (const std::exception& e) {
        throw equation.error("path", e.what());
      }
      if (pictures.empty()) {
        source_width = image.width;
        source_height = image.height;
        width = crop ? std::min(crop->first, image.width) : image.width;
        height = crop ? std::min(crop->second, image.height) : image.height;
        signal_.channels = channels == "grey" ? 1 : channels == "rgb" ? 3 : image.channels >= 3 ? 3 : 1;
      } else if (image.width != source_width || image.height != source_height) {
        throw equation.error("path", file.string() + ": a frame of " + std::to_string(image.width) + " x " +
                                         std::to_string(image.height) + " pixels; the first frame, " +
                                         files.front().filename().string() + ", has " +
                                         std::to_string(source_width) + " x " + std::to_string(source_height));
      }
      pictures.push_back(io::with_channels(io::central_crop(image, width, height), signal_.channels).pixels);
    }
    signal_.width = width;
    signal_.height = height;
    signal_.frames = static_cast<int>(pictures.size());
    const Eigen::Index frame = static_cast<Eigen::Index>(width) * height;
    signal_.values.resize(frame * signal_.frames, signal_.channels);
    for (int f = 0; f < signal_.frames; ++f) signal_.values.middleRows(f * frame, frame) = pictures[static_cast<size_t>(f)];
  }

  // Centre of sample k of n on [-1, 1].
  static double centre(Eigen::Index k, int n) { return -1.0 + (2.0 * static_cast<double>(k) + 1.0) / n; }
  // Its inverse, the nearest sample.
  static Eigen::Index sample_at(double u, int n) {
    const auto k = static_cast<Eigen::Index>(std::lround(((u + 1.0) * n - 1.0) / 2.0));
    return std::clamp<Eigen::Index>(k, 0, n - 1);
  }

  Eigen::MatrixXd coordinates(const Eigen::VectorXi& index) const {
    Eigen::MatrixXd x(index.size(), domain_.input_dim());
    const Eigen::Index w = signal_.width, h = signal_.height;
    for (Eigen::Index i = 0; i < index.size(); ++i) {
      const Eigen::Index k = index(i);
      if (signal_.kind == Kind::kAudio) {
        x(i, 0) = time_scale_ * centre(k, signal_.width);
        continue;
      }
      x(i, 0) = centre(k % w, signal_.width);
      x(i, 1) = -centre((k / w) % h, signal_.height);  // row 0 at the top: y up
      if (signal_.kind == Kind::kVideo) x(i, 2) = time_scale_ * centre(k / (w * h), signal_.frames);
    }
    return x;
  }

  // value − target per channel at samples `index` of `values` (samples × channels).
  std::unique_ptr<Residual> value_residual(const Eigen::VectorXi& index, const Eigen::MatrixXf& values) const {
    Eigen::MatrixXd target(index.size(), signal_.channels);
    for (Eigen::Index i = 0; i < index.size(); ++i) target.row(i) = values.row(index(i)).cast<double>();
    std::vector<LinearResidual::Term> terms;
    for (int c = 0; c < signal_.channels; ++c)
      terms.push_back({c, autodiff::StreamLayout::value(), c, Eigen::VectorXd::Ones(1)});
    return std::make_unique<LinearResidual>(std::move(terms), std::move(target));
  }

  Eigen::Index index_of(const Eigen::Ref<const Eigen::RowVectorXd>& x) const {
    if (signal_.kind == Kind::kAudio) return sample_at(x(0) / time_scale_, signal_.width);
    const Eigen::Index c = sample_at(x(0), signal_.width), r = sample_at(-x(1), signal_.height);
    const Eigen::Index f = signal_.kind == Kind::kVideo ? sample_at(x(2) / time_scale_, signal_.frames) : 0;
    return (f * signal_.height + r) * signal_.width + c;
  }

  // The field at every sample (n × channels), a slice at a time, with a progress line every
  // 5 s (a 4096² picture takes tens of seconds). Pictures and frames go in square tiles of
  // kTile² pixels, rows within a tile, so that a pass of points stays within one or two of a
  // block field's blocks (ACORN evaluates its encoder once per block a pass touches: in
  // picture rows a 4096² evaluation took 2.4× as long).
  Eigen::MatrixXd evaluate_all(const OutputContext& context) const {
    constexpr int kTile = 256;
    const Eigen::Index n = signal_.size();
    Eigen::MatrixXd out(n, signal_.channels);
    SliceProgress progress("fit: the field at all " + std::to_string(n) + " samples");
    const auto evaluate = [&](const Eigen::VectorXi& index, Eigen::Index done) {
      const Eigen::MatrixXd values = context.values(coordinates(index));
      for (Eigen::Index k = 0; k < index.size(); ++k) out.row(index(k)) = values.row(k);
      progress.advance(done, n);
    };
    if (signal_.kind == Kind::kAudio) {
      constexpr Eigen::Index kSlice = 1 << 18;
      for (Eigen::Index first = 0; first < n; first += kSlice) {
        const Eigen::Index count = std::min(kSlice, n - first);
        evaluate(Eigen::VectorXi::LinSpaced(count, static_cast<int>(first), static_cast<int>(first + count - 1)),
                 first + count);
      }
      return out;
    }
    const int w = signal_.width, h = signal_.height;
    Eigen::Index done = 0;
    for (int f = 0; f < signal_.frames; ++f)
      for (int top = 0; top < h; top += kTile)
        for (int left = 0; left < w; left += kTile) {
          const int rows = std::min(kTile, h - top), columns = std::min(kTile, w - left);
          Eigen::VectorXi index(static_cast<Eigen::Index>(rows) * columns);
          for (int r = 0; r < rows; ++r)
            for (int c = 0; c < columns; ++c) index(r * columns + c) = (f * h + top + r) * w + left + c;
          done += index.size();
          evaluate(index, done);
        }
    return out;
  }

  // A multiscale field's image outputs (fields/field.h): per scale s the reconstruction at
  // full resolution (reconstruction_scaleS.png), its PSNR against the picture
  // (psnr_full_scaleS), and, where the scale's band limit is the Nyquist limit of a grid that
  // divides the picture (N = 2 · cut-off · 2 samples over [-1, 1]), its PSNR at that grid's
  // pixel centres against the picture averaged over each coarse pixel's block (psnr_scaleS,
  // resolution_scaleS).
  void write_scale_outputs(const OutputContext& context, std::vector<std::pair<std::string, double>>& metrics) const {
    const Eigen::Index all = signal_.size();
    for (int s = 0; s < context.scales; ++s) {
      const std::string tag = "_scale" + std::to_string(s);
      const Eigen::MatrixXf fitted =
          context.scale_values(coordinates(Eigen::VectorXi::LinSpaced(all, 0, static_cast<int>(all - 1))), s)
              .cwiseMax(0.0)
              .cwiseMin(1.0)
              .cast<float>();
      io::write_png(context.dir / ("reconstruction" + tag + ".png"),
                    io::Image{signal_.width, signal_.height, signal_.channels, fitted});
      metrics.emplace_back("psnr_full" + tag, io::psnr(fitted, signal_.values));
      if (context.scale_cutoffs.rows() <= s) continue;
      const long nx = std::lround(4.0 * context.scale_cutoffs(s, 0)), ny = std::lround(4.0 * context.scale_cutoffs(s, 1));
      if (nx < 1 || ny < 1 || signal_.width % nx || signal_.height % ny) continue;
      const int fx = static_cast<int>(signal_.width / nx), fy = static_cast<int>(signal_.height / ny);
      Eigen::MatrixXd centres(nx * ny, 2);
      Eigen::MatrixXf truth = Eigen::MatrixXf::Zero(nx * ny, signal_.channels);
      for (long r = 0; r < ny; ++r)
        for (long c = 0; c < nx; ++c) {
          centres(r * nx + c, 0) = centre(c, static_cast<int>(nx));
          centres(r * nx + c, 1) = -centre(r, static_cast<int>(ny));
          for (int i = 0; i < fy; ++i)
            for (int j = 0; j < fx; ++j)
              truth.row(r * nx + c) += signal_.values.row((r * fy + i) * signal_.width + c * fx + j);
        }
      truth /= static_cast<float>(fx * fy);
      const Eigen::MatrixXf coarse = context.scale_values(centres, s).cwiseMax(0.0).cwiseMin(1.0).cast<float>();
      const double psnr = io::psnr(coarse, truth);
      metrics.emplace_back("psnr" + tag, psnr);
      metrics.emplace_back("resolution" + tag, static_cast<double>(nx));
      std::printf("scale %d: PSNR %.2f dB at %ld x %ld against the picture averaged to that grid\n", s, psnr, nx, ny);
    }
  }

  void write_audio_outputs(const OutputContext& context, const Eigen::VectorXd& fitted,
                           std::vector<std::pair<std::string, double>>& metrics) const {
    const Eigen::VectorXd target = signal_.values.col(0).cast<double>();
    const Eigen::VectorXd error = fitted - target;
    const double snr = snr_db(fitted, target);
    metrics.emplace_back("snr_db", snr);
    metrics.emplace_back("psnr_db", io::psnr(fitted.cast<float>(), signal_.values));
    metrics.emplace_back("sample_rate", signal_.sample_rate);
    metrics.emplace_back("samples", static_cast<double>(target.size()));
    io::write_audio(context.dir / "reconstruction.wav", io::AudioClip{signal_.sample_rate, fitted});
    const Eigen::VectorXd seconds =
        Eigen::VectorXd::LinSpaced(target.size(), 0.0, static_cast<double>(target.size() - 1)) / signal_.sample_rate;
    io::PlotPanel signals, errors;
    signals.curves.push_back({seconds, target, {0.6f, 0.6f, 0.6f}});
    signals.curves.push_back({seconds, fitted, {0.85f, 0.1f, 0.1f}});
    errors.curves.push_back({seconds, error, {0.1f, 0.2f, 0.85f}});
    io::write_png(context.dir / "waveform.png", io::plot_curves({signals, errors}, 1600, 600));
    std::printf("SNR %.2f dB\n", snr);
  }

  Domain domain_;
  Signal signal_;
  // A family (equation.family): every picture, the training ones first.
  std::vector<Signal> family_;
  std::vector<std::string> family_names_;
  std::size_t training_count_ = 0;
  double time_scale_ = 1.0;
  Eigen::VectorXi progress_samples_;
  // scale_targets: band_limited; per scale of a multiscale field its target (HasScaleTargets).
  bool scale_targets_ = true;
  Eigen::MatrixXd scale_cutoffs_;  // a row per scale; none: every scale against the signal
  int output_scale_ = 0;
  mutable std::once_flag scale_values_once_;
  mutable std::vector<Eigen::MatrixXf> scale_values_;
  mutable std::optional<Eigen::MatrixXd> last_evaluation_;  // reported_error's, for write_outputs
  std::optional<EpochOrder> epochs_;  // draws: epochs
  long step_ = -1;
};

}  // namespace

std::unique_ptr<Problem> make_fit(const ProblemContext& context) { return std::make_unique<Fit>(context); }

}  // namespace nfield::solvers
