// SPDX-License-Identifier: MIT
// H5Reader: datasets and attributes of any HDF5 file, checked for type and shape.
#include <algorithm>
#include <utility>
#include <vector>

#include "io/hdf5_detail.h"
#include "io/hdf5_file.h"

namespace nfield::io {

using namespace hdf5_detail;

struct H5Reader::Impl {
  std::filesystem::path path;
  Id file;

  [[noreturn]] void error(const std::string& message) const {
    throw H5Error(path.string() + ": " + message);
  }

  Id open_dataset(std::string_view name, std::string* clean_out = nullptr) const {
    const std::string clean = clean_name(name, path, false);
    Id object = open_object(file.get(), clean);
    if (kind_of(object) != H5I_DATASET) error("no dataset '" + clean + "'");
    if (clean_out) *clean_out = clean;
    return object;
  }

  std::vector<std::uint64_t> shape_of(hid_t dataset, const std::string& name) const {
    Id space = checked(H5Dget_space(dataset), H5Sclose, path, "cannot read the shape of '" + name + "'");
    const int rank = H5Sget_simple_extent_ndims(space.get());
    if (rank < 0) fail(path, "cannot read the shape of '" + name + "'");
    std::vector<hsize_t> dims(static_cast<std::size_t>(rank));
    H5Sget_simple_extent_dims(space.get(), dims.data(), nullptr);
    return {dims.begin(), dims.end()};
  }

  H5Type type_of(hid_t dataset, const std::string& name) const {
    Id type = checked(H5Dget_type(dataset), H5Tclose, path, "cannot read the type of '" + name + "'");
    return stored_type(type.get(), path, name);
  }

  // Reads dataset `name` of rank `rank` as `wanted` into storage from `allocate(dims)`.
  template <class Allocate>
  void read(std::string_view name, std::size_t rank, H5Type wanted, Allocate allocate) const {
    std::string clean;
    Id dataset = open_dataset(name, &clean);
    const std::vector<std::uint64_t> dims = shape_of(dataset.get(), clean);
    if (dims.size() != rank)
      error("dataset '" + clean + "' has rank " + std::to_string(dims.size()) + ", expected " +
            std::to_string(rank));
    const H5Type stored = type_of(dataset.get(), clean);
    if (wanted != stored && wanted != H5Type::float64)
      error("dataset '" + clean + "' holds " + std::string(to_string(stored)) +
            ", cannot read it as " + std::string(to_string(wanted)) + " (only as " +
            std::string(to_string(stored)) + " or float64)");
    void* data = allocate(dims);
    std::uint64_t count = 1;
    for (std::uint64_t d : dims) count *= d;
    if (count > 0)
      check(H5Dread(dataset.get(), memory_type(wanted), H5S_ALL, H5S_ALL, H5P_DEFAULT, data),
            path, "cannot read dataset '" + clean + "'");
  }

  Id open_attribute(std::string_view object, std::string_view name,
                    std::string* label_out) const {
    const std::string clean = clean_name(object, path, true);
    Id target = open_object(file.get(), clean);
    if (!target.valid()) error("no dataset or group '" + clean + "'");
    const std::string attribute(name);
    *label_out = "attribute '" + attribute + "' of '" + object_label(clean) + "'";
    if (H5Aexists(target.get(), attribute.c_str()) <= 0) {
      H5Eclear2(H5E_DEFAULT);
      error("no " + *label_out);
    }
    return checked(H5Aopen(target.get(), attribute.c_str(), H5P_DEFAULT), H5Aclose, path,
                   "cannot open " + *label_out);
  }

  // Reads a numeric attribute as double or int64 into a vector.
  template <class T>
  std::vector<T> read_numbers(std::string_view object, std::string_view name,
                              bool single) const {
    std::string label;
    Id attribute = open_attribute(object, name, &label);
    Id type = checked(H5Aget_type(attribute.get()), H5Tclose, path, "cannot read " + label);
    const H5T_class_t type_class = H5Tget_class(type.get());
    const bool integer_wanted = std::is_same_v<T, std::int64_t>;
    if (type_class != H5T_INTEGER && (integer_wanted || type_class != H5T_FLOAT))
      error(label + " is not " + (integer_wanted ? "an integer" : "a number"));
    Id space = checked(H5Aget_space(attribute.get()), H5Sclose, path, "cannot read " + label);
    const hssize_t count = H5Sget_simple_extent_npoints(space.get());
    if (count < 0) fail(path, "cannot read " + label);
    if (single && count != 1)
      error(label + " holds " + std::to_string(count) + " values, expected one");
    std::vector<T> values(static_cast<std::size_t>(count));
    if (count > 0)
      check(H5Aread(attribute.get(), integer_wanted ? H5T_NATIVE_INT64 : H5T_NATIVE_DOUBLE,
                    values.data()),
            path, "cannot read " + label);
    return values;
  }

