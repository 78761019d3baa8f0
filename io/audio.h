// SPDX-License-Identifier: MIT
//
// Sound files as sample sequences, read with libsndfile (WAV, FLAC, Ogg/Vorbis, AIFF, …).
// Samples are in [-1, 1] whatever the file's encoding (libsndfile scales integer PCM by
// 1/2^(bits-1)); a file of several channels is read as their mean.
#pragma once

#include <filesystem>

#include <Eigen/Core>

namespace nfield::io {

struct AudioClip {
  double sample_rate = 0;   // samples per second
  Eigen::VectorXd samples;  // mono, in [-1, 1]
  double seconds() const { return sample_rate > 0 ? static_cast<double>(samples.size()) / sample_rate : 0; }
};

// Throws std::runtime_error naming `path` and libsndfile's reason when the file is missing,
// not a sound file, or holds no samples.
AudioClip read_audio(const std::filesystem::path& path);

}  // namespace nfield::io
