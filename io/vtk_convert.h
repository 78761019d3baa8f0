// SPDX-License-Identifier: MIT
// Internal to io/: copies between Eigen matrices (one row per tuple) and VTK arrays.
#pragma once
#include <string>

#include <vtkSmartPointer.h>
#include <Eigen/Core>

#include "io/point_arrays.h"
#include "io/poly_data.h"

class vtkCellArray;
class vtkDataArray;
class vtkDataSetAttributes;
class vtkPoints;
class vtkPolyData;

namespace nfield::io {

// A vtkDoubleArray or vtkFloatArray named `name` with m.cols() components.
vtkSmartPointer<vtkDataArray> to_vtk_array(const std::string& name, const Eigen::MatrixXd& m,
                                           Precision precision);
// Any numeric VTK array as doubles.
Eigen::MatrixXd from_vtk_array(vtkDataArray* array);

// Adds every array to `data`; throws std::invalid_argument when an array has not `rows` rows
// or no column. An array named "Normals" with 3 columns becomes the normals attribute.
void add_point_arrays(vtkDataSetAttributes* data, const PointArrays& arrays, Eigen::Index rows,
                      Precision precision);
// All numeric arrays of `data` by name.
PointArrays get_point_arrays(vtkDataSetAttributes* data);

// Points from an n×2 (z = 0) or n×3 matrix; throws std::invalid_argument for other widths.
vtkSmartPointer<vtkPoints> to_vtk_points(const Eigen::MatrixXd& points, Precision precision);
// n×3.
Eigen::MatrixXd from_vtk_points(vtkPoints* points);

// One cell per row of `cells` (each row the point ids of one cell).
template <int K>
vtkSmartPointer<vtkCellArray> to_vtk_cells(const Eigen::Matrix<int, Eigen::Dynamic, K>& cells);

// A vtkPolyData of `data`: points, arrays, lines and triangles, and one vertex cell per point
// when `vertices_if_no_cells` and there are neither. Throws std::invalid_argument for arrays
// of the wrong size or cell indices out of range.
vtkSmartPointer<vtkPolyData> to_vtk_polydata(const PolyData& data, Precision precision,
                                             bool vertices_if_no_cells = false);
// The points, 2-point lines, 3-point polygons and numeric point arrays of `data` (other cells
// are skipped: triangulate first).
PolyData from_vtk_polydata(vtkPolyData* data);

}  // namespace nfield::io
