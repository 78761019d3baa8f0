// SPDX-License-Identifier: MIT
#pragma once
#include <filesystem>
#include <string>
#include <vector>

namespace nfield::io {

// A ParaView collection file (.pvd): the index of a time series, one data file per time
// (and part). Opening the .pvd in ParaView shows the files as one animated dataset.
//
//   PvdCollection pvd(out / "u.pvd");
//   for (...) { write_vti(out / name, ...); pvd.add(t, name); pvd.write(); }
class PvdCollection {
 public:
  struct Entry {
    double time = 0;
    std::string file;  // relative to the folder of the .pvd
    int part = 0;
  };

  explicit PvdCollection(std::filesystem::path path) : path_(std::move(path)) {}

  // Records that `file` (a path relative to the .pvd's folder) holds part `part` at `time`.
  void add(double time, std::string file, int part = 0);
  // Writes the collection, all entries in the order added, atomically (see
  // io/atomic_write.h); writing after each add keeps a valid index while a run goes on.
  // Throws std::runtime_error naming the file on failure.
  void write() const;

  const std::filesystem::path& path() const { return path_; }
  const std::vector<Entry>& entries() const { return entries_; }

  // The collection in an existing .pvd, e.g. to continue a series. Throws
  // std::runtime_error naming `path` when it is missing or not a VTK collection.
  static PvdCollection read(const std::filesystem::path& path);

 private:
  std::filesystem::path path_;
  std::vector<Entry> entries_;
};

}  // namespace nfield::io
