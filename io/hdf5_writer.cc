// SPDX-License-Identifier: MIT
// H5Writer: datasets and attributes written to a temporary file that commit() renames.
#include <fcntl.h>
#include <unistd.h>

#include <utility>
#include <vector>

#include "io/hdf5_detail.h"
#include "io/hdf5_file.h"

namespace nfield::io {

using namespace hdf5_detail;

struct H5Writer::Impl {
  std::filesystem::path path;
  std::filesystem::path temporary;
  Id file;
  bool committed = false;

  void require_open() const {
    if (committed) throw H5Error(path.string() + ": already committed, cannot write more");
  }

  // Groups along `name` up to (not including) its last part, created as needed, without
  // timestamps so that equal contents give equal files.
  void make_parents(const std::string& name) {
    std::size_t slash = 0;
    while ((slash = name.find('/', slash)) != std::string::npos) {
      make_group(name.substr(0, slash));
      ++slash;
    }
  }

  void make_group(const std::string& name) {
    Id existing = open_object(file.get(), name);
    if (existing.valid()) {
      if (kind_of(existing) != H5I_GROUP)
        throw H5Error(path.string() + ": '" + name + "' is a dataset, not a group");
      return;
    }
    Id properties = checked(H5Pcreate(H5P_GROUP_CREATE), H5Pclose, path, "cannot create group");
    H5Pset_obj_track_times(properties.get(), false);
    checked(H5Gcreate2(file.get(), name.c_str(), H5P_DEFAULT, properties.get(), H5P_DEFAULT),
            H5Gclose, path, "cannot create group '" + name + "'");
  }

  Id open_target(std::string_view object) {
    const std::string name = clean_name(object, path, true);
    Id target = open_object(file.get(), name);
    if (!target.valid())
      throw H5Error(path.string() + ": no dataset or group '" + name +
                    "' to put an attribute on");
    return target;
  }

  void write_attribute(std::string_view object, std::string_view name, hid_t stored,
                       hid_t in_memory, hid_t space, const void* data) {
    require_open();
    Id target = open_target(object);
    const std::string attribute(name);
    if (attribute.empty()) throw H5Error(path.string() + ": empty attribute name");
    if (H5Aexists(target.get(), attribute.c_str()) > 0)
      check(H5Adelete(target.get(), attribute.c_str()), path,
            "cannot replace attribute '" + attribute + "'");
    Id handle = checked(H5Acreate2(target.get(), attribute.c_str(), stored, space, H5P_DEFAULT,
                                   H5P_DEFAULT),
                        H5Aclose, path, "cannot create attribute '" + attribute + "'");
    check(H5Awrite(handle.get(), in_memory, data), path,
          "cannot write attribute '" + attribute + "'");
  }

  // UTF-8 variable-length strings: a scalar when `scalar`, else a 1-D array.
  void write_strings(std::string_view object, std::string_view name,
                     std::span<const std::string> values, bool scalar) {
    Id type = checked(H5Tcopy(H5T_C_S1), H5Tclose, path, "cannot create string type");
    check(H5Tset_size(type.get(), H5T_VARIABLE), path, "cannot create string type");
    check(H5Tset_cset(type.get(), H5T_CSET_UTF8), path, "cannot create string type");
    const hsize_t dims[1] = {values.size()};
    Id space = scalar ? checked(H5Screate(H5S_SCALAR), H5Sclose, path, "cannot create space")
                      : checked(H5Screate_simple(1, dims, nullptr), H5Sclose, path,
                                "cannot create space");
    std::vector<const char*> pointers;
    for (const std::string& value : values) pointers.push_back(value.c_str());
    static const char* const nothing = "";
    write_attribute(object, name, type.get(), type.get(), space.get(),
                    pointers.empty() ? &nothing : pointers.data());
  }

