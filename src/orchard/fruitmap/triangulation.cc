#include "orchard/fruitmap/triangulation.h"

#include <Eigen/SVD>

namespace orchard {

bool TriangulatePoint(const std::vector<const CameraView*>& views, const std::vector<Eigen::Vector2d>& pixels,
                      Eigen::Vector3d* X) {
  const int n = static_cast<int>(views.size());
  if (n < 2 || pixels.size() != views.size()) return false;
  Eigen::MatrixXd A(2 * n, 4);
  for (int i = 0; i < n; ++i) {
    Eigen::Matrix<double, 3, 4> P;
    P << views[i]->R, views[i]->t;
    const Eigen::Vector2d x = views[i]->Normalize(pixels[i]);
    A.row(2 * i) = x.x() * P.row(2) - P.row(0);
    A.row(2 * i + 1) = x.y() * P.row(2) - P.row(1);
  }
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(A, Eigen::ComputeFullV);
  const Eigen::Vector4d h = svd.matrixV().col(3);
  if (std::abs(h(3)) < 1e-12) return false;
  *X = h.head<3>() / h(3);
  // Degenerate (e.g. identical centres): the null space is not unique.
  const auto& s = svd.singularValues();
  if (s(2) < 1e-9 * s(0)) return false;
  return X->allFinite();
}

double ReprojectionError(const CameraView& view, const Eigen::Vector3d& X, const Eigen::Vector2d& pixel) {
  if (view.Depth(X) <= 1e-9) return 1e9;
  Eigen::Vector2d p;
  view.Project(X, &p);  // the pixel may lie outside the image; the distance still counts
  return (p - pixel).norm();
}

}  // namespace orchard
