#include "capture/render/silhouette_iou.h"

#include "capture/render/renderer.h"
#include "graph/error.h"

namespace weft::capture {

double rendered_silhouette_iou(const Camera& camera, const TriangleMesh& body_mesh, const Vertices& body,
                               const TriangleMesh* cloth_mesh, const Vertices* cloth, const cv::Mat& mask) {
  WEFT_CHECK(!cloth || cloth_mesh, "rendered_silhouette_iou: cloth vertices without a cloth mesh");
  if (!in_front(camera, body)) return 0.0;
  std::vector<RenderMesh> meshes(1);
  meshes[0].mesh = &body_mesh;
  meshes[0].vertices = &body;
  if (cloth) {
    meshes.emplace_back();
    meshes[1].mesh = cloth_mesh;
    meshes[1].vertices = cloth;
    meshes[1].part = 2;
  }
  return mask_iou(render(camera, meshes).mask, mask);
}

}  // namespace weft::capture
