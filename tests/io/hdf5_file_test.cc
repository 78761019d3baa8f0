// SPDX-License-Identifier: MIT
#include "io/hdf5_file.h"

#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <random>

#include <gtest/gtest.h>
#include <hdf5.h>

namespace nfield::io {
namespace {

namespace fs = std::filesystem;

fs::path scratch() {
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  const fs::path dir = fs::path(NFIELD_BINARY_DIR) / "test_scratch" / "io_hdf5" /
                       (std::string(info->test_suite_name()) + "." + info->name());
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

std::string read_bytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

void expect_error(const std::function<void()>& action, const std::string& expected) {
  try {
    action();
    ADD_FAILURE() << "no H5Error, expected " << expected;
  } catch (const H5Error& e) {
    EXPECT_EQ(std::string(e.what()), expected);
  }
}

template <class T>
bool same_bits(const T& a, const T& b) {
  return a.rows() == b.rows() && a.cols() == b.cols() &&
         std::memcmp(a.data(), b.data(), sizeof(typename T::Scalar) * a.size()) == 0;
}

// Awkward values: signed zero, subnormals, extremes, infinities, a NaN with a payload.
Eigen::MatrixXd awkward_doubles(int rows, int cols) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> uniform(-1e3, 1e3);
  Eigen::MatrixXd m(rows, cols);
  for (Eigen::Index i = 0; i < m.size(); ++i) m.data()[i] = uniform(rng);
  m(0, 0) = -0.0;
  m(1, 0) = std::numeric_limits<double>::denorm_min();
  m(2, 0) = std::numeric_limits<double>::max();
  m(0, 1) = -std::numeric_limits<double>::infinity();
  std::uint64_t payload = 0x7ff8000000abcdefULL;
  std::memcpy(&m(1, 1), &payload, sizeof payload);
  return m;
}

TEST(H5File, RoundTripsBitExactly) {
  const fs::path file = scratch() / "a.h5";
  const Eigen::MatrixXd doubles = awkward_doubles(3, 5);
  const Eigen::MatrixXf floats = doubles.cast<float>();
  Eigen::Matrix<double, -1, -1, Eigen::RowMajor> row_major = doubles;
  Eigen::Matrix<std::int32_t, -1, -1> ints(2, 3);
  ints << 1, -2, 3, std::numeric_limits<std::int32_t>::min(), 0,
      std::numeric_limits<std::int32_t>::max();
  const std::vector<std::uint64_t> words = {0, 1, std::numeric_limits<std::uint64_t>::max(),
                                            0x0123456789abcdefULL};
  Eigen::Matrix<std::int64_t, -1, 1> longs(3);
  longs << std::numeric_limits<std::int64_t>::min(), -1, std::numeric_limits<std::int64_t>::max();
  Eigen::RowVectorXf row(4);
  row << 1.5f, -2.25f, 1e-40f, 3e38f;
  {
    H5Writer out(file);
    out.write("doubles", doubles);
    out.write("/floats", floats);
    out.write("nested/deep/row_major", row_major);
    out.write("nested/ints", ints);
    out.write("rng/words", words);
    out.write("longs", longs);
    out.write("row", row);
    out.write("block", doubles.block(1, 1, 2, 3));
    out.write("empty", Eigen::MatrixXd(0, 3));
    out.commit();
  }
  H5Reader in(file);
  EXPECT_TRUE(same_bits(in.read_matrix<double>("doubles"), doubles));
  EXPECT_TRUE(same_bits(in.read_matrix<float>("floats"), floats));
  EXPECT_TRUE(same_bits(in.read_matrix<double>("nested/deep/row_major"), doubles));
  EXPECT_EQ(in.read_matrix<std::int32_t>("nested/ints"), ints);
  const Eigen::Matrix<std::uint64_t, -1, 1> read_words = in.read_vector<std::uint64_t>("rng/words");
  EXPECT_EQ(std::vector<std::uint64_t>(read_words.begin(), read_words.end()), words);
  EXPECT_EQ(in.read_vector<std::int64_t>("longs"), longs);
  EXPECT_TRUE(same_bits(Eigen::VectorXf(in.read_vector<float>("row")), Eigen::VectorXf(row.transpose())));
  EXPECT_TRUE(same_bits(in.read_matrix("block"), Eigen::MatrixXd(doubles.block(1, 1, 2, 3))));
  EXPECT_EQ(in.read_matrix("empty").rows(), 0);
  EXPECT_EQ(in.read_matrix("empty").cols(), 3);
  // Any stored type reads as double.
  const Eigen::MatrixXd widened = in.read_matrix<double>("floats");
  EXPECT_TRUE((widened.array() == floats.cast<double>().array() ||
               (widened.array().isNaN() && floats.cast<double>().array().isNaN()))
                  .all());
  EXPECT_EQ(in.read_matrix<double>("nested/ints"), ints.cast<double>());

  EXPECT_EQ(in.shape("doubles"), (std::vector<std::uint64_t>{3, 5}));
  EXPECT_EQ(in.shape("rng/words"), (std::vector<std::uint64_t>{4}));
  EXPECT_EQ(in.shape("row"), (std::vector<std::uint64_t>{4}));
  EXPECT_EQ(in.type("floats"), H5Type::float32);
  EXPECT_EQ(in.type("rng/words"), H5Type::uint64);
  EXPECT_EQ(in.dataset_names(),
            (std::vector<std::string>{"block", "doubles", "empty", "floats", "longs",
                                      "nested/deep/row_major", "nested/ints", "rng/words",
                                      "row"}));
  EXPECT_TRUE(in.has_dataset("nested/ints"));
  EXPECT_TRUE(in.has_dataset("/nested/ints"));
  EXPECT_FALSE(in.has_dataset("nested"));
  EXPECT_TRUE(in.has_group("nested/deep"));
  EXPECT_FALSE(in.has_group("nested/none/deeper"));
}

TEST(H5File, Attributes) {
  const fs::path file = scratch() / "attributes.h5";
  {
    H5Writer out(file);
    out.write("layers/0/weight", Eigen::MatrixXd::Identity(2, 2));
    out.create_group("meta/empty");
    out.write_attribute("/", "version", "0.1.0");
    out.write_attribute("", "step", 3000);
    out.write_attribute("/", "loss", 1.25e-3);
    out.write_attribute("/", "seeds", std::vector<std::int64_t>{1, -2, 3});
    out.write_attribute("layers/0/weight", "bounds", std::vector<double>{-1.5, 2.5});
    out.write_attribute("layers/0/weight", "unit", std::string("m/s \xc2\xb5"));
    out.write_attribute("meta/empty", "count", std::int64_t{-7});
    out.write_attribute("meta/empty", "none", std::vector<double>{});
    out.write_attribute("/", "step", 3001);  // replaces
    out.commit();
  }
  H5Reader in(file);
  EXPECT_EQ(in.read_attribute<std::string>("/", "version"), "0.1.0");
  EXPECT_EQ(in.read_attribute<std::int64_t>("/", "step"), 3001);
  EXPECT_EQ(in.read_attribute<double>("/", "step"), 3001.0);
  EXPECT_EQ(in.read_attribute<double>("", "loss"), 1.25e-3);
  EXPECT_EQ(in.read_attribute<std::vector<std::int64_t>>("/", "seeds"),
            (std::vector<std::int64_t>{1, -2, 3}));
  EXPECT_EQ(in.read_attribute<std::vector<double>>("layers/0/weight", "bounds"),
            (std::vector<double>{-1.5, 2.5}));
  EXPECT_EQ(in.read_attribute<std::string>("layers/0/weight", "unit"), "m/s \xc2\xb5");
  EXPECT_EQ(in.read_attribute<std::int64_t>("meta/empty", "count"), -7);
  EXPECT_TRUE(in.read_attribute<std::vector<double>>("meta/empty", "none").empty());
  EXPECT_EQ(in.attribute_names("/"),
            (std::vector<std::string>{"loss", "seeds", "step", "version"}));
  EXPECT_TRUE(in.has_attribute("layers/0/weight", "unit"));
  EXPECT_FALSE(in.has_attribute("layers/0/weight", "nope"));
  EXPECT_FALSE(in.has_attribute("no/such", "unit"));
  EXPECT_TRUE(in.has_group("meta/empty"));

  const std::string name = file.string();
  expect_error([&] { in.read_attribute<std::string>("/", "missing"); },
               name + ": no attribute 'missing' of '/'");
  expect_error([&] { in.read_attribute<std::int64_t>("/", "loss"); },
               name + ": attribute 'loss' of '/' is not an integer");
  expect_error([&] { in.read_attribute<double>("/", "seeds"); },
               name + ": attribute 'seeds' of '/' holds 3 values, expected one");
  expect_error([&] { in.read_attribute<std::string>("/", "loss"); },
               name + ": attribute 'loss' of '/' is not a string");
  expect_error([&] { in.read_attribute<double>("nothing", "x"); },
               name + ": no dataset or group 'nothing'");
}

// Lists of strings (the names of a table's columns): written as h5py writes a list of str,
// read back from that, from numpy's fixed-length S arrays (written here with the C API, as
// h5py stores np.array([b"x", b"u"])), and from a single string.
TEST(H5File, StringListAttributes) {
  const fs::path file = scratch() / "strings.h5";
  const std::vector<std::string> names = {"x", "y", "u (m) @ t=0.5", ""};
  {
    H5Writer out(file);
    out.write("table", Eigen::MatrixXd::Zero(2, 4));
    out.write_attribute("table", "columns", names);
    out.write_attribute("table", "none", std::vector<std::string>{});
    out.write_attribute("table", "one", "x,y");
    out.commit();
  }
  {  // a fixed-length, null-padded array of 3-byte strings
    const hid_t h5 = H5Fopen(file.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
    const hid_t dataset = H5Dopen2(h5, "table", H5P_DEFAULT);
    const hid_t type = H5Tcopy(H5T_C_S1);
    H5Tset_size(type, 3);
    H5Tset_strpad(type, H5T_STR_NULLPAD);
    const hsize_t dims[1] = {3};
    const hid_t space = H5Screate_simple(1, dims, nullptr);
    const hid_t attribute = H5Acreate2(dataset, "fixed", type, space, H5P_DEFAULT, H5P_DEFAULT);
    const char bytes[9] = {'x', 0, 0, 'y', 'y', 0, 'u', 'v', 'w'};
    ASSERT_GE(H5Awrite(attribute, type, bytes), 0);
    H5Aclose(attribute);
    H5Sclose(space);
    H5Tclose(type);
    H5Dclose(dataset);
    ASSERT_GE(H5Fclose(h5), 0);
  }
  H5Reader in(file);
  EXPECT_EQ(in.read_attribute<std::vector<std::string>>("table", "columns"), names);
  EXPECT_TRUE(in.read_attribute<std::vector<std::string>>("table", "none").empty());
  EXPECT_EQ(in.read_attribute<std::vector<std::string>>("table", "one"),
            (std::vector<std::string>{"x,y"}));
  EXPECT_EQ(in.read_attribute<std::vector<std::string>>("table", "fixed"),
            (std::vector<std::string>{"x", "yy", "uvw"}));
  EXPECT_EQ(in.read_attribute<std::string>("table", "one"), "x,y");
  const std::string name = file.string();
  expect_error([&] { in.read_attribute<std::string>("table", "columns"); },
               name + ": attribute 'columns' of 'table' holds several strings, expected one");
  expect_error([&] { in.read_attribute<std::vector<std::string>>("/", "missing"); },
               name + ": no attribute 'missing' of '/'");
}

TEST(H5File, ErrorsNameFileAndDataset) {
  const fs::path dir = scratch();
  const fs::path file = dir / "e.h5";
  {
    H5Writer out(file);
    out.write("layers/0/bias", Eigen::VectorXd::Ones(3));
    out.write("w", Eigen::MatrixXf::Ones(2, 2));
    expect_error([&] { out.write("w", Eigen::MatrixXf::Ones(2, 2)); },
                 file.string() + ": 'w' already exists");
    expect_error([&] { out.write("w/inside", Eigen::MatrixXf::Ones(2, 2)); },
                 file.string() + ": 'w' is a dataset, not a group");
    expect_error([&] { out.write("a//b", Eigen::VectorXd::Ones(1)); },
                 file.string() + ": invalid name 'a//b'");
    expect_error([&] { out.write_attribute("nowhere", "x", 1.0); },
                 file.string() + ": no dataset or group 'nowhere' to put an attribute on");
    out.commit();
    expect_error([&] { out.write("late", Eigen::VectorXd::Ones(1)); },
                 file.string() + ": already committed, cannot write more");
  }
  H5Reader in(file);
  const std::string name = file.string();
  expect_error([&] { in.read_matrix("layers/0/weight"); }, name + ": no dataset 'layers/0/weight'");
  expect_error([&] { in.read_matrix("layers/0"); }, name + ": no dataset 'layers/0'");
  expect_error([&] { in.read_matrix("layers/0/bias"); },
               name + ": dataset 'layers/0/bias' has rank 1, expected 2");
  expect_error([&] { in.read_vector("w"); }, name + ": dataset 'w' has rank 2, expected 1");
  expect_error([&] { in.read_matrix<std::int32_t>("w"); },
               name + ": dataset 'w' holds float32, cannot read it as int32 (only as float32 or "
                      "float64)");

  std::ofstream(dir / "text.h5") << "not hdf5 at all";
  expect_error([&] { H5Reader bad(dir / "text.h5"); }, (dir / "text.h5").string() + ": not an HDF5 file");
  expect_error([&] { H5Reader bad(dir / "missing.h5"); }, (dir / "missing.h5").string() + ": no such file");
  try {
    H5Writer bad(dir / "no_folder" / "x.h5");
    ADD_FAILURE();
  } catch (const H5Error& e) {
    EXPECT_EQ(std::string(e.what()).rfind((dir / "no_folder" / "x.h5").string() + ": cannot create", 0), 0u)
        << e.what();
  }
}

TEST(H5File, CommitIsAtomic) {
  const fs::path dir = scratch();
  const fs::path file = dir / "ckpt.h5";
  {
    H5Writer out(file);
    out.write("x", Eigen::VectorXd::Constant(2, 1.0));
    EXPECT_TRUE(fs::exists(dir / "ckpt.h5.tmp"));
    EXPECT_FALSE(fs::exists(file));
  }  // abandoned: nothing left behind
  EXPECT_FALSE(fs::exists(file));
  EXPECT_FALSE(fs::exists(dir / "ckpt.h5.tmp"));

  {
    H5Writer out(file);
    out.write("x", Eigen::VectorXd::Constant(2, 1.0));
    out.commit();
  }
  try {
    H5Writer out(file);
    out.write("x", Eigen::VectorXd::Constant(2, 2.0));
    throw std::runtime_error("crash while writing");
  } catch (const std::runtime_error&) {
  }
  EXPECT_EQ(H5Reader(file).read_vector("x"), Eigen::VectorXd::Constant(2, 1.0));  // old file kept
  EXPECT_FALSE(fs::exists(dir / "ckpt.h5.tmp"));
  {
    H5Writer out(file);
    out.write("x", Eigen::VectorXd::Constant(2, 3.0));
    H5Writer moved = std::move(out);
    moved.commit();
  }
  EXPECT_EQ(H5Reader(file).read_vector("x"), Eigen::VectorXd::Constant(2, 3.0));
}

TEST(H5File, EqualContentsGiveEqualFiles) {
  const fs::path dir = scratch();
  for (const char* name : {"one.h5", "two.h5"}) {
    H5Writer out(dir / name);
    out.write("layers/0/weight", awkward_doubles(4, 3));
    out.write_attribute("/", "step", 10);
    out.commit();
  }
  EXPECT_EQ(read_bytes(dir / "one.h5"), read_bytes(dir / "two.h5"));
}

TEST(H5File, ReadableByH5py) {
  if (std::system("/usr/bin/python3 -c 'import h5py' > /dev/null 2>&1") != 0)
    GTEST_SKIP() << "python3 with h5py not available";
  const fs::path dir = scratch();
  const fs::path file = dir / "py.h5";
  Eigen::MatrixXd m(2, 3);
  m << 1, 2, 3, 4, 5, 6.5;
  Eigen::MatrixXf f = m.cast<float>() * 0.1f;
  {
    H5Writer out(file);
    out.write("layers/0/weight", m);
    out.write("single", f);
    out.write("words", std::vector<std::uint64_t>{1, std::numeric_limits<std::uint64_t>::max()});
    out.write("v", Eigen::Vector3d(1, 2, 3));
    out.write_attribute("/", "version", "0.1.0");
    out.write_attribute("/", "step", 42);
    out.write_attribute("layers/0/weight", "bounds", std::vector<double>{-1, 1});
    out.commit();
  }
  const fs::path script = dir / "check.py";
  std::ofstream(script) << R"(import sys, h5py, numpy as np
f = h5py.File(sys.argv[1], "r")
w = f["layers/0/weight"]
assert w.shape == (2, 3), w.shape
assert w.dtype == np.float64
assert w[1, 2] == 6.5 and w[0, 1] == 2.0 and w[1, 0] == 4.0
s = f["single"]
assert s.dtype == np.float32 and s.shape == (2, 3)
assert s[1, 2] == np.float32(np.float32(6.5) * np.float32(0.1)), s[1, 2]
assert f["words"].dtype == np.uint64 and int(f["words"][1]) == 2**64 - 1
assert f["v"].shape == (3,) and list(f["v"][:]) == [1.0, 2.0, 3.0]
assert f.attrs["version"] == "0.1.0", repr(f.attrs["version"])
assert f.attrs["step"] == 42
assert list(w.attrs["bounds"]) == [-1.0, 1.0]
print("ok")
)";
  const std::string command =
      "/usr/bin/python3 " + script.string() + " " + file.string() + " > " +
      (dir / "out.txt").string() + " 2>&1";
  EXPECT_EQ(std::system(command.c_str()), 0) << read_bytes(dir / "out.txt");
}

}  // namespace
}  // namespace nfield::io
