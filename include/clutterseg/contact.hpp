// Beyond the paper: how two adjacent patches meet. Faces of one object meet at convex edges (a box's
// top and side); an object meets its support, or another object it rests on or leans against, in a
// concave crease (a box on the table, a can on a cup, a banana on a box). The paper's cut-free test
// (e) cannot tell these apart: a box face lies on one side of the table's plane whether it stands on
// the table or is the table's own edge. docs/COMPOSITION.md has the measurements behind the defaults.
#pragma once

#include <span>

#include "clutterseg/adjacency.hpp"
#include "clutterseg/normals.hpp"
#include "clutterseg/params.hpp"

namespace clutterseg {

// Step: parallel faces offset along their normal (a book lying on a larger book, a lid on a can): as
// faces of two objects meet, more often than faces of one.
enum class Junction : std::uint8_t { Convex, Flat, Concave, Step };

struct PairJunction {
  PatchPair pair;
  float convexity = 0;  // mean over the contacts of (n_a - n_b) . (p_a - p_b) / |p_a - p_b|, in [-2, 2]
  float step = 0;       // mean |n . (p_a - p_b)| / |p_a - p_b|, n the mean of the two normals: 0 for a
                        // coplanar continuation, 1 for a step straight along the normals
  int samples = 0;      // contacts it was measured on
  Junction kind = Junction::Flat;
};

// For every adjacent pair in `contacts` (sorted by pair, as assign_edge_pixels gives them): the mean
// convexity of the surfaces on both sides of the edge, at most `max_samples` contacts per pair (an even
// stride), from the points and the normals (camera-facing) at the two contact pixels. Convex above
// +tolerance, concave below -tolerance, else a step when step > Params::Convexity::step, else flat
// (coplanar continuations); a pair seen by fewer than 3 contacts needs a crease 3 / samples times as
// sharp. Beyond that, with `patches` (indexed as the contacts' a and b) and params.step_offset > 0: two
// patches whose mean normals are within 10 deg, whose contacts lie offset along the bisector of those
// normals by more than step_offset * max(1, z^2) on average (z their mean depth; 3 / samples times that
// for fewer than 3 contacts), meet in a step, before the convexity is looked at. Sorted by pair.
std::vector<PairJunction> classify_junctions(const std::vector<Contact>& contacts, const cv::Mat& points,
                                             const NormalPlanes& normals, const Params::Convexity& params,
                                             std::span<const Patch> patches = {});

// The junction of patches a and b (either order) in `junctions` (sorted by pair); nullptr if they have none.
const PairJunction* junction_of(const std::vector<PairJunction>& junctions, int a, int b);

// Beyond the paper (Params::Convexity::top_angle_deg): the links between an object resting on a top face and
// the faces below that face's edge. A patch A meets a top face B (mean normal within top_angle_deg of `up`) in
// a concave crease and lies above B's plane; a patch C meets B in a convex edge and lies below that plane (B's
// side face). Where A also touches C (a can standing flush with the front of a box: the can's side runs on into
// the box's front with no crease), that link is a contact between two objects as much as A-B is. Returns those
// pairs (A, C), sorted, of the adjacent pairs in `junctions` that are not concave or a step already. A patch
// lies above (below) a plane when 90 % of its points do, within 5 mm at 1 m depth (times z^2 beyond).
std::vector<PatchPair> contacts_across_tops(const std::vector<PairJunction>& junctions, std::span<const Patch> patches,
                                            const cv::Mat& points, const Eigen::Vector3f& up,
                                            const Params::Convexity& params);

}  // namespace clutterseg