  void write_numbers(std::string_view object, std::string_view name, H5Type type,
                     const void* data, std::size_t count, bool scalar) {
    const hsize_t dims[1] = {count};
    Id space = scalar ? checked(H5Screate(H5S_SCALAR), H5Sclose, path, "cannot create space")
                      : checked(H5Screate_simple(1, dims, nullptr), H5Sclose, path,
                                "cannot create space");
    static const double nothing = 0;
    write_attribute(object, name, file_type(type), memory_type(type), space.get(),
                    count == 0 ? &nothing : data);
  }
};

H5Writer::H5Writer(std::filesystem::path path) : impl_(std::make_unique<Impl>()) {
  silence_hdf5();
  impl_->path = std::move(path);
  impl_->temporary = impl_->path;
  impl_->temporary += ".tmp";
  impl_->file = checked(H5Fcreate(impl_->temporary.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT,
                                  H5P_DEFAULT),
                        H5Fclose, impl_->path,
                        "cannot create '" + impl_->temporary.string() + "'");
}

H5Writer::~H5Writer() {
  if (!impl_ || impl_->committed) return;
  impl_->file.close();
  H5Eclear2(H5E_DEFAULT);
  std::error_code ignored;
  std::filesystem::remove(impl_->temporary, ignored);
}

H5Writer::H5Writer(H5Writer&&) noexcept = default;
H5Writer& H5Writer::operator=(H5Writer&& other) noexcept {
  if (this != &other) {
    H5Writer discarded(std::move(*this));
    impl_ = std::move(other.impl_);
  }
  return *this;
}

const std::filesystem::path& H5Writer::path() const { return impl_->path; }

void H5Writer::write_raw(std::string_view name, H5Type type, std::vector<std::uint64_t> shape,
                         const void* data) {
  impl_->require_open();
  const std::filesystem::path& file = impl_->path;
  const std::string clean = clean_name(name, file, false);
  if (open_object(impl_->file.get(), clean).valid())
    throw H5Error(file.string() + ": '" + clean + "' already exists");
  impl_->make_parents(clean);

  const std::vector<hsize_t> dims(shape.begin(), shape.end());
  Id space = checked(H5Screate_simple(static_cast<int>(dims.size()), dims.data(), nullptr),
                     H5Sclose, file, "cannot create the dataspace of '" + clean + "'");
  Id properties = checked(H5Pcreate(H5P_DATASET_CREATE), H5Pclose, file, "cannot create dataset");
  H5Pset_obj_track_times(properties.get(), false);
  Id dataset = checked(H5Dcreate2(impl_->file.get(), clean.c_str(), file_type(type), space.get(),
                                  H5P_DEFAULT, properties.get(), H5P_DEFAULT),
                       H5Dclose, file, "cannot create dataset '" + clean + "'");
  std::uint64_t count = 1;
  for (std::uint64_t d : shape) count *= d;
  if (count > 0)
    check(H5Dwrite(dataset.get(), memory_type(type), H5S_ALL, H5S_ALL, H5P_DEFAULT, data), file,
          "cannot write dataset '" + clean + "'");
}

void H5Writer::create_group(std::string_view name) {
  impl_->require_open();
  const std::string clean = clean_name(name, impl_->path, false);
  impl_->make_parents(clean);
  impl_->make_group(clean);
}

void H5Writer::write_attribute(std::string_view object, std::string_view name,
                               std::string_view value) {
  const std::string text(value);
  impl_->write_strings(object, name, std::span<const std::string>(&text, 1), true);
}

void H5Writer::write_attribute(std::string_view object, std::string_view name,
                               std::span<const std::string> values) {
  impl_->write_strings(object, name, values, false);
}

void H5Writer::write_attribute(std::string_view object, std::string_view name, double value) {
  impl_->write_numbers(object, name, H5Type::float64, &value, 1, true);
}

void H5Writer::write_attribute(std::string_view object, std::string_view name,
                               std::int64_t value) {
  impl_->write_numbers(object, name, H5Type::int64, &value, 1, true);
}

void H5Writer::write_attribute(std::string_view object, std::string_view name,
                               std::span<const double> values) {
  impl_->write_numbers(object, name, H5Type::float64, values.data(), values.size(), false);
}

void H5Writer::write_attribute(std::string_view object, std::string_view name,
                               std::span<const std::int64_t> values) {
  impl_->write_numbers(object, name, H5Type::int64, values.data(), values.size(), false);
}

void H5Writer::commit() {
  impl_->require_open();
  const std::filesystem::path& file = impl_->path;
  check(H5Fflush(impl_->file.get(), H5F_SCOPE_GLOBAL), file, "cannot flush");
  check(impl_->file.close(), file, "cannot close '" + impl_->temporary.string() + "'");
  // Data on disk before the new name points at it.
  if (const int fd = ::open(impl_->temporary.c_str(), O_RDONLY); fd >= 0) {
    ::fsync(fd);
    ::close(fd);
  }
  std::error_code ec;
  std::filesystem::rename(impl_->temporary, file, ec);
  if (ec)
    throw H5Error(file.string() + ": cannot rename '" + impl_->temporary.string() +
                  "' into place (" + ec.message() + ")");
  impl_->committed = true;
}

}  // namespace nfield::io
