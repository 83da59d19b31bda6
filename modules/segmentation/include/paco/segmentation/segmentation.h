#pragma once
// Everything of paco::segmentation: the PlanarSegmenter base, its four backends, the factory and
// the thinning of dense scans; also, from paco::common, the side a scan's normals face (turn a
// scan whose normals face inwards before segmenting it).
// Usage:
//   #include <paco/segmentation/segmentation.h>
//   auto seg = paco::makePlanarSegmenter<pcl::PointXYZ>("region-growing");
//   seg->setInputCloud(cloud); paco::PlanarSegmentation result; seg->segment(result);
#include <paco/segmentation/efficient_ransac_segmenter.h>
#include <paco/segmentation/gocopp_segmenter.h>
#include <paco/common/normal_sides.h>
#include <paco/segmentation/planar_segmenter.h>
#include <paco/segmentation/ransac_segmenter.h>
#include <paco/segmentation/region_growing_segmenter.h>
#include <paco/segmentation/thinning.h>
