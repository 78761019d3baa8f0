// SPDX-License-Identifier: MIT
#include "io/audio.h"

#include <sndfile.h>

#include <memory>
#include <stdexcept>
#include <vector>

namespace nfield::io {

AudioClip read_audio(const std::filesystem::path& path) {
  SF_INFO info{};
  const std::unique_ptr<SNDFILE, int (*)(SNDFILE*)> file(sf_open(path.c_str(), SFM_READ, &info), sf_close);
  if (!file) throw std::runtime_error(path.string() + ": cannot read as a sound file: " + sf_strerror(nullptr));
  if (info.frames <= 0 || info.channels <= 0 || info.samplerate <= 0)
    throw std::runtime_error(path.string() + ": holds no samples");
  std::vector<double> interleaved(static_cast<size_t>(info.frames) * static_cast<size_t>(info.channels));
  const sf_count_t read = sf_readf_double(file.get(), interleaved.data(), info.frames);
  if (read != info.frames)
    throw std::runtime_error(path.string() + ": read " + std::to_string(read) + " of " +
                             std::to_string(info.frames) + " frames: " + sf_strerror(file.get()));
  AudioClip clip;
  clip.sample_rate = info.samplerate;
  const Eigen::Map<const Eigen::MatrixXd> frames(interleaved.data(), info.channels, info.frames);
  clip.samples = frames.colwise().mean().transpose();
  return clip;
}

}  // namespace nfield::io
