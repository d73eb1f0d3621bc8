// Beyond the paper (SPEC Sec. 2: the support plane as an output of its own, an objects-only view): the
// table the objects stand on, decided per patch before the patch graph is built, so that a piece of
// table never becomes part of an object and an object the edges did not close off from the table is cut
// out of it. docs/OBJECTS.md has the decisions and their measurements.
#pragma once

#include <optional>

#include "clutterseg/params.hpp"
#include "clutterseg/types.hpp"

namespace clutterseg {

// Where a plane is seen: the convex hull of its points in plane coordinates, grown by a margin and
// rasterised at 1 cm, so that "is this point over the table" is a lookup.
struct PlaneRegion {
  Plane plane;
  Eigen::Vector3f u = Eigen::Vector3f::UnitX(), v = Eigen::Vector3f::UnitY();  // orthonormal basis of the plane
  cv::Point2f origin;     // plane coordinates [m] of cell (0, 0)
  cv::Mat cells;          // CV_8U, 255 = over the region; empty = nowhere
  static constexpr float kCell = 0.01f;  // [m]
  bool over(const Eigen::Vector3f& q) const {
    // Cell coordinates; negative ones are outside, so truncation serves as floor.
    const float fx = (u.dot(q) - origin.x) * (1.f / kCell), fy = (v.dot(q) - origin.y) * (1.f / kCell);
    if (!(fx >= 0 && fy >= 0 && fx < static_cast<float>(cells.cols) && fy < static_cast<float>(cells.rows))) return false;
    return cells.at<uchar>(static_cast<int>(fy), static_cast<int>(fx)) != 0;
  }
};

// The region of `pixels` (their points projected into `plane`), grown by `margin` [m].
PlaneRegion region_of(const Plane& plane, const std::vector<int>& pixels, const cv::Mat& points, double margin);

struct Support {
  Plane plane;         // camera frame, normal facing the camera (up, for a table seen from above)
  PlaneRegion region;  // the table as seen: hull of all its patches, grown by Params::Support::region_margin
};

// How far from the plane a point at depth z [m] may lie and still be on it: band * max(1, z^2) [m]. The
// depth noise and quantisation of structured-light and stereo sensors grow with z^2; at 1 m and closer
// the band is as given.
inline float plane_tolerance(double band, float z) { return static_cast<float>(band) * std::max(1.f, z * z); }

// Sums for a least-squares plane: the points and the six distinct entries of their outer products (the
// matrix is symmetric; the other three would repeat the same products).
struct PlaneFit {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  double xx = 0, xy = 0, xz = 0, yy = 0, yz = 0, zz = 0;
  long n = 0;
  void add(const Eigen::Vector3f& point) {
    const Eigen::Vector3d q = point.cast<double>();
    sum += q;
    xx += q.x() * q.x(); xy += q.x() * q.y(); xz += q.x() * q.z();
    yy += q.y() * q.y(); yz += q.y() * q.z(); zz += q.z() * q.z();
    ++n;
  }
  Eigen::Vector3f mean() const { return (sum / static_cast<double>(n)).cast<float>(); }
  // The plane through the mean, normal along the axis of least variance, facing the camera; false for
  // fewer than 10 points or points along a line.
  bool plane(Plane& plane) const;
};

// Least-squares plane of the valid points of `pixels` (at most ~3000 read), normal facing the camera.
bool fit_plane(const std::vector<int>& pixels, const cv::Mat& points, Plane& plane);

// Share of the valid points of `pixels` (a stride of at most ~2000) within plane_tolerance(band, z) of
// `plane` is at least `share`; stops as soon as the answer is known.
bool mostly_within(const std::vector<int>& pixels, const cv::Mat& points, const Plane& plane, double band,
                   double share);

// The support plane: among the large patches that are planar (RANSAC: 60 % of the points on one plane, or
// glued_share of them when that is on), the one with the most pixels of
// other patches resting on its camera-facing side (reaching down to within contact_distance of it, at most
// max_height above it, over its visible region); then
// refitted over every patch lying in it, twice (a table split into pieces by the objects on it is one
// plane, and its far pieces are found with a tolerance that grows with depth). Deterministic.
// Candidates face up: with a pose (Camera::camera_to_robot) within 45 deg of the robot's z axis, without
// one not facing down the image (walls seen from above, ceilings).
std::optional<Plane> find_support_plane(const std::vector<Patch>& patches, const cv::Mat& points, const Camera& camera,
                                        const Params::Support& params);

// The camera-frame direction of up: the robot's z axis when a pose is given, else the image's up (-y).
Eigen::Vector3f up_in_camera(const Camera& camera);

// A patch lying in the plane: mean normal within table_angle_deg of the plane's and at least 80 % of
// its points within half the plane tolerance.
bool lies_in(const Patch& patch, const cv::Mat& points, const Plane& plane, const Params::Support& params);

// Beyond the paper: a patch marked table whose normals fill more than params.curved_bins_ratio times the
// histogram bins (Patch::occupied_bins) of the largest table patch is curved, not table: the floor of a
// bowl or a plate lies within the table's band but its normals spread far more than the table's noise.
// Unmarks such patches; returns how many. A ratio of 0 unmarks nothing.
int unmark_curved_table(std::vector<Patch>& patches, const Params::Support& params);

// Patches that are mostly table (half their points within the plane's tolerance, glued_share when that
// is on) but hold core pixels standing clear of the plane (more than the plane tolerance above it; or
// below it, when glued_share is on: the floor seen past the table's edge): objects the edges did not close
// off (a gap in the edge band, a smooth foot, depth smoothed so much that no edge is left). Marks
// in `edges` (CV_8U, 255 = edge) the pixels where such a part meets the table part of its patch, so that
// extracting the patches again separates them. Returns the number of pixels cut off (0: edges unchanged);
// patches with fewer than min_px such pixels are left whole.
int cut_off_table(cv::Mat& edges, const std::vector<Patch>& patches, const cv::Mat& patch_labels, const cv::Mat& points,
                  const Plane& plane, const Params::Support& params, int min_px);

// Beyond the paper: a flat patch that holds two surfaces (two boxes' parallel tops at different heights,
// joined through a gap in the edges) is split at its dominant plane (RANSAC, plane_tolerance(band, z)):
// when at least min_px of its pixels lie off that plane, the edge pixels between the two parts are
// marked in `edges`, as for cut_off_table. Curved patches (Patch::curved: a half-cylinder is half a plane
// too), patches with less than 60 % of their points on a plane and patches near the table's plane (which
// cut_off_table splits at that plane) are left alone. Returns the number of pixels cut off.
int split_at_planes(cv::Mat& edges, const std::vector<Patch>& patches, const cv::Mat& patch_labels, const cv::Mat& points,
                    double band, int min_px, const std::optional<Plane>& table, const Params::Support& support);

// Edge pixels that step d) gave to a table patch but that stand more than pixel_band clear of the plane
// (the foot of a box face, the lower half of a lying marker): unassigned again (0), for stage j) to give to
// the object they belong to. `edge_pixels`: the pixels step d) labelled (Assignment::assigned). Returns how many.
int release_from_table(cv::Mat& assigned_labels, const std::vector<int>& edge_pixels, const std::vector<Patch>& patches,
                       const cv::Mat& points, const Plane& plane, const Params::Support& params);

// After the graph cut, the table is one object: the group of table patches that holds the largest one,
// and every other piece, whose links the objects on the table cut (their objects are merged into the
// largest one's). Except pieces enclosed by one object: the floor inside a bowl or a cup lies as low as
// the table (a few millimetres above it, within the sensor's noise). A group of table patches (adjacent
// to each other) that does not hold the largest table patch, whose adjacent patches all belong to one
// object and that lies inside that object's image box joins that object (Patch::table cleared). A sliver
// of table between two objects stays table. object_of_patch is updated, objects left without patches are
// removed and the rest renumbered in order (cut_cost with them). Returns the number of patches that
// joined an object.
int settle_table(std::vector<Patch>& patches, const std::vector<std::pair<int, int>>& adjacent,
                 std::vector<int>& object_of_patch, std::vector<float>& cut_cost);

// Beyond the paper, after stage j): settle_table's enclosed floors, judged by pixels. A flat floor inside a
// bowl or a pan seen from above lies within the table's band, and when the wall around it has no patch
// (a thin rim: only edge band) the floor is adjacent to the table across the rim and stays table; stage j)
// then makes the rim an object of its own. A table patch other than the largest whose surroundings (the
// ring of ring_px pixels around the pixels it holds in patch_labels, which lie within reach_px of its core
// pixels: stage d's radius) are at least half labelled and, of
// the labelled pixels, at least `share` one object's that is not the table's, is that object's floor: its
// table-labelled pixels take that object's label, Patch::table is cleared and object_of_patch points to
// the object. A ring that touches the image border never encloses. Returns the patches claimed; share 0 =
// off.
int claim_enclosed_floors(cv::Mat& object_labels, const cv::Mat& patch_labels, std::vector<Patch>& patches,
                          std::vector<int>& object_of_patch, int reach_px, int ring_px, double share);

// The support with its visible region: the hull of all table patches.
Support support_of(const Plane& plane, const std::vector<Patch>& patches, const cv::Mat& points,
                   const Params::Support& params);

}  // namespace clutterseg
