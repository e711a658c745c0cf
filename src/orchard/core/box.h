// Axis-aligned boxes in pixel coordinates and the overlap measures used by the
// detection metrics.
#pragma once

#include <algorithm>

namespace orchard {

// Corners in continuous pixel coordinates (x1 <= x2, y1 <= y2), as in CodaLab
// result files and COCO ([x, y, w, h] converts with FromXYWH).
struct Box {
  double x1 = 0, y1 = 0, x2 = 0, y2 = 0;

  static Box FromXYWH(double x, double y, double w, double h) { return {x, y, x + w, y + h}; }
  double Width() const { return std::max(0.0, x2 - x1); }
  double Height() const { return std::max(0.0, y2 - y1); }
  double Area() const { return Width() * Height(); }
  double CenterX() const { return 0.5 * (x1 + x2); }
  double CenterY() const { return 0.5 * (y1 + y2); }
};

inline double IntersectionArea(const Box& a, const Box& b) {
  const double w = std::min(a.x2, b.x2) - std::max(a.x1, b.x1);
  const double h = std::min(a.y2, b.y2) - std::max(a.y1, b.y1);
  return (w > 0 && h > 0) ? w * h : 0.0;
}

// Intersection over union; 0 when both boxes are empty.
inline double IoU(const Box& a, const Box& b) {
  const double inter = IntersectionArea(a, b);
  const double uni = a.Area() + b.Area() - inter;
  return uni > 0 ? inter / uni : 0.0;
}

}  // namespace orchard
