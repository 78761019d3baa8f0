// SPDX-License-Identifier: MIT
#include "io/vtk_image.h"

#include <stdexcept>

#include <vtkDoubleArray.h>
#include <vtkFieldData.h>
#include <vtkImageData.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkXMLImageDataReader.h>
#include <vtkXMLImageDataWriter.h>

#include "io/atomic_write.h"
#include "io/vtk_convert.h"
#include "io/vtk_errors.h"

namespace nfield::io {
namespace fs = std::filesystem;

void write_vti(const fs::path& path, const Grid& grid, const PointArrays& arrays,
               Precision precision, const FieldData& field_data) {
  for (int d = 0; d < 3; ++d)
    if (grid.dims[d] < 1)
      throw std::invalid_argument("write_vti: '" + path.string() + "': grid dims below 1");
  vtkNew<vtkImageData> image;
  image->SetDimensions(grid.dims.data());
  image->SetOrigin(grid.origin.data());
  image->SetSpacing(grid.spacing.data());
  try {
    add_point_arrays(image->GetPointData(), arrays, grid.point_count(), precision);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument("write_vti: '" + path.string() + "': " + e.what());
  }
  for (const auto& [name, value] : field_data) {
    vtkNew<vtkDoubleArray> array;
    array->SetName(name.c_str());
    array->InsertNextValue(value);
    image->GetFieldData()->AddArray(array);
  }
  write_atomically(path, [&](const fs::path& tmp) {
    vtkNew<vtkXMLImageDataWriter> writer;
    VtkErrorCatcher errors(writer);
    writer->SetInputData(image);
    writer->SetFileName(tmp.c_str());
    writer->SetDataModeToAppended();
    writer->EncodeAppendedDataOff();
    writer->SetCompressorTypeToZLib();
    writer->SetHeaderTypeToUInt64();
    if (!writer->Write() || errors.failed())
      throw std::runtime_error("vtkXMLImageDataWriter: " + errors.message());
  });
}

ImageData read_vti(const fs::path& path) {
  const auto fail = [&](const std::string& why) {
    return std::runtime_error("read_vti: '" + path.string() + "': " + why);
  };
  if (!fs::is_regular_file(path)) throw fail("no such file");
  vtkNew<vtkXMLImageDataReader> reader;
  VtkErrorCatcher errors(reader);
  if (!reader->CanReadFile(path.c_str())) throw fail("not a VTK XML image data (.vti) file");
  reader->SetFileName(path.c_str());
  reader->Update();
  vtkImageData* image = reader->GetOutput();
  if (errors.failed() || !image) throw fail(errors.message());
  ImageData out;
  int extent[6];
  image->GetExtent(extent);
  for (int d = 0; d < 3; ++d) {
    out.grid.dims[d] = extent[2 * d + 1] - extent[2 * d] + 1;
    out.grid.spacing[d] = image->GetSpacing()[d];
    out.grid.origin[d] = image->GetOrigin()[d] + extent[2 * d] * out.grid.spacing[d];
  }
  out.arrays = get_point_arrays(image->GetPointData());
  vtkFieldData* fields = image->GetFieldData();
  for (int k = 0; fields && k < fields->GetNumberOfArrays(); ++k) {
    vtkDataArray* array = fields->GetArray(k);
    if (array && array->GetName() && array->GetNumberOfTuples() == 1 && array->GetNumberOfComponents() == 1)
      out.field_data[array->GetName()] = array->GetTuple1(0);
  }
  return out;
}

}  // namespace nfield::io
