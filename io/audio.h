// SPDX-License-Identifier: MIT
//
// Sound files as sample sequences, read (and written as WAV) with libsndfile (WAV, FLAC, Ogg/Vorbis, AIFF, …).
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

// The samples [first, first + count) of `clip` that cover [start, end] seconds:
// first = ⌊start · rate⌋, the last before ⌈end · rate⌉ (at most the clip's end). The caller
// checks 0 ≤ start < end ≤ clip.seconds().
struct SampleRange {
  Eigen::Index first = 0, count = 0;
};
SampleRange samples_between(const AudioClip& clip, double start, double end);

// Throws std::runtime_error naming `path` and libsndfile's reason when the file is missing,
// not a sound file, or holds no samples.
AudioClip read_audio(const std::filesystem::path& path);

// Writes `clip` as a mono WAV file of 16-bit PCM through libsndfile, atomically (see
// io/atomic_write.h): samples are clipped to [-1, 1] and NaN written as 0; the sample rate is
// clip.sample_rate rounded to an integer. Throws std::invalid_argument for a clip without
// samples or a sample rate outside [1, 2^31), and std::runtime_error naming `path` when
// writing fails.
void write_audio(const std::filesystem::path& path, const AudioClip& clip);

}  // namespace nfield::io