  // A string attribute, variable-length or fixed-length (h5py's str and numpy's S types):
  // exactly one string when `single`, else a 1-D array of them (or one).
  std::vector<std::string> read_strings(std::string_view object, std::string_view name,
                                        bool single) const {
    std::string label;
    Id attribute = open_attribute(object, name, &label);
    Id type = checked(H5Aget_type(attribute.get()), H5Tclose, path, "cannot read " + label);
    if (H5Tget_class(type.get()) != H5T_STRING)
      error(label + " is not " + (single ? "a string" : "a string or a list of strings"));
    Id space = checked(H5Aget_space(attribute.get()), H5Sclose, path, "cannot read " + label);
    const hssize_t count = H5Sget_simple_extent_npoints(space.get());
    if (count < 0) fail(path, "cannot read " + label);
    if (single && count != 1) error(label + " holds several strings, expected one");
    const auto n = static_cast<std::size_t>(count);
    Id memory = checked(H5Tcopy(type.get()), H5Tclose, path, "cannot read " + label);
    std::vector<std::string> out;
    if (n == 0) return out;
    if (H5Tis_variable_str(type.get()) > 0) {
      std::vector<char*> texts(n, nullptr);
      const herr_t status = H5Aread(attribute.get(), memory.get(), texts.data());
      for (char* text : texts) {
        out.emplace_back(text ? text : "");
        H5free_memory(text);
      }
      check(status, path, "cannot read " + label);
      return out;
    }
    const std::size_t size = H5Tget_size(type.get());
    std::string buffer(size * n, '\0');
    check(H5Aread(attribute.get(), memory.get(), buffer.data()), path, "cannot read " + label);
    for (std::size_t i = 0; i < n; ++i) {
      std::string text = buffer.substr(i * size, size);
      text.erase(std::find(text.begin(), text.end(), '\0'), text.end());
      if (H5Tget_strpad(type.get()) == H5T_STR_SPACEPAD) text.erase(text.find_last_not_of(' ') + 1);
      out.push_back(std::move(text));
    }
    return out;
  }
};

H5Reader::H5Reader(std::filesystem::path path) : impl_(std::make_unique<Impl>()) {
  silence_hdf5();
  impl_->path = std::move(path);
  std::error_code ec;
  if (!std::filesystem::exists(impl_->path, ec)) impl_->error("no such file");
  if (!std::filesystem::is_regular_file(impl_->path, ec)) impl_->error("not a regular file");
#if H5_VERSION_GE(1, 12, 0)
  const htri_t is_hdf5 = H5Fis_accessible(impl_->path.c_str(), H5P_DEFAULT);
#else
  const htri_t is_hdf5 = H5Fis_hdf5(impl_->path.c_str());
#endif
  H5Eclear2(H5E_DEFAULT);
  if (is_hdf5 <= 0) impl_->error("not an HDF5 file");
  impl_->file = checked(H5Fopen(impl_->path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT), H5Fclose,
                        impl_->path, "cannot open");
}

H5Reader::~H5Reader() = default;
H5Reader::H5Reader(H5Reader&&) noexcept = default;
H5Reader& H5Reader::operator=(H5Reader&&) noexcept = default;

const std::filesystem::path& H5Reader::path() const { return impl_->path; }

std::vector<std::string> H5Reader::dataset_names() const {
  std::vector<std::string> names;
  // A generic lambda converts to whichever H5L_iterate_t this HDF5 version declares.
  const auto visit = [](hid_t group, const char* name, const auto*, void* data) -> herr_t {
    Id object(H5Oopen(group, name, H5P_DEFAULT), H5Oclose);
    if (!object.valid())
      H5Eclear2(H5E_DEFAULT);  // a dangling link
    else if (H5Iget_type(object.get()) == H5I_DATASET)
      static_cast<std::vector<std::string>*>(data)->emplace_back(name);
    return 0;
  };
  check(H5Lvisit(impl_->file.get(), H5_INDEX_NAME, H5_ITER_INC, visit, &names), impl_->path,
        "cannot list the file");
  std::sort(names.begin(), names.end());
  return names;
}

bool H5Reader::has_dataset(std::string_view name) const {
  return kind_of(open_object(impl_->file.get(), clean_name(name, impl_->path, false))) ==
         H5I_DATASET;
}

bool H5Reader::has_group(std::string_view name) const {
  return kind_of(open_object(impl_->file.get(), clean_name(name, impl_->path, true))) ==
         H5I_GROUP;
}

std::vector<std::uint64_t> H5Reader::shape(std::string_view name) const {
  std::string clean;
  Id dataset = impl_->open_dataset(name, &clean);
  return impl_->shape_of(dataset.get(), clean);
}

H5Type H5Reader::type(std::string_view name) const {
  std::string clean;
  Id dataset = impl_->open_dataset(name, &clean);
  return impl_->type_of(dataset.get(), clean);
}

template <H5Scalar T>
Eigen::Matrix<T, Eigen::Dynamic, Eigen::Dynamic> H5Reader::read_matrix(
    std::string_view name) const {
  Eigen::Matrix<T, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> rows;
  impl_->read(name, 2, h5_type_of<T>(), [&](const std::vector<std::uint64_t>& dims) {
    rows.resize(static_cast<Eigen::Index>(dims[0]), static_cast<Eigen::Index>(dims[1]));
    return static_cast<void*>(rows.data());
  });
  return rows;
}

template <H5Scalar T>
Eigen::Matrix<T, Eigen::Dynamic, 1> H5Reader::read_vector(std::string_view name) const {
  Eigen::Matrix<T, Eigen::Dynamic, 1> values;
  impl_->read(name, 1, h5_type_of<T>(), [&](const std::vector<std::uint64_t>& dims) {
    values.resize(static_cast<Eigen::Index>(dims[0]));
    return static_cast<void*>(values.data());
  });
  return values;
}

bool H5Reader::has_attribute(std::string_view object, std::string_view name) const {
  Id target = open_object(impl_->file.get(), clean_name(object, impl_->path, true));
  if (!target.valid()) return false;
  const htri_t exists = H5Aexists(target.get(), std::string(name).c_str());
  H5Eclear2(H5E_DEFAULT);
  return exists > 0;
}

std::vector<std::string> H5Reader::attribute_names(std::string_view object) const {
  const std::string clean = clean_name(object, impl_->path, true);
  Id target = open_object(impl_->file.get(), clean);
  if (!target.valid()) impl_->error("no dataset or group '" + clean + "'");
  std::vector<std::string> names;
  const auto visit = [](hid_t, const char* name, const auto*, void* data) -> herr_t {
    static_cast<std::vector<std::string>*>(data)->emplace_back(name);
    return 0;
  };
  hsize_t index = 0;
  check(H5Aiterate2(target.get(), H5_INDEX_NAME, H5_ITER_INC, &index, visit, &names),
        impl_->path, "cannot list the attributes of '" + object_label(clean) + "'");
  return names;
}

template <class T>
T H5Reader::read_attribute(std::string_view object, std::string_view name) const {
  if constexpr (std::is_same_v<T, std::string>)
    return impl_->read_strings(object, name, true).front();
  else if constexpr (std::is_same_v<T, std::vector<std::string>>)
    return impl_->read_strings(object, name, false);
  else if constexpr (std::is_same_v<T, double> || std::is_same_v<T, std::int64_t>)
    return impl_->read_numbers<T>(object, name, true).front();
  else
    return impl_->read_numbers<typename T::value_type>(object, name, false);
}

template std::string H5Reader::read_attribute<std::string>(std::string_view,
                                                           std::string_view) const;
template std::vector<std::string> H5Reader::read_attribute<std::vector<std::string>>(
    std::string_view, std::string_view) const;
template double H5Reader::read_attribute<double>(std::string_view, std::string_view) const;
template std::int64_t H5Reader::read_attribute<std::int64_t>(std::string_view,
                                                             std::string_view) const;
template std::vector<double> H5Reader::read_attribute<std::vector<double>>(
    std::string_view, std::string_view) const;
template std::vector<std::int64_t> H5Reader::read_attribute<std::vector<std::int64_t>>(
    std::string_view, std::string_view) const;

#define NFIELD_H5_SCALAR(T)                                                            \
  template Eigen::Matrix<T, Eigen::Dynamic, Eigen::Dynamic> H5Reader::read_matrix<T>( \
      std::string_view) const;                                                         \
  template Eigen::Matrix<T, Eigen::Dynamic, 1> H5Reader::read_vector<T>(std::string_view) const;
NFIELD_H5_SCALAR(float)
NFIELD_H5_SCALAR(double)
NFIELD_H5_SCALAR(std::int32_t)
NFIELD_H5_SCALAR(std::int64_t)
NFIELD_H5_SCALAR(std::uint64_t)
#undef NFIELD_H5_SCALAR

}  // namespace nfield::io
