// SPDX-License-Identifier: MIT
#include "io/pvd.h"

#include <stdexcept>

#include <gtest/gtest.h>

#include "io/vtk_image.h"
#include "tests/io/io_test_paths.h"

namespace nfield::io {
namespace {
using testing::expect_error;
using testing::file_names;
using testing::read_text;
using testing::scratch_dir;

TEST(Pvd, WritesParaViewCollectionOfFrames) {
  const auto dir = scratch_dir();
  const Grid grid{{3, 3, 1}, {}, {1, 1, 1}};
  PvdCollection pvd(dir / "u.pvd");
  for (int i = 1; i <= 3; ++i) {
    const std::string name = "frame_000" + std::to_string(i) + ".vti";
    write_vti(dir / name, grid, {{"u", Eigen::MatrixXd::Constant(9, 1, i)}});
    pvd.add(0.1 * i, name);
    pvd.write();
  }
  EXPECT_EQ(read_text(dir / "u.pvd"),
            "<?xml version=\"1.0\"?>\n"
            "<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n"
            "  <Collection>\n"
            "    <DataSet timestep=\"0.1\" group=\"\" part=\"0\" file=\"frame_0001.vti\"/>\n"
            "    <DataSet timestep=\"0.2\" group=\"\" part=\"0\" file=\"frame_0002.vti\"/>\n"
            "    <DataSet timestep=\"0.30000000000000004\" group=\"\" part=\"0\" "
            "file=\"frame_0003.vti\"/>\n"
            "  </Collection>\n"
            "</VTKFile>\n");
  EXPECT_EQ(file_names(dir).size(), 4u);  // no temporaries left

  // Read back with VTK's XML parser; each entry names a readable frame.
  const PvdCollection back = PvdCollection::read(dir / "u.pvd");
  ASSERT_EQ(back.entries().size(), 3u);
  for (int i = 0; i < 3; ++i) {
    const auto& e = back.entries()[i];
    EXPECT_EQ(e.time, pvd.entries()[i].time);
    EXPECT_EQ(e.part, 0);
    const ImageData frame = read_vti(dir / e.file);
    EXPECT_EQ(frame.arrays.at("u")(0, 0), i + 1);
  }
}

TEST(Pvd, EscapesFileNamesAndKeepsParts) {
  const auto dir = scratch_dir();
  PvdCollection pvd(dir / "s.pvd");
  pvd.add(-2.5e-7, "a&b\"<c>.vtp", 3);
  pvd.write();
  EXPECT_NE(read_text(dir / "s.pvd").find("file=\"a&amp;b&quot;&lt;c&gt;.vtp\""),
            std::string::npos);
  const PvdCollection back = PvdCollection::read(dir / "s.pvd");
  ASSERT_EQ(back.entries().size(), 1u);
  EXPECT_EQ(back.entries()[0].file, "a&b\"<c>.vtp");
  EXPECT_EQ(back.entries()[0].time, -2.5e-7);
  EXPECT_EQ(back.entries()[0].part, 3);
}

TEST(Pvd, Errors) {
  const auto dir = scratch_dir();
  expect_error<std::runtime_error>([&] { PvdCollection::read(dir / "none.pvd"); },
                                   {"none.pvd", "no such file"});
  write_vti(dir / "f.vti", Grid{}, {});
  expect_error<std::runtime_error>([&] { PvdCollection::read(dir / "f.vti"); },
                                   {"f.vti", "Collection"});
  testing::write_text(dir / "t.pvd", "not xml at all <");
  expect_error<std::runtime_error>([&] { PvdCollection::read(dir / "t.pvd"); }, {"t.pvd"});
  expect_error<std::runtime_error>([&] { PvdCollection(dir / "no" / "x.pvd").write(); }, {"x.pvd"});
}

}  // namespace
}  // namespace nfield::io
