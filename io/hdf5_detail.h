// SPDX-License-Identifier: MIT
// What the HDF5 writer and reader (hdf5_writer.cc, hdf5_reader.cc) share: an owning
// identifier, HDF5's error stack as text, the element types in memory and on disk, and the
// clean-up of object names. Internal to io/.
#pragma once

#include <hdf5.h>

#include <filesystem>
#include <string>
#include <string_view>
#include <utility>

#include "io/hdf5_file.h"

namespace nfield::io::hdf5_detail {

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

void silence_hdf5();

// The descriptions on HDF5's error stack, outermost and innermost, then clears it.
std::string hdf5_reason();

[[noreturn]] void fail(const std::filesystem::path& file, const std::string& message);

Id checked(hid_t id, herr_t (*close)(hid_t), const std::filesystem::path& file,
           const std::string& message);

void check(herr_t status, const std::filesystem::path& file, const std::string& message);

hid_t memory_type(H5Type type);

hid_t file_type(H5Type type);

// "layers/0/weight" from "/layers/0/weight"; "" is the root. Empty, "." and ".."
// components are refused.
std::string clean_name(std::string_view name, const std::filesystem::path& file,
                       bool root_allowed);

// The object at `name` ("" = root), or an invalid Id if there is none.
Id open_object(hid_t file, const std::string& name);

H5I_type_t kind_of(const Id& object);

std::string object_label(const std::string& name);

H5Type stored_type(hid_t type_id, const std::filesystem::path& file, const std::string& name);

}  // namespace nfield::io::hdf5_detail
