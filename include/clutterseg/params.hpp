// All tunable values of clutterseg, one struct per stage of the paper (Ückermann et al., IROS 2013,
// Sec. II). Every default is in physical or scale-free units so that it works on any depth sensor and
// resolution; pixel sizes are for the paper's 320x240 Kinect v1 and scaled by PixelScale (bottom of file).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>

namespace clutterseg {

struct Params {
  // a) Depth smoothing.
  struct Smoothing {
    bool median = true;          // 3x3 median on depth, invalid pixels ignored and kept invalid
    bool temporal = true;        // motion-sensitive temporal smoothing (Segmenter only; stateful)
    int temporal_frames = 6;     // n: window length [frames]
    double temporal_band = 0.01;   // k [1/m]: values within k*z^2 of the newest are averaged
                                   // (10 mm at 1 m: 5 sigma of Kinect v1 axial noise; docs/PRESEGMENTATION.md)
    double scene_change_share = 0.5;  // the window restarts when more than this share of the pixels moved
                                      // beyond the band since the previous frame (a new scene) [-]
  } smoothing;

  // a) Normals by cross product of image neighbours on the organized 3D points, then Gaussian-smoothed.
  struct Normals {
    int step_px = 1;             // neighbour distance at 320x240 [px], scaled (PixelScale)
    int smooth_ksize = 5;        // Gaussian kernel at 320x240 [px, odd], scaled (PixelScale)
    double noise_floor = 0.92;   // beyond the paper: when the median edge value (mean |n.n_q|, stage b) over the
                                 // pixels with depth is below this, the normals are smoothed again with a
                                 // kernel twice as wide: a noisy sensor (active stereo's correlated disparity
                                 // noise) would make most of a smooth scene edges [-]; 0 = off
  } normals;

  // b) Normal edges.
  struct Edges {
    double theta = 0.89;         // pixel is an edge when mean_q |n(p).n(q)| over 8 neighbours < theta
    int step_px = 2;             // distance of the 8 neighbours at 320x240 [px], scaled (PixelScale)
    double jump_slope = 10;      // depth discontinuity: |z(p) - z(q)| > jump_slope * lateral distance
                                 // of the two pixels (a surface steeper than ~84 deg to the view ray)
  } edges;

  // c) Surface patches = 4-connected components of non-edge pixels.
  struct Patches {
    int min_size_px = 50;        // smallest patch at 320x240 [px], scaled (PixelScale)
    double metric_beyond_m = 1.3;  // beyond the paper: a component farther than this (mean depth) needs
                                 // only the metric area min_size_px covers at this depth, and at least a
                                 // quarter of min_size_px: far faces keep patches inside their edge band
                                 // [m]; 0 = min_size_px at every depth
    int histogram_bins = 11;     // normal (x, y) histogram bins per axis
    double occupied_share = 0.005;  // a histogram bin counts as occupied above this share [-]
    int flat_max_bins = 8;       // a patch is flat when fewer bins than this are occupied
    double split_band = 0.008;   // beyond the paper: a flat patch with a part of at least min_size_px
                                 // farther than this from its dominant plane is split there [m at 1 m,
                                 // times z^2 beyond]; 0 = off
    double seam_theta = 0.96;    // beyond the paper: a patch whose pixels with an edge value of at least
                                 // this form two or more parts of min_size_px is split along the band of
                                 // weaker pixels between them (a crease too shallow for theta: two stacked
                                 // boxes' fronts; seams.hpp) [-]; 0 = off
    double seam_spread_deg = 15; // ... when every part is nearly planar: its normals' mean angle to their
                                 // mean within this (or the patch is table) [deg]
  } patches;

  // d) Adjacency and assignment of edge pixels to the nearest patch.
  struct Adjacency {
    double radius_px = 7;        // image search radius at 320x240 [px], scaled (PixelScale)
    double d_max = 0.015;        // largest 3D distance to a patch pixel [m]
  } adjacency;

  // e) Cut-free neighbours (RANSAC planes of one patch must not cut the other).
  struct CutFree {
    bool enabled = true;
    int planes = 20;             // RANSAC planes per patch and direction
    double band = 0.008;         // points within +-band of a plane count as on it [m]
    double wrong_side_fraction = 0.1;  // a plane cuts when its minority side holds more points than this
                                       // share of the smaller patch [-]
    double skip_angle_deg = 30;  // pairs with mean normals closer than this skip the test (the authors' choice)
    bool skip_similar = true;    // set false to always test
    double split_share = 0.15;   // beyond the paper: a side face that the plane of a flat top it failed
                                 // this test with cuts into two parts, each at least this share of it
                                 // beyond +-band (two stacked boxes' fronts joined around the thin top
                                 // between them), is split at that plane and d) and e) run again [-];
                                 // 0 = off
  } cutfree;

