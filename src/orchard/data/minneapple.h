// Instance-mask helpers behind the MinneApple reader and writer, public because
// detectors and the segmentation metrics convert between masks and objects too.
#pragma once

#include <vector>

#include <opencv2/core.hpp>

#include "orchard/data/dataset.h"

namespace orchard {

// One object per distinct non-zero id of a CV_32S id image, in increasing id
// order: box = tight pixel bounds [xmin, xmax+1), area = pixel count (holes
// excluded; a split instance is still one object). With `with_polygons`, the
// outer contours of each piece as polygons in pixel-index coordinates (holes
// are not represented, as in COCO polygons).
std::vector<Annotation> InstancesFromMask(const cv::Mat& ids, bool with_polygons);

// A CV_16U id image of `size` with object i drawn as id i+1, larger objects
// (by area) first so that smaller ones on top stay visible: polygons filled
// (boundary pixels included, so the contours of InstancesFromMask give back a
// hole-free instance exactly), boxes without polygons filled as pixels
// round(x1)..round(x2)-1 and at least one pixel. An object entirely covered by
// smaller ones still disappears (masks cannot overlap). Throws above 65535 objects.
cv::Mat RasteriseInstances(const std::vector<Annotation>& objects, cv::Size size);

}  // namespace orchard
