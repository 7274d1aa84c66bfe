#pragma once
// The silhouette constraint E_cons of the simulation loss (the paper's Eq. 1, section
// 3.2): in every view of a frame, each garment vertex on the silhouette of the predicted
// body + garment is tied to the camera ray through the nearest pixel of the mask's
// contour, so that the simulated garment keeps to what the cameras saw instead of sagging
// into a free drape. The rays feed physics::RayConstraintEnergy (½ k · distance² to the
// line) through SimulationWindow::ray_targets.
#include <vector>

#include "geometry/mesh.h"
#include "capture/dataset/multiview_supervision.h"
#include "physics/vertex_energies.h"

namespace weft::capture {

struct SilhouetteRayOptions {
  // A vertex whose projection lies farther than this from the contour (pixels at the
  // supervision's silhouette size) gets no ray: its nearest contour pixel is likely
  // another part's.
  double max_pixels = 6;
  double metres_per_unit = 1;  // the rays are in metres, the vertices in character units
};

// Rays for `frame` (every view of `supervision`): `body` and `cloth` are the predicted
// meshes (character units) with the combined faces `faces` (body first, then the cloth's
// offset by the body's vertex count). Ray vertices index the cloth. A vertex on the
// silhouette of several views gets one ray per view.
std::vector<physics::RayTarget> silhouette_rays(const MultiviewSupervision& supervision, int frame,
                                                const Vertices& body, const Vertices& cloth, const Faces& faces,
                                                const SilhouetteRayOptions& options);

// The mask's contour: foreground pixels (255) with a background 4-neighbour or on the
// image border, as (x, y) pixel centres.
std::vector<Eigen::Vector2d> mask_contour(const cv::Mat& mask);

}  // namespace weft::capture
