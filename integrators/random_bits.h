// SPDX-License-Identifier: MIT
//
// Draws from the raw bits of std::mt19937_64, with no std::*_distribution.
//
// The engine's output sequence is fixed by the C++ standard; the distributions are not (libstdc++
// and libc++ turn the same bits into different numbers). Everything random in this layer goes
// through these two functions, so a seed gives the same rays and samples on every standard
// library.
#pragma once

#include <cstdint>
#include <random>

namespace nfield::integrators {

// u ∈ [0, 1) with 53 random bits: the top 53 bits of one draw times 2⁻⁵³.
inline double uniform01(std::mt19937_64& rng) {
  return static_cast<double>(rng() >> 11) * 0x1.0p-53;
}

// An integer uniform in [0, n), n ≥ 1, without modulo bias (Lemire 2019: the high word of
// x·n is uniform once the few low words below 2⁶⁴ mod n are redrawn).
inline std::uint64_t uniform_index(std::mt19937_64& rng, std::uint64_t n) {
  unsigned __int128 m = static_cast<unsigned __int128>(rng()) * n;
  auto low = static_cast<std::uint64_t>(m);
  if (low < n) {
    const std::uint64_t reject_below = (0 - n) % n;  // 2⁶⁴ mod n
    while (low < reject_below) {
      m = static_cast<unsigned __int128>(rng()) * n;
      low = static_cast<std::uint64_t>(m);
    }
  }
  return static_cast<std::uint64_t>(m >> 64);
}

}  // namespace nfield::integrators
