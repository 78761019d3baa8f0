// SPDX-License-Identifier: MIT
//
// Where sample points come from: the random engine, and the low-discrepancy sequences that
// may stand in for it when a Domain draws points in its box (training.sampler).
//
// Every Domain sampler maps points u of the unit cube [0, 1)^s onto the box, a face or the
// initial slice. With `uniform` the u are independent draws of the engine. With `sobol` or
// `halton` they are consecutive points of a quasi-random sequence, whose star discrepancy
// falls like (log N)^s / N instead of the N^(-1/2) of random points, so a batch covers the
// domain more evenly and sums over it integrate smooth residuals with less error.
//
//   sobol   Boost's Sobol engine (Joe–Kuo direction numbers), 64-bit integers u_j XORed with
//           one random 64-bit mask per coordinate (a random digital shift). A digital shift
//           keeps every (t, m, s)-net property of the sequence, and differs between seeds.
//   halton  coordinate j of point i is the radical inverse φ_{p_j}(i) (digits of i in the
//           j-th prime base, mirrored about the radix point) plus a random shift Δ_j mod 1
//           (Cranley–Patterson rotation). The index starts at a random offset in [1, 2^20].
//
// A sequence continues from batch to batch (batch k uses points kN … (k+1)N − 1), so
// successive batches differ and together stay low-discrepancy. Its whole state is the
// number of points drawn in each dimension used (masks and shifts follow from the seed), so
// a checkpoint stores just those counts and a resumed run draws the same points.
#pragma once

#include <cmath>
#include <cstdint>
#include <iosfwd>
#include <map>
#include <memory>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include <Eigen/Core>

namespace nfield::solvers {

class UnitSequence;

// The random engine of a run (std::mt19937_64), optionally carrying a low-discrepancy
// sequence that Domain's samplers draw their unit-cube points from instead of the engine.
// Only the engine is random state; the attached sequence is owned elsewhere (the trainer
// keeps one per loss term) and is attached just while that term samples.
class Random {
 public:
  using result_type = std::mt19937_64::result_type;
  explicit Random(result_type seed = std::mt19937_64::default_seed) : engine_(seed) {}
  static constexpr result_type min() { return std::mt19937_64::min(); }
  static constexpr result_type max() { return std::mt19937_64::max(); }
  result_type operator()() { return engine_(); }

  UnitSequence* sequence() const { return sequence_; }
  void attach(UnitSequence* sequence) { sequence_ = sequence; }

  friend std::ostream& operator<<(std::ostream& os, const Random& r) { return os << r.engine_; }
  friend std::istream& operator>>(std::istream& is, Random& r) { return is >> r.engine_; }

 private:
  std::mt19937_64 engine_;
  UnitSequence* sequence_ = nullptr;  // not owned; null: draw from the engine
};

// Attaches a sequence for the lifetime of the guard (null: leaves the engine in charge).
class AttachSequence {
 public:
  AttachSequence(Random& rng, UnitSequence* sequence) : rng_(rng), previous_(rng.sequence()) {
    rng_.attach(sequence);
  }
  ~AttachSequence() { rng_.attach(previous_); }
  AttachSequence(const AttachSequence&) = delete;
  AttachSequence& operator=(const AttachSequence&) = delete;

 private:
  Random& rng_;
  UnitSequence* previous_;
};

// One SplitMix64 step: spreads nearby seeds (term 0, 1, …; dimension 2, 3, …; epoch 0, 1, …)
// apart, for engines seeded from a seed and a counter.
std::uint64_t mix(std::uint64_t z);

// Uniform in [0, 1), from the raw engine (independent of the library's distributions).
inline double uniform01(Random& rng) { return static_cast<double>(rng() >> 11) * 0x1.0p-53; }

// A standard normal deviate by Box–Muller on two uniform01 draws (u₁ = 1 − first ∈ (0, 1]):
// the same numbers on every platform, which the library's distributions do not promise.
inline double standard_normal(Random& rng) {
  const double u1 = 1.0 - uniform01(rng), u2 = uniform01(rng);
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * std::numbers::pi * u2);
}

// n points of [0, 1)^dim: from the attached sequence, else engine draws row by row.
Eigen::MatrixXd unit_points(Random& rng, Eigen::Index n, int dim);

// The names accepted by training.sampler.
const std::vector<std::string>& sampler_names();

// A randomized quasi-random sequence (sobol or halton) with one independent stream per
// dimension asked for (a loss term may draw points of several dimensions: faces use one
// more coordinate than the interior to pick the face).
class UnitSequence {
 public:
  UnitSequence(std::string kind, std::uint64_t seed);
  ~UnitSequence();
  UnitSequence(UnitSequence&&) noexcept;
  UnitSequence& operator=(UnitSequence&&) noexcept;

  const std::string& kind() const { return kind_; }
  // The next n points of the dim-dimensional stream (n × dim, in [0, 1)).
  Eigen::MatrixXd next(Eigen::Index n, int dim);

  // Points drawn so far per dimension: the whole state.
  std::map<int, std::uint64_t> counts() const;
  // Rewinds or advances each stream to the given counts (streams not named restart).
  void set_counts(const std::map<int, std::uint64_t>& counts);
  // "dim:count dim:count …" and back, for checkpoints.
  std::string state() const;
  void set_state(const std::string& text);

  static constexpr int kMaxDimension = 16;

 private:
  struct Stream;
  Stream& stream(int dim);
  std::string kind_;
  std::uint64_t seed_;
  std::map<int, std::unique_ptr<Stream>> streams_;
};

}  // namespace nfield::solvers
