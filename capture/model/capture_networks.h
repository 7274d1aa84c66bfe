#pragma once
// The method's two networks and what their outputs mean (../shared/DESIGN.md):
// - PoseNet (a ResNet) regresses the skeleton's dofs θ, except those of the root chain
//   (limited dofs through a sigmoid that keeps them within their limits: pose_dofs.h),
//   and the camera-relative root rotation α (6D representation of Zhou et al. 2019,
//   continuous over all rotations: a person seen from any side of a ring of cameras).
// - PADefNet (a ResNet with a zero-initialised last layer, so training starts from the
//   skinned template) regresses per-node Euler angles A and translations T of the body's
//   and the cloth's embedded graphs.
// The root translation is not regressed: CaptureModel solves it in closed form from the
// 2D keypoints of the frame's views (global_pose.h).
//
// Posing: the root chain's dofs (global translation and rotation, e.g. ddc's Root_* and
// GlobalScale, the generated skeleton's Hips_t*/r*) stay at the rest pose; the skeleton
// posed so is rotated about the rest position p0 of the root chain's last joint and
// moved:  X_world = R_world (X − p0) + t,  R_world = R_cᵀ R(α) C,
// with R_c the input view's world→camera rotation and C = diag(1, −1, −1): α = identity is
// the person upright facing the camera (OpenCV cameras look along +z with y down).
#include <Eigen/Core>
#include <memory>
#include <vector>

#include "capture/character/character.h"
#include "capture/dataset/multiview_supervision.h"
#include "capture/dataset/synthetic_dataset.h"
#include "capture/deformation/deformation_layer.h"
#include "capture/deformation/losses.h"
#include "capture/detection/person_detector.h"
#include "capture/io/camera.h"
#include "capture/model/global_pose.h"
#include "capture/model/network_config.h"
#include "capture/model/pose_dofs.h"
#include "nn/resnet.h"

namespace weft::capture {

// Which dofs PoseNet regresses.
struct PoseParametrisation {
  std::vector<int> root_dofs;  // dofs driving the root chain: held at the rest pose
  std::vector<int> free_dofs;  // the others, in skeleton order: regressed
  int pivot_joint = 0;         // the root chain's last joint
  Eigen::Vector3d pivot = Eigen::Vector3d::Zero();  // its rest-pose position p0 (character units)
};
// The root chain: from the root joint, every following joint placed at its parent's
// origin (zero offset) and the only child of it.
PoseParametrisation pose_parametrisation(const Character& character);

// The world rotation a posed skeleton gives its root chain, in the convention of
// CapturePrediction::rotation: the pivot joint's global rotation times the transpose of its
// rest-pose rotation. The true root orientation that a predicted one is measured against.
Eigen::Matrix3d root_rotation_world(const Character& character, const PoseParametrisation& param,
                                    const PosedCharacter& posed);

// Both networks as one module (checkpoints hold both: "pose_net.*", "deformation_net.*",
// "pose_lift.*" with network.keypoint_input, and "detector.*" with network.detector).
class CaptureNetworks : public nn::Module {
 public:
  CaptureNetworks(const Character& character, const NetworkConfig& config, uint64_t seed);
  Tensor forward(const Tensor& x) override;  // not used: call pose / deformation_net
  // PoseNet's output [B, pose_outputs()] for a batch: the ResNet on the images plus, with
  // network.keypoint_input, the lifting branch on the input view's detections (pose_lift);
  // with network.image_input false, the lifting branch alone (pose_net is not run).
  // Train or evaluation mode is pose_net's (the branch has no batch norm).
  Tensor pose(const Batch& batch);
  // The lifting branch alone on a batch's detections and crop cameras (no images): the
  // whole of PoseNet's output for poses no camera filmed (capture/training/virtual_poses.h).
  // An error without network.keypoint_input.
  Tensor pose_from_keypoints(const Batch& batch) const;
  // PoseNet's trainable parameters, named as in checkpoints ("pose_net.*", "pose_lift.*";
  // without image input, "pose_lift.*" only).
  std::vector<nn::NamedTensor> pose_parameters() const;
  std::shared_ptr<nn::ResNet> pose_net, deformation_net;
  // The lifting branch (null without network.keypoint_input): an MLP from the detections
  // (keypoint_lift_input) to an addition to pose_net's output, last layer zero at the start.
  std::shared_ptr<nn::Sequential> pose_lift;
  // The person detector (null without network.detector): keypoints and mask from the image.
  std::shared_ptr<PersonDetector> detector;
  // The detector, or an error naming the model and what to retrain: `model` is the model
  // folder (or weights) for the message.
  PersonDetector& require_detector(const std::string& model) const;
  int64_t pose_outputs() const { return pose_outputs_; }
  int64_t deformation_outputs() const { return deformation_outputs_; }

