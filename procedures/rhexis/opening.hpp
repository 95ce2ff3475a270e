#pragma once
// The capsulorhexis opening as the microscope sees it: the part of the anterior capsule still held
// at its rim (the triangles connected to an anchored particle), projected down the optical axis
// and rasterised with OpenCV; the opening is the uncovered region around the axis.
//
// From it: area, equivalent diameter 2·√(A/π), the fitted ellipse's mean diameter and axis ratio
// (cv::fitEllipse), circularity 4πA/P² with P the length of the free capsule edges bordering the
// opening (a raw pixel contour would overstate P by its staircase) but never less than the
// opening's contour simplified to within a pixel (a lip folded over the opening hides edges from
// the count), and centring (the opening's
// centroid from the optical axis). An opening that is not closed (the disc still hangs on) has
// no uncovered region: complete = false.
//
// Reads: particles (x, y), triangles, adjacency (through the cut mesh). Writes nothing.
#include <array>
#include <cstdint>
#include <vector>

#include "systems/cut/membrane_edit.hpp"

namespace phaco::rhexis {

struct Opening {
  bool complete = false;
  double area_mm2 = 0.0;
  double diameter_mm = 0.0;          // equivalent: 2·sqrt(A/π)
  double ellipse_diameter_mm = 0.0;  // mean of the fitted ellipse's axes
  double ellipse_axis_ratio = 0.0;   // minor / major
  double perimeter_mm = 0.0;
  double circularity = 0.0;   // 4πA/P²
  double centering_mm = 0.0;  // centroid distance from the optical axis
  // The opening's contour seen down the axis, simplified to within a pixel, closed implicitly
  // (x, y in mm, scene frame): what a report draws against the target circle.
  std::vector<std::array<double, 2>> outline_mm;
};

// Per triangle slot: 1 if it is alive and connected (across joined edges) to a triangle with an
// anchored corner — the capsule still held at its rim; the torn-off disc is 0.
std::vector<uint8_t> held_triangles(const cut::CutMesh& mesh);

// pixel_mm: raster resolution; field_mm: half-width of the square field around the axis.
Opening measure_opening(const cut::CutMesh& mesh, double pixel_mm = 0.01, double field_mm = 5.0);

}  // namespace phaco::rhexis