  // Beyond the paper: convex or concave junctions between adjacent patches (contact.hpp). A concave
  // crease is where an object meets what it stands on or leans against.
  struct Convexity {
    bool enabled = true;
    double tolerance = 0.1;      // |mean (n_a - n_b) . (p_a - p_b) / |p_a - p_b|| below this is flat [-]
    double step = 0.5;           // a flat junction is a step between parallel faces when the points across
                                 // it are offset along the normal by more than this share of their distance
                                 // (sin of 30 deg) [-]
    double concave_weight = 0.2; // a concave or step link's graph weight is multiplied by this [-]
    double step_offset = 0.003;  // beyond: parallel faces (mean normals within 10 deg) offset along their
                                 // common normal by more than this across the contacts meet in a step,
                                 // whatever the contact normals say [m at 1 m, times z^2 beyond]; 0 = off
    double top_angle_deg = 20;   // beyond: a face whose normal is within this of up is a top; a patch resting on
                                 // it (concave crease, above its plane) touching a face below its edge (convex
                                 // edge, below its plane) touches another object there: that link is weighed
                                 // down too (a can flush with a box's front) [deg]; 0 = off
  } convexity;

  // f/g) Co-planarity of flat, non-adjacent patches separated by occlusion.
  struct Coplanarity {
    bool enabled = true;
    double angle_deg = 30;       // mean normals and sampled triple normals within this angle
    int triples = 50;            // random point triples spanning both patches
    int lines = 9;               // random lines for the occlusion check
    double behind_fraction = 0.05;  // a line fails when more samples than this lie behind the 3D segment
    double behind_tolerance = 0.01;  // a sample is behind when deeper than the segment by this [m]
    double lines_pass = 0.8;     // share of lines that must pass
    double max_gap = 0.3;        // patches farther apart than this are never joined [m]
    // Beyond the paper: a patch whose normal histogram counts as curved (sensor noise spreads a thin or far
    // face's normals over many bins) takes part when planar_share of its points lie within planar_band
    // (growing with z^2 beyond 1 m, as plane_tolerance) of the plane through its centroid along its mean
    // normal; 0 = only flat patches, as the paper. A pair with such a patch also needs an occluder:
    // front_fraction of the samples of each passing line in front of it, so that the touching coplanar
    // tops of two boxes are not joined.
    double planar_share = 0.9;   // [-], 0 = off
    double planar_band = 0.008;  // [m]
    double front_fraction = 0.1; // [-]
  } coplanarity;

  // h) Curvature matching of curved patches (normal histograms).
  struct Curvature {
    bool enabled = true;
    double theta_h = 0.5;        // similarity S = sum min(a, b) must exceed this
    bool open_objects = true;    // inner/outer walls of cups and bowls (convex next to concave)
    bool occluded = true;        // curved patches split by an occluder (line through peak-bin points)
    double line_fit = 0.01;      // RMS distance of peak-bin points to their fitted 3D line [m]
    double neighbour_gap_px = 7; // open-object patches are image neighbours within this at 320x240 [px]
    double concentric = 0.4;     // beyond the paper: a convex and a concave image neighbour whose histograms
                                 // differ (a bowl's outer wall and its inside) are one open object when their
                                 // centres of curvature (sphere centre or cylinder axis) lie within this share
                                 // of the outer wall's radius [-]; 0 = off
    double open_centre = 2.2;    // beyond the paper: the open-object rule's walls (similar histograms) must have
                                 // their centres of curvature within this share of the outer wall's radius, as
                                 // a cup's two walls do and two cylinders side by side do not [-]; 0 = off
    double split_inside = 0.6;   // beyond the paper: two concave patches whose centres of curvature (both a
                                 // sphere's or both a cylinder's) lie on each other within this share of the
                                 // larger radius, radii within this share, are one open object's inside that
                                 // something standing in it splits (a can in a bowl) [-]; 0 = off
    bool inside_crease = true;   // beyond the paper: a concave crease between two such patches (split_inside's
                                 // test, image neighbours) is a bowl's wall turning into its floor, not a
                                 // contact between objects: its link is not weighed down by
                                 // convexity.concave_weight; false = every concave crease is (needs split_inside)
  } curvature;