 private:
  int64_t pose_outputs_ = 0, deformation_outputs_ = 0;
  int input_size_ = 128;
  bool image_input_ = true;  // network.image_input: false, PoseNet is the lifting branch alone
};

// The lifting branch's input [B, 77] from a batch: per BODY_25 keypoint its crop position
// scaled to [-0.5, 0.5] and its confidence (all three 0 without a detection), then the
// direction of the crop centre's ray in the input camera (x/z, y/z), which turns the
// person's apparent orientation in the crop into the camera-relative one PoseNet regresses.
constexpr int64_t kLiftInputs = 3 * kBody25Count + 2;
Tensor keypoint_lift_input(const Batch& batch, int input_size);

// Per sample, what places its skeleton in the world: the input view's rotation and the
// root translation terms from the frame's detections.
struct SampleViews {
  std::vector<Eigen::Matrix3d> input_rotations;  // R_c of each sample's input view
  RootTranslationTerms translation;              // over all views of each sample's frame
};
SampleViews sample_views(const std::vector<Camera>& input_cameras,
                         const std::vector<std::vector<KeypointView>>& frame_views,
                         const std::vector<double>& keypoint_mask, DType dtype);

// A prediction in world coordinates (character units), batched over samples B.
struct CapturePrediction {
  Tensor dofs;         // [B,D] (root chain at rest)
  Tensor rotation;     // [B,3,3] R_world
  Tensor translation;  // [B,3] t (the pivot's world position)
  Tensor keypoints;    // [B,25,3] BODY_25 (unmapped rows are meaningless: use the mask)
  Tensor body, cloth;  // [B,V,3]; cloth undefined without a garment
  // Embedded-graph rotations [B,K,3,3] and translations [B,K,3] (undefined without PADefNet).
  Tensor body_rotations, body_translations, cloth_rotations, cloth_translations;
};

// One sample of a batch of points [B,V,3] as plain Eigen (sample b), e.g. a prediction's
// vertices for the simulator or the renderer.
Vertices sample_vertices(const Tensor& vertices, int64_t b);

class CaptureModel {
 public:
  CaptureModel(const Character& character, const NetworkConfig& config);
  const Character& character() const { return character_; }
  const DeformationLayer& layer() const { return layer_; }
  const PoseParametrisation& parametrisation() const { return param_; }
  const PoseDofs& pose_dofs() const { return pose_dofs_; }
  const std::vector<double>& keypoint_mask() const { return keypoint_mask_; }  // 25: 1 mapped
  int64_t pose_outputs() const;         // free dofs + 6
  int64_t deformation_outputs() const;  // 6 (K_body + K_cloth)

  // From PoseNet's output [B, pose_outputs()] and, when given, PADefNet's [B,
  // deformation_outputs()] (undefined: the skinned template). with_meshes = false skips
  // the vertices (PoseNet's stage needs keypoints only). With PADefNet the keypoints also
  // move with the body's embedded graph: each rides on the nodes of the body vertex
  // nearest to it in the bind pose, so L_lm reaches PADefNet while PoseNet is frozen.
  CapturePrediction predict(const Tensor& pose_output, const Tensor& deformation_output,
                            const SampleViews& views, bool with_meshes = true) const;
  // The same from given dofs [B, D] of the whole skeleton, root chain included (the
  // skeleton posed in the world, e.g. a dataset's gt/pose.motion), instead of PoseNet's
  // output and the root translation solve: the oracle pose of the physics experiment,
  // which isolates the garment from pose error. rotation is the identity, translation 0.
  CapturePrediction predict_posed(const Tensor& dofs, const Tensor& deformation_output,
                                  bool with_meshes = true) const;

 private:
  // PADefNet's output [B, deformation_outputs()] as graph angles (radians) and
  // translations (character units); fills p's graph rotations and translations.
  struct GraphMotion {
    Tensor body_angles, body_translations, cloth_angles, cloth_translations;
  };
  GraphMotion graph_motion(const Tensor& deformation_output, int64_t B, CapturePrediction& p) const;
  Tensor to_world(const Tensor& points, const Tensor& rotation_t, const Tensor& translation) const;

  const Character& character_;
  NetworkConfig config_;
  DeformationLayer layer_;
  PoseParametrisation param_;
  std::vector<double> keypoint_mask_;
  PoseDofs pose_dofs_;    // PoseNet's outputs → dofs, within the skeleton's limits
  Tensor pivot_;          // [1,3]
  Tensor canonical_;      // [3,3] C
  Tensor rotation_bias_;  // [6] the identity's 6D vector
  DeformableSurface landmarks_;  // BODY_25 keypoints as points on the body's embedded graph
};

}  // namespace weft::capture

namespace weft::capture {

// Which network learns in a forward pass (the other runs in evaluation mode, no graph).
// deformation_frozen_statistics: PADefNet learns but normalises with its running
// batch-norm statistics (evaluation-mode normalisation, which it does not update), as in
// the physics stage, whose batches are windows of near-identical consecutive frames.
enum class Learning { none, pose, deformation, deformation_frozen_statistics };

// The batch's input views and its frames' detections in every view, for predict().
SampleViews batch_views(const Batch& batch, const MultiviewSupervision& supervision, const CaptureModel& model);

// Both networks on a batch, placed in the world by the frames' detections in every view:
// PoseNet always; PADefNet unless `deformation` is false (then the skinned template).
// with_meshes: see CaptureModel::predict. oracle_dofs ([B, D], defined): the skeleton is
// posed by these instead of PoseNet (CaptureModel::predict_posed), which then does not run.
CapturePrediction predict_batch(CaptureNetworks& networks, const CaptureModel& model, const Batch& batch,
                                const MultiviewSupervision& supervision, Learning learning, bool deformation,
                                bool with_meshes = true, const Tensor& oracle_dofs = Tensor());

}  // namespace weft::capture
