#pragma once
// The silhouette IoU of posed meshes against a mask: the measure behind AMVIoU, RVIoU and
// SVIoU (capture/evaluation/frame_measures.h) and the trainer's validation.
#include <opencv2/core.hpp>

#include "capture/io/camera.h"
#include "geometry/mesh.h"

namespace weft::capture {


// IoU of the body (and the cloth, when given) rendered by `camera` against `mask` (CV_8UC1
// of the camera's size). The meshes give the faces, `body` and `cloth` the posed vertices
// (the meshes' vertex counts). 0 when the body is not wholly in front of the camera.
double rendered_silhouette_iou(const Camera& camera, const TriangleMesh& body_mesh, const Vertices& body,
                               const TriangleMesh* cloth_mesh, const Vertices* cloth, const cv::Mat& mask);

}  // namespace weft::capture
