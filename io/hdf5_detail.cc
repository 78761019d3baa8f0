// SPDX-License-Identifier: MIT
#include "io/hdf5_detail.h"

#include <algorithm>
#include <vector>

namespace nfield::io {
namespace hdf5_detail {

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

}  // namespace hdf5_detail

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

}  // namespace nfield::io
