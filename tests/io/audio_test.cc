// SPDX-License-Identifier: MIT
#include "io/audio.h"

#include <gtest/gtest.h>
#include <sndfile.h>

#include <cmath>
#include <filesystem>
#include <limits>
#include <numbers>
#include <vector>

#include "tests/io/io_test_paths.h"

namespace nfield::io {
namespace {

TEST(ReadAudio, ReadsSixteenBitStereoAsTheMeanOfItsChannelsInUnitRange) {
  const auto path = testing::scratch_dir() / "tone.wav";
  SF_INFO info{};
  info.samplerate = 8000;
  info.channels = 2;
  info.format = SF_FORMAT_WAV | SF_FORMAT_PCM_16;
  std::vector<short> frames;
  for (int n = 0; n < 800; ++n) {
    frames.push_back(static_cast<short>(std::lround(16384 * std::sin(2 * std::numbers::pi * 440 * n / 8000.0))));
    frames.push_back(-8192);
  }
  SNDFILE* file = sf_open(path.c_str(), SFM_WRITE, &info);
  ASSERT_NE(file, nullptr) << sf_strerror(nullptr);
  ASSERT_EQ(sf_writef_short(file, frames.data(), 800), 800);
  sf_close(file);

  const AudioClip clip = read_audio(path);
  EXPECT_EQ(clip.sample_rate, 8000);
  ASSERT_EQ(clip.samples.size(), 800);
  EXPECT_DOUBLE_EQ(clip.seconds(), 0.1);
  for (int n = 0; n < 800; ++n)
    EXPECT_DOUBLE_EQ(clip.samples(n), 0.5 * (frames[2 * n] / 32768.0 - 0.25)) << n;
}

TEST(ReadAudio, ReadsTheCountingClip) {
  const AudioClip clip = read_audio(testing::data_path("audio/counting_espeak.wav"));
  EXPECT_EQ(clip.sample_rate, 16000);
  EXPECT_NEAR(clip.seconds(), 6.66, 0.01);
  EXPECT_LE(clip.samples.cwiseAbs().maxCoeff(), 1.0);
  EXPECT_GT(clip.samples.cwiseAbs().maxCoeff(), 0.1);
}

TEST(ReadAudio, NamesTheFileThatIsNotSound) {
  const auto path = testing::scratch_dir() / "not_sound.wav";
  testing::write_text(path, "hello");
  try {
    read_audio(path);
    FAIL();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("not_sound.wav"), std::string::npos) << e.what();
  }
  EXPECT_THROW(read_audio(testing::scratch_dir() / "missing.wav"), std::runtime_error);
}

TEST(WriteAudio, WritesSixteenBitWavThatReadsBackAtItsRateAndLength) {
  const auto dir = testing::scratch_dir();
  AudioClip clip{22050, Eigen::VectorXd::LinSpaced(1001, -1.0, 1.0)};
  clip.samples(3) = 2.0;                                        // clipped to full scale
  clip.samples(4) = std::numeric_limits<double>::quiet_NaN();  // written as 0
  write_audio(dir / "ramp.wav", clip);
  SF_INFO info{};
  SNDFILE* file = sf_open((dir / "ramp.wav").c_str(), SFM_READ, &info);
  ASSERT_NE(file, nullptr);
  sf_close(file);
  EXPECT_EQ(info.format, SF_FORMAT_WAV | SF_FORMAT_PCM_16);
  EXPECT_EQ(info.channels, 1);
  const AudioClip back = read_audio(dir / "ramp.wav");
  EXPECT_EQ(back.sample_rate, 22050);
  ASSERT_EQ(back.samples.size(), 1001);
  clip.samples(3) = 1.0;
  clip.samples(4) = 0.0;
  // 16 bits: within a step of 2^-15 (libsndfile writes full scale as 32767, reads by 32768).
  EXPECT_LT((back.samples - clip.samples).cwiseAbs().maxCoeff(), 1.5 / 32768);
  EXPECT_THROW(write_audio(dir / "none.wav", AudioClip{22050, Eigen::VectorXd()}), std::invalid_argument);
  EXPECT_THROW(write_audio(dir / "rate.wav", AudioClip{0, clip.samples}), std::invalid_argument);
  EXPECT_THROW(write_audio(dir / "missing" / "ramp.wav", clip), std::runtime_error);
  EXPECT_FALSE(std::filesystem::exists(dir / "none.wav"));
}

}  // namespace
}  // namespace nfield::io
