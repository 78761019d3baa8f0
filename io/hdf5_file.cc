// SPDX-License-Identifier: MIT
#include "io/hdf5_file.h"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <utility>

#include <hdf5.h>

namespace nfield::io {
namespace {

// An HDF5 identifier closed by its own close function.
class Id {
 public:
  Id() = default;
  Id(hid_t id, herr_t (*close)(hid_t)) : id_(id), close_(close) {}
  Id(Id&& other) noexcept
      : id_(std::exchange(other.id_, H5I_INVALID_HID)), close_(other.close_) {}
  Id& operator=(Id&& other) noexcept {
    if (this != &other) {
      reset();
      id_ = std::exchange(other.id_, H5I_INVALID_HID);
      close_ = other.close_;
    }
    return *this;
  }
  ~Id() { reset(); }
  hid_t get() const { return id_; }
  bool valid() const { return id_ >= 0; }
  // Closes now, reporting failure (a file's close writes its metadata).
  herr_t close() {
    const herr_t status = valid() && close_ ? close_(id_) : 0;
    id_ = H5I_INVALID_HID;
    return status;
  }

 private:
  void reset() {
    if (valid() && close_) close_(id_);
    id_ = H5I_INVALID_HID;
  }
  hid_t id_ = H5I_INVALID_HID;
  herr_t (*close_)(hid_t) = nullptr;
};

void silence_hdf5() {
  H5open();
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
}

// The descriptions on HDF5's error stack, outermost and innermost, then clears it.
std::string hdf5_reason() {
  std::vector<std::string> descriptions;
  H5Ewalk2(
      H5E_DEFAULT, H5E_WALK_DOWNWARD,
      [](unsigned, const H5E_error2_t* error, void* data) -> herr_t {
        if (error->desc && *error->desc)
          static_cast<std::vector<std::string>*>(data)->emplace_back(error->desc);
        return 0;
      },
      &descriptions);
  H5Eclear2(H5E_DEFAULT);
  if (descriptions.empty()) return "";
  if (descriptions.size() == 1 || descriptions.front() == descriptions.back())
    return descriptions.front();
  return descriptions.front() + ": " + descriptions.back();
}

[[noreturn]] void fail(const std::filesystem::path& file, const std::string& message) {
  const std::string reason = hdf5_reason();
  throw H5Error(file.string() + ": " + message + (reason.empty() ? "" : " (" + reason + ")"));
}

Id checked(hid_t id, herr_t (*close)(hid_t), const std::filesystem::path& file,
           const std::string& message) {
  if (id < 0) fail(file, message);
  return Id(id, close);
}

void check(herr_t status, const std::filesystem::path& file, const std::string& message) {
  if (status < 0) fail(file, message);
}

hid_t memory_type(H5Type type) {
  switch (type) {
    case H5Type::float32: return H5T_NATIVE_FLOAT;
    case H5Type::float64: return H5T_NATIVE_DOUBLE;
    case H5Type::int32: return H5T_NATIVE_INT32;
    case H5Type::int64: return H5T_NATIVE_INT64;
    case H5Type::uint64: return H5T_NATIVE_UINT64;
  }
  return H5I_INVALID_HID;
}

hid_t file_type(H5Type type) {
  switch (type) {
    case H5Type::float32: return H5T_IEEE_F32LE;
    case H5Type::float64: return H5T_IEEE_F64LE;
    case H5Type::int32: return H5T_STD_I32LE;
    case H5Type::int64: return H5T_STD_I64LE;
    case H5Type::uint64: return H5T_STD_U64LE;
  }
  return H5I_INVALID_HID;
}

// "layers/0/weight" from "/layers/0/weight"; "" is the root. Empty, "." and ".."
// components are refused.
std::string clean_name(std::string_view name, const std::filesystem::path& file,
                       bool root_allowed) {
  while (!name.empty() && name.front() == '/') name.remove_prefix(1);
  if (name.empty()) {
    if (root_allowed) return "";
    throw H5Error(file.string() + ": empty dataset name");
  }
  std::size_t start = 0;
  while (start <= name.size()) {
    const std::size_t end = std::min(name.find('/', start), name.size());
    const std::string_view part = name.substr(start, end - start);
    if (part.empty() || part == "." || part == "..")
      throw H5Error(file.string() + ": invalid name '" + std::string(name) + "'");
    start = end + 1;
  }
  return std::string(name);
}

// The object at `name` ("" = root), or an invalid Id if there is none.
Id open_object(hid_t file, const std::string& name) {
  if (name.empty()) return Id(H5Oopen(file, "/", H5P_DEFAULT), H5Oclose);
  std::size_t slash = 0;
  while (true) {
    slash = name.find('/', slash);
    const std::string prefix = name.substr(0, slash);
    if (H5Lexists(file, prefix.c_str(), H5P_DEFAULT) <= 0) {
      H5Eclear2(H5E_DEFAULT);
      return Id();
    }
    if (slash == std::string::npos) break;
    ++slash;
  }
  Id object(H5Oopen(file, name.c_str(), H5P_DEFAULT), H5Oclose);
  if (!object.valid()) H5Eclear2(H5E_DEFAULT);
  return object;
}

H5I_type_t kind_of(const Id& object) {
  return object.valid() ? H5Iget_type(object.get()) : H5I_BADID;
}

std::string object_label(const std::string& name) { return name.empty() ? "/" : name; }

H5Type stored_type(hid_t type_id, const std::filesystem::path& file, const std::string& name) {
  const H5T_class_t type_class = H5Tget_class(type_id);
  const std::size_t size = H5Tget_size(type_id);
  if (type_class == H5T_FLOAT && size == 4) return H5Type::float32;
  if (type_class == H5T_FLOAT && size == 8) return H5Type::float64;
  if (type_class == H5T_INTEGER) {
    const bool is_signed = H5Tget_sign(type_id) == H5T_SGN_2;
    if (is_signed && size == 4) return H5Type::int32;
    if (is_signed && size == 8) return H5Type::int64;
    if (!is_signed && size == 8) return H5Type::uint64;
  }
  throw H5Error(file.string() + ": dataset '" + name +
                "' has an unsupported element type (not float32, float64, int32, int64 or "
                "uint64)");
}

}  // namespace

std::string_view to_string(H5Type type) {
  switch (type) {
    case H5Type::float32: return "float32";
    case H5Type::float64: return "float64";
    case H5Type::int32: return "int32";
    case H5Type::int64: return "int64";
    case H5Type::uint64: return "uint64";
  }
  return "unknown";
}

// ---- H5Writer ---------------------------------------------------------------------

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

// ---- H5Reader ---------------------------------------------------------------------

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
