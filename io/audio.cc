// SPDX-License-Identifier: MIT
#include "io/audio.h"

#include <sndfile.h>

#include <algorithm>
#include <cmath>

#include <memory>
#include <stdexcept>
#include <vector>

#include "io/atomic_write.h"

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

SampleRange samples_between(const AudioClip& clip, double start, double end) {
  SampleRange range;
  range.first = static_cast<Eigen::Index>(std::floor(start * clip.sample_rate));
  range.count = std::min<Eigen::Index>(static_cast<Eigen::Index>(std::ceil(end * clip.sample_rate)),
                                       clip.samples.size()) - range.first;
  return range;
}

void write_audio(const std::filesystem::path& path, const AudioClip& clip) {
  if (clip.samples.size() == 0) throw std::invalid_argument("write_audio: the clip holds no samples");
  const double rate = std::round(clip.sample_rate);
  if (!(rate >= 1 && rate < 2147483648.0))
    throw std::invalid_argument("write_audio: sample rate " + std::to_string(clip.sample_rate) + " out of range");
  std::vector<double> samples(static_cast<size_t>(clip.samples.size()));
  for (Eigen::Index i = 0; i < clip.samples.size(); ++i) {
    const double s = clip.samples(i);
    samples[static_cast<size_t>(i)] = std::isnan(s) ? 0.0 : std::clamp(s, -1.0, 1.0);
  }
  write_atomically(path, [&](const std::filesystem::path& tmp) {
    SF_INFO info{};
    info.samplerate = static_cast<int>(rate);
    info.channels = 1;
    info.format = SF_FORMAT_WAV | SF_FORMAT_PCM_16;
    SNDFILE* file = sf_open(tmp.c_str(), SFM_WRITE, &info);
    if (!file) throw std::runtime_error(std::string("cannot open as a sound file: ") + sf_strerror(nullptr));
    // Full scale maps to 32767, and nothing wraps around.
    sf_command(file, SFC_SET_CLIPPING, nullptr, SF_TRUE);
    const auto count = static_cast<sf_count_t>(samples.size());
    const sf_count_t written = sf_writef_double(file, samples.data(), count);
    const std::string reason = sf_strerror(file);
    const int closed = sf_close(file);
    if (written != count)
      throw std::runtime_error("wrote " + std::to_string(written) + " of " + std::to_string(count) +
                               " samples: " + reason);
    if (closed != 0) throw std::runtime_error("closing the file failed: " + std::string(sf_error_number(closed)));
  });
}

}  // namespace nfield::io