  // i) Graph cut on the patch graph: w_ij = 1/deg(i), symmetrised.
  struct GraphCut {
    double theta_c = 0.5;        // split a component while a cut cheaper than this exists
  } graph;

  // j) Remaining (unassigned) pixels.
  struct Remaining {
    double grow_distance = 0.01; // 8-connected Euclidean region growing [m per pixel step]
    double gap_px = 1.5;         // beyond the paper: the growing also crosses runs of at most this many pixels
                                 // without depth along the 8 directions (grow_distance per step), so that a
                                 // face seen at a grazing angle, where a Kinect drops most pixels, stays one
                                 // segment instead of specks; at 320x240 [px], scaled; 0 = 8-connected only
    int tiny_px = 20;            // "very few points" at 320x240 [px], scaled (PixelScale)
    double min_contact_share = 0.01;  // beyond the paper: in rule 3 a segment (not tiny, not enclosed) joins
                                 // its one neighbouring face only when that face holds at least this share of
                                 // the segment's ring; touching it in a pixel or two (a pan's wall without a
                                 // patch grazing a cup) it is an object of its own [-]; 0 = the paper's rule
    int hole_px = 4;             // beyond the paper: a run of pixels without depth at most this long
                                 // with one object on both ends (row or column) is that object's
                                 // (holes.hpp); at 320x240 [px], scaled; 0 = pixels without depth stay 0
    double shadow_baseline = 0.075;  // beyond the paper: the projector of a structured-light sensor lies this
                                 // far along +x of the depth camera (Kinect v1, Xtion: 7.5 cm; negative =
                                 // along -x). A row's run without depth left of a nearer object, at most as
                                 // wide as the projector's shadow (f_x b (1/z_near - 1/z_far) + hole_px / 2),
                                 // is the shadow on the farther object, and that object's (holes.hpp) [m];
                                 // 0 = off (needs hole_px > 0)
    double occluded_jump = 0.03; // beyond the paper: a segment whose only neighbouring face (rules 2-3) touches
                                 // it mostly across depth jumps larger than this, the segment behind, and
                                 // comes nowhere this near it in space, is an object that face hides, not a
                                 // part of it; among several faces (rule 5) such a face takes none of it
                                 // [m]; 0 = off (remaining.hpp)
    bool in_front = true;        // beyond the paper: ... and so is a segment that meets its face mostly across such
                                 // jumps in front of it, nowhere near it in space, concave to it (a thin box's steep
                                 // face with no patch before a cylinder; a bowl's wall, convex to its inside, stays
                                 // with it); false = only a segment behind its face
    double speck_band = 0.005;   // beyond the paper: a segment whose one face is the table and whose median height
                                 // above the table's plane lies within this of its ring's table pixels' is the
                                 // table's (a bump of stereo noise on a table a few mm off its fitted plane), not
                                 // an object that the table encloses [m at 1 m, times z^2 beyond]; 0 = off
    bool below_tops = true;      // beyond the paper: in rule 5 a face resting on a top face of another object (95 %
                                 // of its points near the segment above the top's plane) takes no pixel below that
                                 // plane (a box's front below a can flush with it); false = the paper's plane fit
    double hidden_coplanar_band = 0.008;  // beyond the paper (the co-planarity cue f/g for a remaining segment):
                                 // a segment hidden behind its face whose points lie within this of the
                                 // plane of a flat face of another object near it joins that object, the
                                 // far part of an object the occluder cuts in two [m at 1 m, times z^2
                                 // beyond]; 0 = off (a new object, as occluded_jump alone)
    bool hidden_pairs = true;    // beyond the paper: two segments hidden behind one occluder, each an object of its
                                 // own with no far part found, that lie on either side of it with only nearer things
                                 // between them and on one plane or cylinder (hidden_coplanar_band) are one object;
                                 // false = two objects
    bool apart_on_table = true;  // beyond the paper: the growing never passes from a pixel on the table's plane
                                 // (TableHint::pixel_band) to one clear of it, so the unassigned table band between
                                 // two objects' feet joins neither to the other; false = the paper's growing
    bool hidden_curved = true;   // beyond the paper: ... or on the cylinder through such a face's pixels near it
                                 // (fit_cylinder, curvature.hpp; the paper's occluded-curvature cue h for a
                                 // segment: a lying cylinder's far part); false = planes only
  } remaining;

