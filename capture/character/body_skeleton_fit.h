#pragma once
// A skeleton fitted to an unrigged human body mesh from its geometry alone (e.g. the
// MakeHuman base body of Debian's assimp-testmodels): cross-sections of the closed
// surface locate the crotch, armpits, neck, knees, ankles, wrists and feet, and every
// joint is placed at the centroid of a local cross-section, i.e. inside the body.
//
// Conventions of the input mesh (checked where it matters): metres (or any unit: all
// thresholds are fractions of the height), Y up, feet on y = 0, facing +z, the
// character's left at +x, standing in an A-pose (arms down and away from the torso,
// legs apart), closed and manifold.
#include <Eigen/Core>
#include <array>
#include <map>
#include <string>
#include <vector>

#include "capture/character/character.h"
#include "geometry/mesh.h"
#include "capture/character/skeleton.h"

namespace weft::capture {

// ------------------------------------------------------------------ loading (assimp)

struct LoadedBody {
  TriangleMesh mesh;           // the largest mesh of the file: welded, scaled, feet on y = 0
  Vertices extra;              // vertices of the other meshes (MakeHuman: the eyeballs), same transform
  int file_vertices = 0;       // vertex count of the body after assimp's JoinIdenticalVertices
  double file_height = 0;      // the body's height in the file's units, before scaling
  double scale = 1;            // applied: target height / file height
};

// Reads a mesh file with assimp (Triangulate | JoinIdenticalVertices), applies the node
// transforms, keeps the largest mesh as the body and welds its vertices by position
// (assimp splits them at texture seams; the per-corner UVs are kept in uv / uv_faces).
// Scales uniformly so the body is `target_height` tall (≤ 0: keep the file's scale) and
// shifts it so the lowest vertex is at y = 0. Errors name the file.
LoadedBody load_body_mesh(const std::string& path, double target_height = 0);

// ------------------------------------------------------------------ cross-sections

// One closed contour of a mesh cut by a plane.
struct Section {
  std::vector<Eigen::Vector3d> points;  // the contour, in order
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();  // area centroid of the enclosed polygon
  double area = 0;                      // enclosed area (units²)
  Eigen::Vector3d lo = Eigen::Vector3d::Zero(), hi = Eigen::Vector3d::Zero();  // bounding box
};

// The contours of a closed mesh cut by the plane n·x = d (n unit). Vertices exactly on the
// plane count as above it, so every cut triangle gives one segment. Ordered by the lowest
// edge key of each contour (deterministic).
std::vector<Section> slice_mesh(const TriangleMesh& mesh, const Eigen::Vector3d& n, double d);

// Generalised winding number of a closed, outward-oriented mesh at p: 1 inside, 0 outside.
double winding_number(const Vertices& V, const Faces& F, const Eigen::Vector3d& p);
inline bool inside_mesh(const Vertices& V, const Faces& F, const Eigen::Vector3d& p) {
  return winding_number(V, F, p) > 0.5;
}

// ------------------------------------------------------------------ the fit

// Joint names (anatomical joints; each is the LAST joint of its Skeleton chain, whose
// frame carries the joint's full rotation):
//   hips (root), spine, chest, neck, head,
//   l_clavicle, l_shoulder, l_elbow, l_wrist, l_hip, l_knee, l_ankle, l_toe, and r_… .
// End sites (no dof, for bone directions and skinning): head_end, l_hand_end, l_toe_end, r_….
extern const std::vector<std::string> kBodyJointNames;
extern const std::vector<std::string> kBodyEndSiteNames;

struct BodySkeletonFit {
  double height = 0;                            // body height (units)
  double crotch_y = 0, armpit_y = 0, neck_y = 0, waist_y = 0;  // landmark heights
  std::map<std::string, Eigen::Vector3d> joints;    // anatomical joints and end sites (bind pose)
  std::map<std::string, Eigen::Vector3d> markers;   // nose, l_eye, l_ear, l_heel, l_big_toe, l_small_toe, r_…
  Skeleton skeleton;                            // zero pose = the bind pose (all dofs 0)
  std::array<LandmarkSource, kBody25Count> body25;
};

// Fits the skeleton; `eye_points` (may be empty) are the eyeball vertices if the file has
// them, else the eyes are placed from the nose and the head's width. Throws weft::Error
// naming `what` if a landmark cannot be found or a joint falls outside the mesh.
BodySkeletonFit fit_body_skeleton(const TriangleMesh& body, const Vertices& eye_points,
                                  const std::string& what);

// Arm and hand vertices (1) by geometry: between the crotch and the armpits, vertices
// outside the torso's cross-section at their height; above the armpits, vertices beyond
// the plane through the shoulder joint perpendicular to the upper arm. Below the crotch
// there are none (the hands of an A-pose end above it).
std::vector<char> arm_vertices(const TriangleMesh& body, const BodySkeletonFit& fit);

// The Skeleton for joint positions (names as above): root hips = 3 prismatic + 3 revolute
// joints; ball joints = revolute rx, ry, rz with zero offsets between them; knees, elbows
// and toes = one limited revolute hinge; end sites = revolute joints no dof drives. Each
// dof drives one joint with weight 1 and is named like its joint with the axis suffix
// (hips_tx … hips_rz, spine_rx, …, l_knee_rx, l_elbow_flex, l_toe_rx). Ball joints get
// the anatomical limits of default_body_dof_limits (joint_limits.h); shoulders and the
// root are free.
Skeleton build_body_skeleton(const std::map<std::string, Eigen::Vector3d>& joints,
                             const std::map<std::string, Eigen::Vector3d>& markers);
// The dof names build_body_skeleton gives, in its order.
std::vector<std::string> body_skeleton_dof_names();

}  // namespace weft::capture
