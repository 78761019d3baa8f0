// SPDX-License-Identifier: MIT
#pragma once
// HDF5 files of named arrays and attributes (checkpoints, sampled data), laid out so that
// h5py reads them as one would expect:
//
//   H5Writer out("run/checkpoint.h5");
//   out.write("layers/0/weight", W);                 // W: Eigen matrix, rows x cols
//   out.write("rng/state", std::vector<std::uint64_t>{...});
//   out.write_attribute("/", "step", 3000);
//   out.commit();                                     // only now does the file appear
//
//   >>> h5py.File("run/checkpoint.h5")["layers/0/weight"][i, j] == W(i, j)
//
// * Matrices (Eigen types not fixed at compile time to one row or column) become 2-D
//   datasets of shape (rows, cols) whatever their storage order; vectors, spans and
//   std::vectors become 1-D. A MatrixXd with one column is still 2-D, shape (n, 1).
// * Element types: float, double, int32, int64, uint64, stored little-endian. Values
//   round-trip bit for bit.
// * Names are slash-separated paths ("layers/0/weight"); missing groups are created.
//   Attributes hang on "/" (the file) or on a dataset or group.
// * H5Writer writes PATH.tmp and renames it to PATH on commit(); a writer destroyed
//   without commit() (an exception, a crash) deletes the temporary and leaves any
//   existing PATH untouched, so a half-written file never has the final name.
// * Every failure is an H5Error whose message starts with the file name, e.g.
//   `ckpt.h5: no dataset 'layers/0/weight'`. HDF5's own error printing to stderr is
//   switched off process-wide by the first H5Writer or H5Reader.
// * The HDF5 library is not thread-safe: use these classes from one thread at a time.

#include <concepts>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

#include <Eigen/Core>

namespace nfield::io {

class H5Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

enum class H5Type { float32, float64, int32, int64, uint64 };
std::string_view to_string(H5Type type);

template <class T>
concept H5Scalar = std::is_same_v<T, float> || std::is_same_v<T, double> ||
                   std::is_same_v<T, std::int32_t> || std::is_same_v<T, std::int64_t> ||
                   std::is_same_v<T, std::uint64_t>;

template <H5Scalar T>
constexpr H5Type h5_type_of() {
  if constexpr (std::is_same_v<T, float>) return H5Type::float32;
  if constexpr (std::is_same_v<T, double>) return H5Type::float64;
  if constexpr (std::is_same_v<T, std::int32_t>) return H5Type::int32;
  if constexpr (std::is_same_v<T, std::int64_t>) return H5Type::int64;
  if constexpr (std::is_same_v<T, std::uint64_t>) return H5Type::uint64;
}

class H5Writer {
 public:
  // Creates (truncates) PATH.tmp. The folder of PATH must exist.
  explicit H5Writer(std::filesystem::path path);
  // Without commit(): closes and deletes PATH.tmp. Never throws.
  ~H5Writer();
  H5Writer(H5Writer&&) noexcept;
  H5Writer& operator=(H5Writer&&) noexcept;

  // A dataset named `name` (which must not exist yet) holding `array`.
  template <class Derived>
  void write(std::string_view name, const Eigen::DenseBase<Derived>& array);
  template <H5Scalar T>
  void write(std::string_view name, std::span<const T> values) {
    write_raw(name, h5_type_of<T>(), {values.size()}, values.data());
  }
  template <H5Scalar T>
  void write(std::string_view name, const std::vector<T>& values) {
    write(name, std::span<const T>(values));
  }

  // An empty group (groups on the way to a dataset are made by write).
  void create_group(std::string_view name);