  // Beyond the paper: the support plane (table), decided per patch before the graph (support.hpp).
  struct Support {
    bool enabled = true;         // find the table; its patches never join an object
    bool objects_only = false;   // label 0 for the support plane and background surfaces
    double plane_band = 0.015;   // a patch lies in the plane when 80 % of its points are within half
                                 // this; parts of table patches farther above it are cut off [m at 1 m
                                 // depth, times z^2 beyond: plane_tolerance()]
    double pixel_band = 0.005;   // an edge pixel higher than this above the plane is no table [m at 1 m]
    double table_angle_deg = 25; // a table patch's mean normal is within this of the plane's
    double max_height = 0.5;     // objects higher above the table than this are background [m]
    double contact_distance = 0.05;  // a patch rests on a plane when its lowest point is this close [m]
    double region_margin = 0.05; // an object stands on the table when it projects within this of the
                                 // table's visible region (convex hull in the plane) [m]
    double curved_bins_ratio = 2; // a patch whose normal histogram occupies more than this times the bins
                                  // of the largest table patch is curved, never table (a bowl's floor;
                                  // unmark_curved_table, beyond the paper); 0 = off
    double wall_min_extent = 0.35; // a flat object roughly perpendicular to the table (> 60 deg) whose
                                   // largest face is at least this long along the table is a wall [m]
    double wall_hides_share = 0.25; // beyond the paper: ... unless it stands on the table (2 % of its pixels
                                    // within contact_distance) and at least this share of its outline hides
                                    // a surface 10 % farther: a laptop's lid (walls are the farthest
                                    // surface) [-]; 0 = off
    double glued_share = 0.35;     // beyond the paper: a large patch with this share of its points on one
                                   // plane (not only 60 %) is a table candidate, a table patch needs this
                                   // share within the plane's tolerance (not half) to be cut at the plane,
                                   // and is cut below it as well as above: depth smoothed so much (filtered
                                   // stereo) that objects and the floor past the table's edge have no edge
                                   // band around them is one patch with the table [-]; 0 = off
    double enclosed_share = 0.8;   // beyond the paper: a table piece whose surroundings are at least this
                                   // share one object's (after stage j) is that object's floor, as in a pan
                                   // with a thin rim (claim_enclosed_floors) [-]; 0 = off
  } support;

  // Beyond the paper: stable object ids across the frames of a stream (tracking.hpp, docs/TRACKING.md).
  // Segmenter only (stateful); one frame alone gets ids 1..M either way.
  struct Tracking {
    bool enabled = true;         // keep ids from frame to frame; false = ids 1..M afresh every frame
    int max_missed = 30;         // an object unseen (occluded, gone, merged) for more frames than this is
                                 // forgotten; when it comes back later it gets a new id [frames]
    double max_step = 0.03;      // largest move of a centroid between two frames beyond what the track's
                                 // velocity predicts, plus half the object's box diagonal [m]
    double merge_share = 0.5;    // an object that lost its match merges into (or splits from) the object
                                 // holding more than this share of its pixels [-]
    int max_id = 65535;          // ids wrap back to 1 beyond this, skipping ids still in use (fits the
                                 // uint16 label PNGs and ROS images) [-]
  } tracking;

  std::uint64_t seed = 1;        // every random choice is seeded from this
  int threads = 0;               // rows of a frame: 0 = the idle cores but one (serial on 2 cores), N = N;
                                 // Pipeline workers: 0 = one per core; results do not depend on it
  bool keep_freed_memory = true; // tune glibc malloc to reuse a frame's memory (keep_freed_memory())
};

// Pixel sizes in Params are for the paper's camera: a 320x240 Kinect v1, fx = fy = 262.5 px. They are
// scaled by the angular resolution sqrt(fx * fy) / 262.5, so that a window covers the same field of
// view on any sensor and resolution (x2 for a 640x480 Kinect, x4 for YCB-Video's Xtion at fx = 1067).
// The factor is capped at kMax (fx = 8400 px; check_camera bounds the field of view besides), so that no
// focal length makes a kernel or a search window grow without bound.
struct PixelScale {
  static constexpr double kMax = 32;
  double factor = 1;
  PixelScale(double fx, double fy) : factor(std::min(kMax, std::sqrt(fx * fy) / 262.5)) {}
  int length(double px) const { return std::max(1, static_cast<int>(std::lround(px * factor))); }
  int area(double px) const { return std::max(1, static_cast<int>(std::lround(px * factor * factor))); }
  int odd(int ksize) const { return 2 * static_cast<int>(std::lround((ksize - 1) / 2.0 * factor)) + 1; }
};

}  // namespace clutterseg
