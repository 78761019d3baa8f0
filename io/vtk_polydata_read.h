// SPDX-License-Identifier: MIT
// Internal to io/: reading the polygonal formats VTK knows.
#pragma once
#include <filesystem>
#include <string>

#include <vtkSmartPointer.h>

class vtkPolyData;

namespace nfield::io {

// Reads .vtp, .ply, .obj or, when `supported` lists it, .stl (by extension, case-insensitive)
// with VTK's reader, then splits polygons and strips into triangles and polylines into
// segments (points are unchanged).
// Errors are std::runtime_error("<caller>: '<path>': <problem>"); `supported` lists the
// caller's extensions for the unknown-extension message.
vtkSmartPointer<vtkPolyData> read_vtk_polydata(const std::filesystem::path& path,
                                               const std::string& caller,
                                               const std::string& supported);

// The lower-case extension of `path`, with its dot.
std::string lower_extension(const std::filesystem::path& path);

}  // namespace nfield::io