  // An attribute on `object`: "/" (or "") for the file, else a dataset or group written
  // before. An existing attribute of that name is replaced. Strings are stored as UTF-8
  // variable-length strings (str in h5py), numbers as scalars, spans as 1-D arrays.
  void write_attribute(std::string_view object, std::string_view name, std::string_view value);
  void write_attribute(std::string_view object, std::string_view name, double value);
  void write_attribute(std::string_view object, std::string_view name, std::int64_t value);
  void write_attribute(std::string_view object, std::string_view name,
                       std::span<const double> values);
  void write_attribute(std::string_view object, std::string_view name,
                       std::span<const std::int64_t> values);
  // A 1-D array of UTF-8 strings (a list of str in h5py), e.g. the names of a table's columns.
  void write_attribute(std::string_view object, std::string_view name,
                       std::span<const std::string> values);
  void write_attribute(std::string_view object, std::string_view name,
                       const std::vector<std::string>& values) {
    write_attribute(object, name, std::span<const std::string>(values));
  }
  template <std::integral T>
    requires(!std::is_same_v<T, bool> && !std::is_same_v<T, std::int64_t>)
  void write_attribute(std::string_view object, std::string_view name, T value) {
    write_attribute(object, name, static_cast<std::int64_t>(value));
  }
  void write_attribute(std::string_view object, std::string_view name, const char* value) {
    write_attribute(object, name, std::string_view(value));
  }

  // Flushes to disk, closes and renames PATH.tmp to PATH (replacing it atomically).
  // No writes are possible afterwards.
  void commit();

  const std::filesystem::path& path() const;

 private:
  void write_raw(std::string_view name, H5Type type, std::vector<std::uint64_t> shape,
                 const void* data);
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

class H5Reader {
 public:
  // Opens PATH read-only: `PATH: no such file`, `PATH: not an HDF5 file` otherwise.
  explicit H5Reader(std::filesystem::path path);
  ~H5Reader();
  H5Reader(H5Reader&&) noexcept;
  H5Reader& operator=(H5Reader&&) noexcept;

  // Every dataset in the file, as "group/name" paths in sorted order.
  std::vector<std::string> dataset_names() const;
  bool has_dataset(std::string_view name) const;
  bool has_group(std::string_view name) const;
  // Dimensions as h5py reports them; empty for a scalar dataset.
  std::vector<std::uint64_t> shape(std::string_view name) const;
  H5Type type(std::string_view name) const;

  // A rank-2 dataset (read_matrix) or rank-1 dataset (read_vector), read as T: either the
  // stored type, or double from any stored type (converted). Anything else, and a wrong
  // rank, is an H5Error naming the dataset.
  template <H5Scalar T = double>
  Eigen::Matrix<T, Eigen::Dynamic, Eigen::Dynamic> read_matrix(std::string_view name) const;
  template <H5Scalar T = double>
  Eigen::Matrix<T, Eigen::Dynamic, 1> read_vector(std::string_view name) const;

  // Attributes of "/" (the file), a dataset or a group. T is one of std::string, double,
  // std::int64_t, std::vector<double>, std::vector<std::int64_t>, std::vector<std::string>;
  // a double may be read from an integer attribute, not the other way round. Strings may be
  // stored variable- or fixed-length (h5py's str, numpy's S); a vector<string> is also read
  // from a single string (as one element).
  bool has_attribute(std::string_view object, std::string_view name) const;
  std::vector<std::string> attribute_names(std::string_view object) const;
  template <class T>
  T read_attribute(std::string_view object, std::string_view name) const;

  const std::filesystem::path& path() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

template <class Derived>
void H5Writer::write(std::string_view name, const Eigen::DenseBase<Derived>& array) {
  using T = typename Derived::Scalar;
  static_assert(H5Scalar<T>, "H5Writer::write: element type must be float, double, int32, "
                             "int64 or uint64");
  if constexpr (Derived::IsVectorAtCompileTime) {
    const Eigen::Matrix<T, Eigen::Dynamic, 1> flat = array.derived().reshaped();
    write_raw(name, h5_type_of<T>(), {static_cast<std::uint64_t>(flat.size())}, flat.data());
  } else {
    const Eigen::Matrix<T, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> rows = array.derived();
    write_raw(name, h5_type_of<T>(),
              {static_cast<std::uint64_t>(rows.rows()), static_cast<std::uint64_t>(rows.cols())},
              rows.data());
  }
}

}  // namespace nfield::io
