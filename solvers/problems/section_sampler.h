// SPDX-License-Identifier: MIT
//
// AutoInt's sampling network (Lindell et al. 2021, Sec. 4): a small network that places the
// K sections of each ray, so that few sections go where the ray is empty and more where it
// meets the surface.
//
// Sections. For a ray clipped to [near, far], L = far − near, the network S reads the ray's
// entry point p = o + near·d and its direction d and returns K logits z; the sections have
// lengths
//
//   Δᵢ = L (β/K + (1 − β) wᵢ),   w = softmax(z),
//
// so they tile [near, far], and each keeps at least the share β/K of the ray (`min_share`
// β ∈ [0, 1)): a section of length 0 would divide by zero in (Φ(tᵢ₊₁) − Φ(tᵢ))/Δᵢ. The
// boundaries are t₀ = near, tⱼ = near + Σ_{i<j} Δᵢ. An untrained S (small logits) gives
// almost equal sections.
//
// Training. S is trained for the rendering it serves: the colour C(t₀ … t_K) of the ray
// composited from the section means s̄ᵢ = (Φ(tᵢ₊₁) − Φ(tᵢ))/Δᵢ of the integral field Φ, as
// at render time, against the pixel: L_S = mean over rays of ‖C − C_pixel‖², one Adam step
// per update, with Φ held fixed, on the first `rays` rays of the batch (a random subset: S
// is small, and reading the rate of Φ at every section end of every ray of a batch slowed a
// step noticeably; docs/experiments.md). (The integral field's own step then trains at stratified
// samples inside S's sections, which it sees as fixed.) The boundary adjoints are exact:
// with φ = ∂Φ/∂t (a tangent stream of Φ along d at each boundary),
//
//   ∂s̄ᵢ/∂tᵢ₊₁ = (φ(tᵢ₊₁) − s̄ᵢ)/Δᵢ,   ∂s̄ᵢ/∂tᵢ = (s̄ᵢ − φ(tᵢ))/Δᵢ,
//
// and the rendering's own dependence on δᵢ = Δᵢ through τᵢ = σᵢδᵢ is ∂L/∂δᵢ = σ̄ᵢσᵢ/δᵢ
// (integrators/volume_rendering.h gives σ̄ᵢ = ∂L/∂σᵢ). From t̄ⱼ, Δ̄ᵢ = Σ_{j>i} t̄ⱼ,
// w̄ᵢ = L(1 − β)Δ̄ᵢ and z̄ = w ⊙ (w̄ − w·w̄), which S's reverse pass takes to its weights.
//
// Cost at render time: one evaluation of S per ray (hidden [64, 64]: about 1 % of the K + 1
// evaluations of the integral field at K = 16).
#pragma once
#include <cstdint>
#include <functional>
#include <random>
#include <vector>

#include "fields/field.h"
#include "integrators/ray_sampling.h"
#include "io/config.h"
#include "solvers/core/problem.h"
#include "solvers/problems/radiance_scene.h"
#include "solvers/training/adam.h"

namespace nfield::io {
class H5Writer;
class H5Reader;
}  // namespace nfield::io

namespace nfield::solvers {

struct SectionSamplerOptions {
  std::vector<int> hidden{64, 64};  // widths of S's hidden layers (ReLU); each ≥ 1
  int frequencies = 4;              // octaves of the positional encoding of (p, d); ≥ 0
  double learning_rate = 1e-3;      // of S's Adam; > 0
  double min_share = 0.25;          // β: each section ≥ β/K of the ray; in [0, 1)
  int every = 1;                    // steps between updates of S; ≥ 1
  int rays = 256;                   // rays of the batch an update reads (the first ones); ≥ 1
  std::uint64_t seed = 1;           // S's initial weights

  // Throws std::invalid_argument naming the field, its value and the rule.
  void validate() const;
  // Reads `node` (a `render.sampler` section; unknown keys are errors).
  static SectionSamplerOptions from_config(const io::ConfigNode& node);
};

// What one update of S saw: the rendering loss before the step, and how unequal the
// sections were (the largest section over the equal share L/K, averaged over rays).
struct SamplerUpdate {
  double loss = 0;
  double max_section_share = 1;
};

class SectionSampler {
 public:
  SectionSampler(int sections, SectionSamplerOptions options);

  int sections() const { return sections_; }
  const SectionSamplerOptions& options() const { return options_; }
  Eigen::Index parameter_count() const { return network_.parameter_count(); }

  // Section boundaries of every ray with far > near: row k holds t₀ … t_K of the k-th such ray
  // (rays in order, empty ones skipped), t₀ = near and t_K = far.
  Eigen::MatrixXd boundaries(const integrators::Rays<double>& rays) const;
  // The same as RaySamples: one entry per section, t its midpoint, δ its length (the layout
  // of integrators::equal_sections).
  integrators::RaySamples<double> sections(const integrators::Rays<double>& rays) const;

  // Section ends x(tⱼ) = o + tⱼd and the direction, as inputs of a radiance field (6
  // columns), for the rays with sections: rows k(K + 1) … k(K + 1) + K for the k-th.
  static Eigen::MatrixXd end_points(const integrators::Rays<double>& rays,
                                    const Eigen::MatrixXd& boundaries);

  // One Adam step of S on the rendering loss of `rays` (clipped) against `target` (R × 3)
  // on `background` (1 × 3 or R × 3), with Φ's values and tangent streams from `field`.
  using FieldStreams = OutputContext::FieldStreams;
  SamplerUpdate update(const integrators::Rays<double>& rays, const Eigen::MatrixXd& target,
                       const Eigen::MatrixXd& background, const FieldStreams& field,
                       const DensityActivation& density, double density_scale);

  // The loss of update() before its step, and its gradient with respect to S's weights
  // (resized and overwritten; all zero when no ray has sections).
  SamplerUpdate loss_and_gradient(const integrators::Rays<double>& rays, const Eigen::MatrixXd& target,
                                  const Eigen::MatrixXd& background, const FieldStreams& field,
                                  const DensityActivation& density, double density_scale,
                                  Eigen::VectorXd& gradient) const;
  // S's weights (tests perturb them).
  Eigen::VectorXd& parameters() { return network_.parameters(); }

  // S's weights and Adam state under `group` of a checkpoint.
  void save(io::H5Writer& file, const std::string& group) const;
  // Throws io::H5Error or std::runtime_error naming the file when the group is missing or
  // S's shape differs from the config's.
  void load(const io::H5Reader& file, const std::string& group);

 private:
  Eigen::MatrixXd features(const integrators::Rays<double>& rays) const;

  int sections_;
  SectionSamplerOptions options_;
  fields::Field<double> network_;
  Adam<double> adam_;
};

}  // namespace nfield::solvers
